//! Gait metrics of one evaluation rollout (SPEC §6, paper §5 and Fig. 5 c–d).
//!
//! Frames follow REP-103 as in the environment: x forward along the track, y lateral, z up.
//! With n logged steps (one sample per control step, after the step):
//!
//! - track time = the environment's `success_time` when it reports one, else the first logged
//!   `time[i]` with `torso_x[i] ≥ track_length` (track from world x = 0), else `None`;
//! - mean forward velocity = mean of `forward_velocity`; lateral deviation = mean |y|;
//!   vertical deviation = mean z-error and mean |z-error|;
//! - per actuator j: mean |τ_j| and mean |P_j| with P = τ·ω; "overall" = mean of the
//!   per-actuator means (all actuators log every step, so it is also the mean over all entries);
//! - knee torque asymmetry = |T_L − T_R| / ((T_L + T_R)/2) with T = mean |τ| of each knee
//!   (the Robinson et al. 1987 symmetry index: 0 symmetric, 2 at most; 0 when both are 0);
//! - distance = last x − first x; duration = last `time` (time counts from reset, t = 0);
//! - gait cycle ([`GaitCycle`], when the trace has the forces of two feet, left then right):
//!   a foot is in contact when its force exceeds [`GaitThresholds::contact_force`]; phases,
//!   touchdowns, alternation, cadence, stride times and the gait class as in
//!   [`gait_phases`](crate::gait_phases) and [`classify_gait`](crate::classify_gait), with the
//!   sample period `duration / steps`; step lengths and foot speed from `foot_positions` when
//!   logged (foot speed = mean over the feet of |p_last − p_first| / duration, horizontal);
//! - per actuated joint ([`JointMotion`], when `joint_angles` are logged): range of motion
//!   (5th–95th percentile) and time within [`GaitThresholds::limit_margin`] of a limit from
//!   `joint_limits`;
//! - torso pitch ([`TorsoPitch`], when `torso_pitch` is logged): its mean and 5th and 95th
//!   percentiles, forward lean positive.

use serde::{Deserialize, Serialize};

use crate::cycle::{gait_phases, step_lengths, GaitCycle, GaitThresholds};
use crate::error::{check_finite, MetricsError, Result};
use crate::motion::{joint_motion, torso_pitch, JointMotion, TorsoPitch};

/// Per-step log of one rollout. Every per-step `Vec` has one entry per logged step; rows of
/// `torques`, `powers` and `foot_forces` have one entry per actuator / foot, in the order of
/// `actuator_names` / `foot_names` (the environment's actuator order is left_hip, left_knee,
/// left_ankle, right_hip, right_knee, right_ankle, but nothing here relies on it).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct GaitTrace {
    /// Actuator (actuated joint) names, one per column of `torques` and `powers`.
    pub actuator_names: Vec<String>,
    /// Foot names, one per column of `foot_forces` (may be empty, then `foot_forces` too).
    pub foot_names: Vec<String>,
    /// Simulated time after each step (s), counted from reset.
    pub time: Vec<f64>,
    /// Torso x along the track (m).
    pub torso_x: Vec<f64>,
    /// Torso lateral offset from the track centre line (m).
    pub torso_y: Vec<f64>,
    /// Torso height minus its standing height (m).
    pub torso_z_error: Vec<f64>,
    /// Torso forward velocity (m/s).
    pub forward_velocity: Vec<f64>,
    /// Applied joint torques (N·m), `[step][actuator]`.
    pub torques: Vec<Vec<f64>>,
    /// Joint mechanical power τ·ω (W), `[step][actuator]`.
    pub powers: Vec<Vec<f64>>,
    /// Foot contact normal forces, `[step][foot]` (units as the environment logs them).
    pub foot_forces: Vec<Vec<f64>>,
    /// Whether the episode ended in a fall (terminated).
    pub fell: bool,
    /// Time at which the environment declared success (torso past the track end), if it did.
    pub success_time: Option<f64>,
    /// Actuated joint angles (rad), `[step][actuator]`; empty when not logged (then no
    /// [`JointMotion`]).
    #[serde(default)]
    pub joint_angles: Vec<Vec<f64>>,
    /// Position limits `[lower, upper]` (rad) per actuator, `None` for a joint without; empty
    /// when unknown (then no time at a limit).
    #[serde(default)]
    pub joint_limits: Vec<Option<[f64; 2]>>,
    /// Horizontal position `[x, y]` (m, world) of each foot, `[step][foot]`; empty when not
    /// logged (then no step lengths and no foot speed).
    #[serde(default)]
    pub foot_positions: Vec<Vec<[f64; 2]>>,
    /// Torso pitch (rad, forward lean positive: [`crate::pitch_of`] its orientation) per
    /// step; empty when not logged (then no [`GaitMetrics::torso_pitch`]).
    #[serde(default)]
    pub torso_pitch: Vec<f64>,
}

