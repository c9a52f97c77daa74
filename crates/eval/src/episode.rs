//! One evaluation episode: the episode loop of `esrl_sim` with what evaluation keeps — the
//! first observation (for Q₀) and, on the walking task, every step's gait sample and the
//! robot's side view.

use crate::stick::{StickFigure, StickRecorder, DEFAULT_INTERVAL};
use esrl_metrics::{gait_metrics, GaitMetrics, GaitOptions, GaitTrace};
use esrl_run::{Context, Error, Result};
use esrl_sim::{run_episode, Env, EpisodeHook, GaitSample, Step, WalkEnv};
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
}

/// The hook of [`rollout`]: keeps the first observation, acts, and hands every step on.
struct Observe<A, S, E: ?Sized> {
    act: A,
    on_step: S,
    first_obs: Vec<f32>,
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

/// Gait options for these actuators: the default knee names if present, else the actuators
/// whose names contain `knee` and `left` / `right`.
fn gait_options(actuators: &[String], track_length: f64) -> GaitOptions {
    let mut o = GaitOptions {
        track_length,
        ..GaitOptions::default()
    };
    let find = |side: &str| {
        actuators
            .iter()
            .find(|n| {
                let n = n.to_ascii_lowercase();
                n.contains("knee") && n.contains(side)
            })
            .cloned()
    };
    if !actuators.contains(&o.left_knee) {
        if let Some(n) = find("left") {
            o.left_knee = n;
        }
    }
    if !actuators.contains(&o.right_knee) {
        if let Some(n) = find("right") {
            o.right_knee = n;
        }
    }
    o
}

fn finite_sample(g: &GaitSample) -> bool {
    let scalars = [
        g.time,
        g.forward_velocity,
        g.lateral_offset,
        g.height_error,
        g.torso_position[0],
    ];
    scalars
        .iter()
        .chain(&g.joint_torque)
        .chain(&g.joint_power)
        .chain(&g.foot_force)
        .chain(&g.joint_angle)
        .all(|v| v.is_finite())
}

/// Runs one walking episode, logging every step's [`GaitSample`] into a [`GaitTrace`] (with
/// the feet's link-origin positions and the joint limits of the model) and the robot's side
/// view into a [`StickFigure`]. `on_step` is called after every step as in [`rollout`] (e.g.
/// to record it).
pub fn walk_episode(
    env: &mut WalkEnv,
    seed: u64,
    act: impl FnMut(&[f32], &mut [f32]),
    mut on_step: impl FnMut(&WalkEnv, &[f32], &Step) -> Result<()>,
) -> Result<WalkEpisode> {
    let mut trace = GaitTrace::new(
        env.actuated_joint_names().to_vec(),
        env.config().foot_links.to_vec(),
    );
    let model = env.model().clone();
    trace.joint_limits = trace
        .actuator_names
        .iter()
        .map(|n| model.joint_index(n).and_then(|j| model.joints()[j].limits))
        .collect();
    // `WalkEnv` refuses foot links the model lacks, so both are found.
    let feet: Vec<usize> = env
        .config()
        .foot_links
        .iter()
        .filter_map(|n| model.link_index(n))
        .collect();
    let mut stick = StickRecorder::new(
        &env.geometry(),
        f64::from(env.control_period()),
        DEFAULT_INTERVAL,
    );
    let f64s = |v: &[f32]| v.iter().map(|&x| f64::from(x)).collect::<Vec<f64>>();
    let rollout = rollout(env, seed, act, |env, action, step| {
        if let Some(g) = &step.info.gait {
            if g.fell {
                trace.fell = true;
            }
            let poses = env.link_poses();
            let foot_positions: Vec<[f64; 2]> = feet
                .iter()
                .map(|&l| poses[l].translation.map(f64::from))
                .map(|p| [p[0], p[1]])
                .collect();
            let feet_finite = foot_positions.iter().flatten().all(|v| v.is_finite());
            if finite_sample(g) && feet_finite {
                stick.observe(env.steps(), f64::from(g.time), &poses);
                trace.push(&esrl_metrics::GaitStep {
                    time: f64::from(g.time),
                    torso_x: f64::from(g.torso_position[0]),
                    torso_y: f64::from(g.lateral_offset),
                    torso_z_error: f64::from(g.height_error),
                    forward_velocity: f64::from(g.forward_velocity),
                    torques: &f64s(&g.joint_torque),
                    powers: &f64s(&g.joint_abs_power),
                    foot_forces: &f64s(&g.foot_force),
                    joint_angles: &f64s(&g.joint_angle),
                    foot_positions: &foot_positions,
                });
                if g.success && trace.success_time.is_none() {
                    trace.success_time = Some(f64::from(g.time));
                }
            }
        }
        on_step(env, action, step)
    })?;
    Ok(WalkEpisode {
        rollout,
        trace,
        stick: stick.finish(),
    })
}
