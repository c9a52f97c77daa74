//! Throughput of the walking environment on one core (`esrl bench env`), and the rigid-stance
//! creep measurement behind the physics default (crate docs, "Physics step and joint limits").

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use std::convert::Infallible;

use crate::env::{Env, Step};
use crate::episode::{hooks, run_episode};
use crate::error::SimError;
use crate::sim::LimitModel;
use crate::walk::{ActionMode, WalkConfig, WalkEnv};

/// What [`bench_walk`] measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// Control steps per wall-clock second (resets included).
    pub steps_per_s: f64,
    /// Control steps taken.
    pub steps: usize,
    /// Wall-clock time of the stepping loop, s (environment construction excluded).
    pub wall_s: f64,
    /// Episodes started (the first reset included).
    pub episodes: usize,
    /// Episodes that ended in a fall.
    pub falls: usize,
    /// Simulated seconds per wall-clock second.
    pub realtime_factor: f64,
    /// Control period, s.
    pub control_period: f32,
    /// Physics (Rapier) step, s.
    pub dt: f32,
    /// Rapier steps per control step.
    pub substeps: u32,
    /// Rapier solver iterations (each one an integration substep in Rapier 0.36).
    pub solver_iterations: u32,
    /// Joint-limit model.
    pub joint_limits: LimitModel,
    /// Action mode.
    pub action: ActionMode,
    /// Seed of the random actions and resets.
    pub seed: u64,
    /// Observation length.
    pub obs_dim: usize,
    /// Action length.
    pub act_dim: usize,
}

/// Runs `steps` control steps of [`WalkEnv`] with uniformly random actions in `[-1, 1]`,
/// episode after episode (episode `k` resets with seed `seed + k`), on the calling thread.
pub fn bench_walk(config: &WalkConfig, steps: usize, seed: u64) -> Result<BenchReport, SimError> {
    let mut env = WalkEnv::new(config.clone())?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut falls = 0;
    let mut random = hooks(
        |_: &[f32], action: &mut [f32]| {
            for a in action.iter_mut() {
                *a = rng.random_range(-1.0..=1.0);
            }
        },
        |_: &WalkEnv, _: &[f32], _: &[f32], step: &Step| {
            falls += usize::from(step.info.gait.as_ref().is_some_and(|g| g.fell));
            Ok::<(), Infallible>(())
        },
    );
    let start = Instant::now();
    let (mut taken, mut episodes) = (0, 0);
    while taken < steps {
        let seed = seed.wrapping_add(episodes as u64);
        let Ok(end) = run_episode(&mut env, seed, Some(steps - taken), &mut random);
        taken += end.steps;
        episodes += 1;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let steps_per_s = if wall_s > 0.0 {
        steps as f64 / wall_s
    } else {
        0.0
    };
    Ok(BenchReport {
        steps_per_s,
        steps,
        wall_s,
        episodes,
        falls,
        realtime_factor: steps_per_s * config.control_period as f64,
        control_period: config.control_period,
        dt: config.control_period / config.physics.substeps as f32,
        substeps: config.physics.substeps,
        solver_iterations: config.physics.solver_iterations,
        joint_limits: config.physics.joint_limits,
        action: config.action,
        seed,
        obs_dim: env.obs_dim(),
        act_dim: env.act_dim(),
    })
}

/// Horizontal travel (m) of the torso from t = 1 s to t = 60 s of a rigid stance, or None if
/// it fell: both hips and knees pressed into their limits at full effort (action
/// `[1, −1, ankle, 1, −1, ankle]`) from a reset with `seed`, for at most 2400 steps. Such a
/// body is a rigid object on flat ground, so it should not travel after the first second's
/// lurch into the stance.
pub fn rigid_stance_travel(env: &mut WalkEnv, seed: u64, ankle: f32) -> Option<f32> {
    let stance = [1.0, -1.0, ankle, 1.0, -1.0, ankle];
    let (mut start, mut end) = ([0.0f32; 3], [0.0f32; 3]);
    let mut hook = hooks(
        |_: &[f32], action: &mut [f32]| action.copy_from_slice(&stance),
        |env: &WalkEnv, _: &[f32], _: &[f32], step: &Step| {
            if let Some(g) = &step.info.gait {
                if env.steps() == 40 {
                    start = g.torso_position;
                }
                end = g.torso_position;
            }
            Ok::<(), Infallible>(())
        },
    );
    let Ok(episode) = run_episode(env, seed, Some(2400), &mut hook);
    if episode.terminated {
        return None;
    }
    Some((end[0] - start[0]).hypot(end[1] - start[1]))
}
