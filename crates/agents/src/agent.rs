//! One off-policy actor-critic agent covering SAC, TD3 and DDPG.
//!
//! - **SAC** (Haarnoja et al. 2018; paper §3.1, eqs. 1–7): tanh-squashed Gaussian actor, twin
//!   critics with Polyak-averaged targets, target
//!   y = r + γ(1 − d)(minₖ Q_tₖ(s′, a′) − α log π(a′|s′)) with a′ ~ π(·|s′) (eq. 3), critic loss
//!   1/(2M) Σ (y − Qₖ)² (eq. 4), actor loss mean(α log π(ã|s) − minₖ Qₖ(s, ã)) with ã re-sampled
//!   from the current policy at s (eq. 5 as it should read), entropy coefficient learned on
//!   log α with target entropy −|A| (eq. 6), Polyak update (eq. 7).
//! - **TD3** (Fujimoto et al. 2018): deterministic actor tanh(μ), twin critics, target policy
//!   smoothing a′ = clip(μ_t(s′) + clip(ε, −c, c), −1, 1), actor and targets updated every
//!   `policy_delay` critic updates, actor loss −Q₁(s, μ(s)).
//! - **DDPG** (Lillicrap et al. 2016): TD3 with one critic, no smoothing and no delay.
//!
//! Recurrent networks train on sequence batches from [`crate::ReplayBuffer`]: the burn-in
//! prefix runs without gradients, one step at a time so the recurrent state can be zeroed where
//! the batch's `reset` says, then the trained part runs as one sequence from that state. Losses
//! average over the batch's `mask`, so padding past an episode's end never counts.

use crate::config::{Algo, RlConfig};
use crate::nets::NetConfig;
use crate::replay::SequenceBatch;
use esrl_nn::{
    Actor, ActorStepState, Adam, AdamConfig, Critic, Graph, LstmState, Module, NnError, Params,
    Tensor,
};
use esrl_streams::Stream;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
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

/// How a policy chooses actions during a rollout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ActMode {
    /// tanh(μ): evaluation, and ES individuals of TD3/DDPG.
    Deterministic,
    /// The algorithm's exploration: a Gaussian sample for SAC, tanh(μ) plus Gaussian noise
    /// for TD3/DDPG.
    Explore,
}

/// An actor ready to act one step at a time (no graph, no allocation per step).
#[derive(Debug, Clone)]
pub struct Policy {
    actor: Actor,
    state: ActorStepState,
    algo: Algo,
    noise: f32,
}

impl Policy {
    /// Wraps `actor` for rollouts of `algo`, with `noise` the TD3/DDPG exploration std.
    pub fn new(actor: Actor, algo: Algo, noise: f32) -> Self {
        let state = actor.step_state();
        Self {
            actor,
            state,
            algo,
            noise,
        }
    }

    /// Zeroes the recurrent state for a new episode.
    pub fn reset(&mut self) {
        self.state.reset();
    }

    /// The wrapped actor.
    pub fn actor(&self) -> &Actor {
        &self.actor
    }

    /// Takes `actor`'s current weights, keeping the recurrent state (a learner's policy
    /// mid-episode).
    pub fn sync_from(&mut self, actor: &Actor) -> Result<(), AgentError> {
        self.actor.params_mut().copy_from(actor.params())?;
        Ok(())
    }

    /// Chooses the action for `obs` into `action` (each entry in [−1, 1]).
    pub fn act<R: Rng + ?Sized>(
        &mut self,
        obs: &[f32],
        mode: ActMode,
        rng: &mut R,
        action: &mut [f32],
    ) {
        self.actor.step(obs, &mut self.state);
        match (mode, self.algo) {
            (ActMode::Deterministic, _) => self.state.deterministic_action(action),
            (ActMode::Explore, Algo::Sac) => self.state.sample_action(rng, action),
            (ActMode::Explore, _) => {
                self.state.deterministic_action(action);
                for a in action.iter_mut() {
                    let e: f32 = rng.sample(StandardNormal);
                    *a = (*a + self.noise * e).clamp(-1.0, 1.0);
                }
            }
        }
    }
}

