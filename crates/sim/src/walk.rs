//! `WalkEnv`: the humanoid on the 50 m flat track (SPEC §2, paper §5).
//!
//! # Observation (43 values for the embedded humanoid)
//!
//! Sizes follow the model: `n_a` actuated joints, `n_p` passive (non-actuated, movable)
//! joints, in URDF order. All values are SI before scaling (see Scaling below), f32; "body
//! frame" is the torso link frame.
//!
//! | index (humanoid) | size | quantity |
//! |---|---|---|
//! | 0 | 1 | torso height error `z − z_stand`, m |
//! | 1 | 1 | torso lateral offset `y` from the track centre line, m |
//! | 2–5 | 4 | torso orientation quaternion `x, y, z, w` (world) |
//! | 6–8 | 3 | torso linear velocity (of the link origin), body frame, m/s |
//! | 9–11 | 3 | torso angular velocity, body frame, rad/s |
//! | 12–14 | 3 | torso linear acceleration, body frame, m/s² (finite difference of the world velocity over the control period, gravity not included; 0 after reset) |
//! | 15–20 | `n_a` | actuated joint angles, rad (left hip, knee, ankle, right hip, knee, ankle) |
//! | 21–26 | `n_a` | actuated joint velocities, rad/s |
//! | 27–30 | `n_p` | passive joint angles, rad (left shoulder pitch, roll, right shoulder pitch, roll) |
//! | 31–34 | `n_p` | passive joint velocities, rad/s |
//! | 35–36 | 2 | left, right foot normal contact force / body weight |
//! | 37–42 | `n_a` | previous action (the clamped action of the last step; 0 after reset) |
//!
//! [`WalkEnv::obs_layout`] gives the ranges and [`WalkEnv::obs_names`] a name per index.
//!
//! ## Scaling (`normalize_obs`, default on)
//!
//! With [`WalkConfig::normalize_obs`] on, every entry above is multiplied by a fixed factor
//! ([`WalkEnv::obs_scale`]) so that each is of order one for the networks:
//!
//! | quantity | factor | raw spread it tames (std over zero- and random-torque rollouts) |
//! |---|---|---|
//! | height error, lateral offset | 10 (1 = 0.1 m) | 0.07–0.1 m |
//! | orientation quaternion | 1 | 0.01–0.2 |
//! | linear velocity | 1 (m/s) | 0.07–0.7 m/s |
//! | angular velocity | 0.5 (1 = 2 rad/s) | 0.1–2.1 rad/s |
//! | linear acceleration | 0.1 (1 ≈ g) | 1.5–20 m/s², peaks 160 m/s² |
//! | actuated joint angles | 1 (rad) | 0.1–0.7 rad |
//! | actuated joint velocities | 0.1 (1 = 10 rad/s) | 2–9 rad/s, peaks 40 rad/s |
//! | passive joint angles | 1 (rad) | 0.01–0.3 rad |
//! | passive joint velocities | 0.5 (1 = 2 rad/s) | 0.1–1.5 rad/s |
//! | foot forces / weight, previous action | 1 | 0.6–1 |
//!
//! The spreads come from `cargo run --release -p esrl-sim --example obs_stats -- 10000 raw`
//! (the robot falls within about 0.6 s under zero or random torques, so these are the states
//! early training sees). The factors are constants, not running statistics, so a policy
//! means the same thing in every run and checkpoint. Turn it off for the raw SI values above.
//!
//! # Action
//!
//! Actions are clamped to `[-1, 1]` (NaN reads as 0), one per actuated joint.
//!
//! - **`action = "torque"`** (default, the paper's): joint torque `τ = a·τmax`, `τmax` the
//!   joint's URDF `<limit effort>`, commanded for the whole control period and passed through
//!   the joint-limit model ([`PhysicsConfig::joint_limits`](crate::PhysicsConfig); crate docs,
//!   "Physics step and joint limits").
//! - **`action = "target"`**: a joint angle target `q*`, tracked by a position servo that
//!   Rapier integrates inside its solver at every physics substep (a `ForceBased` motor:
//!   `τ = clamp(kp·(q* − q) − kd·q̇, ±τmax)`, implicit, so stable at any gain), as MATLAB's
//!   humanoid walker drives its joints through PD set-points. The map is piecewise linear
//!   through the standing pose: `q* = q_stand + a·(hi − q_stand)` for `a ≥ 0`,
//!   `q_stand + a·(q_stand − lo)` for `a < 0` ([`WalkEnv::target_angle`]), so a zero action
//!   holds the standing pose and ±1 reach the limits. Gains ([`TargetGains`]): `kp` = 1500
//!   N·m/rad, `kd` = 60 N·m·s/rad on every actuated joint, measured: the ankles need more than
//!   the ≈ 620 N·m/rad of `m·g·h` to hold the 70 kg body upright, and with these gains a zero
//!   action stands 20 s from every reset seed tried (torso within 3 cm, joints within 1.2°;
//!   1000/40 drifts 7 cm, 600/30 falls); the servo reaches full effort at 5.7° (hips, knees)
//!   and 4.6° (ankles) of error. With the torso held in the air, a step of the target to
//!   half range is within 2° after 0.09–0.10 s (ankle), 0.13 s (knee), 0.11 s (hip,
//!   extending) and 0.52 s (hip, flexing: lifting the leg to −46°) (`tests/target_mode.rs`).
//!   A servo's motor impulses are constraint impulses in Rapier, which do not conserve
//!   momentum as exactly as external torques do (crate docs, "Known limitations").
//!
//! # Power
//!
//! The power term and the gait data use the mechanical power the actuator delivers at each
//! actuated joint: for every physics (Rapier) step, the work `τ·Δq` over the step's length
//! `h`, where `τ` is the torque actually delivered: in `torque` mode the commanded torque
//! after the joint-limit model (constant over the step, so the work is exact); in `target`
//! mode the servo's torque, the mean of its law at the step's start and end states (a
//! trapezoid rule). [`GaitSample::joint_power`](crate::GaitSample) is the mean of `τ·Δq/h`
//! over the control period's physics steps, [`GaitSample::joint_abs_power`](crate::GaitSample)
//! the mean of its absolute value, and [`GaitSample::joint_torque`](crate::GaitSample) the mean
//! delivered torque. So a servo holding a load, or a torque faded away at a limit, shows in
//! the torque; a joint at rest delivers no mechanical power whatever torque it holds (that is
//! what `reward.torque_sq` prices).
//!
//! # Reward (paper eq. 12)
//!
//! `r = w_v·vx − w_y·y² − w_z·z² − w_P·P + c`, defaults `w_v = 1, w_y = 5, w_z = 25,
//! w_P = 0.0005, c = 0.025`: `vx` the torso's forward (world x) velocity, `y` its lateral
//! offset, `z` its height error, `P` the mean over actuated joints of the delivered `|τ·ω|`
//! (Power above). Each term is reported in [`StepInfo::reward_terms`](crate::StepInfo) as
//! `forward`, `lateral`, `height`, `power`, `alive`; they sum to the reward. The alive bonus
//! `c` is not paid on a step that ends in a fall or off course.
//!
//! Options ([`RewardConfig`], all off by default, which is eq. 12):
//!
//! - `reward.action_sq = w`: adds the term `action_sq = −w·Σ aᵢ²` (MATLAB's walking-robot
//!   examples use `w` = 0.02 with their torques normalised to [−1, 1]);
//! - `reward.torque_sq = w`: adds `torque_sq = −w·Σ (τᵢ/τmaxᵢ)²`, `τᵢ` the mean delivered
//!   torque of the period: prices holding a load (against a limit, gravity or a servo's
//!   target) that the power term does not see;
//! - `reward.forward_gate = { max_tilt, max_height_drop }`: `forward` is 0 on steps where the
//!   torso tilts more than `max_tilt` from vertical or is more than `max_height_drop` below its
//!   standing height (DeepMind Control's walker pays its move reward only in proportion to
//!   its stand reward).
//!
//! # Episode
//!
//! Truncated after `episode_seconds / control_period` steps (60 s / 0.025 s = 2400).
//! Terminated on a fall: torso origin more than [`FallConfig::max_height_drop`] below its
//! standing height, torso z axis tilted more than [`FallConfig::max_tilt`] from vertical, or a
//! non-finite state. Terminated off course ([`GaitSample::off_course`](crate::GaitSample)), when
//! set: torso origin more than [`FallConfig::max_lateral`] from the centre line, or its heading
//! (the angle of its x axis on the ground from world x) more than [`FallConfig::max_yaw`] from
//! the track direction (both off by default, as in the paper). Terminated with success when
//! the torso origin passes `x = track_length`.
//!
//! # Reset
//!
//! The robot starts from a pose ([`ResetConfig::pose`]: `standing` by default; `crouch`,
//! `split`, or `mixed` = one of the three drawn from the seed), plus uniform noise on every
//! movable joint's angle and velocity ([`InitNoise`], ±0.01 rad and ±0.01 rad/s by default;
//! raise them for a wider start distribution), clamped into the joint limits, placed with its
//! lowest point on the ground, at rest. The draws, from a ChaCha8 stream seeded with the reset
//! seed: for each movable joint in URDF order the angle then the velocity noise, each
//! `half-width × U(−1, 1)`; then the `mixed` pose; then the leading leg of `split`.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

