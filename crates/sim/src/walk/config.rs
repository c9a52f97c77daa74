//! The walking task's settings ([`WalkConfig`] and its parts): every field documents its
//! default and where it comes from; [`WalkConfig::validate`] names the field at fault.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::SimError;
use crate::model::RobotModel;
use crate::sim::PhysicsConfig;

/// Reward coefficients of paper eq. 12.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RewardConfig {
    /// Weight of the forward velocity `vx`. Default 1 (eq. 12).
    pub forward: f32,
    /// Weight of the lateral penalty `y²`. Default 5 (eq. 12).
    pub lateral: f32,
    /// Weight of the vertical penalty `z²`. Default 25 (eq. 12).
    pub height: f32,
    /// Weight of the power penalty `P`. Default 0.0005 (eq. 12).
    pub power: f32,
    /// Constant reward per step for staying up, not paid on a step that ends in a fall or
    /// off course. Default 0.025 (eq. 12).
    pub alive: f32,
    /// Weight of the squared-action penalty `Σ aᵢ²` over the actuated joints (the clamped
    /// action of the step). Default 0 (the paper has none; MATLAB's walking-robot examples
    /// use 0.02).
    pub action_sq: f32,
    /// Weight of the squared-torque penalty `Σ (τᵢ/τmaxᵢ)²`, τᵢ the torque the actuator
    /// delivered (mean over the control period's physics steps, servo torque included) and
    /// τmaxᵢ its effort limit. Unlike the power term it prices holding a load still. Default
    /// 0 (the paper has none).
    pub torque_sq: f32,
    /// Weight of the squared-tilt penalty `tilt²`, the angle (rad) between the torso's z axis
    /// and the vertical: prices a leaning trunk (every walk of `walker` leans back 5–24°,
    /// `results/gait`; screened at 0.5 and 2 in `results/upright`, it slowed learning and
    /// left the lean as it was). Default 0 (the paper has none).
    #[serde(skip_serializing_if = "crate::sim::is_zero")]
    pub tilt_sq: f32,
    /// Pay the forward term only while the torso is upright and tall (DeepMind Control's
    /// walker multiplies its move reward by its stand reward): when set, `w_v·vx` is replaced
    /// by 0 on steps where the torso tilts more than `max_tilt` or is lower than
    /// `max_height_drop` under its standing height. Default none (eq. 12 pays it always).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forward_gate: Option<UprightGate>,
    /// Pay the forward term for speed up to this many m/s: `w_v·min(vx, cap)`. On a track
    /// that goes on past its line (`end_at_finish = false`) an uncapped forward term pays
    /// every extra m/s, and the kept policies traded their walk for faster hops and
    /// shuffles; capped, a walk at the cap earns all the forward reward there is. Default
    /// none (eq. 12 pays any speed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forward_cap: Option<f32>,
    /// With [`RewardConfig::forward_cap`] `c`, the price `k` of each m/s above it: `forward`
    /// pays `w_v·(min(vx, c) − k·max(vx − c, 0))`, so with `k > 0` the most it pays is at the
    /// cap and speed beyond costs (a walk sped up by a descent is paid to brake). Default 0
    /// (speed above the cap neither pays nor costs).
    #[serde(skip_serializing_if = "crate::sim::is_zero")]
    pub forward_over_cap: f32,
}

impl Default for RewardConfig {
    fn default() -> Self {
        Self {
            forward: 1.0,
            lateral: 5.0,
            height: 25.0,
            power: 0.0005,
            alive: 0.025,
            action_sq: 0.0,
            torque_sq: 0.0,
            tilt_sq: 0.0,
            forward_gate: None,
            forward_cap: None,
            forward_over_cap: 0.0,
        }
    }
}

/// When the torso counts as upright and tall ([`RewardConfig::forward_gate`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UprightGate {
    /// Largest tilt of the torso's z axis from vertical, rad. Default 0.35 (20°, our choice:
    /// the paper's gaits stay within a few degrees).
    pub max_tilt: f32,
    /// Largest drop of the torso origin below its standing height, m. Default 0.15 (our
    /// choice: half the fall threshold).
    pub max_height_drop: f32,
}

impl Default for UprightGate {
    fn default() -> Self {
        Self {
            max_tilt: 20.0f32.to_radians(),
            max_height_drop: 0.15,
        }
    }
}

