//! Contract: `esrl study run` trains a study file's arms × seeds into records that do not
//! depend on how it was run: stopped with SIGINT part-way and run again it gives the records
//! of an uninterrupted run, and `--shard 0/2` + `--shard 1/2` give those of the whole; `esrl
//! study status` and `report` read them (Wilson and bootstrap intervals, every run, Table 1).
#![cfg(unix)]

mod common;

use common::{fails, ok, read_json};
use std::path::Path;
use std::process::Child;

const STUDY: &str = r#"
description = "smoke study"
seeds = 2
[eval]
episodes = 2
[[arm]]
name = "essac"
agent = "es-sac"
preset = "smoke"
generations = 6
[[arm]]
name = "sac"
agent = "sac"
preset = "smoke"
episodes = 6
"#;

/// `esrl study run STUDY --out OUT --jobs 1` started in the background.
fn spawn_study(study: &Path, out: &Path) -> Child {
    common::spawn(
        &[
            "study",
            "run",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--jobs",
            "1",
            "--no-progress",
        ],
        false,
    )
}

fn write_study(dir: &Path) -> String {
    let p = dir.join("smoke.toml");
    std::fs::write(&p, STUDY).unwrap();
    p.to_str().unwrap().to_owned()
}

/// `esrl study run STUDY --out OUT`, which must fail; its stderr.
fn study_refused(study: &Path, out: &Path) -> String {
    fails(&[
        "study",
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

/// Writes `text` as `dir/own.toml` and runs it with `esrl study run` into `dir/out`; returns
/// the study file and the output folder.
fn run_own_study(dir: &Path, text: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let study = dir.join("own.toml");
    std::fs::write(&study, text).unwrap();
    let out = dir.join("out");
    ok(&[
        "study",
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    (study, out)
}

/// Asserts two record lists are equal, naming the first file that differs.
fn same(a: &[(String, String)], b: &[(String, String)], what: &str) {
    assert_eq!(
        a.iter().map(|x| &x.0).collect::<Vec<_>>(),
        b.iter().map(|x| &x.0).collect::<Vec<_>>(),
        "{what}: the same records"
    );
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.1, y.1, "{what}: {} differs", x.0);
    }
}

/// Everything in a study folder's records but wall-clock times: file name → content.
fn records(dir: &Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let root = dir.join("records");
    let mut names: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    for run in names {
        for file in ["metrics.csv", "summary.json", "eval.json", "config.toml"] {
            let text = std::fs::read_to_string(root.join(&run).join(file)).unwrap();
            let text = match file {
                "metrics.csv" => text
                    .lines()
                    .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_owned())
                    .collect::<Vec<_>>()
                    .join("\n"),
                "summary.json" => {
                    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
                    v.as_object_mut().unwrap().remove("wall_s");
                    v.to_string()
                }
                _ => text,
            };
            out.push((format!("{run}/{file}"), text));
        }
        let actor = std::fs::read(root.join(&run).join("policy/actor.safetensors")).unwrap();
        let hash = actor.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
        });
        out.push((format!("{run}/actor"), format!("FNV-1a {hash:016x}")));
    }
    out
}