/// One step to append to a [`GaitTrace`] with [`GaitTrace::push`].
#[derive(Debug, Clone, Copy)]
pub struct GaitStep<'a> {
    /// Simulated time after the step (s).
    pub time: f64,
    /// Torso x (m).
    pub torso_x: f64,
    /// Torso lateral offset y (m).
    pub torso_y: f64,
    /// Torso height error (m).
    pub torso_z_error: f64,
    /// Forward velocity (m/s).
    pub forward_velocity: f64,
    /// Torque per actuator (N·m).
    pub torques: &'a [f64],
    /// Power τ·ω per actuator (W).
    pub powers: &'a [f64],
    /// Contact normal force per foot.
    pub foot_forces: &'a [f64],
    /// Actuated joint angles (rad); empty when not logged.
    pub joint_angles: &'a [f64],
    /// Horizontal position `[x, y]` of each foot (m); empty when not logged.
    pub foot_positions: &'a [[f64; 2]],
    /// Torso pitch (rad, forward lean positive); `None` when not logged.
    pub torso_pitch: Option<f64>,
}

impl GaitTrace {
    /// An empty trace for the given actuator and foot names.
    pub fn new(actuator_names: Vec<String>, foot_names: Vec<String>) -> Self {
        Self {
            actuator_names,
            foot_names,
            ..Self::default()
        }
    }

    /// Appends one step (lengths are checked by [`gait_metrics`], not here). Empty
    /// `joint_angles` / `foot_positions` and a missing `torso_pitch` are not appended, so a
    /// trace that never logs them keeps them empty.
    pub fn push(&mut self, step: &GaitStep<'_>) {
        self.time.push(step.time);
        self.torso_x.push(step.torso_x);
        self.torso_y.push(step.torso_y);
        self.torso_z_error.push(step.torso_z_error);
        self.forward_velocity.push(step.forward_velocity);
        self.torques.push(step.torques.to_vec());
        self.powers.push(step.powers.to_vec());
        self.foot_forces.push(step.foot_forces.to_vec());
        if !step.joint_angles.is_empty() {
            self.joint_angles.push(step.joint_angles.to_vec());
        }
        if !step.foot_positions.is_empty() {
            self.foot_positions.push(step.foot_positions.to_vec());
        }
        if let Some(pitch) = step.torso_pitch {
            self.torso_pitch.push(pitch);
        }
    }

    /// Number of logged steps.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether no step was logged.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
}

/// Options of [`gait_metrics`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitOptions {
    /// Track length (m) for the track time. Default 50 (the paper's 50 m track).
    pub track_length: f64,
    /// Actuator name of the left knee. Default `"left_knee"`.
    pub left_knee: String,
    /// Actuator name of the right knee. Default `"right_knee"`.
    pub right_knee: String,
    /// Thresholds of the gait-cycle metrics, the gait class and the time at a limit.
    #[serde(default)]
    pub thresholds: GaitThresholds,
}

impl Default for GaitOptions {
    fn default() -> Self {
        Self {
            track_length: 50.0,
            left_knee: "left_knee".into(),
            right_knee: "right_knee".into(),
            thresholds: GaitThresholds::default(),
        }
    }
}

/// Behavioural summary of one rollout (one object of `eval.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitMetrics {
    /// Track length used for `track_time` (m).
    pub track_length: f64,
    /// Time to pass the end of the track (s); `None` if it never did.
    pub track_time: Option<f64>,
    /// Mean forward velocity (m/s).
    pub mean_forward_velocity: f64,
    /// Lateral deviation: mean |y| (m).
    pub mean_abs_lateral: f64,
    /// Mean vertical deviation: mean z-error (m), signed (negative = crouched).
    pub mean_vertical: f64,
    /// Mean |z-error| (m).
    pub mean_abs_vertical: f64,
    /// Actuator names, the order of the per-actuator vectors below.
    pub actuator_names: Vec<String>,
    /// Mean |τ| per actuator (N·m).
    pub mean_abs_torque: Vec<f64>,
    /// Mean |τ·ω| per actuator (W).
    pub mean_abs_power: Vec<f64>,
    /// Mean of `mean_abs_torque` over actuators (N·m).
    pub mean_abs_torque_overall: f64,
    /// Mean of `mean_abs_power` over actuators (W).
    pub mean_abs_power_overall: f64,
    /// Knee symmetry index |T_L − T_R| / ((T_L + T_R)/2), T = mean |τ| of a knee; 0 = symmetric.
    pub knee_torque_asymmetry: f64,
    /// Foot names, the order of `mean_foot_force`.
    pub foot_names: Vec<String>,
    /// Mean contact normal force per foot.
    pub mean_foot_force: Vec<f64>,
    /// Last x − first x (m).
    pub distance: f64,
    /// Whether the rollout ended in a fall.
    pub fell: bool,
    /// Number of logged steps.
    pub steps: usize,
    /// Last logged time (s since reset).
    pub duration: f64,
    /// Gait-cycle metrics and the gait class; `None` without the contact forces of two feet.
    #[serde(default)]
    pub cycle: Option<GaitCycle>,
    /// Range of motion and time at a limit per actuated joint; empty without joint angles.
    #[serde(default)]
    pub joints: Vec<JointMotion>,
    /// How far the torso leaned; `None` without a logged torso pitch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torso_pitch: Option<TorsoPitch>,
}

