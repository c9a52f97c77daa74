//! Checkpoints of earlier versions: the one place that knows what their `state.json` lacked
//! and what it means, so [`EsState`] and the loop see only required values.
//!
//! The hybrid loop's keys of `state.json` as every version wrote them ([`EsStateFile`]):
//! `sigma` and `es_generation` have always been written by an ES run, so their absence is an
//! error naming the key; `rl_trained` and `loop_stats` came later. A checkpoint without
//! `rl_trained` resumes with the RL actor counted as trained after generation 0 (the loop
//! had no untrained generations then; [`crate::Hybrid`] still clears it when the run has no
//! inner training), and one without `loop_stats` restarts the loop's counts from zero.

use crate::hybrid::{EsState, LoopStats};
use serde::Deserialize;

/// `state.json`'s ES keys, any version.
#[derive(Debug, Clone, Deserialize)]
pub(crate) struct EsStateFile {
    generations: usize,
    sigma: Option<f64>,
    es_generation: Option<u64>,
    #[serde(default)]
    rl_trained: Option<bool>,
    #[serde(default)]
    loop_stats: Option<LoopStats>,
}

impl TryFrom<EsStateFile> for EsState {
    type Error = String;

    fn try_from(f: EsStateFile) -> Result<Self, String> {
        let missing = |key: &str| format!("`{key}` is missing from an ES run's state.json");
        Ok(EsState {
            generations: f.generations,
            sigma: f.sigma.ok_or_else(|| missing("sigma"))?,
            es_generation: f.es_generation.ok_or_else(|| missing("es_generation"))?,
            rl_trained: f.rl_trained.unwrap_or(f.generations > 0),
            loop_stats: f.loop_stats.unwrap_or_default(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn old_states_load_with_their_documented_defaults() {
        let old: EsStateFile =
            serde_json::from_str(r#"{"generations": 3, "sigma": 0.1, "es_generation": 3}"#)
                .unwrap();
        let s = EsState::try_from(old).unwrap();
        assert!(s.rl_trained, "trained after generation 0");
        assert_eq!(s.loop_stats, LoopStats::default());
        let first: EsStateFile =
            serde_json::from_str(r#"{"generations": 0, "sigma": 0.1, "es_generation": 0}"#)
                .unwrap();
        assert!(!EsState::try_from(first).unwrap().rl_trained);
        let bad: EsStateFile =
            serde_json::from_str(r#"{"generations": 3, "es_generation": 3}"#).unwrap();
        let err = EsState::try_from(bad).unwrap_err();
        assert!(err.contains("`sigma`"), "{err}");
    }
}
