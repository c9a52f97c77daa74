//! Evaluating a trained policy: deterministic rollouts on the track, with the gait metrics of
//! SPEC §6, written to `RUN/eval.json` (what `esrl eval` and `esrl_rs` do).
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
//!                "truncated": .., "start_phase": φ (with a gait clock),
//!                "return_terms": {"alive": .., "forward": .., ..},
//!                "gait": {GaitMetrics with "cycle": {GaitCycle}, "joints": [{JointMotion}],
//!                         "torso_pitch": {TorsoPitch}} | null,
//!                "trace": {"time": [..], "x": [..], "y": [..], "z_error": [..],
//!                          "forward_velocity": [..], "contact": [[l, r], ..],
//!                          "joint_names": [..], "joint_limits": [[lo, hi] | null, ..],
//!                          "joint_angle": [[..], ..], "torso_pitch": [..],
//!                          "stick": {StickFigure}}}],
//!  "mean": {"episodes": K, "return": .., "return_sd": .. | null, "length": .., "q0": ..,
//!           "falls": n, "finished": n, "return_terms": {..}, "gait": {GaitMetrics} | null}}
//! ```
//!
//! `start_phase` is the gait-clock phase φ ∈ [0, 1) the episode started from (drawn from its
//! seed): which starts a policy falls from, by phase.
//!
//! `return_terms` splits the return by the environment's reward terms (`StepInfo::reward_terms`
//! summed over the episode): what pays a policy, e.g. how much of a shuffle's return is
//! speed and how much the gait clock. `mean.return_terms` is their mean over the episodes.
//!
//! `mean.gait` has the shape of one episode's gait metrics: every number is the mean over the
//! episodes (per actuator and per foot element-wise); `track_time` is the mean track time when
//! *every* episode reached the end of the track and `null` otherwise, and `fell` is true when
//! *any* episode fell — a policy that only sometimes finishes is not counted as finishing.
//! `mean.gait.cycle` averages the episodes' gait-cycle metrics ([`esrl_metrics::mean_cycle`]:
//! its `gait_classes` counts the episodes per class, its `gait_class` is the most frequent) and
//! `mean.gait.joints` their ranges of motion and times at a limit, `mean.gait.torso_pitch`
//! the torso's mean pitch and its 5th and 95th percentiles (forward lean positive).
//!
//! The per-step trace keeps what the figures of `python -m esrl_rs.report` need: the torso path,
//! each foot's contact flag (1 when its normal force exceeds `gait.cycle.contact_force`, the
//! same test as the metrics), the actuated joint angles (rad, rounded to 1e-4 rad = 0.006°) with
//! their names and limits, and the side view of the robot every 0.1 s ([`crate::stick`], mm).
//! A 60 s episode adds about 0.4 MB to `eval.json` (0.25 MB of it the side view).
//!
//! Samples with non-finite values (a simulation that blew up on its last step; the
//! environment then reports a fall) are left out of the trace and the metrics.