/// When an episode ends in a fall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FallConfig {
    /// Fall when the torso origin is more than this below its standing height, m. Default 0.30
    /// (our choice: the paper's walking gaits stay within ±0.12 m, a deep squat does not).
    pub max_height_drop: f32,
    /// Fall when the torso's z axis is tilted more than this from vertical, rad. Default
    /// π/4 (45°, our choice, as MATLAB's walking-robot examples stop at 45° roll/pitch).
    pub max_tilt: f32,
    /// End the episode off course when the torso origin is more than this from the track
    /// centre line (`|y|`), m. Default none (the paper has no such termination).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_lateral: Option<f32>,
    /// End the episode off course when the torso's heading (yaw, the rotation of its x axis
    /// about world z) is more than this from the track direction, rad. Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_yaw: Option<f32>,
}

impl Default for FallConfig {
    fn default() -> Self {
        Self {
            max_height_drop: 0.30,
            max_tilt: std::f32::consts::FRAC_PI_4,
            max_lateral: None,
            max_yaw: None,
        }
    }
}

/// The pose a reset starts from, before [`InitNoise`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ResetPose {
    /// [`WalkConfig::standing_pose`].
    Standing,
    /// The standing pose lowered by [`ResetConfig::crouch`] (see there).
    Crouch,
    /// The standing pose with the legs apart by [`ResetConfig::split`] (see there).
    Split,
    /// One of the three above, drawn uniformly from the reset seed.
    Mixed,
}

/// Where episodes start ([`WalkConfig::reset`]).
///
/// `crouch` and `split` read the actuated joints as (hip, knee, ankle) of each leg in turn,
/// as the default `actuated_joints` list them, and keep each foot at the standing pose's
/// angle to the torso (hip + knee + ankle unchanged), so the feet start flat.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ResetConfig {
    /// The pose. Default `standing` (SPEC §2: "standing pose with small seeded
    /// perturbations").
    pub pose: ResetPose,
    /// `crouch` depth `c`, rad: hips −c, knees +2c, ankles −c from the standing pose (the
    /// thighs and shanks tilt by `c` each, the torso stays upright). Default 10° (0.1745),
    /// which the ankles' −20° limit allows from the standing −8°.
    pub crouch: f32,
    /// `split` half-angle `s`, rad: the leading leg's hip −s and ankle +s, the trailing
    /// leg's hip +s and ankle −s; which leg leads is drawn from the reset seed. The feet stay
    /// flat but not level: the robot is placed with its lowest point on the ground and the
    /// other foot starts up to about a centimetre above it. Default 10° (0.1745).
    pub split: f32,
}

impl Default for ResetConfig {
    fn default() -> Self {
        Self {
            pose: ResetPose::Standing,
            crouch: 10.0f32.to_radians(),
            split: 10.0f32.to_radians(),
        }
    }
}

/// How an action drives the actuated joints ([`WalkConfig::action`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ActionMode {
    /// `τ = a·τmax`, held for the control period (the paper's).
    Torque,
    /// `a` sets a joint angle target, tracked by an in-solver position servo (module docs,
    /// "Action").
    Target,
}

/// What the torso orientation of the observation is measured against
/// ([`WalkConfig::orientation_frame`]). The two differ only on a slope
/// ([`PhysicsConfig::slope`](crate::PhysicsConfig::slope), `perturb.slope_range`), which tilts
/// gravity over flat ground.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OrientationFrame {
    /// The ground's frame (x along the track, z normal to the ground): on a slope, a robot
    /// upright against gravity reads as leaning by the slope's angle, and one upright against
    /// the ground as upright.
    #[default]
    Ground,
    /// Gravity's frame, as an IMU on a real slope reports it: the ground's frame turned by the
    /// slope about the lateral axis, so a robot upright against gravity reads as upright.
    Gravity,
}

impl OrientationFrame {
    /// Whether this is the default, [`OrientationFrame::Ground`].
    pub fn is_ground(&self) -> bool {
        *self == Self::Ground
    }
}

