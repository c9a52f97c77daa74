//! `esrl eval`: deterministic rollouts of a trained policy on the track, with the gait metrics
//! of SPEC §6, written to `RUN/eval.json`.
//!
//! Episode `k` (0-based) resets the environment with seed `S + k`; the policy acts with
//! `tanh(μ)` (no exploration noise), so the same checkpoint and seed give the same numbers on
//! any machine and thread count. The environment is the run's own (`WalkConfig` of its
//! `config.toml`, so its episode length and track length too).
//!
//! `eval.json` (read by the Python package):
//!
//! ```text
//! {"run": "...", "agent": "es-sac", "env": "walk", "checkpoint": "...", "seed": S,
//!  "track_length": 50.0,
//!  "episodes": [{"seed": S, "return": .., "length": .., "q0": .., "terminated": ..,
//!                "truncated": ..,
//!                "gait": {GaitMetrics with "cycle": {GaitCycle}, "joints": [{JointMotion}]}
//!                        | null,
//!                "trace": {"time": [..], "x": [..], "y": [..], "z_error": [..],
//!                          "forward_velocity": [..], "contact": [[l, r], ..],
//!                          "joint_names": [..], "joint_limits": [[lo, hi] | null, ..],
//!                          "joint_angle": [[..], ..], "stick": {StickFigure}}}],
//!  "mean": {"episodes": K, "return": .., "return_sd": .. | null, "length": .., "q0": ..,
//!           "falls": n, "finished": n, "gait": {GaitMetrics} | null}}
//! ```
//!
//! `mean.gait` has the shape of one episode's gait metrics: every number is the mean over the
//! episodes (per actuator and per foot element-wise); `track_time` is the mean track time when
//! *every* episode reached the end of the track and `null` otherwise, and `fell` is true when
//! *any* episode fell — a policy that only sometimes finishes is not counted as finishing.
//! `mean.gait.cycle` averages the episodes' gait-cycle metrics ([`esrl_metrics::mean_cycle`]:
//! its `gait_classes` counts the episodes per class, its `gait_class` is the most frequent) and
//! `mean.gait.joints` their ranges of motion and times at a limit.
//!
//! The per-step trace keeps what the figures of `python -m esrl_rs.report` need: the torso path,
//! each foot's contact flag (1 when its normal force exceeds `gait.cycle.contact_force`, the
//! same test as the metrics), the actuated joint angles (rad, rounded to 1e-4 rad = 0.006°) with
//! their names and limits, and the side view of the robot every 0.1 s ([`crate::stick`], mm).
//! A 60 s episode adds about 0.4 MB to `eval.json` (0.25 MB of it the side view).
//!
//! Samples with non-finite values (a simulation that blew up on its last step; the
//! environment then reports a fall) are left out of the trace and the metrics.

use crate::args::{EnvKind, EvalArgs};
use crate::checkpoint;
use crate::config::TrainConfig;
use crate::run_dir::{write_json_atomic, RunDir};
use crate::stick::{StickFigure, StickRecorder, DEFAULT_INTERVAL};
use crate::train::algo_of;
use anyhow::{bail, Context, Result};
use esrl_agents::{ActMode, Agent};
use esrl_metrics::{
    format_number, gait_classes_text, gait_metrics, mean_cycle, mean_joint_motion, mean_sd,
    GaitCycle, GaitMetrics, GaitOptions, GaitTrace, JointMotion,
};
use esrl_sim::{Env, GaitSample, Pendulum, RobotModel, Step, WalkEnv};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// File name of the evaluation inside a run folder.
pub const EVAL_FILE: &str = "eval.json";

/// A trained agent loaded from a run or checkpoint folder.
pub struct LoadedRun {
    /// The run folder (holds `config.toml`).
    pub run: PathBuf,
    /// The checkpoint folder the weights came from.
    pub checkpoint: PathBuf,
    /// The run's configuration.
    pub config: TrainConfig,
    /// The agent with the checkpoint's weights.
    pub agent: Agent,
    /// The robot model (walking runs).
    pub model: Option<Arc<RobotModel>>,
}

