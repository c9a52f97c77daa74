//! Hyperparameters of the off-policy agents, each with its default and where it comes from.
//!
//! Sources: the paper (§5: batch 256, warm start 1000), MATLAB's `rlSACAgentOptions` /
//! `rlTD3AgentOptions` / `rlDDPGAgentOptions` and `rlOptimizerOptions` where the paper keeps
//! MATLAB's defaults, and the SAC (Haarnoja et al. 2018) and TD3 (Fujimoto et al. 2018) papers
//! for what MATLAB leaves to the user.

use serde::{Deserialize, Serialize};

/// Which algorithm updates the networks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algo {
    /// Soft actor-critic: stochastic tanh-Gaussian actor, twin critics, learned entropy weight.
    Sac,
    /// TD3: deterministic actor, twin critics, target policy smoothing, delayed actor updates.
    Td3,
    /// DDPG: TD3 with one critic and, by default ([`RlConfig::for_algo`]), neither target
    /// smoothing nor delay.
    Ddpg,
}

impl Algo {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Algo::Sac => "sac",
            Algo::Td3 => "td3",
            Algo::Ddpg => "ddpg",
        }
    }
}

/// When gradient updates happen during plain (non-ES) training.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LearnEvery {
    /// Every `n` environment steps (SAC/TD3 papers: every step).
    Steps(usize),
    /// At the end of every episode (MATLAB's `LearningFrequency = -1`).
    Episode,
}

/// Hyperparameters shared by SAC, TD3 and DDPG.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RlConfig {
    /// Discount factor γ. Default 0.99 (MATLAB `DiscountFactor`, SAC and TD3 papers).
    pub gamma: f64,
    /// Polyak factor τ of eq. 7. Default 0.005 (SAC and TD3 papers; MATLAB's 1e-3 learns
    /// slower at the paper's short budgets).
    pub tau: f64,
    /// Minibatch size M: sequences for recurrent networks, transitions otherwise. Default 256
    /// (paper §5).
    pub batch_size: usize,
    /// Replay capacity in transitions. Default 1,000,000 (MATLAB `ExperienceBufferLength`).
    pub buffer_size: usize,
    /// Random-action steps before learning starts. Default 1000 (paper §5).
    pub warm_start: usize,
    /// Trained steps per sampled sequence (recurrent networks). Default 8 (esrl's choice;
    /// the length the PyTorch baseline times).
    pub seq_len: usize,
    /// Steps before each trained sequence that only warm up the recurrent state. Default 8
    /// (esrl's choice, after R2D2's burn-in; 0 starts every sequence from a zero state).
    pub burn_in: usize,
    /// Actor learning rate. Default 3e-4 (SAC and TD3 papers).
    pub actor_lr: f64,
    /// Critic learning rate. Default 3e-4 (SAC and TD3 papers).
    pub critic_lr: f64,
    /// Adam learning rate of log α. Default 3e-4 (MATLAB `EntropyWeightOptions.LearnRate`).
    pub alpha_lr: f64,
    /// Global gradient-norm clip. Default 10 (esrl's choice: MATLAB's default is ∞, the paper
    /// uses a threshold without giving it).
    pub grad_clip: f64,
    /// Clips the TD target y of eq. 3 to the discounted returns the stored rewards allow:
    /// [(min(r_lo, 0) − e)/(1 − γ), (max(r_hi, 0) + e)/(1 − γ)], r_lo and r_hi the smallest
    /// and largest reward in the replay buffer, e = α·|A|·ln 2 for SAC (the largest mean
    /// entropy bonus a tanh-squashed policy earns per step) and 0 for TD3/DDPG. A guard
    /// against a critic that runs away from every reachable value; the upper bound is exact,
    /// the lower one is for SAC a floor that policies keeping their entropy above −|A|·ln 2
    /// never reach. Default false (the paper bootstraps unclipped).
    pub clip_targets: bool,
    /// Left↔right mirrored transitions: every odd-numbered window of each batch (1, 3, …) is
    /// replaced by its mirror image through the sagittal plane (observations, next
    /// observations and actions; rewards and ends unchanged), as if the buffer held every
    /// transition and its mirror image (`esrl_sim::Mirror`; Yu, Turk & Liu 2018's remedy for
    /// lopsided gaits). Needs a task with a mirror (the walking task). Default false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub mirror: bool,
    /// Splits each update's batch into this many fixed chunks of consecutive sequences (or
    /// transitions) whose TD targets, critic losses and actor loss run side by side on the
    /// rayon pool, their gradients summed in chunk order (the update's noise is drawn for the
    /// whole batch first and split like it). The split depends on this
    /// number only, never on the thread count, so results stay the same at any number of
    /// threads; a value other than 1 re-associates the batch sums once, so its numbers
    /// differ (in the last bits, then along the run) from those of 1. Default 1 (one graph
    /// over the whole batch, as before this key existed). On one thread chunks cost time; at
    /// 2 threads 2 chunks suit an MLP update and 4 an LSTM one (`results/threads`).
    pub batch_chunks: usize,
    /// L2 regularisation factor. Default 1e-4 (MATLAB `L2RegularizationFactor`).
    pub l2: f64,
    /// Initial entropy weight α (SAC). Default 1.0 (MATLAB `EntropyWeight`, CleanRL).
    pub initial_alpha: f64,
    /// Target entropy of the α loss; `None` means −|A| (SAC paper, MATLAB). Default None.
    pub target_entropy: Option<f64>,
    /// Whether α is learned (eq. 6). Default true.
    pub learn_alpha: bool,
    /// Std of the Gaussian exploration noise on actions in [−1, 1] (TD3/DDPG; SAC explores
    /// by sampling its policy). Default 0.1 (TD3 paper).
    pub exploration_noise: f64,
    /// Std of the target policy smoothing noise (TD3/DDPG; SAC samples its target action);
    /// 0 turns smoothing off. Default 0.2 (TD3 paper); DDPG's default is 0
    /// ([`RlConfig::for_algo`]).
    pub target_noise: f64,
    /// Clip of the target smoothing noise (TD3/DDPG). Default 0.5 (TD3 paper).
    pub target_noise_clip: f64,
    /// Critic updates per actor and target update (TD3/DDPG; SAC updates its actor at every
    /// update). Default 2 (TD3 paper); DDPG's default is 1 ([`RlConfig::for_algo`]).
    pub policy_delay: usize,
    /// When plain agents learn. Default every step (SAC/TD3 papers).
    pub learn_every: LearnEvery,
    /// Gradient updates each time they learn. Default 1.
    pub updates_per_learn: usize,
}