/// The `target` action mode's servos ([`WalkConfig::target`]): their gains and the span of
/// the targets the actions address.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TargetServo {
    /// Stiffness `kp`, N·m/rad, every actuated joint. Default 1500 (module docs, "Action":
    /// above the ≈ 620 N·m/rad the ankles need to hold the 70 kg body upright, and full
    /// effort at 5.7° of error).
    pub stiffness: f32,
    /// Damping `kd`, N·m·s/rad. Default 60 (module docs, "Action").
    pub damping: f32,
    /// When set, the targets span the standing angle ± this many radians (`q* = q_stand +
    /// a·range`, clamped to the joint's limits) instead of reaching the limits at ±1: a
    /// residual around standing, so an untrained policy's actions do not throw the legs
    /// across their whole range. Default none (±1 reach the limits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range: Option<f32>,
    /// Per actuated joint (by name), a span in radians that replaces `range` for that joint:
    /// `q* = q_stand + a·span`, clamped to its limits. The walking recipe's `range = 0.3`
    /// stops the knees at 27° (10° standing + 17°); `{ left_knee = 0.6, right_knee = 0.6 }`
    /// lets them bend to 44°. Default none.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub joint_range: BTreeMap<String, f32>,
}

impl Default for TargetServo {
    fn default() -> Self {
        Self {
            stiffness: 1500.0,
            damping: 60.0,
            range: None,
            joint_range: BTreeMap::new(),
        }
    }
}

/// A gait clock ([`WalkConfig::gait_clock`]): a phase φ that advances at one cycle per
/// `period` seconds, given to the policy as (sin 2πφ, cos 2πφ) at the end of the observation,
/// and a reward for foot contacts that follow it (the periodic reward composition of
/// Siekmann et al., "Sim-to-real learning of all common bipedal gaits via periodic reward
/// composition", ICRA 2021, reduced to contact).
///
/// The left foot is meant to be down for φ ∈ [0, duty), the right foot for (φ + ½) mod 1 ∈
/// [0, duty): with `duty` > ½ the feet alternate with two double-support phases of
/// `duty − ½` each. Each step pays `reward · (m_L + m_R)/2`, with `m` = +1 for a foot whose
/// contact (normal force above `contact_force`) matches its phase and −1 otherwise. The
/// phase starts at a value drawn from the reset seed, so the policy meets every phase at
/// reset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaitClock {
    /// Seconds per gait cycle (stride). Default 1.0 (adult walking at 1.2–1.4 m/s: cadence
    /// ≈ 110 steps/min, a stride of ≈ 1.1 s; Perry & Burnfield, *Gait Analysis*).
    pub period: f32,
    /// Share of the cycle each foot is meant to be down. Default 0.6 (stance 60 % of the
    /// cycle at normal walking speed, double support 2 × 10 %; Perry & Burnfield).
    pub duty: f32,
    /// Reward per step for contacts that follow the clock. Default 0.5 (esrl's choice: of the
    /// order of the forward term at a walking speed).
    pub reward: f32,
    /// Normal force above which a foot counts as down, N. Default 10 (the gait metrics'
    /// threshold, `esrl_metrics::GaitThresholds`).
    pub contact_force: f32,
    /// Penalty for each contact or air phase of a foot that ends shorter than `min_phase`:
    /// foot chatter, a foot lifting off for a control step inside its stance or tapping the
    /// ground inside its swing, which the gait metrics count as extra steps. Paid at the
    /// step that ends the phase, as the term `chatter`. Default 0 (off).
    pub chatter: f32,
    /// The shortest contact or air phase that is not chatter, s. Default 0.1 (4 control
    /// steps of 25 ms; the default clock's swing lasts 0.4 s).
    pub min_phase: f32,
    /// Reward per step for swing-foot clearance: each foot in its swing window earns
    /// `clearance · min(h / clearance_height, 1) / 2`, `h` its link origin's height above
    /// where it is in the standing pose (0 below), paid as the term `clearance`. Against
    /// shuffles, whose feet tap and slide instead of stepping. Default 0 (off).
    #[serde(skip_serializing_if = "crate::sim::is_zero")]
    pub clearance: f32,
    /// The swing-foot height that earns the whole clearance reward, m. Default 0.05 (a
    /// human's foot rises 5–15 cm in mid-swing; Winter, *Biomechanics and Motor Control of
    /// Human Movement*, 4th ed.).
    #[serde(skip_serializing_if = "is_default_clearance_height")]
    pub clearance_height: f32,
}

fn is_default_clearance_height(v: &f32) -> bool {
    *v == 0.05
}