fn check_len(len: usize, expected: usize, what: &str) -> Result<()> {
    if len != expected {
        return Err(MetricsError::LengthMismatch {
            what: what.into(),
            found: len,
            expected,
        });
    }
    Ok(())
}

fn mean(values: impl Iterator<Item = f64>, n: usize) -> f64 {
    values.sum::<f64>() / n as f64
}

/// Checks a `[step][column]` table and returns the mean |value| of each column.
fn column_abs_means(rows: &[Vec<f64>], n: usize, width: usize, what: &str) -> Result<Vec<f64>> {
    check_len(rows.len(), n, what)?;
    for (step, row) in rows.iter().enumerate() {
        let name = format!("{what}[{step}]");
        check_len(row.len(), width, &name)?;
        check_finite(row, &name)?;
    }
    Ok((0..width)
        .map(|j| mean(rows.iter().map(|r| r[j].abs()), n))
        .collect())
}

fn actuator_index(names: &[String], name: &str) -> Result<usize> {
    names
        .iter()
        .position(|n| n == name)
        .ok_or_else(|| MetricsError::UnknownActuator {
            name: name.into(),
            available: names.to_vec(),
        })
}

/// Computes the [`GaitMetrics`] of a rollout (formulas in the module docs).
///
/// Errors: an empty trace, per-step vectors of different lengths, rows of the wrong width,
/// NaN/inf anywhere, an unknown knee name, a non-positive track length, invalid thresholds,
/// or joint limits / foot positions that do not match the actuators / feet.
pub fn gait_metrics(trace: &GaitTrace, options: &GaitOptions) -> Result<GaitMetrics> {
    options.thresholds.validate()?;
    if !(options.track_length.is_finite() && options.track_length > 0.0) {
        return Err(MetricsError::InvalidParameter {
            what: "track_length".into(),
            value: options.track_length.to_string(),
            why: "must be finite and > 0".into(),
        });
    }
    let n = trace.time.len();
    if n == 0 {
        return Err(MetricsError::Empty {
            what: "gait trace (no steps)".into(),
        });
    }
    for (values, what) in [
        (&trace.time, "time"),
        (&trace.torso_x, "torso_x"),
        (&trace.torso_y, "torso_y"),
        (&trace.torso_z_error, "torso_z_error"),
        (&trace.forward_velocity, "forward_velocity"),
    ] {
        check_len(values.len(), n, what)?;
        check_finite(values, what)?;
    }
    if let Some(t) = trace.success_time {
        check_finite(&[t], "success_time")?;
    }
    let n_act = trace.actuator_names.len();
    let left = actuator_index(&trace.actuator_names, &options.left_knee)?;
    let right = actuator_index(&trace.actuator_names, &options.right_knee)?;
    let mean_abs_torque = column_abs_means(&trace.torques, n, n_act, "torques")?;
    let mean_abs_power = column_abs_means(&trace.powers, n, n_act, "powers")?;
    let mean_foot_force = if trace.foot_names.is_empty() && trace.foot_forces.is_empty() {
        Vec::new()
    } else {
        let n_feet = trace.foot_names.len();
        check_len(trace.foot_forces.len(), n, "foot_forces")?;
        for (step, row) in trace.foot_forces.iter().enumerate() {
            let name = format!("foot_forces[{step}]");
            check_len(row.len(), n_feet, &name)?;
            check_finite(row, &name)?;
        }
        (0..n_feet)
            .map(|j| mean(trace.foot_forces.iter().map(|r| r[j]), n))
            .collect()
    };

    let track_time = trace.success_time.or_else(|| {
        trace
            .torso_x
            .iter()
            .position(|&x| x >= options.track_length)
            .map(|i| trace.time[i])
    });
    let duration = trace.time[n - 1];
    let cycle = gait_cycle(trace, options, duration)?;
    let joints = joint_motions(trace, &options.thresholds)?;
    let torso_pitch = if trace.torso_pitch.is_empty() {
        None
    } else {
        check_len(trace.torso_pitch.len(), n, "torso_pitch")?;
        Some(torso_pitch(&trace.torso_pitch)?)
    };
    let (tl, tr) = (mean_abs_torque[left], mean_abs_torque[right]);
    let knee_torque_asymmetry = if tl + tr == 0.0 {
        0.0
    } else {
        (tl - tr).abs() / (0.5 * (tl + tr))
    };
    Ok(GaitMetrics {
        track_length: options.track_length,
        track_time,
        mean_forward_velocity: mean(trace.forward_velocity.iter().copied(), n),
        mean_abs_lateral: mean(trace.torso_y.iter().map(|y| y.abs()), n),
        mean_vertical: mean(trace.torso_z_error.iter().copied(), n),
        mean_abs_vertical: mean(trace.torso_z_error.iter().map(|z| z.abs()), n),
        actuator_names: trace.actuator_names.clone(),
        mean_abs_torque_overall: mean(mean_abs_torque.iter().copied(), n_act),
        mean_abs_power_overall: mean(mean_abs_power.iter().copied(), n_act),
        mean_abs_torque,
        mean_abs_power,
        knee_torque_asymmetry,
        foot_names: trace.foot_names.clone(),
        mean_foot_force,
        distance: trace.torso_x[n - 1] - trace.torso_x[0],
        fell: trace.fell,
        steps: n,
        duration,
        cycle,
        joints,
        torso_pitch,
    })
}