impl Default for RlConfig {
    fn default() -> Self {
        Self {
            gamma: 0.99,
            tau: 0.005,
            batch_size: 256,
            buffer_size: 1_000_000,
            warm_start: 1000,
            seq_len: 8,
            burn_in: 8,
            actor_lr: 3e-4,
            critic_lr: 3e-4,
            alpha_lr: 3e-4,
            grad_clip: 10.0,
            clip_targets: false,
            mirror: false,
            batch_chunks: 1,
            l2: 1e-4,
            initial_alpha: 1.0,
            target_entropy: None,
            learn_alpha: true,
            exploration_noise: 0.1,
            target_noise: 0.2,
            target_noise_clip: 0.5,
            policy_delay: 2,
            learn_every: LearnEvery::Steps(1),
            updates_per_learn: 1,
        }
    }
}

impl RlConfig {
    /// The defaults for `algo`. DDPG is TD3 with its tricks off, as in Stable-Baselines3's
    /// `ddpg.py`: one critic (fixed by the algorithm), `policy_delay` 1 and `target_noise` 0;
    /// a DDPG config that sets them runs DDPG with TD3's delay or smoothing. SAC and TD3
    /// take [`RlConfig::default`].
    pub fn for_algo(algo: Algo) -> Self {
        match algo {
            Algo::Sac | Algo::Td3 => Self::default(),
            Algo::Ddpg => Self {
                policy_delay: 1,
                target_noise: 0.0,
                ..Self::default()
            },
        }
    }
}

