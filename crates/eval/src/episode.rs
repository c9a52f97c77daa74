//! One evaluation episode: the episode loop of `esrl_sim` with what evaluation keeps — the
//! first observation (for Q₀), the return split by reward term and, on the walking task,
//! every step's gait sample and the robot's side view.

use crate::stick::{StickFigure, StickRecorder, DEFAULT_INTERVAL};
use esrl_metrics::{gait_metrics, GaitMetrics, GaitTrace};
use esrl_run::check::{gait_options, GaitLog};
use esrl_run::{Context, Error, Result};
use esrl_sim::{run_episode, Env, EpisodeHook, Step, WalkEnv};
use std::marker::PhantomData;

/// One finished evaluation episode of any environment.
#[derive(Debug, Clone, PartialEq)]
pub struct Rollout {
    /// Seed given to `reset`.
    pub seed: u64,
    /// Undiscounted return.
    pub ret: f64,
    /// Steps taken.
    pub length: usize,
    /// Ended by the task (fall or success).
    pub terminated: bool,
    /// Ended by the time limit.
    pub truncated: bool,
    /// The first observation (for Q₀).
    pub first_obs: Vec<f32>,
    /// The return split by reward term: each term summed over the episode's steps (in f64),
    /// in the environment's order. The terms of a step sum to its reward, so these sum to
    /// [`Rollout::ret`] up to the rounding of the single-precision rewards.
    pub return_terms: Vec<(&'static str, f64)>,
}

/// The hook of [`rollout`]: keeps the first observation, acts, and hands every step on.
struct Observe<A, S, E: ?Sized> {
    act: A,
    on_step: S,
    first_obs: Vec<f32>,
    return_terms: Vec<(&'static str, f64)>,
    env: PhantomData<fn(&E)>,
}

impl<E, A, S> EpisodeHook<E> for Observe<A, S, E>
where
    E: ?Sized,
    A: FnMut(&[f32], &mut [f32]),
    S: FnMut(&E, &[f32], &Step) -> Result<()>,
{
    type Error = Error;

    fn start(&mut self, obs: &[f32]) -> Result<()> {
        self.first_obs = obs.to_vec();
        Ok(())
    }

    fn act(&mut self, obs: &[f32], action: &mut [f32]) {
        (self.act)(obs, action);
    }

    fn step(&mut self, env: &E, _: &[f32], action: &[f32], step: &Step) -> Result<()> {
        for &(name, value) in &step.info.reward_terms {
            match self.return_terms.iter_mut().find(|(n, _)| *n == name) {
                Some((_, sum)) => *sum += f64::from(value),
                None => self.return_terms.push((name, f64::from(value))),
            }
        }
        (self.on_step)(env, action, step)
    }
}

/// Runs one episode from `env.reset(seed)` through [`esrl_sim::run_episode`]: `act(obs,
/// action)` fills the action, `on_step` sees the environment, the action and the step after
/// every step. Stops at termination, truncation, or after `max_episode_steps` steps (counted
/// as truncation).
pub fn rollout<E: Env + ?Sized>(
    env: &mut E,
    seed: u64,
    act: impl FnMut(&[f32], &mut [f32]),
    on_step: impl FnMut(&E, &[f32], &Step) -> Result<()>,
) -> Result<Rollout> {
    let limit = env.max_episode_steps().max(1);
    let mut hook = Observe {
        act,
        on_step,
        first_obs: Vec::new(),
        return_terms: Vec::new(),
        env: PhantomData,
    };
    let end = run_episode(env, seed, Some(limit), &mut hook)?;
    Ok(Rollout {
        seed,
        ret: end.ret,
        length: end.steps,
        terminated: end.terminated,
        truncated: end.truncated,
        first_obs: hook.first_obs,
        return_terms: hook.return_terms,
    })
}

/// A walking episode: the rollout plus its gait log.
#[derive(Debug, Clone, PartialEq)]
pub struct WalkEpisode {
    /// Return, length, how it ended.
    pub rollout: Rollout,
    /// Per-step gait log (finite samples only), `fell` and `success_time` filled in, with the
    /// joint angles and limits and the feet's horizontal positions.
    pub trace: GaitTrace,
    /// The side view of the robot every [`DEFAULT_INTERVAL`] seconds.
    pub stick: StickFigure,
    /// The gait-clock phase φ ∈ [0, 1) the episode started from (0 without a clock).
    pub start_phase: f32,
}

impl WalkEpisode {
    /// The gait metrics of the episode on a track of `track_length` m; `None` when no finite
    /// sample was logged.
    pub fn metrics(&self, track_length: f64) -> Result<Option<GaitMetrics>> {
        if self.trace.is_empty() {
            return Ok(None);
        }
        let options = gait_options(&self.trace.actuator_names, track_length);
        Ok(Some(
            gait_metrics(&self.trace, &options).context("computing the gait metrics")?,
        ))
    }
}

/// Runs one walking episode, logging every step's gait sample into a [`GaitTrace`]
/// ([`esrl_run::check::GaitLog`]: with the feet's link-origin positions and the joint limits
/// of the model) and the robot's side view into a [`StickFigure`]. `on_step` is called after
/// every step as in [`rollout`] (e.g. to record it).
pub fn walk_episode(
    env: &mut WalkEnv,
    seed: u64,
    act: impl FnMut(&[f32], &mut [f32]),
    mut on_step: impl FnMut(&WalkEnv, &[f32], &Step) -> Result<()>,
) -> Result<WalkEpisode> {
    let mut log = GaitLog::new(env);
    let mut stick = StickRecorder::new(
        &env.geometry(),
        f64::from(env.control_period()),
        DEFAULT_INTERVAL,
    );
    let rollout = rollout(env, seed, act, |env, action, step| {
        if log.observe(env, step) {
            if let Some(g) = &step.info.gait {
                stick.observe(env.steps(), f64::from(g.time), &env.link_poses());
            }
        }
        on_step(env, action, step)
    })?;
    Ok(WalkEpisode {
        rollout,
        trace: log.finish(),
        stick: stick.finish(),
        start_phase: env.reset_phase(),
    })
}
