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
//! | 2–5 | 4 | torso orientation quaternion `x, y, z, w` (world; on a slope, see [`WalkConfig::orientation_frame`]) |
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
//!   holds the standing pose and ±1 reach the limits. Gains ([`TargetServo`]): `kp` = 1500
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
//! - `reward.tilt_sq = w`: adds `tilt_sq = −w·tilt²`, `tilt` the angle (rad) between the
//!   torso's z axis and the vertical (the fall rule's tilt): prices a leaning trunk;
//! - `reward.forward_gate = { max_tilt, max_height_drop }`: `forward` is 0 on steps where the
//!   torso tilts more than `max_tilt` from vertical or is more than `max_height_drop` below its
//!   standing height (DeepMind Control's walker pays its move reward only in proportion to
//!   its stand reward);
//! - `reward.forward_cap = c`: `forward` pays `w_v·min(vx, c)`, no reward for speed above `c`
//!   m/s (for a track that goes on past its line, where every extra m/s would pay);
//!   `reward.forward_over_cap = k` makes each m/s above `c` cost `w_v·k`.
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
//! the torso origin passes `x = track_length`, unless `end_at_finish = false`: then every
//! step past the line reports success (the first one times the track) and the episode
//! runs on to its truncation.
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
//!
//! # Code
//!
//! The settings are in `config` ([`WalkConfig`]), `setup` resolves them against the model
//! and draws reset states, `observation` builds the vector above, `reward` judges each step;
//! this file holds [`WalkEnv`] and its [`Env`] implementation, which ties them together.

mod config;
mod mirror;
mod observation;
mod reward;
mod setup;

use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::prelude::Vector;

pub use config::{
    ActionMode, FallConfig, GaitClock, InitNoise, OrientationFrame, Perturb, PushDirection,
    ResetConfig, ResetPose, RewardConfig, TargetServo, UprightGate, WalkConfig,
};
pub use mirror::Mirror;
pub use observation::ObsLayout;

use crate::env::{Env, GaitSample, Step, StepInfo};
use crate::error::SimError;
use crate::math::Iso;
use crate::model::{LinkGeometry, LinkPose, RobotModel};
use crate::sim::RobotSim;
use setup::WalkShared;

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
    /// When set, the gait-clock phase of every following reset instead of the seed's draw.
    start_phase: Option<f32>,
    /// Each foot's contact phase, for the gait clock's chatter term.
    feet: reward::FootPhases,
    /// The disturbances' state (`[walk.perturb]`).
    disturb: Disturb,
}

/// The state of `[walk.perturb]`'s disturbances in an episode: their random stream, the time
/// of the next push, and the actions still waiting to act.
struct Disturb {
    rng: ChaCha8Rng,
    next_push: f32,
    delayed: std::collections::VecDeque<Vec<f32>>,
    /// This episode's motor strength (`strength`, or drawn from `strength_range`).
    strength: f32,
}

/// Mixed into the reset seed for the disturbances' own stream.
const PERTURB_STREAM: u64 = 0x5045_5254_5552_4221;

impl Disturb {
    fn reset(seed: u64, p: &Perturb, n_a: usize) -> Self {
        let mut d = Self {
            rng: ChaCha8Rng::seed_from_u64(seed ^ PERTURB_STREAM),
            next_push: 0.0,
            delayed: (0..p.action_delay).map(|_| vec![0.0; n_a]).collect(),
            strength: p.strength,
        };
        d.next_push = d.jittered(p.push_every);
        d
    }

    /// A draw uniform in `[lo, hi]`.
    fn uniform(&mut self, [lo, hi]: [f32; 2]) -> f32 {
        if hi > lo {
            self.rng.random_range(lo..=hi)
        } else {
            lo
        }
    }

    /// `every` ± up to a quarter of it.
    fn jittered(&mut self, every: f32) -> f32 {
        every * (1.0 + self.rng.random_range(-0.25f32..=0.25))
    }