impl LoadedRun {
    /// A fresh walking environment of this run (`None` for a pendulum run).
    pub fn walk_env(&self) -> Result<Option<WalkEnv>> {
        match &self.model {
            Some(model) => Ok(Some(
                WalkEnv::from_model(model.clone(), self.config.walk.clone())
                    .context("building the walking environment")?,
            )),
            None => Ok(None),
        }
    }
}

/// Finds the run folder and the checkpoint folder for a path that is either.
pub fn locate(path: &Path) -> Result<(PathBuf, PathBuf)> {
    if !path.exists() {
        bail!("{}: no such run or checkpoint folder", path.display());
    }
    if !path.is_dir() {
        bail!(
            "{} is a file; expected a run folder (with config.toml) or a checkpoint folder \
             (with agent.safetensors)",
            path.display()
        );
    }
    // A checkpoint folder (it holds the weights; checkpoints also keep a copy of the run's
    // config.toml, so test for the weights first).
    if path.join("agent.safetensors").is_file() {
        let abs = path
            .canonicalize()
            .with_context(|| format!("resolving {}", path.display()))?;
        if let Some(run) = abs.parent().filter(|r| r.join(RunDir::CONFIG).is_file()) {
            return Ok((run.to_path_buf(), path.to_path_buf()));
        }
        if path.join(RunDir::CONFIG).is_file() {
            return Ok((path.to_path_buf(), path.to_path_buf()));
        }
        bail!(
            "{} looks like a checkpoint folder, but neither it nor its parent folder has a \
             config.toml, so the architecture of the networks is unknown",
            path.display()
        );
    }
    if path.join(RunDir::CONFIG).is_file() {
        let ckpt = checkpoint::find(path).with_context(|| {
            format!(
                "{} has no complete checkpoint (checkpoint/ with state.json and \
                 agent.safetensors); a run killed before its first checkpoint has none",
                path.display()
            )
        })?;
        return Ok((path.to_path_buf(), ckpt));
    }
    bail!(
        "{} is neither a run folder (no config.toml) nor a checkpoint folder (no \
         agent.safetensors)",
        path.display()
    )
}

/// Loads the run's config and the checkpoint's weights (run or checkpoint folder).
pub fn load_run(path: &Path) -> Result<LoadedRun> {
    let (run, ckpt) = locate(path)?;
    let config = TrainConfig::load(&run.join(RunDir::CONFIG))?;
    let (model, obs_dim, act_dim) = match config.env {
        EnvKind::Walk => {
            let model = config
                .walk
                .load_model()
                .with_context(|| match &config.walk.urdf {
                    Some(u) => format!("loading URDF {} named in the run config", u.display()),
                    None => "loading the embedded humanoid".into(),
                })?;
            let env = WalkEnv::from_model(model.clone(), config.walk.clone())
                .context("building the walking environment of the run config")?;
            let dims = (env.obs_dim(), env.act_dim());
            (Some(model), dims.0, dims.1)
        }
        EnvKind::Pendulum => {
            let env = Pendulum::new();
            (None, env.obs_dim(), env.act_dim())
        }
    };
    let mut agent = Agent::new(
        algo_of(config.agent),
        obs_dim,
        act_dim,
        &config.network,
        &config.rl,
        config.seed,
    )
    .with_context(|| {
        format!(
            "building the {} agent of {}",
            config.agent.name(),
            run.display()
        )
    })?;
    checkpoint::load_agent(&ckpt, &mut agent)?;
    Ok(LoadedRun {
        run,
        checkpoint: ckpt,
        config,
        agent,
        model,
    })
}

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

