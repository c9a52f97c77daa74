//! Contract of `[restart]`: a run whose checks never went `min_distance` by `at_steps` env
//! steps starts over as seed + 1000, keeping the abandoned attempt's files under
//! `RUN/restarts/seed-S/`; the new attempt is exactly the run of seed + 1000 (same rows, same
//! weights); a run stopped after its restart resumes the new attempt exactly; the summary
//! names the attempt's seed and counts what the abandoned attempt cost.

mod common;

use common::{ok_output, read_json, rows, smoke, tensors};
use std::path::Path;

/// Checks every 100 env steps from 2 starts of the smoke preset's 1 s episodes: no check goes
/// 5 m, so with `restart` the run starts over once it has taken 150 steps.
fn config(dir: &Path, restart: bool) -> String {
    let p = dir.join(if restart {
        "restart.toml"
    } else {
        "plain.toml"
    });
    let mut text = "check = { starts = 2, every_steps = 100 }\n".to_string();
    if restart {
        text += "restart = { at_steps = 150, min_distance = 5.0, max = 1 }\n";
    }
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

fn train(dir: &Path, seed: &str, generations: &str, config: &str) -> String {
    train_with(
        dir,
        seed,
        Path::new(config),
        &["--generations", generations],
    )
}

#[test]
fn a_run_that_has_not_got_going_starts_over_as_the_run_of_seed_plus_1000() {
    let tmp = tempfile::tempdir().unwrap();
    let (with_restart, plain) = (config(tmp.path(), true), config(tmp.path(), false));
    let run = tmp.path().join("run");
    let stderr = train(&run, "3", "8", &with_restart);
    assert!(
        stderr.contains("starting over as seed 1003"),
        "the restart is announced: {stderr}"
    );

    let restarts = read_json(&run.join("restarts.json"));
    let restarts = restarts.as_array().unwrap();
    assert_eq!(restarts.len(), 1, "max = 1");
    let first = &restarts[0];
    assert_eq!(first["seed"], 3);
    assert_eq!(first["settled"], true);
    assert!(first["env_steps"].as_u64().unwrap() >= 150);
    assert!(first["best_distance"].as_f64().unwrap() < 5.0);
    let old = run.join("restarts/seed-3");
    let old_rows = rows(&old);
    assert_eq!(old_rows.len(), first["rows"].as_u64().unwrap() as usize);
    let last_steps = old_rows.last().unwrap()["env_steps"].as_u64().unwrap();
    let before_last = old_rows[old_rows.len() - 2]["env_steps"].as_u64().unwrap();
    assert!(
        before_last < 150 && last_steps >= 150,
        "abandoned at the first row past at_steps: {before_last}, {last_steps}"
    );
    for f in [
        "config.toml",
        "checks.jsonl",
        "summary.json",
        "best/best.json",
    ] {
        assert!(old.join(f).exists(), "restarts/seed-3/{f}");
    }
    assert!(!old.join("checkpoint").exists() && !old.join("replay").exists());

    // The attempt that followed is the plain run of seed 1003, row for row and weight for
    // weight (the run's budget is each attempt's).
    let reference = tmp.path().join("seed-1003");
    train(&reference, "1003", "8", &plain);
    assert_eq!(rows(&run).len(), 8);
    assert_eq!(rows(&run), rows(&reference));
    for file in ["actor.safetensors", "agent.safetensors"] {
        assert_eq!(
            tensors(&run.join("checkpoint").join(file)),
            tensors(&reference.join("checkpoint").join(file)),
            "{file}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(run.join("checks.jsonl"))
            .unwrap()
            .lines()
            .count(),
        std::fs::read_to_string(reference.join("checks.jsonl"))
            .unwrap()
            .lines()
            .count()
    );
    // config.toml keeps the seed the run was given; the summary names the attempt's.
    let cfg = std::fs::read_to_string(run.join("config.toml")).unwrap();
    assert!(cfg.contains("seed = 3"), "{cfg}");
    let summary = read_json(&run.join("summary.json"));
    assert_eq!(summary["seed"], 3);
    assert_eq!(summary["attempt_seed"], 1003);
    assert_eq!(summary["restarts"], 1);
    assert_eq!(summary["restart_env_steps"], first["env_steps"]);

    // Stopped after the restart and resumed: the same rows and weights.
    let split = tmp.path().join("split");
    train(
        &split,
        "3",
        &(old_rows.len() + 2).to_string(),
        &with_restart,
    );
    assert!(
        split.join("restarts/seed-3").is_dir(),
        "restarted before the stop"
    );
    let p = split.to_str().unwrap();
    ok_output(&[
        "train",
        "es-sac",
        "--resume",
        p,
        "--generations",
        "8",
        "--no-progress",
    ]);
    assert_eq!(rows(&split), rows(&run));
    for file in ["actor.safetensors", "agent.safetensors"] {
        assert_eq!(
            tensors(&split.join("checkpoint").join(file)),
            tensors(&run.join("checkpoint").join(file)),
            "resumed {file}"
        );
    }
    assert_eq!(
        read_json(&split.join("restarts.json"))
            .as_array()
            .unwrap()
            .len(),
        1,
        "the resumed attempt is not restarted again"
    );

    // Killed after the restart, before the new attempt's first checkpoint: resumed, the
    // attempt starts over from its seed and ends as the uninterrupted run did.
    let killed = tmp.path().join("killed");
    train(
        &killed,
        "3",
        &(old_rows.len() + 2).to_string(),
        &with_restart,
    );
    for gone in ["checkpoint", "checkpoint.old", "replay"] {
        let p = killed.join(gone);
        if p.exists() {
            std::fs::remove_dir_all(p).unwrap();
        }
    }
    let again = common::esrl(&["train", "es-sac", "--out", killed.to_str().unwrap()]);
    assert!(
        !again.status.success(),
        "a new run is not trained into a folder that started over"
    );
    ok_output(&[
        "train",
        "es-sac",
        "--resume",
        killed.to_str().unwrap(),
        "--generations",
        "8",
        "--no-progress",
    ]);
    assert_eq!(rows(&killed), rows(&run));
    assert_eq!(
        tensors(&killed.join("checkpoint/actor.safetensors")),
        tensors(&run.join("checkpoint/actor.safetensors"))
    );
}

/// With `restart.whole_budget`, `max_env_steps` is the whole run's: the attempt after a
/// restart stops at the first row where its steps and the abandoned attempt's together reach
/// the budget, its rows those of the run of seed + 1000 so far (which, given the budget for
/// itself, goes on).
#[test]
fn a_whole_budget_counts_the_abandoned_attempts_steps() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole.toml");
    std::fs::write(
        &whole,
        "check = { starts = 2, every_steps = 100 }\n\
         restart = { at_steps = 150, min_distance = 5.0, max = 1, whole_budget = true }\n",
    )
    .unwrap();
    let budget = 400;
    let run = tmp.path().join("run");
    let args = ["--generations", "60", "--steps", "400"];
    train_with(&run, "3", &whole, &args);
    let abandoned = read_json(&run.join("restarts.json"))[0]["env_steps"]
        .as_u64()
        .unwrap();
    assert!(abandoned >= 150 && abandoned < budget, "{abandoned}");
    let attempt = rows(&run);
    let steps = |r: &serde_json::Value| r["env_steps"].as_u64().unwrap();
    let (before, last) = (
        steps(&attempt[attempt.len() - 2]),
        steps(attempt.last().unwrap()),
    );
    assert!(
        abandoned + before < budget && abandoned + last >= budget,
        "stopped at the first row past the whole budget: {abandoned} + {before}, {last}"
    );
    let summary = read_json(&run.join("summary.json"));
    assert_eq!(summary["finished"], true);
    assert_eq!(summary["restart_env_steps"], abandoned);

    let reference = tmp.path().join("seed-1003");
    train_with(
        &reference,
        "1003",
        Path::new(&config(tmp.path(), false)),
        &args,
    );
    let full = rows(&reference);
    assert!(steps(full.last().unwrap()) >= budget, "its own budget");
    assert!(full.len() > attempt.len());
    assert_eq!(attempt, full[..attempt.len()]);
}

fn train_with(dir: &Path, seed: &str, config: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "--seed",
        seed,
        "--threads",
        "1",
        "--config",
        config.to_str().unwrap(),
    ];
    args.extend(extra);
    smoke("es-sac", dir, &args)
}

