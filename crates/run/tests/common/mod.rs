//! Helpers shared by the preset tests.
#![allow(dead_code)]

use esrl_run::{Overrides, Preset, TrainConfig};
use std::path::PathBuf;

/// Overrides as the command line gives them: a preset, an optional `--config` file and
/// `--generations`, one thread.
pub fn options(preset: Preset, config: Option<PathBuf>, generations: Option<usize>) -> Overrides {
    Overrides {
        preset,
        config,
        threads: Some(1),
        generations,
        ..Overrides::default()
    }
}

/// A resolved configuration as TOML, without the recorded preset name.
pub fn without_preset_name(c: &TrainConfig) -> String {
    c.to_toml()
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("preset ="))
        .collect::<Vec<_>>()
        .join("\n")
}