/// Runs one episode from `env.reset(seed)`: `act(obs, action)` fills the action, `on_step`
/// sees the environment, the action and the step after every step. Stops at termination,
/// truncation, or after `max_episode_steps` steps (counted as truncation).
pub fn run_episode<E: Env + ?Sized>(
    env: &mut E,
    seed: u64,
    mut act: impl FnMut(&[f32], &mut [f32]),
    mut on_step: impl FnMut(&E, &[f32], &Step) -> Result<()>,
) -> Result<Rollout> {
    let mut obs = env.reset(seed);
    let first_obs = obs.clone();
    let mut action = vec![0.0f32; env.act_dim()];
    let limit = env.max_episode_steps().max(1);
    let mut out = Rollout {
        seed,
        ret: 0.0,
        length: 0,
        terminated: false,
        truncated: false,
        first_obs,
    };
    loop {
        act(&obs, &mut action);
        let step = env.step(&action);
        out.ret += f64::from(step.reward);
        out.length += 1;
        on_step(env, &action, &step)?;
        if step.terminated || step.truncated || out.length >= limit {
            out.terminated = step.terminated;
            out.truncated = !step.terminated;
            return Ok(out);
        }
        obs = step.obs;
    }
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
/// view into a [`StickFigure`]. `on_step` is called after every step as in [`run_episode`]
/// (e.g. to record it).
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
    let rollout = run_episode(env, seed, act, |env, action, step| {
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

/// The path, foot contacts, joint angles and side view of a walking episode, for plots
/// (paper Fig. 5c; the gait figures of `esrl_rs.report`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Trace {
    /// Simulated time after each step (s).
    pub time: Vec<f64>,
    /// Torso x (m).
    pub x: Vec<f64>,
    /// Torso y (m).
    pub y: Vec<f64>,
    /// Torso height minus standing height (m).
    pub z_error: Vec<f64>,
    /// Torso forward velocity (m/s).
    pub forward_velocity: Vec<f64>,
    /// Per step, left and right foot: 1 in contact (normal force above the gait metrics'
    /// contact threshold), else 0.
    #[serde(default)]
    pub contact: Vec<[u8; 2]>,
    /// Actuated joint names, the order of each `joint_angle` row.
    #[serde(default)]
    pub joint_names: Vec<String>,
    /// Position limits `[lower, upper]` (rad) per actuated joint, `null` for none.
    #[serde(default)]
    pub joint_limits: Vec<Option<[f64; 2]>>,
    /// Actuated joint angles per step (rad, rounded to 1e-4).
    #[serde(default)]
    pub joint_angle: Vec<Vec<f32>>,
    /// The side view of the robot every 0.1 s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stick: Option<StickFigure>,
}

impl Trace {
    /// The trace of `episode`, with contact above `contact_force` (N).
    pub fn new(episode: &WalkEpisode, contact_force: f64) -> Self {
        let t = &episode.trace;
        Self {
            time: t.time.clone(),
            x: t.torso_x.clone(),
            y: t.torso_y.clone(),
            z_error: t.torso_z_error.clone(),
            forward_velocity: t.forward_velocity.clone(),
            contact: t
                .foot_forces
                .iter()
                .filter(|r| r.len() == 2)
                .map(|r| {
                    [
                        u8::from(r[0] > contact_force),
                        u8::from(r[1] > contact_force),
                    ]
                })
                .collect(),
            joint_names: t.actuator_names.clone(),
            joint_limits: t.joint_limits.clone(),
            joint_angle: t
                .joint_angles
                .iter()
                .map(|r| {
                    r.iter()
                        .map(|&q| ((q * 1e4).round() / 1e4) as f32)
                        .collect()
                })
                .collect(),
            stick: Some(episode.stick.clone()),
        }
    }
}

/// One episode of `eval.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeEval {
    /// Seed of the episode's initial state.
    pub seed: u64,
    /// Undiscounted return.
    #[serde(rename = "return")]
    pub ret: f64,
    /// Steps taken.
    pub length: usize,
    /// Q₀: the critics' estimate at the first state and the deterministic action.
    pub q0: f64,
    /// Ended by a fall or success.
    pub terminated: bool,
    /// Ended by the time limit.
    pub truncated: bool,
    /// Gait metrics (walking runs), else `null`.
    pub gait: Option<GaitMetrics>,
    /// The torso's path (walking runs), else absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace: Option<Trace>,
}

/// Aggregates over the episodes of `eval.json` (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalMean {
    /// Number of episodes.
    pub episodes: usize,
    /// Mean return.
    #[serde(rename = "return")]
    pub ret: f64,
    /// Sample SD of the return (`null` for one episode).
    pub return_sd: Option<f64>,
    /// Mean length (steps).
    pub length: f64,
    /// Mean Q₀.
    pub q0: f64,
    /// Episodes that fell.
    pub falls: usize,
    /// Episodes that reached the end of the track.
    pub finished: usize,
    /// Mean gait metrics (walking runs), else `null`.
    pub gait: Option<GaitMetrics>,
}