use crate::episode::{rollout, walk_episode, WalkEpisode};
use crate::load::LoadedRun;
use crate::recording::{metadata, Recorder};
use crate::stick::StickFigure;
use esrl_agents::ActMode;
use esrl_metrics::{
    mean_cycle, mean_joint_motion, mean_sd, mean_torso_pitch, GaitMetrics, GaitOptions, JointMotion,
};
use esrl_run::checkpoint;
use esrl_run::run_dir::write_json_atomic;
use esrl_run::{bail, Context, EnvKind, Result};
use esrl_sim::Pendulum;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// File name of the evaluation inside a run folder.
pub const EVAL_FILE: &str = "eval.json";

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
    /// Torso height minus standing height (m). Empty in the reports of versions that traced
    /// only the path (as every field below).
    #[serde(default)]
    pub z_error: Vec<f64>,
    /// Torso forward velocity (m/s).
    #[serde(default)]
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
    /// Torso pitch per step (rad, forward lean positive; `esrl_metrics::pitch_of`).
    #[serde(default)]
    pub torso_pitch: Vec<f64>,
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
            torso_pitch: t.torso_pitch.clone(),
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
    /// Q₀: the critics' estimate at the first state and the deterministic action; `null` for
    /// a policy folder that keeps the actor alone.
    pub q0: Option<f64>,
    /// Ended by a fall or success.
    pub terminated: bool,
    /// Ended by the time limit.
    pub truncated: bool,
    /// The gait-clock phase φ ∈ [0, 1) the episode started from (walking runs with a gait
    /// clock; drawn from the episode's seed), else absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_phase: Option<f64>,
    /// The return split by reward term (name → the term summed over the episode; they sum
    /// to `return` up to single-precision rounding): what pays the policy.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub return_terms: BTreeMap<String, f64>,
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
    /// Mean Q₀ (`null` without critics).
    pub q0: Option<f64>,
    /// Episodes that fell.
    pub falls: usize,
    /// Episodes that reached the end of the track.
    pub finished: usize,
    /// The mean over the episodes of each reward term's share of the return (episodes
    /// without a term count 0 for it).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub return_terms: BTreeMap<String, f64>,
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
    /// Episodes asked for: more than `episodes` holds when the evaluation was stopped early
    /// (0 in reports written before this field).
    #[serde(default)]
    pub requested: usize,
    /// Track length (m) of the walking environment, `null` for the pendulum.
    pub track_length: Option<f64>,
    /// One entry per episode.
    pub episodes: Vec<EpisodeEval>,
    /// Aggregates over the episodes.
    pub mean: EvalMean,
    /// The disturbances the episodes ran under (`esrl eval --perturb`; empty: none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub perturb: Vec<crate::disturbance::Disturbance>,
    /// Whether the episodes ran without the run's own training-time disturbances
    /// (`[walk.perturb]`; `esrl eval --undisturbed`), `perturb` then added to the plain task.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub undisturbed: bool,
    /// Whether the episodes started from the task's default starts instead of the run's own
    /// (`walk.init_noise` and `walk.reset` at their defaults; `esrl eval --default-starts`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub default_starts: bool,
    /// What the observed torso orientation was measured against on slopes
    /// (`walk.orientation_frame`, or `esrl eval --orientation-frame`); absent: `ground`.
    #[serde(default, skip_serializing_if = "esrl_sim::OrientationFrame::is_ground")]
    pub orientation_frame: esrl_sim::OrientationFrame,
    /// The robustness card (`esrl eval --robustness`): the policy under each disturbance of
    /// the standard set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robustness: Option<Vec<crate::disturbance::CardRow>>,
    /// Which rows of the robustness goal the card meets ([`crate::robustness::goal_rows`]),
    /// beside the card.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robustness_goal: Option<crate::robustness::GoalRows>,
}

/// Evaluates `loaded` on `episodes` deterministic episodes with seeds `seed, seed + 1, …`
/// (in parallel; the results do not depend on the thread count). With `record`, each
/// episode is also written to `record/episode-NNN.mcap` (walking runs only). Every episode
/// keeps its trace ([`evaluate_with`] bounds them).
pub fn evaluate(
    loaded: &LoadedRun,
    seed: u64,
    episodes: usize,
    record: Option<&Path>,
) -> Result<EvalReport> {
    evaluate_with(
        loaded,
        seed,
        episodes,
        record,
        &EvalOptions {
            traces: episodes,
            stop: None,
        },
    )
}

/// How [`evaluate_with`] runs.
pub struct EvalOptions<'a> {
    /// Episodes (the first ones) whose per-step trace is kept in the report (≈ 0.4 MB each
    /// for a 60 s walking episode); the others keep their metrics only.
    pub traces: usize,
    /// Polled between batches of episodes: when it says stop, the episodes done so far are
    /// reported (the report's `requested` says how many were asked for).
    pub stop: Option<&'a (dyn Fn() -> bool + Sync)>,
}