impl Default for GaitClock {
    fn default() -> Self {
        Self {
            period: 1.0,
            duty: 0.6,
            reward: 0.5,
            contact_force: 10.0,
            chatter: 0.0,
            min_phase: 0.1,
            clearance: 0.0,
            clearance_height: 0.05,
        }
    }
}

impl GaitClock {
    /// Whether each foot (left, right) is meant to be down at phase `phi` ∈ [0, 1).
    pub fn stance(&self, phi: f32) -> [bool; 2] {
        let right = (phi + 0.5).rem_euclid(1.0);
        [phi.rem_euclid(1.0) < self.duty, right < self.duty]
    }

    /// The control steps below which a contact or air phase is chatter, for control period
    /// `dt`: `min_phase / dt`, rounded.
    pub fn min_phase_steps(&self, dt: f32) -> u32 {
        (self.min_phase / dt).round() as u32
    }

    /// The clearance reward (see [`GaitClock::clearance`]) for feet whose link origins are
    /// `height` m above their standing height at phase `phi`.
    pub fn clearance_reward(&self, phi: f32, height: [f32; 2]) -> f32 {
        let want = self.stance(phi);
        let lift: f32 = (0..2)
            .filter(|&i| !want[i])
            .map(|i| (height[i] / self.clearance_height).clamp(0.0, 1.0))
            .sum();
        self.clearance * lift / 2.0
    }

    /// The clock's reward for the feet's normal forces at phase `phi`.
    pub fn contact_reward(&self, phi: f32, foot_force: [f32; 2]) -> f32 {
        let want = self.stance(phi);
        let matched: f32 = (0..2)
            .map(|i| {
                if (foot_force[i] > self.contact_force) == want[i] {
                    1.0
                } else {
                    -1.0
                }
            })
            .sum();
        self.reward * matched / 2.0
    }
}

/// Seeded perturbation of the standing pose at reset (uniform, ± the given half-widths).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InitNoise {
    /// Joint angle half-width, rad. Default 0.01 (Gymnasium Humanoid-v5 `reset_noise_scale`).
    pub joint_angle: f32,
    /// Joint velocity half-width, rad/s. Default 0.01 (Gymnasium Humanoid-v5).
    pub joint_velocity: f32,
}

impl Default for InitNoise {
    fn default() -> Self {
        Self {
            joint_angle: 0.01,
            joint_velocity: 0.01,
        }
    }
}

/// Which way a push kicks ([`Perturb::push_direction`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PushDirection {
    /// Forward or backward (±x), the sign drawn per push.
    Sagittal,
    /// Left or right (±y), the sign drawn per push.
    Lateral,
    /// Any horizontal direction, the angle drawn per push.
    Any,
}

/// Disturbances for robustness tests (`[walk.perturb]`): pushes, motor strength,
/// observation noise and action delay; with the physics' `friction`, `mass_scale` and
/// `slope` they make the disturbance set of `esrl eval --perturb`. Every default leaves
/// the task as it is. The draws (push times and directions, observation noise) come from a
/// ChaCha8 stream of the reset seed of its own, so a disturbed episode is as repeatable as
/// an undisturbed one and draws nothing from the reset's own stream.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Perturb {
    /// Speed of each push, m/s: a horizontal velocity change of the whole robot (the root's
    /// velocity changes by it with the joint velocities held, so every link's does; an
    /// impulse of `mass · push_speed` on the body), the way legged-robot training kicks its
    /// bases (legged_gym's `push_robots`). Default 0 (no pushes).
    pub push_speed: f32,
    /// Mean seconds between pushes: the k-th push comes at `k·push_every` s plus a jitter of
    /// up to ±¼ of it drawn per push. Default 5.
    pub push_every: f32,
    /// Which way pushes kick. Default `any`.
    pub push_direction: PushDirection,
    /// Motor strength: every actuated joint's effort limit (torque at action ±1, the servo's
    /// torque bound) times this. Default 1.
    pub strength: f32,
    /// Standard deviation of Gaussian noise added to every observation entry (after the
    /// scaling of `normalize_obs`, so in units of order one). Default 0.
    pub obs_noise: f32,
    /// Control steps between an action and its effect: the joints get the action of this
    /// many steps before (zero before the first). Default 0.
    pub action_delay: u32,
    /// Domain randomisation for training: per episode, the ground friction coefficient drawn
    /// uniformly from `[lo, hi]` (replacing `physics.friction`). Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_range: Option<[f32; 2]>,
    /// Per episode, `physics.mass_scale` drawn uniformly from `[lo, hi]`. Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_range: Option<[f32; 2]>,
    /// Per episode, `strength` drawn uniformly from `[lo, hi]`. Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strength_range: Option<[f32; 2]>,
    /// Per episode, `physics.contact_frequency` (Hz) drawn uniformly from `[lo, hi]`: softer
    /// and stiffer ground contact. Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_frequency_range: Option<[f32; 2]>,
    /// Per episode, the ground slope in degrees drawn uniformly from `[lo, hi]` (positive
    /// uphill along the track; replacing `physics.slope`, which is in radians): gravity
    /// tilted about the lateral axis, as `esrl eval --perturb slope=DEG` does. Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slope_range: Option<[f32; 2]>,
}