/// The content of `eval.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// The run folder.
    pub run: String,
    /// Agent name.
    pub agent: String,
    /// Environment.
    pub env: EnvKind,
    /// The checkpoint folder evaluated.
    pub checkpoint: String,
    /// Seed of the first episode (episode k uses seed + k).
    pub seed: u64,
    /// Track length (m) of the walking environment, `null` for the pendulum.
    pub track_length: Option<f64>,
    /// One entry per episode.
    pub episodes: Vec<EpisodeEval>,
    /// Aggregates over the episodes.
    pub mean: EvalMean,
}

/// Evaluates `loaded` on `episodes` deterministic episodes with seeds `seed, seed + 1, …`
/// (in parallel; the results do not depend on the thread count). With `record`, each
/// episode is also written to `record/episode-NNN.mcap` (walking runs only).
pub fn evaluate(
    loaded: &LoadedRun,
    seed: u64,
    episodes: usize,
    record: Option<&Path>,
) -> Result<EvalReport> {
    if episodes == 0 {
        bail!("--episodes 0: evaluate at least one episode");
    }
    if record.is_some() && loaded.config.env != EnvKind::Walk {
        bail!(
            "{} is a pendulum run; --record draws the walking humanoid and needs a walking run",
            loaded.run.display()
        );
    }
    if let Some(dir) = record {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let track_length = match loaded.config.env {
        EnvKind::Walk => Some(f64::from(loaded.config.walk.track_length)),
        EnvKind::Pendulum => None,
    };
    let results: Vec<EpisodeEval> = (0..episodes)
        .into_par_iter()
        .map(|k| {
            let path = record.map(|d| d.join(format!("episode-{k:03}.mcap")));
            evaluate_episode(loaded, seed + k as u64, path.as_deref())
        })
        .collect::<Result<_>>()?;
    let mean = aggregate(&results)?;
    Ok(EvalReport {
        run: loaded.run.display().to_string(),
        agent: loaded.config.agent.name().into(),
        env: loaded.config.env,
        checkpoint: loaded.checkpoint.display().to_string(),
        seed,
        track_length,
        episodes: results,
        mean,
    })
}

fn evaluate_episode(loaded: &LoadedRun, seed: u64, record: Option<&Path>) -> Result<EpisodeEval> {
    let mut policy = loaded.agent.policy();
    policy.reset();
    // Deterministic actions draw nothing from the stream; it only satisfies the signature.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let act = |obs: &[f32], action: &mut [f32]| {
        policy.act(obs, ActMode::Deterministic, &mut rng, action);
    };
    let (rollout, gait, trace) = match loaded.walk_env()? {
        Some(mut env) => {
            let mut recorder = match record {
                Some(path) => Some(crate::record::Recorder::create(
                    path,
                    &env,
                    crate::record::metadata(loaded, seed),
                )?),
                None => None,
            };
            let ep = walk_episode(
                &mut env,
                seed,
                act,
                |env, action, step| match &mut recorder {
                    Some(r) => r.frame(env, action, step),
                    None => Ok(()),
                },
            )?;
            if let Some(r) = recorder {
                r.finish()?;
            }
            let track = f64::from(loaded.config.walk.track_length);
            let gait = ep.metrics(track)?;
            let contact_force = gait
                .as_ref()
                .and_then(|g| g.cycle.as_ref())
                .map_or(GaitOptions::default().thresholds.contact_force, |c| {
                    c.contact_force
                });
            let trace = Trace::new(&ep, contact_force);
            (ep.rollout, gait, Some(trace))
        }
        None => {
            let mut env = Pendulum::new();
            let r = run_episode(&mut env, seed, act, |_, _, _| Ok(()))?;
            (r, None, None)
        }
    };
    Ok(EpisodeEval {
        seed,
        ret: rollout.ret,
        length: rollout.length,
        q0: loaded.agent.q0(&rollout.first_obs),
        terminated: rollout.terminated,
        truncated: rollout.truncated,
        gait,
        trace,
    })
}

