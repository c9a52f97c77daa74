//! The environment contract shared by every task (Gymnasium semantics: `terminated` is a
//! real end of the task, `truncated` a time limit).

use serde::Serialize;

/// A reinforcement-learning environment with continuous actions in `[-1, 1]`.
pub trait Env: Send {
    /// Length of the observation vector.
    fn obs_dim(&self) -> usize;
    /// Length of the action vector.
    fn act_dim(&self) -> usize;
    /// Resets to a seeded initial state and returns the first observation.
    fn reset(&mut self, seed: u64) -> Vec<f32>;
    /// Applies `action` (each entry in [-1, 1]) for one control period.
    fn step(&mut self, action: &[f32]) -> Step;
    /// Control period in seconds.
    fn control_period(&self) -> f32;
    /// Steps after which an episode is truncated.
    fn max_episode_steps(&self) -> usize;
}

/// Makes a fresh environment at every call, from any thread: how parallel rollouts and
/// learners get theirs (an `Arc<MakeEnv>` is cheap to share).
pub type MakeEnv = dyn Fn() -> Box<dyn Env> + Send + Sync;

/// The outcome of one [`Env::step`].
#[derive(Clone, Debug, Serialize)]
pub struct Step {
    /// Observation after the step.
    pub obs: Vec<f32>,
    /// Reward of the step.
    pub reward: f32,
    /// The episode ended by the task itself (fall, success): do not bootstrap.
    pub terminated: bool,
    /// The episode was cut by the time limit: bootstrap from `obs`.
    pub truncated: bool,
    /// Diagnostics.
    pub info: StepInfo,
}

/// Per-step diagnostics.
#[derive(Clone, Debug, Default, Serialize)]
pub struct StepInfo {
    /// Named reward terms; they sum to [`Step::reward`].
    pub reward_terms: Vec<(&'static str, f32)>,
    /// Gait data (walk env only).
    pub gait: Option<GaitSample>,
}

/// Walk-env only: what the gait metrics and recordings need, for this step (after it).
#[derive(Clone, Debug, Default, Serialize)]
pub struct GaitSample {
    /// s since reset.
    pub time: f32,
    /// Torso link origin, world, m.
    pub torso_position: [f32; 3],
    /// Torso orientation, quaternion x, y, z, w.
    pub torso_rotation: [f32; 4],
    /// m/s, world x (torso link origin).
    pub forward_velocity: f32,
    /// Torso y, m.
    pub lateral_offset: f32,
    /// Torso z − standing z, m.
    pub height_error: f32,
    /// Actuated joints, rad, order of `WalkEnv::actuated_joint_names()`.
    pub joint_angle: Vec<f32>,
    /// rad/s.
    pub joint_velocity: Vec<f32>,
    /// Torque the actuator delivered, averaged over the control period's physics steps, N·m
    /// (after the joint-limit model; the servo's torque in `target` mode).
    pub joint_torque: Vec<f32>,
    /// Mechanical power delivered, W: each physics step's work `τ·Δq` over its length,
    /// averaged over the control period's physics steps (`walk` module docs, "Power").
    pub joint_power: Vec<f32>,
    /// The same with the absolute value taken per physics step, W: what the reward's power
    /// term averages over the joints.
    pub joint_abs_power: Vec<f32>,
    /// Left, right normal contact force, N.
    pub foot_force: [f32; 2],
    /// The torso fell (termination).
    pub fell: bool,
    /// The torso left the lateral band or turned beyond the yaw limit (termination; only when
    /// `fall.max_lateral` / `fall.max_yaw` are set).
    pub off_course: bool,
    /// The torso passed the end of the track (termination).
    pub success: bool,
}
