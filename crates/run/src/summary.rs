//! `summary.json`: the learning-curve metrics of SPEC §6 and what the run did, rewritten
//! after every row. One struct writes it and reads it back (`esrl compare`, resume).

use crate::config::EnvKind;
use crate::error::{Context, Result};
use crate::run_dir::RunDir;
use esrl_metrics::CurveSummary;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use std::path::Path;

/// The content of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Agent name.
    pub agent: String,
    /// Environment.
    pub env: EnvKind,
    /// Run seed.
    pub seed: u64,
    /// Curve metrics (AUC, nAUC, Final-50, Best-Win-50, Episodes-to-Target).
    #[serde(flatten)]
    pub curve: CurveSummary,
    /// Mean Q₀ over the curve ([`esrl_metrics::q0_mean`]).
    pub q0_mean: Option<f64>,
    /// Generations or episodes done.
    pub length: usize,
    /// Environment steps taken.
    pub env_steps: u64,
    /// Best curve value.
    pub best: f64,
    /// Wall-clock seconds of training (summed over resumes).
    pub wall_s: f64,
    /// Whether the configured budget was completed.
    pub finished: bool,
    /// The learner's own figures ([`esrl_agents::Learner::summary_figures`]); for ES-X the shares of
    /// trained generations whose actor was best (`rl_trained_best_share`) or an elite
    /// (`rl_trained_elite_share`), and of generations that replaced it (`rl_replaced_share`).
    #[serde(flatten)]
    pub learner: Map<String, Value>,
}

impl Summary {
    /// Reads `RUN/summary.json`, if the run has one.
    pub fn read(run: &Path) -> Result<Option<Self>> {
        let p = run.join(RunDir::SUMMARY);
        if !p.exists() {
            return Ok(None);
        }
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let summary =
            serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
        Ok(Some(summary))
    }
}
