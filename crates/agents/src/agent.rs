//! One off-policy actor-critic agent covering SAC, TD3 and DDPG: its networks, optimisers,
//! entropy coefficient and random stream, and what differs between the three algorithms,
//! resolved once when the agent is built ([`Agent::new`]). The update itself is
//! [`Agent::update`] (`update.rs`, `sac.rs`, `td3.rs`, `steps.rs`).
//!
//! - **SAC** (Haarnoja et al. 2018; paper §3.1, eqs. 1–7): tanh-squashed Gaussian actor, twin
//!   critics with Polyak-averaged targets, a learned entropy coefficient α.
//! - **TD3** (Fujimoto et al. 2018): deterministic actor tanh(μ) with a target actor, twin
//!   critics, target policy smoothing, actor and targets updated every `policy_delay` critic
//!   updates.
//! - **DDPG** (Lillicrap et al. 2016): TD3 with one critic, and by default neither smoothing
//!   nor delay ([`RlConfig::for_algo`](crate::RlConfig::for_algo)); it honours
//!   `policy_delay` and `target_noise` when a config sets them.

use crate::config::{Algo, RlConfig};
use crate::nets::NetConfig;
use crate::policy::{Exploration, Policy};
use esrl_nn::{Actor, Adam, AdamConfig, Critic, Graph, Module, NnError, Params, Tensor};
use esrl_streams::Stream;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// What can go wrong inside an agent.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// A network, optimiser or checkpoint error.
    #[error(transparent)]
    Nn(#[from] NnError),
    /// A loss or gradient became NaN or infinite.
    #[error("non-finite {what} at update {update}: training diverged")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
        /// Updates completed before it.
        update: u64,
    },
    /// A genome of the wrong length.
    #[error("genome has {found} values, the actor needs {expected}")]
    GenomeLength {
        /// Values expected.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A saved learner state that does not fit this learner.
    #[error("{field}: {reason}")]
    State {
        /// The field or tensor at fault.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
}

/// Losses and coefficients of one update.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct UpdateStats {
    /// Critic loss (sum over critics of eq. 4).
    pub critic_loss: f64,
    /// Actor loss, when the actor was updated.
    pub actor_loss: Option<f64>,
    /// Entropy coefficient α after the update (SAC).
    pub alpha: Option<f64>,
    /// Mean Q₁ over the trained steps.
    pub q_mean: f64,
}

/// The algorithm's choices, resolved once from [`Algo`] and [`RlConfig`] at construction, so
/// the update reads properties instead of branching on the algorithm's name.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Rules {
    /// Critics trained against the minimum of their targets: 2 (clipped double Q, SAC and
    /// TD3) or 1 (DDPG).
    pub(crate) critics: usize,
    /// SAC's maximum-entropy objective (a sampled policy, an entropy term weighted by α);
    /// `None` for the deterministic policy tanh(μ) of TD3/DDPG, which has a target actor.
    pub(crate) entropy: Option<Entropy>,
    /// Target policy smoothing (TD3/DDPG with `target_noise` > 0).
    pub(crate) smoothing: Option<Smoothing>,
    /// Critic updates per actor and target update.
    pub(crate) policy_delay: u64,
}

/// SAC's entropy coefficient: learned or fixed, and the entropy it aims at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Entropy {
    /// Whether α is learned (eq. 6).
    pub(crate) learn: bool,
    /// Target entropy H̄ (−|A| by default).
    pub(crate) target: f32,
}

/// TD3's target policy smoothing: noise N(0, sd²) clipped to ±clip on the target action.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Smoothing {
    pub(crate) sd: f32,
    pub(crate) clip: f32,
}

