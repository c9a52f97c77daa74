//! Shared helpers of the CLI integration tests: run the binary, read a run folder.
#![allow(dead_code)]

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

/// Runs `esrl args…` and asserts success; returns stderr.
pub fn ok(args: &[&str]) -> String {
    let out = esrl(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "esrl {args:?}: {stderr}");
    stderr
}

/// Runs `esrl args…`, asserts it fails, and returns stderr.
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

/// The metric rows of a run without their wall-clock field.
pub fn rows(dir: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("wall_s");
            v
        })
        .collect()
}

/// Every tensor of a safetensors file, by name, as bit patterns.
pub fn tensors(path: &Path) -> BTreeMap<String, Vec<u32>> {
    esrl_nn::load_tensors(path)
        .unwrap()
        .into_iter()
        .map(|(k, t)| (k, t.data.iter().map(|x| x.to_bits()).collect()))
        .collect()
}

/// Training options as the command line gives them: a preset, an optional `--config` file
/// and `--generations`, one thread, no progress bar.
pub fn train_options(
    preset: esrl::args::Preset,
    config: Option<std::path::PathBuf>,
    generations: Option<usize>,
) -> esrl::args::TrainOptions {
    esrl::args::TrainOptions {
        preset,
        config,
        env: None,
        urdf: None,
        threads: Some(1),
        generations,
        episodes: None,
        steps: None,
        no_progress: true,
    }
}

/// A resolved configuration as TOML, without the recorded preset name.
pub fn without_preset_name(c: &esrl::config::TrainConfig) -> String {
    c.to_toml()
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("preset ="))
        .collect::<Vec<_>>()
        .join("\n")
}