impl Default for Perturb {
    fn default() -> Self {
        Self {
            push_speed: 0.0,
            push_every: 5.0,
            push_direction: PushDirection::Any,
            strength: 1.0,
            obs_noise: 0.0,
            action_delay: 0,
            friction_range: None,
            mass_range: None,
            strength_range: None,
            contact_frequency_range: None,
            slope_range: None,
        }
    }
}

impl Perturb {
    /// Whether every setting leaves the task undisturbed.
    pub fn is_none(&self) -> bool {
        self.push_speed == 0.0
            && self.strength == 1.0
            && self.obs_noise == 0.0
            && self.action_delay == 0
            && self.friction_range.is_none()
            && self.mass_range.is_none()
            && self.strength_range.is_none()
            && self.contact_frequency_range.is_none()
            && self.slope_range.is_none()
    }

    fn validate(&self) -> Result<(), SimError> {
        let check = |field: &str, v: f32, ok: bool, why: &str| {
            if v.is_finite() && ok {
                Ok(())
            } else {
                Err(config_err(&format!("perturb.{field}"), v, why))
            }
        };
        check(
            "push_speed",
            self.push_speed,
            (0.0..=20.0).contains(&self.push_speed),
            "must be in [0, 20] m/s",
        )?;
        check(
            "push_every",
            self.push_every,
            self.push_every >= 0.1,
            "must be ≥ 0.1 s",
        )?;
        check(
            "strength",
            self.strength,
            self.strength > 0.0 && self.strength <= 10.0,
            "must be in (0, 10]",
        )?;
        check(
            "obs_noise",
            self.obs_noise,
            (0.0..=10.0).contains(&self.obs_noise),
            "must be in [0, 10]",
        )?;
        for (field, range, lo, hi) in [
            ("friction_range", self.friction_range, 0.0, 10.0),
            ("mass_range", self.mass_range, 0.01, 100.0),
            ("strength_range", self.strength_range, 0.01, 10.0),
            (
                "contact_frequency_range",
                self.contact_frequency_range,
                1.0,
                10_000.0,
            ),
            ("slope_range", self.slope_range, -30.0, 30.0),
        ] {
            if let Some([a, b]) = range {
                if !(a.is_finite() && b.is_finite() && lo <= a && a <= b && b <= hi) {
                    return Err(config_err(
                        &format!("perturb.{field}"),
                        format!("[{a}, {b}]"),
                        "must be [lo, hi] with lo ≤ hi inside the field's bounds",
                    ));
                }
            }
        }
        if self.action_delay > 100 {
            return Err(config_err(
                "perturb.action_delay",
                self.action_delay,
                "must be at most 100 control steps",
            ));
        }
        Ok(())
    }
}