impl Rules {
    fn new(algo: Algo, cfg: &RlConfig, act_dim: usize) -> Self {
        match algo {
            Algo::Sac => Self {
                critics: 2,
                entropy: Some(Entropy {
                    learn: cfg.learn_alpha,
                    target: cfg.target_entropy.unwrap_or(-(act_dim as f64)) as f32,
                }),
                smoothing: None,
                policy_delay: 1,
            },
            Algo::Td3 | Algo::Ddpg => Self {
                critics: if algo == Algo::Td3 { 2 } else { 1 },
                entropy: None,
                smoothing: (cfg.target_noise > 0.0).then_some(Smoothing {
                    sd: cfg.target_noise as f32,
                    clip: cfg.target_noise_clip as f32,
                }),
                policy_delay: cfg.policy_delay.max(1) as u64,
            },
        }
    }

    /// How the policy explores: SAC samples, TD3/DDPG add Gaussian noise to tanh(μ).
    fn exploration(&self, cfg: &RlConfig) -> Exploration {
        match self.entropy {
            Some(_) => Exploration::Sample,
            None => Exploration::Noise(cfg.exploration_noise as f32),
        }
    }
}

/// The SAC / TD3 / DDPG agent: actor, critics, targets, optimisers, entropy coefficient.
#[derive(Debug, Clone)]
pub struct Agent {
    pub(crate) algo: Algo,
    pub(crate) cfg: RlConfig,
    pub(crate) rules: Rules,
    pub(crate) obs_dim: usize,
    pub(crate) act_dim: usize,
    pub(crate) actor: Actor,
    /// The target actor of the deterministic algorithms (SAC has none).
    pub(crate) actor_target: Option<Actor>,
    pub(crate) critics: Vec<Critic>,
    pub(crate) critic_targets: Vec<Critic>,
    pub(crate) opt_actor: Adam,
    pub(crate) opt_critics: Vec<Adam>,
    pub(crate) log_alpha: Params,
    pub(crate) opt_alpha: Adam,
    pub(crate) updates: u64,
    /// [`Stream::Updates`]: SAC's action samples, TD3's smoothing noise.
    pub(crate) rng: ChaCha8Rng,
}