    /// The velocity change of a push of `speed` m/s in `direction`.
    fn push(&mut self, speed: f32, direction: PushDirection) -> [f32; 3] {
        let sign = if self.rng.random_bool(0.5) { 1.0 } else { -1.0 };
        match direction {
            PushDirection::Sagittal => [sign * speed, 0.0, 0.0],
            PushDirection::Lateral => [0.0, sign * speed, 0.0],
            PushDirection::Any => {
                let a = self.rng.random_range(0.0..std::f32::consts::TAU);
                [speed * a.cos(), speed * a.sin(), 0.0]
            }
        }
    }
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
        let shared = WalkShared::new(model, config)?;
        // The checked constructor, once: every later world is built from the same setup.
        let sim = RobotSim::new(
            shared.model.clone(),
            &shared.setup,
            &shared.standing_state(),
        )?;
        Ok(Self::with_sim(Arc::new(shared), sim))
    }

    /// Another environment on the same parsed model and config, standing still (cheap: no
    /// URDF parsing). Call [`Env::reset`] before use.
    pub fn spawn(&self) -> Self {
        let s = &self.shared;
        let sim = RobotSim::build(s.model.clone(), &s.setup, &s.standing_state());
        Self::with_sim(self.shared.clone(), sim)
    }

    fn with_sim(shared: Arc<WalkShared>, sim: RobotSim) -> Self {
        let n_a = shared.actuated.len();
        let disturb = Disturb::reset(0, &shared.config.perturb, n_a);
        Self {
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
            start_phase: None,
            feet: reward::FootPhases::reset([false; 2]),
            disturb,
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

    /// The left↔right mirror of this task's observations and actions ([`Mirror`], module
    /// `mirror`): an error names the joint or foot without a mirror partner.
    pub fn mirror(&self) -> Result<Mirror, SimError> {
        mirror::mirror(&self.shared)
    }

    /// A name for every observation index, e.g. `joint_angle/left_knee`.
    pub fn obs_names(&self) -> Vec<String> {
        let s = &self.shared;
        observation::names(
            &s.model,
            &s.sources(),
            &s.config.foot_links,
            s.config.gait_clock.is_some(),
        )
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

    /// The ground's normal force on each foot now (left, right), N.
    pub fn foot_forces(&self) -> [f32; 2] {
        self.shared.feet.map(|f| self.sim.ground_normal_force(f))
    }

    /// Each foot link origin's height in the standing pose (left, right), m.
    pub fn standing_foot_heights(&self) -> [f32; 2] {
        self.shared.foot_height.map(|h| h as f32)
    }

    /// Each foot link origin's height above where it is in the standing pose (left, right),
    /// m: what the gait clock's clearance term reads.
    pub fn foot_heights(&self) -> [f32; 2] {
        let s = &self.shared;
        [0, 1].map(|i| self.sim.link_pose(s.feet[i]).translation.z - s.foot_height[i] as f32)
    }

    /// Whether each foot is down now by the gait clock's contact force (no clock: neither).
    fn feet_down(&self, s: &WalkShared) -> [bool; 2] {
        match &s.config.gait_clock {
            Some(c) => self.foot_forces().map(|n| n > c.contact_force),
            None => [false; 2],
        }
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

    /// The gait-clock phase φ ∈ [0, 1) the current episode started from: the reset seed's
    /// draw, or the phase set by [`WalkEnv::set_start_phase`] (0 without a clock).
    pub fn reset_phase(&self) -> f32 {
        self.phase0
    }

    /// Sets the gait-clock phase φ ∈ [0, 1) that every following [`Env::reset`] starts from
    /// instead of the one drawn from its seed (the rest of the reset is the seed's, and the
    /// seed's stream is drawn as before), or, with `None`, goes back to the seed's draw. A
    /// value outside [0, 1) is wrapped into it. No effect without a gait clock. The walking
    /// check of `esrl-run` starts its episodes at phases spread over the cycle this way.
    pub fn set_start_phase(&mut self, phase: Option<f32>) {
        self.start_phase = phase.map(|p| p.rem_euclid(1.0));
    }

    /// The joint angle target of actuated joint `k` for action `a` in `target` mode (module
    /// docs, "Action"): the standing angle at 0, the joint's limits at ±1, linear in between
    /// on each side; with [`TargetServo::range`] (or the joint's
    /// [`TargetServo::joint_range`]), `q_stand + a·span` clamped to the limits.
    pub fn target_angle(&self, k: usize, a: f32) -> f32 {
        let s = &self.shared;
        let stand = s.standing_q[s.actuated[k]] as f32;
        let [lo, hi] = s.range[k];
        let a = if a.is_finite() {
            a.clamp(-1.0, 1.0)
        } else {
            0.0
        };
        if let Some(span) = s.target_span[k] {
            return (stand + a * span).clamp(lo, hi);
        }
        if a >= 0.0 {
            stand + a * (hi - stand)
        } else {
            stand + a * (stand - lo)
        }
    }

    /// Clamps `action` (NaN reads as 0), keeps it as the previous action of the next
    /// observation, and hands the action due now to the joints (module docs, "Action"): this
    /// one, or with `perturb.action_delay` = d the one of d steps before.
    fn apply_action(&mut self, action: &[f32]) {
        let s = self.shared.clone();
        for (k, a) in self.prev_action.iter_mut().enumerate() {
            let v = action.get(k).copied().unwrap_or(0.0);
            *a = if v.is_finite() {
                v.clamp(-1.0, 1.0)
            } else {
                0.0
            };
        }
        let due = if s.config.perturb.action_delay > 0 {
            self.disturb.delayed.push_back(self.prev_action.clone());
            self.disturb
                .delayed
                .pop_front()
                .unwrap_or_else(|| vec![0.0; s.actuated.len()])
        } else {
            self.prev_action.clone()
        };
        let strength = self.disturb.strength;
        for (k, &j) in s.actuated.iter().enumerate() {
            let a = due[k];
            let effort = s.effort[k] * strength;
            match s.config.action {
                ActionMode::Torque => self.sim.set_joint_torque(j, a * effort),
                ActionMode::Target => {
                    let t = &s.config.target;
                    let target = self.target_angle(k, a);
                    self.sim
                        .set_joint_motor(j, target, t.stiffness, t.damping, effort);
                }
            }
        }
    }

    /// A push due now (`perturb.push_speed` > 0): the robot's velocity changes by the push,
    /// and the next one is scheduled.
    fn push_if_due(&mut self) {
        let p = &self.shared.config.perturb;
        if p.push_speed <= 0.0 {
            return;
        }
        let t = self.steps as f32 * self.shared.config.control_period;
        if t + 1e-6 >= self.disturb.next_push {
            let dv = self.disturb.push(p.push_speed, p.push_direction);
            self.sim.push_root(dv);
            let every = p.push_every;
            self.disturb.next_push += self.disturb.jittered(every);
        }
    }

    /// The observation with `perturb.obs_noise` added.
    fn noisy(&mut self, mut obs: Vec<f32>) -> Vec<f32> {
        let sd = self.shared.config.perturb.obs_noise;
        if sd > 0.0 {
            for o in &mut obs {
                let e: f32 = self.disturb.rng.sample(rand_distr::StandardNormal);
                *o += sd * e;
            }
        }
        obs
    }

    /// Runs the control period's Rapier steps, averaging each actuated joint's delivered
    /// torque, power and |power| over them (module docs, "Power").
    fn advance_physics(&mut self) {
        let s = self.shared.clone();
        let substeps = s.config.physics.substeps as usize;
        let share = 1.0 / substeps as f32;
        let h = self.sim.dt();
        self.last_torque.fill(0.0);
        self.last_power.fill(0.0);
        self.last_abs_power.fill(0.0);
        let mut start = vec![(0.0f32, 0.0f32); s.actuated.len()];
        for _ in 0..substeps {
            for (k, st) in start.iter_mut().enumerate() {
                let j = s.actuated[k];
                *st = (self.sim.joint_position(j), self.sim.servo_torque(j));
            }
            self.sim.step();
            for (k, &(q0, servo0)) in start.iter().enumerate() {
                let j = s.actuated[k];
                // The work of the physics step over its length. The applied torque is
                // constant over the step; a servo's is taken as the mean of its law at the
                // step's start and end.
                let tau = self.sim.applied_torque(j) + 0.5 * (servo0 + self.sim.servo_torque(j));
                let p = tau * (self.sim.joint_position(j) - q0) / h;
                self.last_torque[k] += tau * share;
                self.last_power[k] += p * share;
                self.last_abs_power[k] += p.abs() * share;
            }
        }
    }

    fn observation(&self) -> Vec<f32> {
        let sources = self.shared.sources();
        let phase = self
            .shared
            .config
            .gait_clock
            .is_some()
            .then(|| self.phase());
        observation::observe(
            &sources,
            &self.sim,
            &self.prev_action,
            self.acceleration,
            phase,
        )
    }
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
        let (state, drawn) = s.initial_state(seed);
        self.disturb = Disturb::reset(seed, &s.config.perturb, s.actuated.len());
        let p = &s.config.perturb;
        if p.friction_range.is_some()
            || p.mass_range.is_some()
            || p.contact_frequency_range.is_some()
            || p.slope_range.is_some()
        {
            // Domain randomisation: this episode's friction, masses, ground contact and
            // slope.
            let mut setup = s.setup.clone();
            if let Some(r) = p.friction_range {
                setup.physics.friction = self.disturb.uniform(r);
            }
            if let Some(r) = p.mass_range {
                setup.physics.mass_scale = self.disturb.uniform(r);
            }
            if let Some(r) = p.contact_frequency_range {
                setup.physics.contact_frequency = self.disturb.uniform(r);
            }
            if let Some(r) = p.slope_range {
                setup.physics.slope = self.disturb.uniform(r).to_radians();
            }
            self.sim = RobotSim::build(s.model.clone(), &setup, &state);
        } else {
            self.sim = RobotSim::build(s.model.clone(), &s.setup, &state);
        }
        self.disturb.strength = match p.strength_range {
            Some(r) => self.disturb.uniform(r),
            None => p.strength,
        };
        self.phase0 = match (&s.config.gait_clock, self.start_phase) {
            (Some(_), Some(phase)) => phase,
            _ => drawn,
        };
        self.prev_action.fill(0.0);
        self.prev_velocity = self.sim.link_origin_velocity(s.torso);
        self.acceleration = Vector::ZERO;
        self.steps = 0;
        self.last_torque.fill(0.0);
        self.last_power.fill(0.0);
        self.last_abs_power.fill(0.0);
        self.feet = reward::FootPhases::reset(self.feet_down(&s));
        let obs = self.observation();
        self.noisy(obs)
    }

    fn step(&mut self, action: &[f32]) -> Step {
        let s = self.shared.clone();
        self.apply_action(action);
        self.push_if_due();
        self.advance_physics();
        self.steps += 1;
        let v_world = self.sim.link_origin_velocity(s.torso);
        self.acceleration = (v_world - self.prev_velocity) / s.config.control_period;
        self.prev_velocity = v_world;

        let obs = self.observation();
        let pose = self.sim.link_pose(s.torso);
        let torso = reward::Torso {
            pose,
            vx: v_world.x,
            z: pose.translation.z - s.standing_height as f32,
        };
        let effort = reward::Effort {
            action: &self.prev_action,
            torque: &self.last_torque,
            abs_power: &self.last_abs_power,
            limit: &s.effort,
        };
        let force = self.foot_forces();
        let short_phases = match &s.config.gait_clock {
            Some(c) => {
                let down = force.map(|n| n > c.contact_force);
                let min_steps = c.min_phase_steps(s.config.control_period);
                self.feet.advance(down, min_steps)
            }
            None => 0,
        };
        let feet = reward::Feet {
            force,
            height: self.foot_heights(),
            phase: self.phase(),
            short_phases,
        };
        let finite = obs.iter().all(|v| v.is_finite());
        let outcome = reward::step_outcome(&s.config, &torso, finite, &effort, &feet);
        let obs = self.noisy(obs);
        let terminated =
            outcome.fell || outcome.off_course || (outcome.success && s.config.end_at_finish);
        let truncated = !terminated && self.steps >= s.max_steps;
        let gait = GaitSample {
            time: self.steps as f32 * s.config.control_period,
            torso_position: pose.translation.to_array(),
            torso_rotation: pose.rotation.to_array(),
            forward_velocity: torso.vx,
            lateral_offset: pose.translation.y,
            height_error: torso.z,
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
            foot_force: feet.force,
            fell: outcome.fell,
            off_course: outcome.off_course,
            success: outcome.success,
        };
        Step {
            obs,
            reward: outcome.reward,
            terminated,
            truncated,
            info: StepInfo {
                reward_terms: outcome.terms,
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