/// Configuration of [`WalkEnv`](super::WalkEnv). Every field has a default; TOML files may give any subset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WalkConfig {
    /// URDF file to load instead of the embedded humanoid. Default none (embedded
    /// `assets/humanoid.urdf`, SPEC §1).
    pub urdf: Option<PathBuf>,
    /// Control period Ts, s. Default 0.025 (paper §5).
    pub control_period: f32,
    /// Episode length Tf, s; truncation after `Tf / Ts` steps. Default 60 (paper §5).
    pub episode_seconds: f32,
    /// Track length, m: success when the torso passes `x = track_length`. Default 50 (paper
    /// Fig. 4).
    pub track_length: f32,
    /// Whether success ends the episode (terminal, no bootstrapping). Default true. With
    /// `false` the robot walks on past the line until the episode's time is up (the track
    /// time is still taken where it crosses): over a track that ends the episode the forward
    /// term sums to the same (length / control period) at any speed while the per-step terms
    /// (alive, gait clock) pay for time spent, so the most rewarding policy reaches the line
    /// just as the episode ends; on a track that goes on, speed pays.
    pub end_at_finish: bool,
    /// Physics settings (step, solver, contact).
    pub physics: PhysicsConfig,
    /// Reward coefficients (paper eq. 12).
    pub reward: RewardConfig,
    /// Fall thresholds.
    pub fall: FallConfig,
    /// Reset noise.
    pub init_noise: InitNoise,
    /// Reset pose.
    pub reset: ResetConfig,
    /// How actions drive the joints: `torque` or `target`. Default `torque` (paper §5).
    pub action: ActionMode,
    /// The servos of the `target` action mode: gains and target span.
    pub target: TargetServo,
    /// Optional gait clock: phase features at the end of the observation and a reward for
    /// contacts that follow them ([`GaitClock`]). Default none (the paper's observation and
    /// reward).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gait_clock: Option<GaitClock>,
    /// Multiply the observation by the fixed per-quantity factors of the module docs
    /// ([`WalkEnv::obs_scale`](super::WalkEnv::obs_scale)) so every entry is of order one. Default true (esrl's choice:
    /// the raw values span three orders of magnitude, accelerations reach 160 m/s²).
    pub normalize_obs: bool,
    /// Torque-controlled joints, in action order. Default the six leg joints `left_hip,
    /// left_knee, left_ankle, right_hip, right_knee, right_ankle` (SPEC §1).
    pub actuated_joints: Vec<String>,
    /// Left and right foot links (contact-force observations). Default `left_foot, right_foot`.
    pub foot_links: [String; 2],
    /// Standing pose, joint name → angle (rad); unlisted joints stand at 0 clamped into their
    /// limits. Default hips −2°, knees 10°, ankles −8°: knees bent (≥ 5°, paper §5), torso
    /// upright, feet flat, and the body leaning forward so that the centre of mass lies 4.6 cm
    /// in front of the ankles, as in quiet human standing (Winter 1995, "Human balance and
    /// posture control during standing and walking", Gait & Posture 3:193–214).
    pub standing_pose: BTreeMap<String, f32>,
    /// Disturbances for robustness tests ([`Perturb`]). Default none.
    #[serde(skip_serializing_if = "Perturb::is_none")]
    pub perturb: Perturb,
    /// What the observed torso orientation is measured against on a slope: `ground`
    /// (default, every result before 2026-12-06) or `gravity` (as an IMU on a real slope
    /// reports it). The same bit for bit on flat ground ([`OrientationFrame`]).
    #[serde(skip_serializing_if = "OrientationFrame::is_ground")]
    pub orientation_frame: OrientationFrame,
}

impl Default for WalkConfig {
    fn default() -> Self {
        let deg = std::f32::consts::PI / 180.0;
        let mut standing_pose = BTreeMap::new();
        for side in ["left", "right"] {
            standing_pose.insert(format!("{side}_hip"), -2.0 * deg);
            standing_pose.insert(format!("{side}_knee"), 10.0 * deg);
            standing_pose.insert(format!("{side}_ankle"), -8.0 * deg);
        }
        Self {
            urdf: None,
            control_period: 0.025,
            episode_seconds: 60.0,
            track_length: 50.0,
            end_at_finish: true,
            physics: PhysicsConfig::default(),
            reward: RewardConfig::default(),
            fall: FallConfig::default(),
            init_noise: InitNoise::default(),
            reset: ResetConfig::default(),
            action: ActionMode::Torque,
            target: TargetServo::default(),
            gait_clock: None,
            normalize_obs: true,
            actuated_joints: [
                "left_hip",
                "left_knee",
                "left_ankle",
                "right_hip",
                "right_knee",
                "right_ankle",
            ]
            .map(String::from)
            .to_vec(),
            foot_links: ["left_foot".into(), "right_foot".into()],
            standing_pose,
            perturb: Perturb::default(),
            orientation_frame: OrientationFrame::Ground,
        }
    }
}

fn config_err(field: &str, value: impl ToString, reason: &str) -> SimError {
    SimError::Config {
        field: field.to_owned(),
        value: value.to_string(),
        reason: reason.to_owned(),
    }
}

