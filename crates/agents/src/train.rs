//! Plain (non-ES) training: one episode at a time, learning as [`RlConfig::learn_every`] says.

use crate::agent::{ActMode, Agent, AgentError, UpdateStats};
use crate::config::{LearnEvery, RlConfig};
use crate::replay::{ReplayBuffer, SequenceBatch, Transition};
use esrl_sim::Env;
use esrl_streams::Stream;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// One training episode's row of `metrics.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeReport {
    /// Episode index, from 0.
    pub episode: usize,
    /// Environment steps taken so far, this episode included.
    pub env_steps: u64,
    /// The training episode's return (the learning curve of plain agents).
    pub ret: f64,
    /// Steps in the episode.
    pub length: usize,
    /// Whether it ended in a terminal state (fall or success) rather than the time limit.
    pub terminated: bool,
    /// Q₀ at the episode's first state (SPEC §6).
    pub q0: f64,
    /// Mean critic loss over the episode's updates.
    pub critic_loss: Option<f64>,
    /// Mean actor loss over the episode's actor updates.
    pub actor_loss: Option<f64>,
    /// Entropy coefficient after the episode (SAC).
    pub alpha: Option<f64>,
    /// Gradient updates so far.
    pub updates: u64,
}

/// Running means of update statistics.
#[derive(Debug, Default, Clone, Copy)]
pub struct LossMeans {
    critic: f64,
    actor: f64,
    n_critic: usize,
    n_actor: usize,
}

impl LossMeans {
    /// Adds one update's losses.
    pub fn add(&mut self, s: &UpdateStats) {
        self.critic += s.critic_loss;
        self.n_critic += 1;
        if let Some(a) = s.actor_loss {
            self.actor += a;
            self.n_actor += 1;
        }
    }

    /// Mean critic loss, if any update happened.
    pub fn critic(&self) -> Option<f64> {
        (self.n_critic > 0).then(|| self.critic / self.n_critic as f64)
    }

    /// Mean actor loss, if any actor update happened.
    pub fn actor(&self) -> Option<f64> {
        (self.n_actor > 0).then(|| self.actor / self.n_actor as f64)
    }
}

/// Draws the batch the agent's networks expect: sequences for recurrent networks, single
/// transitions otherwise.
pub fn sample_batch(
    buffer: &ReplayBuffer,
    cfg: &RlConfig,
    recurrent: bool,
    rng: &mut ChaCha8Rng,
) -> SequenceBatch {
    if recurrent {
        buffer.sample_sequences(rng, cfg.batch_size, cfg.seq_len, cfg.burn_in)
    } else {
        buffer.sample_transitions(rng, cfg.batch_size)
    }
}

/// An agent, its replay buffer and its random stream, trained episode by episode.
#[derive(Debug, Clone)]
pub struct Trainer {
    /// The agent.
    pub agent: Agent,
    /// Its replay buffer.
    pub buffer: ReplayBuffer,
    /// Random stream for warm-start actions, exploration and batch sampling.
    pub rng: ChaCha8Rng,
    /// Seed of the run (episode seeds derive from it).
    pub seed: u64,
    /// Environment steps taken.
    pub env_steps: u64,
    /// Episodes completed.
    pub episodes: usize,
}

impl Trainer {
    /// A trainer around `agent` with an empty buffer sized by the agent's config.
    pub fn new(agent: Agent, seed: u64) -> Self {
        let cfg = agent.config();
        let buffer = ReplayBuffer::new(agent.obs_dim(), agent.act_dim(), cfg.buffer_size);
        Self {
            agent,
            buffer,
            rng: Stream::Trainer.rng(seed),
            seed,
            env_steps: 0,
            episodes: 0,
        }
    }

    fn recurrent(&self) -> bool {
        self.agent.actor().lstm_hidden().is_some()
            || self
                .agent
                .critics()
                .iter()
                .any(|c| c.lstm_hidden().is_some())
    }

    /// One gradient update on a fresh batch.
    pub fn update(&mut self) -> Result<UpdateStats, AgentError> {
        let batch = sample_batch(
            &self.buffer,
            self.agent.config(),
            self.recurrent(),
            &mut self.rng,
        );
        self.agent.update(&batch)
    }

    /// Runs one training episode on `env`, learning along the way.
    pub fn episode(&mut self, env: &mut dyn Env) -> Result<EpisodeReport, AgentError> {
        let cfg = self.agent.config().clone();
        let env_seed = Stream::EpisodeReset(self.episodes as u64).seed(self.seed);
        let mut obs = env.reset(env_seed);
        let q0 = self.agent.q0(&obs);
        let mut policy = self.agent.policy();
        policy.reset();
        let mut action = vec![0.0f32; env.act_dim()];
        let mut losses = LossMeans::default();
        let (mut ret, mut length, terminated);
        ret = 0.0;
        length = 0;
        loop {
            if self.env_steps < cfg.warm_start as u64 {
                action
                    .iter_mut()
                    .for_each(|x| *x = self.rng.random_range(-1.0..=1.0));
            } else {
                policy.act(&obs, ActMode::Explore, &mut self.rng, &mut action);
            }
            let step = env.step(&action);
            self.buffer.push(Transition {
                obs: &obs,
                action: &action,
                reward: step.reward,
                next_obs: &step.obs,
                terminated: step.terminated,
            });
            self.env_steps += 1;
            length += 1;
            ret += f64::from(step.reward);
            if let LearnEvery::Steps(n) = cfg.learn_every {
                if self.env_steps >= cfg.warm_start as u64 && self.env_steps % n as u64 == 0 {
                    for _ in 0..cfg.updates_per_learn {
                        losses.add(&self.update()?);
                    }
                    policy.sync_from(self.agent.actor())?;
                }
            }
            if step.terminated || step.truncated {
                terminated = step.terminated;
                break;
            }
            obs = step.obs;
        }
        self.buffer.end_episode();
        if cfg.learn_every == LearnEvery::Episode && self.env_steps >= cfg.warm_start as u64 {
            for _ in 0..cfg.updates_per_learn {
                losses.add(&self.update()?);
            }
        }
        let report = EpisodeReport {
            episode: self.episodes,
            env_steps: self.env_steps,
            ret,
            length,
            terminated,
            q0,
            critic_loss: losses.critic(),
            actor_loss: losses.actor(),
            alpha: (self.agent.algo() == crate::Algo::Sac).then(|| self.agent.alpha()),
            updates: self.agent.updates(),
        };
        self.episodes += 1;
        Ok(report)
    }
}
