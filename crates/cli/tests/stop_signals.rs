//! Contract: SIGTERM and SIGINT stop a training like a finished generation: the signal is
//! acknowledged at once, a checkpoint is written, the command exits with 128 + the signal
//! (143, 130), and `--resume` then produces exactly the rows and weights of an uninterrupted
//! run. A stopped `esrl compare` starts no queued run and writes no report; the same command
//! resumes it exactly. A stopped `esrl eval` writes the report of the episodes it finished.
#![cfg(unix)]

mod common;

use common::{ok, rows, tensors};
use std::path::Path;
use std::time::Duration;

fn row_count(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("metrics.jsonl"))
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

/// Starts `esrl ARGS`, sends `signal` once `watched` has 3 rows, and returns the exit status
/// and stderr.
fn stop_after_three_rows(args: &[String], watched: &Path, signal: &str) -> (Option<i32>, String) {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let child = common::spawn(&args, true);
    common::wait_until(120, "no rows", || row_count(watched) >= 3);
    common::stop(child, signal)
}

fn stop_and_resume(signal: &str, status: i32) {
    let tmp = tempfile::tempdir().unwrap();
    let (straight, split) = (tmp.path().join("straight"), tmp.path().join("split"));
    let args = |dir: &Path| {
        vec![
            "train".to_string(),
            "es-td3".into(),
            "--preset".into(),
            "smoke".into(),
            "--seed".into(),
            "4".into(),
            "--generations".into(),
            "60".into(),
            "--threads".into(),
            "1".into(),
            "--out".into(),
            dir.to_str().unwrap().into(),
        ]
    };
    let (exit, stderr) = stop_after_three_rows(&args(&split), &split, signal);
    assert_eq!(exit, Some(status), "{signal}: {stderr}");
    assert!(
        stderr.contains("received: a training finishes the current"),
        "{stderr}"
    );
    assert!(stderr.contains("--resume"), "{stderr}");
    let stopped_at = row_count(&split);
    assert!(stopped_at < 60, "stopped early");
    let state: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(split.join("checkpoint/state.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        state["rows"], stopped_at,
        "the checkpoint covers every written row"
    );

    ok(&["train", "es-td3", "--resume", split.to_str().unwrap()]);
    let straight_args = args(&straight);
    let refs: Vec<&str> = straight_args.iter().map(String::as_str).collect();
    ok(&refs);
    assert_eq!(rows(&straight), rows(&split), "{signal}");
    assert_eq!(
        tensors(&straight.join("checkpoint/agent.safetensors")),
        tensors(&split.join("checkpoint/agent.safetensors"))
    );
}

#[test]
fn sigterm_checkpoints_exits_143_and_resumes_exactly() {
    stop_and_resume("-TERM", 143);
}

#[test]
fn sigint_checkpoints_exits_130_and_resumes_exactly() {
    stop_and_resume("-INT", 130);
}

/// `esrl compare` stopped by SIGTERM while its first run trains: that run checkpoints, no
/// queued run starts, no report is written, the exit status is 143; the same command then
/// resumes and finishes, its runs identical to runs trained without a stop.
#[test]
fn a_stopped_comparison_starts_no_other_run_and_resumes_exactly() {
    let tmp = tempfile::tempdir().unwrap();
    let (split, straight) = (tmp.path().join("split"), tmp.path().join("straight"));
    let args = |dir: &Path| {
        vec![
            "compare".to_string(),
            "--agents".into(),
            "es-td3,sac,td3".into(),
            "--seeds".into(),
            "1".into(),
            "--preset".into(),
            "smoke".into(),
            "--generations".into(),
            "60".into(),
            "--jobs".into(),
            "1".into(),
            "--threads".into(),
            "1".into(),
            "--no-progress".into(),
            "--eval-episodes".into(),
            "2".into(),
            "--out".into(),
            dir.to_str().unwrap().into(),
        ]
    };
    let first = split.join("runs/es-td3-s0");
    let (exit, stderr) = stop_after_three_rows(&args(&split), &first, "-TERM");
    assert_eq!(exit, Some(143), "{stderr}");
    assert!(row_count(&first) < 60, "stopped early: {stderr}");
    assert!(first.join("checkpoint/state.json").is_file());
    for queued in ["sac-s0", "td3-s0"] {
        assert!(
            !split.join("runs").join(queued).exists(),
            "{queued} started: {stderr}"
        );
        assert!(
            stderr.contains(&format!("{queued}: not started")),
            "{stderr}"
        );
    }
    assert!(!split.join("report.md").exists(), "{stderr}");

    let resume = args(&split);
    let resumed = ok(&resume.iter().map(String::as_str).collect::<Vec<_>>());
    // The resumed run reports its time in this command and its whole training time.
    let line = resumed
        .lines()
        .find(|l| l.contains("finished") && l.contains("es-td3-s0"))
        .unwrap_or_else(|| panic!("{resumed}"));
    let total: f64 = line
        .split('(')
        .nth(1)
        .and_then(|t| t.strip_suffix(" s of training in all)"))
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(first.join("summary.json")).unwrap())
            .unwrap();
    assert!(
        (total - summary["wall_s"].as_f64().unwrap()).abs() < 0.051,
        "{line}"
    );
    let whole = args(&straight);
    ok(&whole.iter().map(String::as_str).collect::<Vec<_>>());
    for run in ["es-td3-s0", "sac-s0", "td3-s0"] {
        let (a, b) = (
            straight.join("runs").join(run),
            split.join("runs").join(run),
        );
        assert_eq!(rows(&a), rows(&b), "{run}");
        let eval = |d: &Path| common::read_json(&d.join("records").join(run).join("eval.json"));
        assert_eq!(eval(&straight)["mean"], eval(&split)["mean"], "{run}");
    }
}

#[test]
fn a_stopped_evaluation_reports_the_episodes_it_finished() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    common::smoke("es-sac", &run, &["--generations", "1"]);
    let out = tmp.path().join("eval.json");
    let child = common::spawn(
        &[
            "eval",
            run.to_str().unwrap(),
            "--episodes",
            "100000",
            "--out",
            out.to_str().unwrap(),
        ],
        true,
    );
    std::thread::sleep(Duration::from_millis(1500));
    let (exit, stderr) = common::stop(child, "-INT");
    assert_eq!(exit, Some(130), "{stderr}");
    let report = common::read_json(&out);
    let done = report["episodes"].as_array().unwrap().len();
    assert!(done > 0 && done < 100_000, "{done} episodes");
    assert_eq!(report["requested"], 100_000);
    assert_eq!(report["mean"]["episodes"].as_u64(), Some(done as u64));
    assert!(stderr.contains("stopped:"), "{stderr}");
}