impl WalkConfig {
    /// Checks every value, naming the field at fault.
    pub fn validate(&self) -> Result<(), SimError> {
        let pos = |field: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(config_err(field, v, "must be finite and > 0"))
            }
        };
        let nonneg = |field: &str, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(config_err(field, v, "must be finite and ≥ 0"))
            }
        };
        let fin = |field: &str, v: f32| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(config_err(field, v, "must be finite"))
            }
        };
        pos("control_period", self.control_period)?;
        pos("episode_seconds", self.episode_seconds)?;
        if self.episode_seconds / self.control_period > 1e8 {
            return Err(config_err(
                "episode_seconds",
                self.episode_seconds,
                "gives more than 1e8 steps per episode",
            ));
        }
        pos("track_length", self.track_length)?;
        self.physics.validate("physics.")?;
        self.perturb.validate()?;
        fin("reward.forward", self.reward.forward)?;
        fin("reward.lateral", self.reward.lateral)?;
        fin("reward.height", self.reward.height)?;
        fin("reward.power", self.reward.power)?;
        fin("reward.alive", self.reward.alive)?;
        nonneg("reward.action_sq", self.reward.action_sq)?;
        nonneg("reward.torque_sq", self.reward.torque_sq)?;
        nonneg("reward.tilt_sq", self.reward.tilt_sq)?;
        if let Some(c) = self.reward.forward_cap {
            pos("reward.forward_cap", c)?;
        }
        nonneg("reward.forward_over_cap", self.reward.forward_over_cap)?;
        if self.reward.forward_over_cap > 0.0 && self.reward.forward_cap.is_none() {
            return Err(config_err(
                "reward.forward_over_cap",
                self.reward.forward_over_cap,
                "prices speed above reward.forward_cap, which is not set",
            ));
        }
        if let Some(g) = &self.reward.forward_gate {
            pos("reward.forward_gate.max_tilt", g.max_tilt)?;
            pos("reward.forward_gate.max_height_drop", g.max_height_drop)?;
        }
        pos("fall.max_height_drop", self.fall.max_height_drop)?;
        pos("fall.max_tilt", self.fall.max_tilt)?;
        if let Some(v) = self.fall.max_lateral {
            pos("fall.max_lateral", v)?;
        }
        if let Some(v) = self.fall.max_yaw {
            pos("fall.max_yaw", v)?;
        }
        nonneg("reset.crouch", self.reset.crouch)?;
        nonneg("reset.split", self.reset.split)?;
        nonneg("target.stiffness", self.target.stiffness)?;
        nonneg("target.damping", self.target.damping)?;
        if let Some(r) = self.target.range {
            pos("target.range", r)?;
        }
        for (joint, &r) in &self.target.joint_range {
            pos(&format!("target.joint_range.{joint}"), r)?;
        }
        if let Some(c) = &self.gait_clock {
            pos("gait_clock.period", c.period)?;
            if !(c.duty > 0.0 && c.duty < 1.0) {
                return Err(config_err(
                    "gait_clock.duty",
                    c.duty.to_string(),
                    "must be in (0, 1)",
                ));
            }
            fin("gait_clock.reward", c.reward)?;
            nonneg("gait_clock.contact_force", c.contact_force)?;
            nonneg("gait_clock.chatter", c.chatter)?;
            nonneg("gait_clock.min_phase", c.min_phase)?;
            nonneg("gait_clock.clearance", c.clearance)?;
            pos("gait_clock.clearance_height", c.clearance_height)?;
        }
        nonneg("init_noise.joint_angle", self.init_noise.joint_angle)?;
        nonneg("init_noise.joint_velocity", self.init_noise.joint_velocity)?;
        if self.actuated_joints.is_empty() {
            return Err(config_err(
                "actuated_joints",
                "[]",
                "needs at least one joint",
            ));
        }
        for (name, v) in &self.standing_pose {
            fin(&format!("standing_pose.{name}"), *v)?;
        }
        Ok(())
    }

    /// Loads the model this config names (the embedded humanoid by default).
    pub fn load_model(&self) -> Result<Arc<RobotModel>, SimError> {
        Ok(match &self.urdf {
            Some(path) => Arc::new(RobotModel::from_urdf_path(path)?),
            None => RobotModel::humanoid_shared()?,
        })
    }
}
