//! Shared helpers of the CLI integration tests: run the binary, read a run folder.
#![allow(dead_code)]

use serde_json::Value;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `esrl args…` to completion.
pub fn esrl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_esrl"))
        .args(args)
        .output()
        .expect("run esrl")
}

/// Runs `esrl args…` in the working directory `dir`.
pub fn esrl_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_esrl"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run esrl")
}

/// Runs `esrl args…`, asserts success and returns its output.
pub fn ok_output(args: &[&str]) -> Output {
    let out = esrl(args);
    assert!(
        out.status.success(),
        "esrl {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `esrl args…` and asserts success; returns stderr.
pub fn ok(args: &[&str]) -> String {
    String::from_utf8_lossy(&ok_output(args).stderr).into_owned()
}

/// Runs `esrl args…` and asserts success; returns stdout.
pub fn stdout(args: &[&str]) -> String {
    String::from_utf8_lossy(&ok_output(args).stdout).into_owned()
}

/// Runs `esrl args…`, asserts it fails without a panic, and returns stderr.
pub fn fails(args: &[&str]) -> String {
    let out = esrl(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "esrl {args:?} should fail: {stderr}");
    assert!(
        !stderr.contains("panicked"),
        "esrl {args:?} panicked: {stderr}"
    );
    stderr
}

/// Trains `agent` with the smoke preset into `dir`, plus `extra` flags; asserts success.
pub fn smoke(agent: &str, dir: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "train",
        agent,
        "--preset",
        "smoke",
        "--out",
        dir.to_str().unwrap(),
        "--no-progress",
    ];
    args.extend(extra);
    ok(&args)
}

/// A JSON file.
pub fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The metric rows of a run without their wall-clock field.
pub fn rows(dir: &Path) -> Vec<Value> {
    jsonl_without(&dir.join("metrics.jsonl"), &["wall_s"])
}

/// The lines of a JSON-lines file, each without the fields `drop` (timings that differ
/// between equal runs).
pub fn jsonl_without(path: &Path, drop: &[&str]) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            let m = v.as_object_mut().unwrap();
            for key in drop {
                m.remove(*key);
            }
            v
        })
        .collect()
}

/// The `curve` column of a run.
pub fn curve(dir: &Path) -> Vec<f64> {
    rows(dir)
        .iter()
        .map(|r| r["curve"].as_f64().unwrap())
        .collect()
}

/// Every tensor of a safetensors file, by name, as bit patterns (file bytes may differ in
/// header order).
pub fn tensors(path: &Path) -> BTreeMap<String, Vec<u32>> {
    esrl_nn::load_tensors(path)
        .unwrap()
        .into_iter()
        .map(|(k, t)| (k, t.data.iter().map(|x| x.to_bits()).collect()))
        .collect()
}

/// Starts `esrl args…` in the background; its stderr piped (read by [`stop`]) when `stderr`,
/// else dropped (a long run's progress would fill an unread pipe).
pub fn spawn(args: &[&str], stderr: bool) -> Child {
    Command::new(env!("CARGO_BIN_EXE_esrl"))
        .args(args)
        .stderr(if stderr {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .spawn()
        .expect("start esrl")
}

/// Polls `done` every 10 ms until it holds; fails the test with `what` after `limit_s`
/// seconds.
pub fn wait_until(limit_s: u64, what: &str, mut done: impl FnMut() -> bool) {
    let started = Instant::now();
    while !done() {
        assert!(
            started.elapsed() < Duration::from_secs(limit_s),
            "{what} (after {limit_s} s)"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Sends `signal` (`"-INT"`, `"-TERM"`) to `child` and waits for it; returns its exit code
/// and its stderr (empty unless [`spawn`] piped it).
pub fn stop(mut child: Child, signal: &str) -> (Option<i32>, String) {
    let sent = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success(), "kill {signal}");
    let code = child.wait().unwrap().code();
    let mut stderr = String::new();
    if let Some(mut pipe) = child.stderr.take() {
        pipe.read_to_string(&mut stderr).unwrap();
    }
    (code, stderr)
}

/// The `episodes` of an evaluation report without their `q0` (a policy folder holds the actor
/// alone, so its evaluations have none), to compare with a run's own.
pub fn episodes_without_q0(report: &Value) -> Value {
    let mut episodes = report["episodes"].clone();
    for e in episodes.as_array_mut().unwrap() {
        e.as_object_mut().unwrap().remove("q0");
    }
    episodes
}