#[test]
fn a_stopped_study_resumes_to_the_records_of_an_uninterrupted_one() {
    let tmp = tempfile::tempdir().unwrap();
    let study = write_study(tmp.path());
    let (whole, split) = (tmp.path().join("whole"), tmp.path().join("split"));
    ok(&[
        "study",
        "run",
        &study,
        "--out",
        whole.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    // Stopped once the first run has rows, then run again.
    let child = common::spawn(
        &[
            "study",
            "run",
            &study,
            "--out",
            split.to_str().unwrap(),
            "--jobs",
            "2",
        ],
        false,
    );
    let first = split.join("runs/essac-s0/metrics.jsonl");
    common::wait_until(60, "no rows", || {
        std::fs::read_to_string(&first).map_or(0, |t| t.lines().count()) >= 2
    });
    assert_eq!(common::stop(child, "-INT").0, Some(130));
    ok(&[
        "study",
        "run",
        &study,
        "--out",
        split.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    same(&records(&whole), &records(&split), "stopped and continued");

    // Two shards make the whole.
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    ok(&[
        "study",
        "run",
        &study,
        "--out",
        a.to_str().unwrap(),
        "--shard",
        "0/2",
    ]);
    ok(&[
        "study",
        "run",
        &study,
        "--out",
        b.to_str().unwrap(),
        "--shard",
        "1/2",
    ]);
    let mut merged = records(&a);
    merged.extend(records(&b));
    merged.sort();
    let mut all = records(&whole);
    all.sort();
    same(&merged, &all, "two shards");
    // Shard 1's records copied into shard 0's folder: the whole study is recorded there, so
    // running it again trains nothing (no run folder appears for the copied records).
    for e in std::fs::read_dir(b.join("records")).unwrap() {
        let e = e.unwrap();
        let to = a.join("records").join(e.file_name());
        std::fs::create_dir_all(to.join("policy")).unwrap();
        for f in std::fs::read_dir(e.path()).unwrap() {
            let f = f.unwrap();
            if f.path().is_file() {
                std::fs::copy(f.path(), to.join(f.file_name())).unwrap();
            }
        }
        for f in std::fs::read_dir(e.path().join("policy")).unwrap() {
            let f = f.unwrap();
            std::fs::copy(f.path(), to.join("policy").join(f.file_name())).unwrap();
        }
    }
    ok(&["study", "run", &study, "--out", a.to_str().unwrap()]);
    for name in std::fs::read_dir(b.join("runs")).unwrap() {
        let name = name.unwrap().file_name();
        assert!(
            !a.join("runs").join(&name).exists(),
            "{name:?} was trained again although its record was there"
        );
    }
    let mut merged = records(&a);
    merged.sort();
    same(&merged, &all, "merged records");

    // Status and report read the folder.
    let status = common::stdout(&["study", "status", whole.to_str().unwrap()]);
    assert_eq!(status.matches("| recorded |").count(), 4, "{status}");
    ok(&["study", "report", whole.to_str().unwrap()]);
    let md = std::fs::read_to_string(whole.join("report.md")).unwrap();
    for want in [
        "## Per arm",
        "| essac | 2 | 0 | 0 % [0–66 %]",
        // Smoke runs have no walking check: nothing to say about when they walked.
        "| – (no check) | – |",
        "## Every run",
        "| sac-s1 |",
        "## Table 1",
        "## Probability of improvement",
    ] {
        assert!(md.contains(want), "missing {want:?} in:\n{md}");
    }
    let json = common::stdout(&["study", "report", whole.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["runs"].as_array().unwrap().len(), 4);
    // A record's policy folder is evaluated again to the same numbers.
    let policy = whole.join("records/essac-s1/policy");
    let again = tmp.path().join("again.json");
    ok(&[
        "eval",
        policy.to_str().unwrap(),
        "--episodes",
        "2",
        "--seed",
        "1000",
        "--out",
        again.to_str().unwrap(),
    ]);
    assert_eq!(
        read_json(&again)["episodes"][1]["return"],
        read_json(&whole.join("records/essac-s1/eval.json"))["episodes"][1]["return"]
    );
}

#[test]
fn a_study_folder_holds_one_study_and_bad_files_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let study = write_study(tmp.path());
    let (_, out) = run_own_study(tmp.path(), &STUDY.replace("seeds = 2", "seeds = 1"));
    let err = fails(&["study", "run", &study, "--out", out.to_str().unwrap()]);
    assert!(err.contains("holds another study"), "{err}");
    let bad = tmp.path().join("bad.toml");
    for (text, want) in [
        ("seeds = 2\n", "arm"),
        (
            "seeds = 2\n[[arm]]\nname = \"a b\"\nagent = \"sac\"\n",
            "arm name",
        ),
        (
            "seeds = 2\n[[arm]]\nname = \"a\"\nagent = \"sac\"\nset = { seed = 3 }\n",
            "seed",
        ),
        (
            "seeds = 2\n[[arm]]\nname = \"a\"\nagent = \"sac\"\nset = { rl = { gamma = 7.0 } }\n",
            "gamma",
        ),
        (
            "seeds = 2\n[[arm]]\nname = \"a\"\nagent = \"sac\"\nseeds = [3, 3]\n",
            "arm `a`: seeds: a seed is listed twice",
        ),
        (
            "seeds = 2\n[[arm]]\nname = \"a\"\nagent = \"sac\"\nseeds = []\n",
            "arm `a`: seeds: no seed",
        ),
    ] {
        std::fs::write(&bad, text).unwrap();
        let err = study_refused(&bad, &tmp.path().join("x"));
        assert!(err.contains(want), "{text}: {err}");
    }
    let err = fails(&["study", "report", tmp.path().to_str().unwrap()]);
    assert!(err.contains("not a study folder"), "{err}");
}

/// A run's record is written as soon as the run finishes, not when the whole study does: a
/// study stopped while its second run trains keeps the first run's record.
#[test]
fn each_run_is_recorded_as_it_finishes() {
    let tmp = tempfile::tempdir().unwrap();
    let study = tmp.path().join("two.toml");
    std::fs::write(
        &study,
        r#"
seeds = [0]
[eval]
episodes = 1
[[arm]]
name = "short"
agent = "sac"
preset = "smoke"
episodes = 2
[[arm]]
name = "long"
agent = "sac"
preset = "smoke"
episodes = 100000
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let mut child = spawn_study(&study, &out);
    let first = out.join("records/short-s0/eval.json");
    common::wait_until(
        120,
        "no record of the finished run while the study goes on",
        || first.is_file(),
    );
    assert_eq!(
        child.try_wait().unwrap(),
        None,
        "the second run still trains"
    );
    // `study status` tells the run in training from a stopped one (by the run's lock).
    let long = out.join("runs/long-s0/metrics.jsonl");
    common::wait_until(120, "the second run has no rows", || long.is_file());
    let status = || common::stdout(&["study", "status", out.to_str().unwrap()]);
    let during = status();
    assert!(during.contains("| short-s0 | recorded |"), "{during}");
    assert!(during.contains("| long-s0 | training now |"), "{during}");
    assert_eq!(common::stop(child, "-INT").0, Some(130));
    assert!(first.is_file());
    assert!(!out.join("records/long-s0").exists());
    let after = status();
    assert!(after.contains("| long-s0 | stopped"), "{after}");
}

/// A run trained before the study (by `esrl train` into the study's `runs/` folder, or by an
/// earlier `esrl study run` stopped before it wrote the record) is recorded before any
/// training starts: a study stopped during its first training keeps that record.
#[test]
fn runs_finished_before_the_study_are_recorded_first() {
    let tmp = tempfile::tempdir().unwrap();
    let study = tmp.path().join("two.toml");
    std::fs::write(
        &study,
        r#"
seeds = [0]
[eval]
episodes = 1
[[arm]]
name = "long"
agent = "sac"
preset = "smoke"
episodes = 100000
[[arm]]
name = "short"
agent = "sac"
preset = "smoke"
episodes = 2
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    common::smoke(
        "sac",
        &out.join("runs/short-s0"),
        &["--episodes", "2", "--seed", "0"],
    );
    let mut child = spawn_study(&study, &out);
    let record = out.join("records/short-s0/eval.json");
    let long = out.join("runs/long-s0/metrics.jsonl");
    common::wait_until(
        120,
        "no record of the run trained before the study while the study trains",
        || record.is_file() && long.is_file(),
    );
    assert_eq!(child.try_wait().unwrap(), None, "the long run still trains");
    assert_eq!(common::stop(child, "-INT").0, Some(130));
    assert!(record.is_file());
    assert!(!out.join("records/long-s0").exists());
}

/// `{seed}` in an arm's `init` is the run's seed: each seed of a fine-tuning study starts from
/// its own policy, and a missing one is named.
#[test]
fn an_arms_init_names_each_seeds_own_policy() {
    let tmp = tempfile::tempdir().unwrap();
    for seed in ["0", "1"] {
        let src = tmp.path().join(format!("src-s{seed}"));
        common::smoke("sac", &src, &["--episodes", "2", "--seed", seed]);
    }
    let text = r#"
seeds = [0, 1]
[eval]
episodes = 1
[[arm]]
name = "tuned"
agent = "sac"
preset = "smoke"
episodes = 2
set = { init = "src-s{seed}" }
"#;
    let (study, out) = run_own_study(tmp.path(), text);
    for seed in [0, 1] {
        let record: toml::Table =
            std::fs::read_to_string(out.join(format!("records/tuned-s{seed}/config.toml")))
                .unwrap()
                .parse()
                .unwrap();
        let init = record["init"].as_str().unwrap();
        assert!(
            init.ends_with(&format!("src-s{seed}")),
            "seed {seed}: {init}"
        );
        let loaded = read_json(&out.join(format!("runs/tuned-s{seed}/init.json")));
        assert!(
            loaded["from"]
                .as_str()
                .unwrap()
                .ends_with(&format!("src-s{seed}")),
            "seed {seed}: {loaded}"
        );
    }
    std::fs::write(&study, text.replace("[0, 1]", "[2]")).unwrap();
    let err = study_refused(&study, &tmp.path().join("missing"));
    assert!(err.contains("src-s2"), "{err}");
}

/// An arm may run seeds of its own instead of the study's: its runs are named by them and
/// the report says how many each arm has.
#[test]
fn an_arm_may_have_seeds_of_its_own() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, out) = run_own_study(
        tmp.path(),
        r#"
seeds = 2
[eval]
episodes = 1
[[arm]]
name = "all"
agent = "sac"
preset = "smoke"
episodes = 2
[[arm]]
name = "few"
agent = "sac"
preset = "smoke"
episodes = 2
seeds = [5]
"#,
    );
    let mut names: Vec<String> = std::fs::read_dir(out.join("records"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["all-s0", "all-s1", "few-s5"]);
    let few: toml::Table = std::fs::read_to_string(out.join("records/few-s5/config.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(few["seed"].as_integer(), Some(5));
    ok(&["study", "report", out.to_str().unwrap()]);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("2 arm(s), seeds per arm (all 2, few 1); 3 of 3 runs recorded"),
        "{report}"
    );
}

/// `[eval] robustness_episodes = n` puts each handed-over policy's robustness card in its
/// record, with the goal rows it meets, and the report counts the runs meeting them; an arm
/// that does not walk is refused before anything trains.
#[test]
fn a_study_may_card_each_policy_and_report_the_robustness_goal() {
    let tmp = tempfile::tempdir().unwrap();
    let text = r#"
seeds = [0]
[eval]
episodes = 1
robustness_episodes = 1
[[arm]]
name = "carded"
agent = "es-sac"
preset = "smoke"
generations = 1
"#;
    let (study, out) = run_own_study(tmp.path(), text);
    let eval = read_json(&out.join("records/carded-s0/eval.json"));
    let card = eval["robustness"].as_array().unwrap();
    assert_eq!(
        card.len(),
        1 + 25,
        "the undisturbed task and 25 disturbances"
    );
    assert!(card.iter().all(|r| r["episodes"] == 1), "{card:?}");
    let goal = &eval["robustness_goal"];
    let (rows, met) = (
        goal["rows"].as_u64().unwrap(),
        goal["met"].as_u64().unwrap(),
    );
    assert_eq!(rows, 12, "{goal}");
    assert_eq!(
        met + goal["missed"].as_array().unwrap().len() as u64,
        rows,
        "{goal}"
    );
    ok(&["study", "report", out.to_str().unwrap()]);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Robustness goal"), "{md}");
    assert!(md.contains(&format!("| carded-s0 | {met} of 12 |")), "{md}");
    let figures = read_json(&out.join("report.json"));
    assert_eq!(figures["robustness"]["arms"][0]["runs"], 1, "{figures}");

    std::fs::write(
        &study,
        text.replace(
            "preset = \"smoke\"",
            "preset = \"smoke\"\nset = { env = \"pendulum\" }",
        ),
    )
    .unwrap();
    let err = study_refused(&study, &tmp.path().join("pendulum"));
    assert!(err.contains("robustness_episodes"), "{err}");
}