/// The SAC / TD3 / DDPG agent: actor, critics, targets, optimisers, entropy coefficient.
#[derive(Debug, Clone)]
pub struct Agent {
    algo: Algo,
    cfg: RlConfig,
    obs_dim: usize,
    act_dim: usize,
    actor: Actor,
    actor_target: Option<Actor>,
    critics: Vec<Critic>,
    critic_targets: Vec<Critic>,
    opt_actor: Adam,
    opt_critics: Vec<Adam>,
    log_alpha: Params,
    opt_alpha: Adam,
    updates: u64,
    rng: ChaCha8Rng,
}

/// Zeroes the rows of `state` whose `reset` flag is set.
fn apply_resets(state: &mut Option<LstmState>, reset: &[bool]) {
    let Some(s) = state else { return };
    let h = s.h.cols();
    for (b, _) in reset.iter().enumerate().filter(|(_, &r)| r) {
        s.h.data_mut()[b * h..(b + 1) * h].fill(0.0);
        s.c.data_mut()[b * h..(b + 1) * h].fill(0.0);
    }
}

/// TD3 target policy smoothing on a batch of target actions.
fn smooth(a: &mut Tensor, cfg: &RlConfig, rng: &mut ChaCha8Rng) {
    let (sd, clip) = (cfg.target_noise as f32, cfg.target_noise_clip as f32);
    for x in a.data_mut() {
        let e: f32 = rng.sample(StandardNormal);
        *x = (*x + (sd * e).clamp(-clip, clip)).clamp(-1.0, 1.0);
    }
}

/// Rows `[t0·B, t1·B)` of a time-major `(W·B, cols)` array as a tensor.
fn steps(data: &[f32], batch: usize, cols: usize, t0: usize, t1: usize) -> Tensor {
    Tensor::from_slice(
        (t1 - t0) * batch,
        cols,
        &data[t0 * batch * cols..t1 * batch * cols],
    )
}

