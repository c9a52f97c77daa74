//! Rapier multibody humanoid built from URDF, the walking environment and a pendulum sanity task.
//!
//! - [`RobotModel`]: a URDF parsed with urdf-rs and validated (tree structure, physical
//!   inertials, primitive geometry, supported joints) into plain data. Parse once, share it
//!   with [`std::sync::Arc`], build any number of worlds from it.
//! - [`RobotSim`]: one model in one Rapier world: a reduced-coordinate multibody with the
//!   URDF's masses, centres of mass and full inertia tensors, revolute joints with limits,
//!   `<dynamics>` damping and friction, colliders from `<collision>`, a flat ground, joint
//!   torques in, state out.
//! - [`WalkEnv`]: the walking task of the paper (SPEC §2) behind the [`Env`] trait, with the
//!   observation, reward and episode documented in [`walk`]. [`Pendulum`] is Gymnasium's
//!   `Pendulum-v1` behind the same trait. [`bench::bench_walk`] measures throughput.
//!
//! ```
//! use esrl_sim::{Env, WalkConfig, WalkEnv};
//!
//! let mut env = WalkEnv::new(WalkConfig::default())?;
//! let obs = env.reset(42);
//! assert_eq!(obs.len(), env.obs_dim()); // 43 for the embedded humanoid
//! let step = env.step(&vec![0.0; env.act_dim()]);
//! let total: f32 = step.info.reward_terms.iter().map(|(_, r)| r).sum();
//! assert!((total - step.reward).abs() < 1e-6);
//! // Siblings share the parsed model: cheap to make one per worker thread.
//! let _other = env.spawn();
//! # Ok::<(), esrl_sim::SimError>(())
//! ```
//!
//! # Frames
//!
//! ROS REP-103: world z up, the track runs along +x from the origin, y is lateral (left
//! positive). **The paper calls forward `y` and lateral `x`: its `ẏ` is our `vx`, its `x` our
//! `y`.** Joint angles follow the URDF axes; for the humanoid (all pitch axes +y), positive
//! hip, knee and ankle angles swing the distal segment backwards: hip extension, knee flexion,
//! ankle plantarflexion. See `assets/README.md` for the robot.
//!
//! # Torque control
//!
//! A joint torque τ enters as a pair of external torques `+τ·a` on the child link and `−τ·a`
//! on the parent, `a` the joint axis in the world at the start of each Rapier step (SPEC §9,
//! first option). Rapier maps link wrenches to generalised forces through the link Jacobians,
//! so the pair adds exactly τ to the joint's coordinate and cancels on every other one
//! (`tests/pendulum_urdf.rs` checks `α = τ/I` on a pendulum and on two free bodies). The
//! torque is held for the whole control period; with more than one solver iteration per step
//! the axis is the one at the start of the step, which scales the torque by `cos Δφ` for a
//! parent rotating by `Δφ` within 25 ms (< 1 % below 8 rad/s). `WalkEnv` scales actions in
//! `[-1, 1]` (clamped; NaN reads as 0) by each joint's `<limit effort>`.
//!
//! # Physics step
//!
//! Defaults ([`PhysicsConfig`]): one Rapier step per 25 ms control period with 16 solver
//! iterations (in Rapier 0.36 each iteration is an integration substep, so the integrator step
//! is 1.56 ms), friction 1, and an actuator armature of 0.1 kg·m² on the six torque-controlled
//! joints. Measured on this repository's machine (2 shared cores):
//!
//! | solver iterations (× 1 step of 25 ms) | 1 | 2 | 3 | 4 | 8 | 16 | 32 |
//! |---|---|---|---|---|---|---|---|
//! | 60 s PD standing, max torso drift (< 5 cm required) | 3.4 cm | 1.4 cm | 1.4 cm | 1.4 cm | 1.4 cm | 1.5 cm | 1.5 cm |
//! | worst joint-limit overshoot, full effort, armature 0.1 (< 6° required) | 68° | 11° | 17° | 4.9° | 3.6° | 1.1° | 0.4° |
//! | same without armature | 208° | 88° | 60° | 35° | 6.8° | 1.8° | 0.5° |
//! | rigid-stance creep over 59 s, armature 0.5, worst of those that stay up (< 2.95 m, i.e. 0.05 m/s, required) | fell | fell | 11.2 m | 9.0 m | 4.1 m | 1.75 m | 0.90 m |
//! | control steps/s, random actions, one core (approx.) | 20k | 12k | 10k | 8k | 4k | 2.1k | 1.1k |
//!
//! The creep row is what decided the default. A stance with both hips and knees pressed into
//! their limits at full effort and constant ankle torques is a rigid object on flat ground: it
//! should not travel. With a coarse integrator step the limit-pressed joints chatter (mean
//! joint speed 0.5 rad/s at 4 iterations, 0.12 at 16, falling in proportion to the step), and
//! the chattering feet ratchet the body across the floor: 9 m forward and up to 6 m sideways
//! in a minute at 4 iterations, the former default. Learned policies found this: trained at
//! 4 iterations, the best ES-SAC policy pressed hips and knees into their limits and "walked"
//! 9 m in 60 s without a step (`results/README.md`). 16 iterations bring the creep under
//! 0.03 m/s (3 % of the paper's ES-SAC walking speed of 1.05 m/s; `tests/rigid_stance.rs`
//! requires < 0.05 m/s) at a quarter of the throughput; 32 halve it again at half that.
//!
//! (`cargo run --release -p esrl-sim --example physics_table` reproduces the table; the
//! throughput varies by ±20 % with the load of the 2 shared cores it was measured on.
//! `cargo run --release -p esrl-sim --example bench_env -- 30000` or `esrl bench env` measure
//! the default settings alone.)
//!
//! Substeps (several Rapier steps per control period) cost more than solver iterations for
//! the same integrator step (collision detection runs each step) and gave nothing the
//! iterations do not. One iteration already stands still, so standing is not what bounds the
//! step: joint limits are (next section). Throughput is bounded by Rapier's multibody
//! dynamics: about 55 % of the time goes into assembling the 16 × 16 joint-space mass matrix
//! (`Multibody::update_mass_matrix`, dense nalgebra `quadform` per link) at every solver
//! substep, so the cost grows linearly with the iterations. Reset (building a fresh world)
//! costs about 80 µs.
//!
//! # Joint limits
//!
//! Rapier's multibody joint limits only act once a joint is past them. A joint that reaches a
//! limit at speed `v` overshoots by about `v·h` (`h` the integrator step), and a joint pushed
//! into a limit by torque `τ` through inertia `I` chatters by about `½(τ/I)h²`. The foot is the
//! worst case: 1 kg with 0.012 kg·m² about the ankle against 120 N·m is 10⁴ rad/s², 22° of
//! chatter at `h` = 6.25 ms. A reflected actuator inertia (MuJoCo's `armature`, standard for
//! geared actuators and used by MuJoCo's humanoids) of 0.1 kg·m² on the actuated joints brings
//! this to 2.4° held and 4.9° worst overshoot on full-speed, full-effort swings
//! (`tests/joint_limits.rs`); 0.3 kg·m² would bring everything under 3° but slows the swing
//! leg noticeably. During falls, ground impacts can still push a joint up to ~13° past its
//! limit for a step. Set [`PhysicsConfig::actuator_armature`] to 0 for none.
//!
//! # Standing
//!
//! `tests/standing.rs` holds the standing pose for 60 s with a PD law run inside Rapier as an
//! implicit spring-damper ([`RobotSim::set_joint_servo`]). A PD sampled once per 25 ms cannot
//! hold this body: with a zero-order hold, a joint is stable only for
//! `kp·T/2 < kd < 2·I/T` (T = 25 ms), the near-straight knee and the thigh modes have effective
//! inertias of 0.1–0.3 kg·m², and balancing the 70 kg inverted pendulum needs ankle stiffness
//! above `m·g·h` ≈ 620 N·m/rad. Searches over hundreds of gain sets found none that keeps the
//! torso within 5 cm for a minute across seeds (the best stood but shuffled 25 cm in a limit
//! cycle). That is a property of the 40 Hz control loop (the agents face it too), not of the
//! simulator: the same explicit PD (kp = 800, kd = 4) keeps the robot upright when sampled at
//! 200 Hz.
//!
//! # Known limitations
//!
//! - Rapier 0.36 integrates a free multibody root's centre-of-mass velocity as the velocity of
//!   its frame origin; [`RobotSim`] therefore puts the root body's frame at its centre of mass
//!   and converts ([`RobotSim::link_pose`] reports URDF link frames).
//! - Rapier's first-order multibody integrator does not conserve momentum exactly: floating in
//!   zero gravity, the humanoid's centre of mass drifts 2 mm over 4 s at joint speeds of
//!   3 rad/s, 3–8 cm at 9 rad/s and decimetres at 25 rad/s (a spurious acceleration of ≲ 1 %
//!   of g even then).
//! - Rigid-body velocities of multibody links lag one solver substep after a step; this crate
//!   reads link velocities from the multibody's generalised velocities instead.
//! - Only revolute, continuous and fixed joints, and box, cylinder and sphere collision shapes.
//!   Self-collisions are off by default ([`PhysicsConfig::self_collisions`]).
#![forbid(unsafe_code)]

pub mod bench;
mod env;
mod error;
mod math;
mod model;
pub mod pendulum;
mod sim;
pub mod walk;

pub use env::{Env, GaitSample, Step, StepInfo};
pub use error::{SimError, UrdfError};
pub use model::{
    JointKind, JointModel, LinkGeometry, LinkModel, LinkPose, RobotModel, Shape, ShapeGeometry,
    HUMANOID_URDF, MAX_LINKS,
};
pub use pendulum::Pendulum;
pub use sim::{Base, PhysicsConfig, RobotSim, RobotState, SimSetup};
pub use walk::{FallConfig, InitNoise, ObsLayout, RewardConfig, WalkConfig, WalkEnv};