/// A configuration value that cannot work, naming the field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("rl.{field} = {value}: {reason}")]
pub struct ConfigError {
    /// Field name inside `[rl]`.
    pub field: &'static str,
    /// The offending value.
    pub value: String,
    /// What a valid value looks like.
    pub reason: &'static str,
}

impl RlConfig {
    /// Checks every field, returning the first that cannot work.
    pub fn validate(&self) -> Result<(), ConfigError> {
        fn check(
            ok: bool,
            field: &'static str,
            value: f64,
            reason: &'static str,
        ) -> Result<(), ConfigError> {
            if ok {
                Ok(())
            } else {
                Err(ConfigError {
                    field,
                    value: value.to_string(),
                    reason,
                })
            }
        }
        let unit = |x: f64| x.is_finite() && (0.0..=1.0).contains(&x);
        let pos = |x: f64| x.is_finite() && x > 0.0;
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        check(unit(self.gamma), "gamma", self.gamma, "must be in [0, 1]")?;
        check(unit(self.tau), "tau", self.tau, "must be in [0, 1]")?;
        check(
            self.batch_size > 0,
            "batch_size",
            self.batch_size as f64,
            "must be ≥ 1",
        )?;
        check(
            self.buffer_size > 0,
            "buffer_size",
            self.buffer_size as f64,
            "must be ≥ 1",
        )?;
        check(
            self.batch_size <= self.buffer_size,
            "batch_size",
            self.batch_size as f64,
            "must be ≤ buffer_size (a batch is drawn from the buffer)",
        )?;
        check(
            (1..=self.batch_size).contains(&self.batch_chunks),
            "batch_chunks",
            self.batch_chunks as f64,
            "must be in [1, batch_size]",
        )?;
        check(
            self.seq_len > 0,
            "seq_len",
            self.seq_len as f64,
            "must be ≥ 1",
        )?;
        check(
            pos(self.actor_lr),
            "actor_lr",
            self.actor_lr,
            "must be finite and > 0",
        )?;
        check(
            pos(self.critic_lr),
            "critic_lr",
            self.critic_lr,
            "must be finite and > 0",
        )?;
        check(
            pos(self.alpha_lr),
            "alpha_lr",
            self.alpha_lr,
            "must be finite and > 0",
        )?;
        check(
            pos(self.grad_clip),
            "grad_clip",
            self.grad_clip,
            "must be finite and > 0",
        )?;
        check(nonneg(self.l2), "l2", self.l2, "must be finite and ≥ 0")?;
        check(
            pos(self.initial_alpha),
            "initial_alpha",
            self.initial_alpha,
            "must be finite and > 0",
        )?;
        if let Some(h) = self.target_entropy {
            check(h.is_finite(), "target_entropy", h, "must be finite")?;
        }
        check(
            nonneg(self.exploration_noise),
            "exploration_noise",
            self.exploration_noise,
            "must be finite and ≥ 0",
        )?;
        check(
            nonneg(self.target_noise),
            "target_noise",
            self.target_noise,
            "must be finite and ≥ 0",
        )?;
        check(
            nonneg(self.target_noise_clip),
            "target_noise_clip",
            self.target_noise_clip,
            "must be finite and ≥ 0",
        )?;
        check(
            self.policy_delay > 0,
            "policy_delay",
            self.policy_delay as f64,
            "must be ≥ 1",
        )?;
        check(
            self.updates_per_learn > 0,
            "updates_per_learn",
            self.updates_per_learn as f64,
            "must be ≥ 1",
        )?;
        if let LearnEvery::Steps(n) = self.learn_every {
            check(n > 0, "learn_every", n as f64, "must be ≥ 1 steps")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_name_their_field() {
        assert!(RlConfig::default().validate().is_ok());
        let e = RlConfig {
            batch_size: 0,
            ..RlConfig::default()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field, "batch_size");
        let e = RlConfig {
            gamma: f64::NAN,
            ..RlConfig::default()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field, "gamma");
        assert!(e.to_string().starts_with("rl.gamma = NaN"));
        let e = RlConfig {
            actor_lr: -1e-3,
            ..RlConfig::default()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field, "actor_lr");
    }
}