/// [`evaluate`] with a bound on the traces kept and a way to stop early.
pub fn evaluate_with(
    loaded: &LoadedRun,
    seed: u64,
    episodes: usize,
    record: Option<&Path>,
    options: &EvalOptions<'_>,
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
    // Batches of a few episodes per thread, so a stop request is answered within one
    // batch and the episodes done are kept.
    let batch = 4 * rayon::current_num_threads().max(1);
    let mut results: Vec<EpisodeEval> = Vec::with_capacity(episodes.min(1 << 20));
    for start in (0..episodes).step_by(batch) {
        if options.stop.is_some_and(|stop| stop()) {
            break;
        }
        let done: Vec<EpisodeEval> = (start..(start + batch).min(episodes))
            .into_par_iter()
            .map(|k| {
                let path = record.map(|d| d.join(format!("episode-{k:03}.mcap")));
                let mut e = evaluate_episode(loaded, seed + k as u64, path.as_deref())?;
                if k >= options.traces {
                    e.trace = None;
                }
                Ok(e)
            })
            .collect::<Result<_>>()?;
        results.extend(done);
    }
    if results.is_empty() {
        bail!("stopped before the first episode finished; nothing to report");
    }
    let mean = aggregate(&results)?;
    Ok(EvalReport {
        run: loaded.run.display().to_string(),
        agent: loaded.config.agent.name().into(),
        env: loaded.config.env,
        checkpoint: loaded.checkpoint.display().to_string(),
        seed,
        requested: episodes,
        track_length,
        episodes: results,
        mean,
        perturb: Vec::new(),
        undisturbed: false,
        default_starts: false,
        orientation_frame: loaded.config.walk.orientation_frame,
        robustness: None,
        robustness_goal: None,
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
    let (rollout, gait, trace, start_phase) = match loaded.walk_env()? {
        Some(mut env) => {
            let mut recorder = match record {
                Some(path) => Some(Recorder::create(path, &env, metadata(loaded, seed))?),
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
            let start_phase = env
                .config()
                .gait_clock
                .is_some()
                .then_some(f64::from(ep.start_phase));
            (ep.rollout, gait, Some(trace), start_phase)
        }
        None => {
            let mut env = Pendulum::new();
            let r = rollout(&mut env, seed, act, |_, _, _| Ok(()))?;
            (r, None, None, None)
        }
    };
    Ok(EpisodeEval {
        seed,
        ret: rollout.ret,
        length: rollout.length,
        q0: esrl_run::checkpoint::has_critics(&loaded.checkpoint)
            .then(|| loaded.agent.q0(&rollout.first_obs)),
        terminated: rollout.terminated,
        truncated: rollout.truncated,
        start_phase,
        return_terms: rollout
            .return_terms
            .iter()
            .map(|&(name, sum)| (name.to_string(), sum))
            .collect(),
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
        torso_pitch: mean_torso_pitch(
            &gaits
                .iter()
                .filter_map(|g| g.torso_pitch.as_ref())
                .collect::<Vec<_>>(),
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
        q0: episodes
            .iter()
            .map(|e| e.q0)
            .collect::<Option<Vec<f64>>>()
            .map(|q| mean_of(q.into_iter())),
        falls: gaits.iter().filter(|g| g.fell).count(),
        finished: gaits.iter().filter(|g| g.track_time.is_some()).count(),
        return_terms: mean_terms(episodes),
        gait: mean_gait(&gaits),
    })
}

/// Each reward term's mean over `episodes` (0 where an episode lacks it).
fn mean_terms(episodes: &[EpisodeEval]) -> BTreeMap<String, f64> {
    let mut sums = BTreeMap::new();
    for e in episodes {
        for (name, value) in &e.return_terms {
            *sums.entry(name.clone()).or_insert(0.0) += value;
        }
    }
    let n = episodes.len().max(1) as f64;
    sums.values_mut().for_each(|v| *v /= n);
    sums
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
