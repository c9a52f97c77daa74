//! Running a policy through one episode, keeping its transitions.

use crate::agent::{ActMode, Policy};
use crate::replay::{ReplayBuffer, Transition};
use esrl_sim::{Env, Step};
use rand::Rng;

/// One finished episode: its transitions in order, its return and how it ended.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Episode {
    /// Observations, `(len, obs_dim)` row-major.
    pub obs: Vec<f32>,
    /// Actions, `(len, act_dim)`.
    pub action: Vec<f32>,
    /// Rewards, `len`.
    pub reward: Vec<f32>,
    /// Next observations, `(len, obs_dim)`.
    pub next_obs: Vec<f32>,
    /// Terminal flags, `len` (only the last can be true).
    pub terminated: Vec<bool>,
    /// Undiscounted return.
    pub ret: f64,
    /// The episode hit the time limit.
    pub truncated: bool,
    /// Observation width.
    pub obs_dim: usize,
    /// Action width.
    pub act_dim: usize,
}

impl Episode {
    /// Steps taken.
    pub fn len(&self) -> usize {
        self.reward.len()
    }

    /// True when no step was taken.
    pub fn is_empty(&self) -> bool {
        self.reward.is_empty()
    }

    /// Appends every transition to `buffer` as one episode.
    pub fn push_into(&self, buffer: &mut ReplayBuffer) {
        let (o, a) = (self.obs_dim, self.act_dim);
        for i in 0..self.len() {
            buffer.push(Transition {
                obs: &self.obs[i * o..(i + 1) * o],
                action: &self.action[i * a..(i + 1) * a],
                reward: self.reward[i],
                next_obs: &self.next_obs[i * o..(i + 1) * o],
                terminated: self.terminated[i],
            });
        }
        buffer.end_episode();
    }
}

/// How actions are chosen in [`rollout`].
#[derive(Debug)]
pub enum Actor<'p> {
    /// Uniform random actions in [−1, 1] (warm start).
    Random,
    /// A policy in the given mode.
    Policy(&'p mut Policy, ActMode),
}

/// Runs one episode from `env.reset(env_seed)` until it terminates or is truncated (or after
/// `max_steps`, counted as truncation), calling `on_step` after every step.
pub fn rollout<R: Rng + ?Sized>(
    env: &mut dyn Env,
    mut actor: Actor<'_>,
    env_seed: u64,
    max_steps: Option<usize>,
    rng: &mut R,
    mut on_step: impl FnMut(&Step),
) -> Episode {
    let (o, a) = (env.obs_dim(), env.act_dim());
    let mut ep = Episode {
        obs_dim: o,
        act_dim: a,
        ..Episode::default()
    };
    let mut obs = env.reset(env_seed);
    if let Actor::Policy(p, _) = &mut actor {
        p.reset();
    }
    let limit = max_steps.unwrap_or(usize::MAX);
    let mut action = vec![0.0f32; a];
    loop {
        match &mut actor {
            Actor::Random => action
                .iter_mut()
                .for_each(|x| *x = rng.random_range(-1.0..=1.0)),
            Actor::Policy(p, mode) => p.act(&obs, *mode, rng, &mut action),
        }
        let step = env.step(&action);
        on_step(&step);
        ep.obs.extend_from_slice(&obs);
        ep.action.extend_from_slice(&action);
        ep.reward.push(step.reward);
        ep.next_obs.extend_from_slice(&step.obs);
        ep.terminated.push(step.terminated);
        ep.ret += f64::from(step.reward);
        let hit_limit = ep.len() >= limit;
        if step.terminated || step.truncated || hit_limit {
            ep.truncated = !step.terminated;
            return ep;
        }
        obs = step.obs;
    }
}