#[test]
fn restart_without_the_walking_check_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("bad.toml");
    std::fs::write(&p, "restart = { at_steps = 150 }\n").unwrap();
    let stderr = common::fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--config",
        p.to_str().unwrap(),
        "--out",
        tmp.path().join("run").to_str().unwrap(),
    ]);
    assert!(
        stderr.contains("[restart] needs the walking check"),
        "{stderr}"
    );
}

#[test]
fn a_study_records_the_abandoned_attempts_and_reports_the_kept_seed() {
    let tmp = tempfile::tempdir().unwrap();
    let study = tmp.path().join("restart.toml");
    std::fs::write(
        &study,
        r#"
description = "restart smoke study"
seeds = [3]
[eval]
episodes = 2
[[arm]]
name = "restart"
agent = "es-sac"
preset = "smoke"
generations = 6
set = { check = { starts = 2, every_steps = 100 }, restart = { at_steps = 150, min_distance = 5.0, max = 1 } }
"#,
    )
    .unwrap();
    let dir = tmp.path().join("study");
    let d = dir.to_str().unwrap();
    common::ok(&[
        "study",
        "run",
        study.to_str().unwrap(),
        "--out",
        d,
        "--jobs",
        "1",
        "--threads",
        "1",
        "--no-progress",
    ]);
    let record = dir.join("records/restart-s3");
    let restarts = read_json(&record.join("restarts.json"));
    assert_eq!(restarts[0]["seed"], 3);
    for f in ["metrics.csv", "summary.json", "checks.jsonl"] {
        assert!(record.join("restarts/seed-3").join(f).is_file(), "{f}");
    }
    common::ok(&["study", "report", d]);
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        report.contains("restart-s3 (restarted as seed 1003)"),
        "{report}"
    );
    // The run's cost counts the abandoned attempt.
    let csv = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    let summary = read_json(&record.join("summary.json"));
    let total = summary["env_steps"].as_u64().unwrap() + restarts[0]["env_steps"].as_u64().unwrap();
    assert!(csv.contains(&format!(",{total},")), "{csv}");
}