impl Agent {
    /// Builds an agent for observations of `obs_dim` and actions of `act_dim`, with every
    /// weight and random stream drawn from the run seed `seed`.
    pub fn new(
        algo: Algo,
        obs_dim: usize,
        act_dim: usize,
        nets: &NetConfig,
        cfg: &RlConfig,
        seed: u64,
    ) -> Result<Self, AgentError> {
        let rules = Rules::new(algo, cfg, act_dim);
        let actor = Actor::new(
            obs_dim,
            act_dim,
            &nets.actor,
            Stream::ActorWeights.seed(seed),
        )?;
        let critics = (0..rules.critics)
            .map(|k| {
                Critic::new(
                    obs_dim,
                    act_dim,
                    &nets.critic,
                    Stream::CriticWeights(k as u64).seed(seed),
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        let adam = |lr: f64| AdamConfig {
            lr: lr as f32,
            l2: cfg.l2 as f32,
            grad_clip: Some(cfg.grad_clip as f32),
            ..AdamConfig::default()
        };
        let opt_actor = Adam::new(adam(cfg.actor_lr), actor.params())?;
        let opt_critics = critics
            .iter()
            .map(|c| Adam::new(adam(cfg.critic_lr), c.params()))
            .collect::<Result<Vec<_>, _>>()?;
        let mut log_alpha = Params::new();
        let init = (cfg.initial_alpha as f32).ln();
        log_alpha.add("log_alpha", &[1], false, || init);
        let opt_alpha = Adam::new(
            AdamConfig {
                lr: cfg.alpha_lr as f32,
                l2: 0.0,
                grad_clip: None,
                ..AdamConfig::default()
            },
            &log_alpha,
        )?;
        let actor_target = rules.entropy.is_none().then(|| actor.clone());
        Ok(Self {
            algo,
            cfg: cfg.clone(),
            rules,
            obs_dim,
            act_dim,
            critic_targets: critics.clone(),
            actor,
            actor_target,
            critics,
            opt_actor,
            opt_critics,
            log_alpha,
            opt_alpha,
            updates: 0,
            rng: Stream::Updates.rng(seed),
        })
    }

    /// The algorithm.
    pub fn algo(&self) -> Algo {
        self.algo
    }

    /// The hyperparameters.
    pub fn config(&self) -> &RlConfig {
        &self.cfg
    }

    /// Observation width.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action width.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// The actor.
    pub fn actor(&self) -> &Actor {
        &self.actor
    }

    /// The critics (two for SAC/TD3, one for DDPG).
    pub fn critics(&self) -> &[Critic] {
        &self.critics
    }

    /// Whether the networks carry LSTM state (so they train on sequences).
    pub fn recurrent(&self) -> bool {
        self.actor.lstm_hidden().is_some() || self.critics.iter().any(|c| c.lstm_hidden().is_some())
    }

    /// Gradient updates done.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// Whether the agent learns an entropy coefficient (SAC).
    pub fn has_entropy(&self) -> bool {
        self.rules.entropy.is_some()
    }

    /// Entropy coefficient α (SAC; 0 for TD3/DDPG).
    pub fn alpha(&self) -> f64 {
        if self.has_entropy() {
            f64::from(self.log_alpha.as_slice()[0]).exp()
        } else {
            0.0
        }
    }

    /// How the agent's policy explores.
    pub fn exploration(&self) -> Exploration {
        self.rules.exploration(&self.cfg)
    }

    /// A rollout policy from the current actor.
    pub fn policy(&self) -> Policy {
        Policy::new(self.actor.clone(), self.exploration())
    }

    /// Length of the ES genome: the actor's weights and biases (both heads), plus log α for SAC.
    pub fn genome_len(&self) -> usize {
        self.actor.num_params() + usize::from(self.has_entropy())
    }

    /// The ES genome (see [`Agent::genome_len`]).
    pub fn genome(&self) -> Vec<f32> {
        let mut g = self.actor.params().to_flat();
        if self.has_entropy() {
            g.push(self.log_alpha.as_slice()[0]);
        }
        g
    }

    fn check_genome(&self, genome: &[f32]) -> Result<(), AgentError> {
        if genome.len() != self.genome_len() {
            return Err(AgentError::GenomeLength {
                expected: self.genome_len(),
                found: genome.len(),
            });
        }
        Ok(())
    }

    /// Takes a genome's parameters (elitist replacement).
    pub fn set_genome(&mut self, genome: &[f32]) -> Result<(), AgentError> {
        self.check_genome(genome)?;
        let n = self.actor.num_params();
        self.actor.params_mut().set_flat(&genome[..n])?;
        if self.has_entropy() {
            self.log_alpha.as_mut_slice()[0] = genome[n];
        }
        Ok(())
    }

    /// A rollout policy whose actor has `genome`'s parameters.
    pub fn policy_from_genome(&self, genome: &[f32]) -> Result<Policy, AgentError> {
        self.check_genome(genome)?;
        let mut policy = self.policy();
        policy.set_weights(&genome[..self.actor.num_params()])?;
        Ok(policy)
    }

    /// Q₀: the critics' estimate (minimum over critics) at `obs` from a zero state, for the
    /// policy's deterministic action (SPEC §6).
    pub fn q0(&self, obs: &[f32]) -> f64 {
        let mut g = Graph::no_grad();
        let o = g.constant(Tensor::from_slice(1, self.obs_dim, obs));
        let out = self.actor.forward(&mut g, o, 1, None);
        let a = self.actor.deterministic(&mut g, &out);
        let qs: Vec<f32> = self
            .critics
            .iter()
            .map(|c| {
                let q = c.forward(&mut g, o, a, 1, None).q;
                g.value(q).item()
            })
            .collect();
        f64::from(qs.into_iter().fold(f32::INFINITY, f32::min))
    }

    /// Every tensor of the agent, for checkpoints: networks, targets, Adam moments, log α.
    pub fn state_tensors(&self) -> Vec<(String, Vec<f32>)> {
        let mut out = Vec::new();
        let mut put = |name: String, p: &Params, opt: Option<&Adam>| {
            out.push((name.clone(), p.to_flat()));
            if let Some(opt) = opt {
                let s = opt.state();
                out.push((format!("{name}.adam_m"), s.m.clone()));
                out.push((format!("{name}.adam_v"), s.v.clone()));
                out.push((format!("{name}.adam_t"), vec![s.t as f32]));
            }
        };
        put("actor".into(), self.actor.params(), Some(&self.opt_actor));
        if let Some(t) = &self.actor_target {
            put("actor_target".into(), t.params(), None);
        }
        for (k, (c, opt)) in self.critics.iter().zip(&self.opt_critics).enumerate() {
            put(format!("critic{}", k + 1), c.params(), Some(opt));
        }
        for (k, c) in self.critic_targets.iter().enumerate() {
            put(format!("critic{}_target", k + 1), c.params(), None);
        }
        put("log_alpha".into(), &self.log_alpha, Some(&self.opt_alpha));
        out
    }

    /// Restores what [`Agent::state_tensors`] produced (same architecture required).
    pub fn load_state_tensors(
        &mut self,
        tensors: &std::collections::HashMap<String, Vec<f32>>,
    ) -> Result<(), AgentError> {
        let get = |name: &str| -> Result<&Vec<f32>, AgentError> {
            tensors.get(name).ok_or_else(|| {
                AgentError::Nn(NnError::Config {
                    field: name.into(),
                    value: "missing".into(),
                    reason: "the checkpoint lacks this tensor".into(),
                })
            })
        };
        let load = |name: &str, p: &mut Params, opt: Option<&mut Adam>| -> Result<(), AgentError> {
            p.set_flat(get(name)?)?;
            if let Some(opt) = opt {
                let t = get(&format!("{name}.adam_t"))?
                    .first()
                    .copied()
                    .unwrap_or(0.0) as u64;
                opt.set_state(esrl_nn::AdamState {
                    t,
                    m: get(&format!("{name}.adam_m"))?.clone(),
                    v: get(&format!("{name}.adam_v"))?.clone(),
                })?;
            }
            Ok(())
        };
        load("actor", self.actor.params_mut(), Some(&mut self.opt_actor))?;
        if let Some(t) = &mut self.actor_target {
            load("actor_target", t.params_mut(), None)?;
        }
        for (k, (c, opt)) in self
            .critics
            .iter_mut()
            .zip(&mut self.opt_critics)
            .enumerate()
        {
            load(&format!("critic{}", k + 1), c.params_mut(), Some(opt))?;
        }
        for (k, c) in self.critic_targets.iter_mut().enumerate() {
            load(&format!("critic{}_target", k + 1), c.params_mut(), None)?;
        }
        load("log_alpha", &mut self.log_alpha, Some(&mut self.opt_alpha))?;
        Ok(())
    }

    /// Loads the actor alone from an `actor.safetensors` file ([`esrl_nn::save_params`] with
    /// prefix ""): a policy folder that keeps no critics or optimiser state. The critics stay
    /// as built, so [`Agent::q0`] means nothing afterwards.
    pub fn load_actor(&mut self, path: &std::path::Path) -> Result<(), AgentError> {
        esrl_nn::load_params(path, &mut [("", self.actor.params_mut())])?;
        Ok(())
    }

    /// Updates done and the agent's random stream, for checkpoints.
    pub fn counters(&self) -> (u64, ChaCha8Rng) {
        (self.updates, self.rng.clone())
    }

    /// Restores [`Agent::counters`].
    pub fn set_counters(&mut self, updates: u64, rng: ChaCha8Rng) {
        self.updates = updates;
        self.rng = rng;
    }
}