use crate::env::{Env, GaitSample, Step, StepInfo};
use crate::error::SimError;
use crate::math::Iso;
use crate::model::{JointKind, LinkGeometry, LinkPose, RobotModel};
use crate::sim::{Base, PhysicsConfig, RobotSim, RobotState, SimSetup};

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
    /// Pay the forward term only while the torso is upright and tall (DeepMind Control's
    /// walker multiplies its move reward by its stand reward): when set, `w_v·vx` is replaced
    /// by 0 on steps where the torso tilts more than `max_tilt` or is lower than
    /// `max_height_drop` under its standing height. Default none (eq. 12 pays it always).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forward_gate: Option<UprightGate>,
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
            forward_gate: None,
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

/// Gains of the `target` action mode's servos ([`WalkConfig::target`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TargetGains {
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
}

impl Default for TargetGains {
    fn default() -> Self {
        Self {
            stiffness: 1500.0,
            damping: 60.0,
            range: None,
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
}

impl Default for GaitClock {
    fn default() -> Self {
        Self {
            period: 1.0,
            duty: 0.6,
            reward: 0.5,
            contact_force: 10.0,
        }
    }
}

impl GaitClock {
    /// Whether each foot (left, right) is meant to be down at phase `phi` ∈ [0, 1).
    pub fn stance(&self, phi: f32) -> [bool; 2] {
        let right = (phi + 0.5).rem_euclid(1.0);
        [phi.rem_euclid(1.0) < self.duty, right < self.duty]
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

/// Configuration of [`WalkEnv`]. Every field has a default; TOML files may give any subset.
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
    /// Track length, m: success (termination) when the torso passes `x = track_length`.
    /// Default 50 (paper Fig. 4).
    pub track_length: f32,
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
    /// Servo gains of the `target` action mode.
    pub target: TargetGains,
    /// Optional gait clock: phase features at the end of the observation and a reward for
    /// contacts that follow them ([`GaitClock`]). Default none (the paper's observation and
    /// reward).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gait_clock: Option<GaitClock>,
    /// Multiply the observation by the fixed per-quantity factors of the module docs
    /// ([`WalkEnv::obs_scale`]) so every entry is of order one. Default true (esrl's choice:
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
            physics: PhysicsConfig::default(),
            reward: RewardConfig::default(),
            fall: FallConfig::default(),
            init_noise: InitNoise::default(),
            reset: ResetConfig::default(),
            action: ActionMode::Torque,
            target: TargetGains::default(),
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
        fin("reward.forward", self.reward.forward)?;
        fin("reward.lateral", self.reward.lateral)?;
        fin("reward.height", self.reward.height)?;
        fin("reward.power", self.reward.power)?;
        fin("reward.alive", self.reward.alive)?;
        nonneg("reward.action_sq", self.reward.action_sq)?;
        nonneg("reward.torque_sq", self.reward.torque_sq)?;
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

/// Index ranges of the observation vector (see the module docs for units and frames).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ObsLayout {
    /// Torso height error.
    pub height_error: usize,
    /// Torso lateral offset.
    pub lateral_offset: usize,
    /// Torso quaternion x, y, z, w.
    pub orientation: Range<usize>,
    /// Torso linear velocity, body frame.
    pub linear_velocity: Range<usize>,
    /// Torso angular velocity, body frame.
    pub angular_velocity: Range<usize>,
    /// Torso linear acceleration, body frame.
    pub acceleration: Range<usize>,
    /// Actuated joint angles.
    pub joint_angles: Range<usize>,
    /// Actuated joint velocities.
    pub joint_velocities: Range<usize>,
    /// Passive joint angles.
    pub passive_angles: Range<usize>,
    /// Passive joint velocities.
    pub passive_velocities: Range<usize>,
    /// Left, right foot normal force / body weight.
    pub foot_forces: Range<usize>,
    /// Previous action.
    pub previous_action: Range<usize>,
    /// Gait clock (sin 2πφ, cos 2πφ), when [`WalkConfig::gait_clock`] is set.
    pub clock: Option<Range<usize>>,
    /// Total length.
    pub len: usize,
}

impl ObsLayout {
    fn new(n_a: usize, n_p: usize, clock: bool) -> Self {
        let mut at = 2;
        let mut take = |n: usize| {
            let r = at..at + n;
            at += n;
            r
        };
        let orientation = take(4);
        let linear_velocity = take(3);
        let angular_velocity = take(3);
        let acceleration = take(3);
        let joint_angles = take(n_a);
        let joint_velocities = take(n_a);
        let passive_angles = take(n_p);
        let passive_velocities = take(n_p);
        let foot_forces = take(2);
        let previous_action = take(n_a);
        let clock = clock.then(|| take(2));
        Self {
            height_error: 0,
            lateral_offset: 1,
            orientation,
            linear_velocity,
            angular_velocity,
            acceleration,
            joint_angles,
            joint_velocities,
            passive_angles,
            passive_velocities,
            foot_forces,
            previous_action,
            clock,
            len: at,
        }
    }

    /// The factor each index is multiplied by when `normalize_obs` is on (module docs).
    fn scale(&self) -> Vec<f32> {
        let mut s = vec![1.0; self.len];
        s[self.height_error] = 10.0;
        s[self.lateral_offset] = 10.0;
        for (range, f) in [
            (&self.angular_velocity, 0.5),
            (&self.acceleration, 0.1),
            (&self.joint_velocities, 0.1),
            (&self.passive_velocities, 0.5),
        ] {
            s[range.clone()].fill(f);
        }
        s
    }
}

/// Everything a [`WalkEnv`] shares with its siblings: the parsed model and resolved names.
#[derive(Debug)]
struct WalkShared {
    model: Arc<RobotModel>,
    config: WalkConfig,
    torso: usize,
    feet: [usize; 2],
    actuated: Vec<usize>,
    passive: Vec<usize>,
    effort: Vec<f32>,
    /// Per actuated joint: lower and upper limit, rad (±∞ without limits).
    range: Vec<[f32; 2]>,
    /// Standing pose, one entry per joint (URDF order).
    standing_q: Vec<f64>,
    standing_height: f64,
    weight: f32,
    setup: SimSetup,
    max_steps: usize,
    layout: ObsLayout,
    /// Per-index observation factor (all 1 when `normalize_obs` is off).
    obs_scale: Vec<f32>,
}

/// The walking task. See the [module docs](self) for observation, reward and episode.
pub struct WalkEnv {
    shared: Arc<WalkShared>,
    sim: RobotSim,
    prev_action: Vec<f32>,
    prev_velocity: Vector,
    acceleration: Vector,
    steps: usize,
    /// Per actuated joint, over the last control period's physics steps: mean delivered
    /// torque, mean power τ·ω and mean |τ·ω|.
    last_torque: Vec<f32>,
    last_power: Vec<f32>,
    last_abs_power: Vec<f32>,
    /// Gait-clock phase at reset, drawn from the reset seed (0 without a clock).
    phase0: f32,
}

impl WalkEnv {
    /// Builds the environment described by `config` (loading its URDF).
    pub fn new(config: WalkConfig) -> Result<Self, SimError> {
        config.validate()?;
        let model = config.load_model()?;
        Self::from_model(model, config)
    }

    /// Builds the environment on an already parsed model (`config.urdf` is ignored).
    pub fn from_model(model: Arc<RobotModel>, config: WalkConfig) -> Result<Self, SimError> {
        config.validate()?;
        let torso = model.root();
        if model.links()[torso].mass <= 0.0 {
            return Err(crate::error::UrdfError::MasslessFloatingRoot {
                link: model.links()[torso].name.clone(),
            }
            .into());
        }
        let mut actuated = Vec::with_capacity(config.actuated_joints.len());
        for name in &config.actuated_joints {
            let Some(j) = model.joint_index(name) else {
                return Err(SimError::Model {
                    field: "actuated_joints".into(),
                    reason: format!("the model has no joint `{name}`"),
                });
            };
            let joint = &model.joints()[j];
            if joint.kind == JointKind::Fixed {
                return Err(SimError::Model {
                    field: "actuated_joints".into(),
                    reason: format!("joint `{name}` is fixed"),
                });
            }
            if !(joint.effort.is_finite() && joint.effort > 0.0) {
                return Err(SimError::Model {
                    field: "actuated_joints".into(),
                    reason: format!(
                        "joint `{name}` needs a finite <limit effort> > 0 to scale actions, got {}",
                        joint.effort
                    ),
                });
            }
            if actuated.contains(&j) {
                return Err(SimError::Model {
                    field: "actuated_joints".into(),
                    reason: format!("joint `{name}` is listed twice"),
                });
            }
            actuated.push(j);
        }
        let passive: Vec<usize> = (0..model.joints().len())
            .filter(|j| model.joints()[*j].is_movable() && !actuated.contains(j))
            .collect();
        let mut feet = [0; 2];
        for (k, name) in config.foot_links.iter().enumerate() {
            feet[k] = model.link_index(name).ok_or_else(|| SimError::Model {
                field: "foot_links".into(),
                reason: format!("the model has no link `{name}`"),
            })?;
        }
        for name in config.standing_pose.keys() {
            if model.joint_index(name).is_none() {
                return Err(SimError::Model {
                    field: format!("standing_pose.{name}"),
                    reason: format!("the model has no joint `{name}`"),
                });
            }
        }
        let standing_q: Vec<f64> = model
            .joints()
            .iter()
            .map(|j| {
                let q = config.standing_pose.get(&j.name).copied().unwrap_or(0.0) as f64;
                match j.limits {
                    Some([lo, hi]) => q.clamp(lo, hi),
                    None => q,
                }
            })
            .collect();
        let poses = model.forward_kinematics(&Iso::IDENTITY, &standing_q);
        let standing_height = -model.lowest_point(&poses);
        if !standing_height.is_finite() {
            return Err(SimError::Model {
                field: "urdf".into(),
                reason: "the model has no collision shape to stand on".into(),
            });
        }
        let substeps = config.physics.substeps;
        let mut armature = vec![0.0; model.joints().len()];
        for &j in &actuated {
            armature[j] = config.physics.actuator_armature;
        }
        let setup = SimSetup {
            dt: config.control_period / substeps as f32,
            physics: config.physics.clone(),
            base: Base::Floating,
            ground: true,
            armature,
        };
        let max_steps = (config.episode_seconds / config.control_period)
            .round()
            .max(1.0) as usize;
        let effort = actuated
            .iter()
            .map(|&j| model.joints()[j].effort as f32)
            .collect();
        let range: Vec<[f32; 2]> = actuated
            .iter()
            .map(|&j| {
                model.joints()[j]
                    .limits
                    .map_or([f32::NEG_INFINITY, f32::INFINITY], |[lo, hi]| {
                        [lo as f32, hi as f32]
                    })
            })
            .collect();
        if config.action == ActionMode::Target {
            if let Some(k) = range
                .iter()
                .position(|r| !r[0].is_finite() || !r[1].is_finite())
            {
                return Err(SimError::Model {
                    field: "action".into(),
                    reason: format!(
                        "`target` maps actions onto joint ranges, and joint `{}` has no limits",
                        config.actuated_joints[k]
                    ),
                });
            }
        }
        if config.reset.pose != ResetPose::Standing && actuated.len() % 3 != 0 {
            return Err(SimError::Model {
                field: "reset.pose".into(),
                reason: format!(
                    "`crouch`, `split` and `mixed` read the actuated joints as (hip, knee, ankle) \
                     per leg, and {} joints are not a multiple of 3",
                    actuated.len()
                ),
            });
        }
        let weight = (model.total_mass() * config.physics.gravity as f64) as f32;
        let layout = ObsLayout::new(actuated.len(), passive.len(), config.gait_clock.is_some());
        let obs_scale = if config.normalize_obs {
            layout.scale()
        } else {
            vec![1.0; layout.len]
        };
        let state = RobotState {
            base_position: [0.0, 0.0, standing_height],
            q: standing_q.clone(),
            qd: vec![0.0; standing_q.len()],
        };
        let sim = RobotSim::new(model.clone(), &setup, &state)?;
        let n_a = actuated.len();
        let shared = Arc::new(WalkShared {
            model,
            config,
            torso,
            feet,
            actuated,
            passive,
            effort,
            range,
            standing_q,
            standing_height,
            weight,
            setup,
            max_steps,
            layout,
            obs_scale,
        });
        Ok(Self {
            shared,
            sim,
            prev_action: vec![0.0; n_a],
            prev_velocity: Vector::ZERO,
            acceleration: Vector::ZERO,
            steps: 0,
            last_torque: vec![0.0; n_a],
            last_power: vec![0.0; n_a],
            last_abs_power: vec![0.0; n_a],
            phase0: 0.0,
        })
    }

    /// Another environment on the same parsed model and config, standing still (cheap: no
    /// URDF parsing). Call [`Env::reset`] before use.
    pub fn spawn(&self) -> Self {
        let s = &self.shared;
        let state = RobotState {
            base_position: [0.0, 0.0, s.standing_height],
            q: s.standing_q.clone(),
            qd: vec![0.0; s.standing_q.len()],
        };
        let sim = RobotSim::build(s.model.clone(), &s.setup, &state);
        let n_a = s.actuated.len();
        Self {
            shared: self.shared.clone(),
            sim,
            prev_action: vec![0.0; n_a],
            prev_velocity: Vector::ZERO,
            acceleration: Vector::ZERO,
            steps: 0,
            last_torque: vec![0.0; n_a],
            last_power: vec![0.0; n_a],
            last_abs_power: vec![0.0; n_a],
            phase0: 0.0,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &WalkConfig {
        &self.shared.config
    }

    /// The robot model.
    pub fn model(&self) -> &Arc<RobotModel> {
        &self.shared.model
    }

    /// The physics world (for inspection and tests).
    pub fn sim(&self) -> &RobotSim {
        &self.sim
    }

    /// The physics world, mutable (e.g. to add joint servos in tests). Changes last until the
    /// next [`Env::reset`], which rebuilds the world.
    pub fn sim_mut(&mut self) -> &mut RobotSim {
        &mut self.sim
    }

    /// Actuated joint names, in action order.
    pub fn actuated_joint_names(&self) -> &[String] {
        &self.shared.config.actuated_joints
    }

    /// Passive joint names, in observation order.
    pub fn passive_joint_names(&self) -> Vec<&str> {
        self.shared
            .passive
            .iter()
            .map(|&j| self.shared.model.joints()[j].name.as_str())
            .collect()
    }

    /// Effort limits of the actuated joints (torque at action ±1), N·m.
    pub fn effort_limits(&self) -> &[f32] {
        &self.shared.effort
    }

    /// Standing-pose angles of the actuated joints, rad.
    pub fn standing_pose(&self) -> Vec<f32> {
        self.shared
            .actuated
            .iter()
            .map(|&j| self.shared.standing_q[j] as f32)
            .collect()
    }

    /// Whole-body centre of mass in the standing pose, relative to the torso origin, m
    /// (from the model, not the simulation).
    pub fn standing_com(&self) -> [f32; 3] {
        let s = &self.shared;
        s.model
            .center_of_mass(&Iso::IDENTITY, &s.standing_q)
            .map(|v| v as f32)
    }

    /// Torso origin height in the standing pose with the feet on the ground, m.
    pub fn standing_height(&self) -> f32 {
        self.shared.standing_height as f32
    }

    /// Total mass × gravity, N.
    pub fn body_weight(&self) -> f32 {
        self.shared.weight
    }

    /// Index ranges of the observation.
    pub fn obs_layout(&self) -> &ObsLayout {
        &self.shared.layout
    }

    /// The factor every observation index is multiplied by: the module docs' table when
    /// [`WalkConfig::normalize_obs`] is on, all 1 otherwise. Divide an observation by it for
    /// the SI values.
    pub fn obs_scale(&self) -> &[f32] {
        &self.shared.obs_scale
    }

    /// A name for every observation index, e.g. `joint_angle/left_knee`.
    pub fn obs_names(&self) -> Vec<String> {
        let s = &self.shared;
        let joint = |j: &usize| s.model.joints()[*j].name.clone();
        let mut names = vec!["height_error".to_owned(), "lateral_offset".to_owned()];
        names.extend(["x", "y", "z", "w"].map(|c| format!("orientation/{c}")));
        names.extend(["x", "y", "z"].map(|c| format!("linear_velocity/{c}")));
        names.extend(["x", "y", "z"].map(|c| format!("angular_velocity/{c}")));
        names.extend(["x", "y", "z"].map(|c| format!("acceleration/{c}")));
        names.extend(
            s.actuated
                .iter()
                .map(|j| format!("joint_angle/{}", joint(j))),
        );
        names.extend(
            s.actuated
                .iter()
                .map(|j| format!("joint_velocity/{}", joint(j))),
        );
        names.extend(
            s.passive
                .iter()
                .map(|j| format!("passive_angle/{}", joint(j))),
        );
        names.extend(
            s.passive
                .iter()
                .map(|j| format!("passive_velocity/{}", joint(j))),
        );
        names.extend(
            s.config
                .foot_links
                .iter()
                .map(|f| format!("foot_force/{f}")),
        );
        names.extend(
            s.actuated
                .iter()
                .map(|j| format!("previous_action/{}", joint(j))),
        );
        names
    }

    /// World poses of every link frame (URDF link order).
    pub fn link_poses(&self) -> Vec<LinkPose> {
        self.sim.link_poses()
    }

    /// Collision geometry of every link, in its link frame (URDF link order).
    pub fn geometry(&self) -> Vec<LinkGeometry> {
        self.shared.model.geometry()
    }

    /// Steps taken since the last reset.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The gait-clock phase φ ∈ [0, 1) now ([`GaitClock`]; 0 without a clock).
    pub fn phase(&self) -> f32 {
        match &self.shared.config.gait_clock {
            Some(c) => {
                let t = self.steps as f32 * self.shared.config.control_period;
                (self.phase0 + t / c.period).rem_euclid(1.0)
            }
            None => 0.0,
        }
    }

    /// The joint angle target of actuated joint `k` for action `a` in `target` mode (module
    /// docs, "Action"): the standing angle at 0, the joint's limits at ±1, linear in between
    /// on each side; with [`TargetGains::range`], `q_stand + a·range` clamped to the limits.
    pub fn target_angle(&self, k: usize, a: f32) -> f32 {
        let s = &self.shared;
        let stand = s.standing_q[s.actuated[k]] as f32;
        let [lo, hi] = s.range[k];
        let a = if a.is_finite() {
            a.clamp(-1.0, 1.0)
        } else {
            0.0
        };
        if let Some(range) = self.config().target.range {
            return (stand + a * range).clamp(lo, hi);
        }
        if a >= 0.0 {
            stand + a * (hi - stand)
        } else {
            stand + a * (stand - lo)
        }
    }

    fn observation(&self) -> Vec<f32> {
        let s = &self.shared;
        let pose = self.sim.link_pose(s.torso);
        let inv = pose.rotation.inverse();
        let v = inv * self.sim.link_origin_velocity(s.torso);
        let w = inv * self.sim.link_angular_velocity(s.torso);
        let a = inv * self.acceleration;
        let q = pose.rotation;
        let mut obs = Vec::with_capacity(s.layout.len);
        obs.push(pose.translation.z - s.standing_height as f32);
        obs.push(pose.translation.y);
        obs.extend([q.x, q.y, q.z, q.w]);
        obs.extend(v.to_array());
        obs.extend(w.to_array());
        obs.extend(a.to_array());
        obs.extend(s.actuated.iter().map(|&j| self.sim.joint_position(j)));
        obs.extend(s.actuated.iter().map(|&j| self.sim.joint_velocity(j)));
        obs.extend(s.passive.iter().map(|&j| self.sim.joint_position(j)));
        obs.extend(s.passive.iter().map(|&j| self.sim.joint_velocity(j)));
        obs.extend(
            s.feet
                .iter()
                .map(|&f| self.sim.ground_normal_force(f) / s.weight),
        );
        obs.extend(self.prev_action.iter().copied());
        if s.config.gait_clock.is_some() {
            let angle = std::f32::consts::TAU * self.phase();
            obs.extend([angle.sin(), angle.cos()]);
        }
        for (o, f) in obs.iter_mut().zip(&s.obs_scale) {
            *o *= f;
        }
        obs
    }
}

/// Angle between the torso's z axis and the world's, rad.
fn torso_tilt(rotation: Rotation) -> f32 {
    (rotation * Vector::Z).z.clamp(-1.0, 1.0).acos()
}

/// Heading of the torso: the angle of its x axis projected on the ground from world x, rad
/// (positive to the left); 0 when the x axis points straight up or down.
fn torso_yaw(rotation: Rotation) -> f32 {
    let x = rotation * Vector::X;
    if x.x == 0.0 && x.y == 0.0 {
        0.0
    } else {
        x.y.atan2(x.x)
    }
}

/// Offsets of the actuated joints from the standing pose for a reset `pose` (module docs of
/// [`ResetConfig`]), joints read as (hip, knee, ankle) per leg.
fn reset_offsets(
    config: &ResetConfig,
    pose: ResetPose,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f32> {
    let mut d = vec![0.0f32; n];
    match pose {
        ResetPose::Standing | ResetPose::Mixed => {}
        ResetPose::Crouch => {
            let c = config.crouch;
            for leg in d.chunks_exact_mut(3) {
                leg.copy_from_slice(&[-c, 2.0 * c, -c]);
            }
        }
        ResetPose::Split => {
            let s = config.split;
            let lead = rng.random_range(0..n / 3);
            for (i, leg) in d.chunks_exact_mut(3).enumerate() {
                let sign = if i == lead { -1.0 } else { 1.0 };
                leg.copy_from_slice(&[sign * s, 0.0, -sign * s]);
            }
        }
    }
    d
}

impl Env for WalkEnv {
    fn obs_dim(&self) -> usize {
        self.shared.layout.len
    }

    fn act_dim(&self) -> usize {
        self.shared.actuated.len()
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        let s = self.shared.clone();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = &s.config.init_noise;
        let mut q = s.standing_q.clone();
        let mut qd = vec![0.0; q.len()];
        let mut dq = vec![0.0; q.len()];
        for (j, joint) in s.model.joints().iter().enumerate() {
            if !joint.is_movable() {
                continue;
            }
            dq[j] = noise.joint_angle as f64 * rng.random_range(-1.0..=1.0);
            qd[j] = noise.joint_velocity as f64 * rng.random_range(-1.0..=1.0);
        }
        // Drawn after the noise, so that `standing` resets are those of earlier versions.
        let pose = match s.config.reset.pose {
            ResetPose::Mixed => {
                [ResetPose::Standing, ResetPose::Crouch, ResetPose::Split][rng.random_range(0..3)]
            }
            p => p,
        };
        let offsets = reset_offsets(&s.config.reset, pose, s.actuated.len(), &mut rng);
        for (k, &j) in s.actuated.iter().enumerate() {
            q[j] += offsets[k] as f64;
        }
        for (j, joint) in s.model.joints().iter().enumerate() {
            if !joint.is_movable() {
                continue;
            }
            q[j] += dq[j];
            if let Some([lo, hi]) = joint.limits {
                q[j] = q[j].clamp(lo, hi);
            }
        }
        let poses = s.model.forward_kinematics(&Iso::IDENTITY, &q);
        let state = RobotState {
            base_position: [0.0, 0.0, -s.model.lowest_point(&poses)],
            q,
            qd,
        };
        self.sim = RobotSim::build(s.model.clone(), &s.setup, &state);
        self.prev_action.fill(0.0);
        self.prev_velocity = self.sim.link_origin_velocity(s.torso);
        self.acceleration = Vector::ZERO;
        self.steps = 0;
        self.last_torque.fill(0.0);
        self.last_power.fill(0.0);
        self.last_abs_power.fill(0.0);
        // Drawn last, so that resets without a clock are those of earlier versions.
        self.phase0 = if s.config.gait_clock.is_some() {
            rng.random_range(0.0..1.0)
        } else {
            0.0
        };
        self.observation()
    }

    fn step(&mut self, action: &[f32]) -> Step {
        let s = self.shared.clone();
        let n_a = s.actuated.len();
        for k in 0..n_a {
            let a = action.get(k).copied().unwrap_or(0.0);
            let a = if a.is_finite() {
                a.clamp(-1.0, 1.0)
            } else {
                0.0
            };
            self.prev_action[k] = a;
            let j = s.actuated[k];
            match s.config.action {
                ActionMode::Torque => self.sim.set_joint_torque(j, a * s.effort[k]),
                ActionMode::Target => {
                    let t = &s.config.target;
                    let target = self.target_angle(k, a);
                    self.sim
                        .set_joint_motor(j, target, t.stiffness, t.damping, s.effort[k]);
                }
            }
        }
        let substeps = s.config.physics.substeps as usize;
        let share = 1.0 / substeps as f32;
        let h = self.sim.dt();
        self.last_torque.fill(0.0);
        self.last_power.fill(0.0);
        self.last_abs_power.fill(0.0);
        let mut start = vec![(0.0f32, 0.0f32); n_a];
        for _ in 0..substeps {
            for (k, st) in start.iter_mut().enumerate() {
                let j = s.actuated[k];
                *st = (self.sim.joint_position(j), self.sim.servo_torque(j));
            }
            self.sim.step();
            for (k, &(q0, servo0)) in start.iter().enumerate() {
                let j = s.actuated[k];
                // Module docs, "Power": the work of the physics step over its length. The
                // applied torque is constant over the step; a servo's is taken as the mean of
                // its law at the step's start and end.
                let tau = self.sim.applied_torque(j) + 0.5 * (servo0 + self.sim.servo_torque(j));
                let p = tau * (self.sim.joint_position(j) - q0) / h;
                self.last_torque[k] += tau * share;
                self.last_power[k] += p * share;
                self.last_abs_power[k] += p.abs() * share;
            }
        }
        self.steps += 1;
        let v_world = self.sim.link_origin_velocity(s.torso);
        self.acceleration = (v_world - self.prev_velocity) / s.config.control_period;
        self.prev_velocity = v_world;

        let obs = self.observation();
        let pose = self.sim.link_pose(s.torso);
        let vx = v_world.x;
        let y = pose.translation.y;
        let z = pose.translation.z - s.standing_height as f32;
        let tilt = torso_tilt(pose.rotation);
        let finite = obs.iter().all(|v| v.is_finite());
        let fall = &s.config.fall;
        let fell = !finite || z < -fall.max_height_drop || tilt > fall.max_tilt;
        let off_course = !fell
            && (fall.max_lateral.is_some_and(|m| y.abs() > m)
                || fall
                    .max_yaw
                    .is_some_and(|m| torso_yaw(pose.rotation).abs() > m));
        let w = &s.config.reward;
        let upright = w
            .forward_gate
            .as_ref()
            .is_none_or(|g| tilt <= g.max_tilt && z >= -g.max_height_drop);
        let p_mean = self.last_abs_power.iter().sum::<f32>() / n_a as f32;
        let mut terms = vec![
            ("forward", if upright { w.forward * vx } else { 0.0 }),
            ("lateral", -w.lateral * y * y),
            ("height", -w.height * z * z),
            ("power", -w.power * p_mean),
            ("alive", if fell || off_course { 0.0 } else { w.alive }),
        ];
        if w.action_sq != 0.0 {
            let a2: f32 = self.prev_action.iter().map(|a| a * a).sum();
            terms.push(("action_sq", -w.action_sq * a2));
        }
        let feet = s.feet.map(|f| self.sim.ground_normal_force(f));
        if let Some(clock) = &s.config.gait_clock {
            let r = if fell || off_course {
                0.0
            } else {
                clock.contact_reward(self.phase(), feet)
            };
            terms.push(("gait_clock", r));
        }
        if w.torque_sq != 0.0 {
            let t2: f32 = self
                .last_torque
                .iter()
                .zip(&s.effort)
                .map(|(t, e)| (t / e).powi(2))
                .sum();
            terms.push(("torque_sq", -w.torque_sq * t2));
        }
        let mut reward: f32 = terms.iter().map(|t| t.1).sum();
        let fell = fell || !reward.is_finite();
        if !finite || !reward.is_finite() {
            reward = 0.0;
        }
        let success = !fell && !off_course && pose.translation.x >= s.config.track_length;
        let terminated = fell || off_course || success;
        let truncated = !terminated && self.steps >= s.max_steps;
        let gait = GaitSample {
            time: self.steps as f32 * s.config.control_period,
            torso_position: pose.translation.to_array(),
            torso_rotation: pose.rotation.to_array(),
            forward_velocity: vx,
            lateral_offset: y,
            height_error: z,
            joint_angle: s
                .actuated
                .iter()
                .map(|&j| self.sim.joint_position(j))
                .collect(),
            joint_velocity: s
                .actuated
                .iter()
                .map(|&j| self.sim.joint_velocity(j))
                .collect(),
            joint_torque: self.last_torque.clone(),
            joint_power: self.last_power.clone(),
            joint_abs_power: self.last_abs_power.clone(),
            foot_force: feet,
            fell,
            off_course,
            success,
        };
        Step {
            obs,
            reward,
            terminated,
            truncated,
            info: StepInfo {
                reward_terms: terms,
                gait: Some(gait),
            },
        }
    }

    fn control_period(&self) -> f32 {
        self.shared.config.control_period
    }

    fn max_episode_steps(&self) -> usize {
        self.shared.max_steps
    }
}