fn mean_of(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// Element-wise mean of equally long vectors.
fn mean_vec<'a>(rows: impl Iterator<Item = &'a Vec<f64>> + Clone) -> Vec<f64> {
    let width = rows.clone().next().map_or(0, Vec::len);
    (0..width)
        .map(|j| mean_of(rows.clone().filter_map(|r| r.get(j).copied())))
        .collect()
}

/// The mean of several episodes' gait metrics (rules in the module docs). `None` if empty.
pub fn mean_gait(gaits: &[&GaitMetrics]) -> Option<GaitMetrics> {
    let first = gaits.first()?;
    let m = |f: fn(&GaitMetrics) -> f64| mean_of(gaits.iter().map(|g| f(g)));
    let track_time = if gaits.iter().all(|g| g.track_time.is_some()) {
        Some(mean_of(gaits.iter().filter_map(|g| g.track_time)))
    } else {
        None
    };
    Some(GaitMetrics {
        track_length: first.track_length,
        track_time,
        mean_forward_velocity: m(|g| g.mean_forward_velocity),
        mean_abs_lateral: m(|g| g.mean_abs_lateral),
        mean_vertical: m(|g| g.mean_vertical),
        mean_abs_vertical: m(|g| g.mean_abs_vertical),
        actuator_names: first.actuator_names.clone(),
        mean_abs_torque: mean_vec(gaits.iter().map(|g| &g.mean_abs_torque)),
        mean_abs_power: mean_vec(gaits.iter().map(|g| &g.mean_abs_power)),
        mean_abs_torque_overall: m(|g| g.mean_abs_torque_overall),
        mean_abs_power_overall: m(|g| g.mean_abs_power_overall),
        knee_torque_asymmetry: m(|g| g.knee_torque_asymmetry),
        foot_names: first.foot_names.clone(),
        mean_foot_force: mean_vec(gaits.iter().map(|g| &g.mean_foot_force)),
        distance: m(|g| g.distance),
        fell: gaits.iter().any(|g| g.fell),
        steps: (mean_of(gaits.iter().map(|g| g.steps as f64))).round() as usize,
        duration: m(|g| g.duration),
        cycle: mean_cycle(
            &gaits
                .iter()
                .filter_map(|g| g.cycle.as_ref())
                .collect::<Vec<_>>(),
        ),
        joints: mean_joint_motion(
            &gaits
                .iter()
                .filter(|g| !g.joints.is_empty())
                .map(|g| g.joints.as_slice())
                .collect::<Vec<&[JointMotion]>>(),
        ),
    })
}

fn aggregate(episodes: &[EpisodeEval]) -> Result<EvalMean> {
    let returns: Vec<f64> = episodes.iter().map(|e| e.ret).collect();
    let ret = mean_sd(&returns).context("aggregating the episode returns")?;
    let gaits: Vec<&GaitMetrics> = episodes.iter().filter_map(|e| e.gait.as_ref()).collect();
    Ok(EvalMean {
        episodes: episodes.len(),
        ret: ret.mean,
        return_sd: ret.sd,
        length: mean_of(episodes.iter().map(|e| e.length as f64)),
        q0: mean_of(episodes.iter().map(|e| e.q0)),
        falls: gaits.iter().filter(|g| g.fell).count(),
        finished: gaits.iter().filter(|g| g.track_time.is_some()).count(),
        gait: mean_gait(&gaits),
    })
}

/// Evaluates and writes `RUN/eval.json` atomically; returns the report.
pub fn evaluate_and_write(
    loaded: &LoadedRun,
    seed: u64,
    episodes: usize,
    record: Option<&Path>,
) -> Result<EvalReport> {
    let report = evaluate(loaded, seed, episodes, record)?;
    write_json_atomic(&eval_path(loaded), &report)?;
    Ok(report)
}

