//! Contract: `esrl compare` is a front for a study. `esrl compare --agents es-sac,sac --seeds
//! 2 --preset smoke --out DIR` writes the study its options describe to `DIR/study.toml`
//! (one arm per agent), trains and records every agent × seed under `DIR/runs/` and
//! `DIR/records/`, and writes the report `esrl study report DIR` writes (Table 1 with one row
//! per agent, the per-actuator and per-joint tables); while training, each run logs lines
//! prefixed with its name. A second invocation trains and evaluates nothing and writes the
//! same report; `esrl study run DIR/study.toml --out DIR` takes the same folder as finished;
//! other options on the same folder are refused; `--steps N` gives every run the same
//! environment-step budget; unknown agent names fail with the list of valid ones.

mod common;

use common::{esrl, ok_output as ok, read_json};
use std::path::Path;
use std::time::SystemTime;

const RUNS: [&str; 4] = ["es-sac-s0", "es-sac-s1", "sac-s0", "sac-s1"];

fn mtimes(dir: &Path) -> Vec<(String, SystemTime)> {
    let mut out = Vec::new();
    for run in RUNS {
        for f in [
            "runs/{run}/metrics.jsonl",
            "runs/{run}/summary.json",
            "runs/{run}/checkpoint/state.json",
            "records/{run}/eval.json",
        ] {
            let p = dir.join(f.replace("{run}", run));
            let t = std::fs::metadata(&p)
                .and_then(|m| m.modified())
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            out.push((p.display().to_string(), t));
        }
    }
    out
}

/// `esrl compare` of ES-SAC and SAC, 2 seeds each, on `smoke` into `out`, two at a time,
/// 2 evaluation episodes each, then `extra`.
fn smoke_compare<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "compare",
        "--agents",
        "es-sac,sac",
        "--seeds",
        "2",
        "--preset",
        "smoke",
        "--out",
        out,
        "--no-progress",
        "--jobs",
        "2",
        "--eval-episodes",
        "2",
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn compare_runs_the_study_its_options_describe_and_reuses_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let d = dir.to_str().unwrap();
    let args = smoke_compare(d, &[]);
    let first = ok(&args);
    // Runs trained side by side report themselves by name, from their first row on.
    let log = String::from_utf8_lossy(&first.stderr);
    for (run, unit) in [
        ("es-sac-s0", "generations"),
        ("es-sac-s1", "generations"),
        ("sac-s0", "episodes"),
        ("sac-s1", "episodes"),
    ] {
        let line = log
            .lines()
            .find(|l| l.starts_with(&format!("[{run}] 1/")))
            .unwrap_or_else(|| panic!("no first-row line of {run} in:\n{log}"));
        assert!(
            line.contains(&format!(" {unit}, ")) && line.contains("env steps | best so far"),
            "{line}"
        );
    }
    let study = std::fs::read_to_string(dir.join("study.toml")).unwrap();
    for key in [
        "seeds = 2",
        "name = \"es-sac\"",
        "name = \"sac\"",
        "preset = \"smoke\"",
        "episodes = 2",
    ] {
        assert!(study.contains(key), "`{key}` missing from\n{study}");
    }
    for run in RUNS {
        let eval = read_json(&dir.join("records").join(run).join("eval.json"));
        assert_eq!(eval["episodes"].as_array().unwrap().len(), 2, "{run}");
        assert_eq!(eval["seed"], 1000, "{run}");
    }
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let stdout = String::from_utf8_lossy(&first.stdout).to_string();
    assert_eq!(stdout, md, "the report is printed and written");
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| ")).collect();
    // Per arm, Table 1, the actuator table and the joint table: one row per agent each, and
    // one per run in the run table.
    assert_eq!(
        rows.iter().filter(|l| l.starts_with("| es-sac |")).count(),
        4,
        "{md}"
    );
    assert_eq!(
        rows.iter().filter(|l| l.starts_with("| sac |")).count(),
        4,
        "{md}"
    );
    assert!(md.contains("left_knee ROM (°)"), "{md}");
    assert!(md.contains("Best-Win-50") && md.contains("Episodes-to-Target"));

    // The same report from `esrl study report`, and nothing redone the second time.
    let again = ok(&["study", "report", d]);
    assert_eq!(String::from_utf8_lossy(&again.stdout), md);
    let before = mtimes(&dir);
    let second = ok(&args);
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(!err.contains("training "), "nothing retrained: {err}");
    assert!(err.contains("0 to train"), "{err}");
    assert_eq!(mtimes(&dir), before, "runs and records are untouched");
    assert_eq!(String::from_utf8_lossy(&second.stdout), md);
    let study_run = ok(&[
        "study",
        "run",
        dir.join("study.toml").to_str().unwrap(),
        "--out",
        d,
    ]);
    assert!(String::from_utf8_lossy(&study_run.stderr).contains("0 to train"));

    // Other options on the same folder: refused, nothing touched.
    let other = esrl(&smoke_compare(d, &["--steps", "100000"])[..]);
    assert_eq!(other.status.code(), Some(1));
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(err.contains("holds another comparison"), "{err}");
    assert_eq!(mtimes(&dir), before);
}

#[test]
fn steps_gives_every_run_the_same_budget() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let d = dir.to_str().unwrap();
    ok(&[
        "compare",
        "--agents",
        "sac,es-td3",
        "--seeds",
        "1",
        "--preset",
        "smoke",
        "--generations",
        "50",
        "--episodes",
        "50",
        "--steps",
        "600",
        "--eval-episodes",
        "1",
        "--out",
        d,
        "--no-progress",
    ]);
    for run in ["sac-s0", "es-td3-s0"] {
        let cfg = std::fs::read_to_string(dir.join("runs").join(run).join("config.toml")).unwrap();
        assert!(cfg.contains("max_env_steps = 600"), "{run}: {cfg}");
        let steps = read_json(&dir.join("runs").join(run).join("summary.json"))["env_steps"]
            .as_u64()
            .unwrap();
        // Each stops at the first episode/generation boundary past the budget.
        assert!(
            (600..600 + 400).contains(&steps),
            "{run}: {steps} env steps"
        );
    }
}

#[test]
fn unknown_agents_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let out = esrl(&[
        "compare",
        "--agents",
        "es-sac,nonsense",
        "--preset",
        "smoke",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown agent `nonsense`"), "{err}");
    assert!(
        err.contains("es-sac, es-td3, es-ddpg, sac, td3, ddpg"),
        "{err}"
    );
    assert!(!dir.exists(), "nothing trained or written");
}
