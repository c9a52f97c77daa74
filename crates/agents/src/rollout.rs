//! Running a policy (or random actions) through one episode and keeping its transitions.

use crate::policy::{ActMode, Policy};
use crate::replay::{ReplayBuffer, Transition};
use esrl_sim::{run_episode, Env, EpisodeHook, Step};
use rand::Rng;
use std::convert::Infallible;

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

    /// The first observation (the state the episode started from).
    pub fn first_obs(&self) -> &[f32] {
        &self.obs[..self.obs_dim.min(self.obs.len())]
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

/// The hook of [`rollout`]: acts as `actor` says and keeps every transition.
struct Keep<'a, 'p, R: ?Sized> {
    actor: Actor<'p>,
    rng: &'a mut R,
    episode: Episode,
}

impl<E: ?Sized, R: Rng + ?Sized> EpisodeHook<E> for Keep<'_, '_, R> {
    type Error = Infallible;

    fn act(&mut self, obs: &[f32], action: &mut [f32]) {
        match &mut self.actor {
            Actor::Random => action
                .iter_mut()
                .for_each(|x| *x = self.rng.random_range(-1.0..=1.0)),
            Actor::Policy(p, mode) => p.act(obs, *mode, self.rng, action),
        }
    }

    fn step(&mut self, _: &E, obs: &[f32], action: &[f32], step: &Step) -> Result<(), Infallible> {
        let ep = &mut self.episode;
        ep.obs.extend_from_slice(obs);
        ep.action.extend_from_slice(action);
        ep.reward.push(step.reward);
        ep.next_obs.extend_from_slice(&step.obs);
        ep.terminated.push(step.terminated);
        Ok(())
    }
}

/// Runs one episode from `env.reset(env_seed)` until it terminates or is truncated (or after
/// `max_steps`, counted as truncation), drawing actions' randomness from `rng`, and returns
/// its transitions. Subnormal floats are flushed to zero meanwhile ([`esrl_nn::subnormal`]).
pub fn rollout<R: Rng + ?Sized>(
    env: &mut dyn Env,
    actor: Actor<'_>,
    env_seed: u64,
    max_steps: Option<usize>,
    rng: &mut R,
) -> Episode {
    esrl_nn::subnormal::flushing(|| rollout_here(env, actor, env_seed, max_steps, rng))
}

fn rollout_here<R: Rng + ?Sized>(
    env: &mut dyn Env,
    mut actor: Actor<'_>,
    env_seed: u64,
    max_steps: Option<usize>,
    rng: &mut R,
) -> Episode {
    if let Actor::Policy(p, _) = &mut actor {
        p.reset();
    }
    let mut keep = Keep {
        episode: Episode {
            obs_dim: env.obs_dim(),
            act_dim: env.act_dim(),
            ..Episode::default()
        },
        actor,
        rng,
    };
    let Ok(end) = run_episode(env, env_seed, max_steps, &mut keep);
    let mut episode = keep.episode;
    episode.ret = end.ret;
    episode.truncated = end.truncated;
    episode
}