/// Where `esrl eval` writes its report: `RUN/eval.json` for the run's last checkpoint,
/// `RUN/best/eval.json` for its best policy (so the two never overwrite each other).
pub fn eval_path(loaded: &LoadedRun) -> PathBuf {
    if loaded.checkpoint.file_name() == Some(std::ffi::OsStr::new(checkpoint::BEST)) {
        loaded.checkpoint.join(EVAL_FILE)
    } else {
        loaded.run.join(EVAL_FILE)
    }
}

/// Runs `esrl eval`.
pub fn run(args: &EvalArgs) -> Result<()> {
    if args.episodes == 0 {
        bail!("--episodes 0: evaluate at least one episode");
    }
    let loaded = load_run(&args.path)?;
    let report = evaluate_and_write(&loaded, args.seed, args.episodes, args.record.as_deref())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", render_table(&report));
    }
    eprintln!("wrote {}", eval_path(&loaded).display());
    if let Some(dir) = &args.record {
        eprintln!(
            "recorded {} episode(s) to {}/episode-NNN.mcap",
            report.episodes.len(),
            dir.display()
        );
    }
    Ok(())
}

fn opt_number(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), format_number)
}

/// Pads each column to its widest cell (right-aligned, first column left-aligned).
fn text_table(header: &[String], rows: &[Vec<String>]) -> String {
    let widths: Vec<usize> = (0..header.len())
        .map(|j| {
            rows.iter()
                .map(|r| r[j].chars().count())
                .chain([header[j].chars().count()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[String]| {
        let parts: Vec<String> = cells
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(j, (c, &w))| {
                let pad = " ".repeat(w.saturating_sub(c.chars().count()));
                if j == 0 {
                    format!("{c}{pad}")
                } else {
                    format!("{pad}{c}")
                }
            })
            .collect();
        parts.join("  ").trim_end().to_string() + "\n"
    };
    let mut out = line(header);
    out.push_str(&line(
        &widths.iter().map(|&w| "-".repeat(w)).collect::<Vec<_>>(),
    ));
    for r in rows {
        out.push_str(&line(r));
    }
    out
}

fn percent(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{:.1} %", 100.0 * v))
}

/// The gait-cycle table of `esrl eval`: one row per episode and the mean (empty without
/// contact data).
fn cycle_table(report: &EvalReport) -> String {
    let cycles: Vec<(String, &GaitCycle)> = report
        .episodes
        .iter()
        .enumerate()
        .filter_map(|(k, e)| Some((k.to_string(), e.gait.as_ref()?.cycle.as_ref()?)))
        .chain(
            report
                .mean
                .gait
                .as_ref()
                .and_then(|g| g.cycle.as_ref())
                .filter(|_| report.episodes.len() > 1)
                .map(|c| ("mean".to_string(), c)),
        )
        .collect();
    if cycles.is_empty() {
        return String::new();
    }
    let header: Vec<String> = [
        "episode",
        "gait",
        "touchdowns L/R",
        "alternation",
        "double sup.",
        "single sup.",
        "flight",
        "cadence (1/min)",
        "step (m)",
        "step SD (m)",
        "stride CV",
    ]
    .map(String::from)
    .to_vec();
    let rows: Vec<Vec<String>> = cycles
        .iter()
        .map(|(label, c)| {
            let gait = if label == "mean" {
                gait_classes_text(&c.gait_classes)
            } else {
                c.gait_class.to_string()
            };
            vec![
                label.clone(),
                gait,
                format!("{:.0}/{:.0}", c.touchdowns[0], c.touchdowns[1]),
                opt_number(c.alternation),
                percent(Some(c.double_support)),
                percent(Some(c.single_support)),
                percent(Some(c.flight)),
                format!("{:.1}", c.cadence),
                opt_number(c.step_length_mean),
                opt_number(c.step_length_sd),
                opt_number(c.stride_time_cv),
            ]
        })
        .collect();
    format!(
        "\ngait cycle (contact above {} N; classes and thresholds: esrl_metrics::GaitThresholds)\n{}",
        cycles[0].1.contact_force,
        text_table(&header, &rows)
    )
}

/// The human-readable report of `esrl eval`.
pub fn render_table(report: &EvalReport) -> String {
    let mut out = format!(
        "{} ({}, {}) — checkpoint {}\n",
        report.run,
        report.agent,
        match report.env {
            EnvKind::Walk => "walk",
            EnvKind::Pendulum => "pendulum",
        },
        report.checkpoint
    );
    let walk = report.env == EnvKind::Walk;
    let mut header: Vec<String> = ["episode", "seed", "return", "steps", "Q0"]
        .map(String::from)
        .to_vec();
    if walk {
        let track = report
            .track_length
            .map_or_else(|| "track".into(), |l| format!("{l} m time (s)"));
        header.extend(
            [
                &track,
                "fwd v (m/s)",
                "|lat| (m)",
                "vert (m)",
                "|vert| (m)",
                "|τ| (N·m)",
                "|P| (W)",
                "knee asym",
                "dist (m)",
                "fell",
            ]
            .map(String::from),
        );
    }
    let gait_cells = |g: Option<&GaitMetrics>| -> Vec<String> {
        match g {
            Some(g) => vec![
                opt_number(g.track_time),
                format_number(g.mean_forward_velocity),
                format_number(g.mean_abs_lateral),
                format_number(g.mean_vertical),
                format_number(g.mean_abs_vertical),
                format_number(g.mean_abs_torque_overall),
                format_number(g.mean_abs_power_overall),
                format_number(g.knee_torque_asymmetry),
                format_number(g.distance),
                if g.fell { "yes" } else { "no" }.into(),
            ],
            None => vec!["-".into(); 10],
        }
    };
    let mut rows: Vec<Vec<String>> = report
        .episodes
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let mut r = vec![
                k.to_string(),
                e.seed.to_string(),
                format_number(e.ret),
                e.length.to_string(),
                format_number(e.q0),
            ];
            if walk {
                r.extend(gait_cells(e.gait.as_ref()));
            }
            r
        })
        .collect();
    if report.episodes.len() > 1 {
        let m = &report.mean;
        let ret = match m.return_sd {
            Some(sd) => format!("{} ± {}", format_number(m.ret), format_number(sd)),
            None => format_number(m.ret),
        };
        let mut r = vec![
            "mean".into(),
            String::new(),
            ret,
            format!("{:.1}", m.length),
            format_number(m.q0),
        ];
        if walk {
            let mut cells = gait_cells(m.gait.as_ref());
            if let Some(last) = cells.last_mut() {
                *last = format!("{}/{}", m.falls, m.episodes);
            }
            r.extend(cells);
        }
        rows.push(r);
    }
    out.push_str(&text_table(&header, &rows));
    if walk {
        out.push_str(&cycle_table(report));
    }
    if let Some(g) = &report.mean.gait {
        out.push('\n');
        let header: Vec<String> = [
            "actuator",
            "mean |τ| (N·m)",
            "mean |P| (W)",
            "p5 (°)",
            "p95 (°)",
            "ROM (°)",
            "at limit",
        ]
        .map(String::from)
        .to_vec();
        let rows: Vec<Vec<String>> = g
            .actuator_names
            .iter()
            .enumerate()
            .map(|(j, n)| {
                let joint = g.joints.iter().find(|m| &m.name == n);
                let deg = |f: fn(&JointMotion) -> f64| {
                    joint.map_or_else(|| "-".into(), |m| format!("{:.1}", f(m).to_degrees()))
                };
                vec![
                    n.clone(),
                    opt_number(g.mean_abs_torque.get(j).copied()),
                    opt_number(g.mean_abs_power.get(j).copied()),
                    deg(|m| m.p5),
                    deg(|m| m.p95),
                    deg(|m| m.range),
                    percent(joint.and_then(|m| m.at_limit)),
                ]
            })
            .collect();
        out.push_str(&text_table(&header, &rows));
        if report.episodes.len() > 1 {
            out.push_str(&format!(
                "(means over {} episodes; {} reached the end of the track, {} fell)\n",
                report.mean.episodes, report.mean.finished, report.mean.falls
            ));
        }
    }
    out
}
