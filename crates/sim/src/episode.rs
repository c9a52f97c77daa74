//! The one episode loop of esrl: reset with a seed, then act and step until the episode
//! ends. Training, the population's rollouts, evaluation, recording and the benchmarks all
//! run it; what each needs besides (learning, keeping transitions, gait samples, an MCAP
//! frame) is an [`EpisodeHook`].
//!
//! ```
//! use esrl_sim::{hooks, run_episode, Env, Pendulum};
//!
//! let mut env = Pendulum::new();
//! let mut rewards = Vec::new();
//! let mut hook = hooks(
//!     |_obs: &[f32], action: &mut [f32]| action.fill(0.0),
//!     |_env: &Pendulum, _obs: &[f32], _action: &[f32], step: &esrl_sim::Step| {
//!         rewards.push(step.reward);
//!         Ok::<(), std::convert::Infallible>(())
//!     },
//! );
//! let end = run_episode(&mut env, 7, None, &mut hook).unwrap();
//! assert_eq!((end.steps, end.truncated), (200, true));
//! assert_eq!(rewards.len(), 200);
//! ```

use std::marker::PhantomData;

use crate::env::{Env, Step};

/// What a caller adds to [`run_episode`]: how to act, and what to do with every step.
pub trait EpisodeHook<E: ?Sized> {
    /// Why the hook may stop an episode early.
    type Error;

    /// Sees the first observation, right after the reset.
    fn start(&mut self, _obs: &[f32]) -> Result<(), Self::Error> {
        Ok(())
    }

    /// Fills `action` (each entry in [−1, 1]) for `obs`.
    fn act(&mut self, obs: &[f32], action: &mut [f32]);

    /// Sees the step just taken from `obs` with `action`; `env` is the environment after it.
    fn step(
        &mut self,
        env: &E,
        obs: &[f32],
        action: &[f32],
        step: &Step,
    ) -> Result<(), Self::Error>;
}

/// How an episode ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeEnd {
    /// Steps taken.
    pub steps: usize,
    /// Undiscounted return, summed in f64.
    pub ret: f64,
    /// Ended by the task (a fall, success): its last step is terminal.
    pub terminated: bool,
    /// Ended by the time limit or by `max_steps` (not terminal: bootstrap).
    pub truncated: bool,
}

/// Runs one episode of `env` from `env.reset(seed)` until a step terminates or truncates it,
/// or after `max_steps` steps (counted as truncation). The hook acts, and sees each step
/// after it is taken; its first error ends the episode and is returned.
pub fn run_episode<E, H>(
    env: &mut E,
    seed: u64,
    max_steps: Option<usize>,
    hook: &mut H,
) -> Result<EpisodeEnd, H::Error>
where
    E: Env + ?Sized,
    H: EpisodeHook<E>,
{
    let limit = max_steps.unwrap_or(usize::MAX);
    let mut obs = env.reset(seed);
    hook.start(&obs)?;
    let mut action = vec![0.0f32; env.act_dim()];
    let mut end = EpisodeEnd {
        steps: 0,
        ret: 0.0,
        terminated: false,
        truncated: false,
    };
    loop {
        hook.act(&obs, &mut action);
        let step = env.step(&action);
        end.steps += 1;
        end.ret += f64::from(step.reward);
        hook.step(env, &obs, &action, &step)?;
        if step.terminated || step.truncated || end.steps >= limit {
            end.terminated = step.terminated;
            end.truncated = !step.terminated;
            return Ok(end);
        }
        obs = step.obs;
    }
}

/// A hook made of two closures, `act(obs, action)` and `on_step(env, obs, action, step)`.
pub struct Hooks<A, S, Er> {
    act: A,
    on_step: S,
    error: PhantomData<fn() -> Er>,
}

/// The hook of [`run_episode`] from two closures: one acts, the other sees each step.
pub fn hooks<A, S, Er>(act: A, on_step: S) -> Hooks<A, S, Er> {
    Hooks {
        act,
        on_step,
        error: PhantomData,
    }
}

impl<E, A, S, Er> EpisodeHook<E> for Hooks<A, S, Er>
where
    E: ?Sized,
    A: FnMut(&[f32], &mut [f32]),
    S: FnMut(&E, &[f32], &[f32], &Step) -> Result<(), Er>,
{
    type Error = Er;

    fn act(&mut self, obs: &[f32], action: &mut [f32]) {
        (self.act)(obs, action);
    }

    fn step(&mut self, env: &E, obs: &[f32], action: &[f32], step: &Step) -> Result<(), Er> {
        (self.on_step)(env, obs, action, step)
    }
}
