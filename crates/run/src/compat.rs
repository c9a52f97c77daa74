//! Run folders of earlier versions: the one place that knows what their files meant, so the
//! rest of the crate reads every run as the current format describes it. (The hybrid loop's
//! keys of `state.json` have their own, in `esrl-es`.)
//!
//! - `state.json` version 1: DDPG ignored `rl.policy_delay` and `rl.target_noise` (TD3's
//!   tricks, which its config.toml still lists at TD3's 2 and 0.2) and trained as if they
//!   were 1 and 0; from version 2 DDPG honours them ([`as_trained`]).
//! - Checkpoints have had a `manifest.json` since version 2 ([`has_manifest`]); earlier ones,
//!   and `best/` folders and policy copies written before `best/` had one, have none.

use crate::config::TrainConfig;

/// Whether a checkpoint of `state.json` version `version` always has a `manifest.json`.
pub(crate) fn has_manifest(version: u32) -> bool {
    version >= 2
}

/// Sets `cfg`, read from a run whose checkpoint has `state.json` version `version`, to what
/// that run was trained with; says whether anything changed.
pub(crate) fn as_trained(cfg: &mut TrainConfig, version: u32) -> bool {
    if version >= 2 || cfg.agent.algo() != esrl_agents::Algo::Ddpg {
        return false;
    }
    let before = (cfg.rl.policy_delay, cfg.rl.target_noise);
    cfg.rl.policy_delay = 1;
    cfg.rl.target_noise = 0.0;
    before != (1, 0.0)
}
