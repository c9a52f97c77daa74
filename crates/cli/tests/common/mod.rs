//! Shared helpers of the CLI integration tests: run the binary, read a run folder.
#![allow(dead_code)]

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

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
    std::fs::read_to_string(dir.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("wall_s");
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