impl Agent {
    /// Builds an agent for observations of `obs_dim` and actions of `act_dim`, with every
    /// weight and random stream drawn from `seed`.
    pub fn new(
        algo: Algo,
        obs_dim: usize,
        act_dim: usize,
        nets: &NetConfig,
        cfg: &RlConfig,
        seed: u64,
    ) -> Result<Self, AgentError> {
        let actor = Actor::new(
            obs_dim,
            act_dim,
            &nets.actor,
            Stream::ActorWeights.seed(seed),
        )?;
        let n_critics = if algo == Algo::Ddpg { 1 } else { 2 };
        let critics = (0..n_critics)
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
        let actor_target = (algo != Algo::Sac).then(|| actor.clone());
        Ok(Self {
            algo,
            cfg: cfg.clone(),
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

    /// Gradient updates done.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// Entropy coefficient α (SAC; 0 for TD3/DDPG).
    pub fn alpha(&self) -> f64 {
        if self.algo == Algo::Sac {
            f64::from(self.log_alpha.as_slice()[0]).exp()
        } else {
            0.0
        }
    }

    /// A rollout policy from the current actor.
    pub fn policy(&self) -> Policy {
        Policy::new(
            self.actor.clone(),
            self.algo,
            self.cfg.exploration_noise as f32,
        )
    }

    /// Length of the ES genome: the actor's weights and biases (both heads), plus log α for SAC.
    pub fn genome_len(&self) -> usize {
        self.actor.num_params() + usize::from(self.algo == Algo::Sac)
    }

    /// The ES genome (see [`Agent::genome_len`]).
    pub fn genome(&self) -> Vec<f32> {
        let mut g = self.actor.params().to_flat();
        if self.algo == Algo::Sac {
            g.push(self.log_alpha.as_slice()[0]);
        }
        g
    }

    /// Takes a genome's parameters (elitist replacement).
    pub fn set_genome(&mut self, genome: &[f32]) -> Result<(), AgentError> {
        if genome.len() != self.genome_len() {
            return Err(AgentError::GenomeLength {
                expected: self.genome_len(),
                found: genome.len(),
            });
        }
        let n = self.actor.num_params();
        self.actor.params_mut().set_flat(&genome[..n])?;
        if self.algo == Algo::Sac {
            self.log_alpha.as_mut_slice()[0] = genome[n];
        }
        Ok(())
    }

    /// A rollout policy whose actor has `genome`'s parameters.
    pub fn policy_from_genome(&self, genome: &[f32]) -> Result<Policy, AgentError> {
        if genome.len() != self.genome_len() {
            return Err(AgentError::GenomeLength {
                expected: self.genome_len(),
                found: genome.len(),
            });
        }
        let mut actor = self.actor.clone();
        let n = actor.num_params();
        actor.params_mut().set_flat(&genome[..n])?;
        Ok(self.policy_with_actor(actor))
    }

    /// A rollout policy around a given actor.
    pub fn policy_with_actor(&self, actor: Actor) -> Policy {
        Policy::new(actor, self.algo, self.cfg.exploration_noise as f32)
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

    /// One gradient update on `batch` (critics; actor and targets when due; α for SAC).
    pub fn update(&mut self, batch: &SequenceBatch) -> Result<UpdateStats, AgentError> {
        let b = batch.batch;
        let (o, a) = (self.obs_dim, self.act_dim);
        let (burn, w) = (batch.burn_in, batch.window);
        let len = w - burn;
        let n_masked: f32 = batch.mask[burn * b..].iter().sum();
        let norm = 1.0 / n_masked.max(1.0);
        let gamma = self.cfg.gamma as f32;
        let alpha = self.alpha() as f32;

        let obs = steps(&batch.obs, b, o, burn, w);
        let act = steps(&batch.action, b, a, burn, w);
        let next_obs = steps(&batch.next_obs, b, o, burn, w);
        let mask = steps(&batch.mask, b, 1, burn, w);
        let reward = steps(&batch.reward, b, 1, burn, w);
        let not_done = Tensor::from_vec(
            len * b,
            1,
            batch.terminated[burn * b..]
                .iter()
                .map(|d| 1.0 - d)
                .collect(),
        );

        let st = self.burn_in(batch);

        // Target y (eq. 3 for SAC; TD3/DDPG without the entropy term), no gradient.
        let y = {
            let mut g = Graph::no_grad();
            let o2 = g.constant(next_obs);
            let (a2, entropy) = match self.algo {
                Algo::Sac => {
                    let out = self.actor.forward(&mut g, o2, b, st.actor_next.as_ref());
                    let s = self.actor.sample(&mut g, &out, &mut self.rng);
                    let ent = g
                        .value(s.log_prob)
                        .data()
                        .iter()
                        .map(|lp| -alpha * lp)
                        .collect();
                    (g.value(s.action).clone(), Some(ent))
                }
                _ => {
                    let target = self.actor_target.as_ref().unwrap_or(&self.actor);
                    let out = target.forward(&mut g, o2, b, st.actor_next.as_ref());
                    let det = target.deterministic(&mut g, &out);
                    let mut a2 = g.value(det).clone();
                    if self.algo == Algo::Td3 {
                        smooth(&mut a2, &self.cfg, &mut self.rng);
                    }
                    (a2, None)
                }
            };
            let a2v = g.constant(a2);
            let mut qmin: Option<Vec<f32>> = None;
            for (k, c) in self.critic_targets.iter().enumerate() {
                let q = c
                    .forward(&mut g, o2, a2v, b, st.critic_targets[k].as_ref())
                    .q;
                let q = g.value(q).data().to_vec();
                qmin = Some(match qmin {
                    None => q,
                    Some(m) => m.iter().zip(&q).map(|(x, y)| x.min(*y)).collect(),
                });
            }
            let qmin = qmin.unwrap_or_default();
            let mut y = Vec::with_capacity(len * b);
            for i in 0..len * b {
                let soft = qmin[i] + entropy.as_ref().map_or(0.0, |e: &Vec<f32>| e[i]);
                y.push(reward.data()[i] + gamma * not_done.data()[i] * soft);
            }
            Tensor::from_vec(len * b, 1, y)
        };

        // Critic loss (eq. 4), masked mean, gradients into every critic.
        let (mut grads, critic_loss, q_mean) = {
            let mut g = Graph::new();
            let (ov, av, yv, mv) = (
                g.constant(obs.clone()),
                g.constant(act),
                g.constant(y),
                g.constant(mask.clone()),
            );
            let mut total = None;
            let mut q_mean = 0.0;
            for (k, c) in self.critics.iter().enumerate() {
                let q = c.forward(&mut g, ov, av, b, st.critics[k].as_ref()).q;
                if k == 0 {
                    let qv = g.value(q).data();
                    q_mean = qv.iter().zip(mask.data()).map(|(q, m)| q * m).sum::<f32>() * norm;
                }
                let d = g.sub(q, yv);
                let d2 = g.square(d);
                let d2 = g.mul(d2, mv);
                let s = g.sum(d2);
                let l = g.scale(s, 0.5 * norm);
                total = Some(match total {
                    None => l,
                    Some(t) => g.add(t, l),
                });
            }
            let loss = total.expect("at least one critic");
            let lv = g.value(loss).item();
            (g.backward(loss), lv, q_mean)
        };
        if !critic_loss.is_finite() {
            return Err(AgentError::NonFinite {
                what: "critic loss",
                update: self.updates,
            });
        }
        for (c, opt) in self.critics.iter_mut().zip(&mut self.opt_critics) {
            opt.apply(c.params_mut(), &mut grads)?;
        }

        let actor_due = self.algo != Algo::Td3 || self.updates % self.cfg.policy_delay as u64 == 0;
        let mut actor_loss = None;
        if actor_due {
            actor_loss = Some(self.update_actor(obs, &mask, norm, alpha, &st)?);
            self.update_targets()?;
        }
        self.updates += 1;
        Ok(UpdateStats {
            critic_loss: f64::from(critic_loss),
            actor_loss,
            alpha: (self.algo == Algo::Sac).then(|| self.alpha()),
            q_mean: f64::from(q_mean),
        })
    }

    /// Actor loss (eq. 5 for SAC, −Q₁(s, μ(s)) for TD3/DDPG) and, for SAC, the α step (eq. 6).
    fn update_actor(
        &mut self,
        obs: Tensor,
        mask: &Tensor,
        norm: f32,
        alpha: f32,
        st: &BurnIn,
    ) -> Result<f64, AgentError> {
        let batch = st.batch.max(1);
        let (mut grads, loss, log_prob) = {
            let mut g = Graph::new();
            for c in &self.critics {
                g.freeze(c.params());
            }
            let ov = g.constant(obs);
            let mv = g.constant(mask.clone());
            let out = self.actor.forward(&mut g, ov, batch, st.actor.as_ref());
            let (act, log_prob) = match self.algo {
                Algo::Sac => {
                    let s = self.actor.sample(&mut g, &out, &mut self.rng);
                    (s.action, Some(s.log_prob))
                }
                _ => (self.actor.deterministic(&mut g, &out), None),
            };
            let critics = if self.algo == Algo::Sac {
                self.critics.len()
            } else {
                1
            };
            let mut qmin = None;
            for (k, c) in self.critics.iter().take(critics).enumerate() {
                let q = c.forward(&mut g, ov, act, batch, st.critics[k].as_ref()).q;
                qmin = Some(match qmin {
                    None => q,
                    Some(m) => g.minimum(m, q),
                });
            }
            let qmin = qmin.expect("at least one critic");
            let per_step = match log_prob {
                Some(lp) => {
                    let alp = g.scale(lp, alpha);
                    g.sub(alp, qmin)
                }
                None => g.neg(qmin),
            };
            let masked = g.mul(per_step, mv);
            let s = g.sum(masked);
            let loss = g.scale(s, norm);
            let lv = g.value(loss).item();
            let lp_values = log_prob.map(|lp| g.value(lp).clone());
            (g.backward(loss), lv, lp_values)
        };
        if !loss.is_finite() {
            return Err(AgentError::NonFinite {
                what: "actor loss",
                update: self.updates,
            });
        }
        self.opt_actor.apply(self.actor.params_mut(), &mut grads)?;

        if let (Some(lp), true) = (log_prob, self.cfg.learn_alpha) {
            // L(log α) = −mean(log α · (log π + H̄)) ⇒ ∂L/∂log α = −mean(log π + H̄).
            let target = self.cfg.target_entropy.unwrap_or(-(self.act_dim as f64)) as f32;
            let mean_lp: f32 = lp
                .data()
                .iter()
                .zip(mask.data())
                .map(|(l, m)| l * m)
                .sum::<f32>()
                * norm;
            let mut grad = [-(mean_lp + target)];
            if grad[0].is_finite() {
                self.opt_alpha.step(&mut self.log_alpha, &mut grad)?;
            }
        }
        Ok(f64::from(loss))
    }

    /// Polyak update (eq. 7) of the target critics, and of the target actor for TD3/DDPG.
    fn update_targets(&mut self) -> Result<(), AgentError> {
        let tau = self.cfg.tau as f32;
        for (t, c) in self.critic_targets.iter_mut().zip(&self.critics) {
            t.params_mut().polyak_update(c.params(), tau)?;
        }
        if let Some(t) = &mut self.actor_target {
            t.params_mut().polyak_update(self.actor.params(), tau)?;
        }
        Ok(())
    }

    /// Runs the burn-in prefix without gradients and returns every network's state at the
    /// start of the trained part.
    fn burn_in(&mut self, batch: &SequenceBatch) -> BurnIn {
        let b = batch.batch;
        let (o, a) = (self.obs_dim, self.act_dim);
        let mut st = BurnIn {
            batch: b,
            actor: self.actor.zero_state(b),
            actor_next: self.actor.zero_state(b),
            critics: self.critics.iter().map(|c| c.zero_state(b)).collect(),
            critic_targets: self
                .critic_targets
                .iter()
                .map(|c| c.zero_state(b))
                .collect(),
        };
        let recurrent = st.actor.is_some() || st.critics.iter().any(Option::is_some);
        if !recurrent {
            return st;
        }
        let alpha_free = self.algo != Algo::Sac;
        for t in 0..=batch.burn_in {
            let reset = &batch.reset[t * b..(t + 1) * b];
            apply_resets(&mut st.actor, reset);
            apply_resets(&mut st.actor_next, reset);
            for s in st.critics.iter_mut().chain(st.critic_targets.iter_mut()) {
                apply_resets(s, reset);
            }
            if t == batch.burn_in {
                break;
            }
            let mut g = Graph::no_grad();
            let ov = g.constant(steps(&batch.obs, b, o, t, t + 1));
            let av = g.constant(steps(&batch.action, b, a, t, t + 1));
            let o2 = g.constant(steps(&batch.next_obs, b, o, t, t + 1));
            st.actor = self.actor.forward(&mut g, ov, b, st.actor.as_ref()).state;
            for (k, c) in self.critics.iter().enumerate() {
                st.critics[k] = c.forward(&mut g, ov, av, b, st.critics[k].as_ref()).state;
            }
            let next_actor = if alpha_free {
                self.actor_target.as_ref().unwrap_or(&self.actor)
            } else {
                &self.actor
            };
            let out = next_actor.forward(&mut g, o2, b, st.actor_next.as_ref());
            st.actor_next = out.state.clone();
            let a2 = match self.algo {
                Algo::Sac => self.actor.sample(&mut g, &out, &mut self.rng).action,
                _ => next_actor.deterministic(&mut g, &out),
            };
            for (k, c) in self.critic_targets.iter().enumerate() {
                st.critic_targets[k] = c
                    .forward(&mut g, o2, a2, b, st.critic_targets[k].as_ref())
                    .state;
            }
        }
        st
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

/// Recurrent states after burn-in (`None` entries for feed-forward networks).
struct BurnIn {
    batch: usize,
    actor: Option<LstmState>,
    actor_next: Option<LstmState>,
    critics: Vec<Option<LstmState>>,
    critic_targets: Vec<Option<LstmState>>,
}