/// The gait cycle of a trace with two feet (forces already checked by the caller).
fn gait_cycle(
    trace: &GaitTrace,
    options: &GaitOptions,
    duration: f64,
) -> Result<Option<GaitCycle>> {
    if trace.foot_names.len() != 2 || trace.foot_forces.is_empty() {
        return Ok(None);
    }
    let n = trace.time.len();
    let t = &options.thresholds;
    let dt = duration / n as f64;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(MetricsError::InvalidParameter {
            what: "time".into(),
            value: duration.to_string(),
            why: "the last time must be > 0 (time counts from reset) for the gait cycle".into(),
        });
    }
    let contact = |foot: usize| -> Vec<bool> {
        trace
            .foot_forces
            .iter()
            .map(|r| r[foot] > t.contact_force)
            .collect()
    };
    let (left, right) = (contact(0), contact(1));
    let phases = gait_phases(&left, &right, dt, t.sync_window)?;
    let (steps, foot_speed) = if trace.foot_positions.is_empty() {
        (Vec::new(), None)
    } else {
        check_len(trace.foot_positions.len(), n, "foot_positions")?;
        for (step, row) in trace.foot_positions.iter().enumerate() {
            let name = format!("foot_positions[{step}]");
            check_len(row.len(), 2, &name)?;
            check_finite(&[row[0][0], row[0][1], row[1][0], row[1][1]], &name)?;
        }
        let x: Vec<[f64; 2]> = trace
            .foot_positions
            .iter()
            .map(|r| [r[0][0], r[1][0]])
            .collect();
        let steps = step_lengths(&left, &right, &x, dt, t.sync_window)?;
        let (a, b) = (&trace.foot_positions[0], &trace.foot_positions[n - 1]);
        let travel = |f: usize| (b[f][0] - a[f][0]).hypot(b[f][1] - a[f][1]);
        (steps, Some(0.5 * (travel(0) + travel(1)) / duration))
    };
    Ok(Some(GaitCycle::from_parts(
        &phases, &steps, foot_speed, trace.fell, t,
    )))
}

/// Range of motion and time at a limit of every actuator (empty without joint angles).
fn joint_motions(trace: &GaitTrace, t: &GaitThresholds) -> Result<Vec<JointMotion>> {
    if trace.joint_angles.is_empty() {
        return Ok(Vec::new());
    }
    let n_act = trace.actuator_names.len();
    check_len(trace.joint_angles.len(), trace.time.len(), "joint_angles")?;
    for (step, row) in trace.joint_angles.iter().enumerate() {
        check_len(row.len(), n_act, &format!("joint_angles[{step}]"))?;
    }
    if !trace.joint_limits.is_empty() {
        check_len(trace.joint_limits.len(), n_act, "joint_limits")?;
    }
    (0..n_act)
        .map(|j| {
            let angles: Vec<f64> = trace.joint_angles.iter().map(|r| r[j]).collect();
            let limits = trace.joint_limits.get(j).copied().flatten();
            joint_motion(&trace.actuator_names[j], &angles, limits, t.limit_margin)
        })
        .collect()
}
