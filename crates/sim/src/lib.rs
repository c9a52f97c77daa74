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
//! - [`run_episode`]: the one episode loop of esrl (reset, act, step until the episode ends),
//!   with an [`EpisodeHook`] for what each caller needs: learning, keeping transitions, gait
//!   samples, recording.
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
//! torque is commanded for the whole control period and re-applied, through the joint-limit
//! model, at each of its Rapier steps; within a step the axis is the one at its start, which
//! scales the torque by `cos Δφ` for a parent rotating by `Δφ` within 6.25 ms. `WalkEnv` scales
//! actions in `[-1, 1]` (clamped; NaN reads as 0) by each joint's `<limit effort>`, or, with
//! `walk.action = "target"`, sets the targets of in-solver position servos ([`walk`] module
//! docs, "Action").
//!
//! # Physics step and joint limits
//!
//! Defaults ([`PhysicsConfig`]): 4 Rapier steps of 6.25 ms per 25 ms control period, one
//! solver iteration each (in Rapier 0.36 each iteration is an integration substep, so 1 × 4
//! and 4 × 1 integrate with the same step), `fade` joint limits with a 2° band, friction 1,
//! and an actuator armature of 0.1 kg·m² on the six torque-controlled joints.
//!
//! **Joint-limit models** ([`LimitModel`]):
//!
//! - `hard`: Rapier's rigid one-sided limit, torques applied unchanged. A torque pushing into
//!   a limit is held there for free (eq. 12's power term is `|τ·ω|` and `ω ≈ 0` there), and
//!   with a coarse integrator step the pressed joint chatters against the stop.
//! - `fade` (default): the rigid limit, and a torque that pushes a joint towards a limit is
//!   scaled by `clamp(d/band, 0, 1)`, `d` the joint's distance to that limit, at the start of
//!   every Rapier step: full torque until 2° before the limit, none at and past it; a torque
//!   pulling away from the limit is untouched. Near a limit the actuator therefore behaves like
//!   a spring of stiffness `τ/band` towards the limit that cannot push past it: it can hold a
//!   joint next to its stop against a load (and pays for it in torque, `reward.torque_sq`),
//!   but it cannot press the joint into the stop. A load from the rest of the body (gravity
//!   on a straight knee, the torso leaning on its hips) still rests on the rigid stop for free,
//!   as on a real joint's end stop or ligament. The 2° band (the probe's,
//!   `notes/walking-probes.md`) is the narrowest that passes at the default step: at 1° the
//!   stiffer fade (`τ/band`, sampled every 6.25 ms) lets joints be seen 7.8° past their limits
//!   and 2 of the 30 pressing stances stay up (0.37 m); 4° passes too (5.0°, held 2.5°) but
//!   takes torque away over a fifth of the ankle's ±20° range. `tests/actuators.rs` checks
//!   the law on a pendulum (rest where `τ·d/band = m g l sin q`, off the stop, where `hard`
//!   rests on it).
//! - `soft`: no rigid stop; Rapier's limit constraint made compliant (natural frequency 20 Hz,
//!   damping ratio 1 about the joint's effective inertia), a one-sided implicit spring-damper
//!   past the limit as Simscape models joint limits. Torques unchanged.
//!
//! Measured on this repository's machine (`cargo run --release -p esrl-sim --example
//! physics_table`; instructions per control step from `valgrind --tool=callgrind` on
//! `examples/bench_env.rs`, 2000 steps of random actions with resets, immune to the load of
//! the 2 shared cores):
//!
//! | limits | Rapier steps × iterations (integrator step) | 60 s PD standing, max drift (< 5 cm) | overshoot seen per control step (< 6°) | peak overshoot between control steps | held from the limit (< 3°) | limit-pressing stances up 60 s, of 30 | their worst travel in 59 s (< 2.95 m) | instructions per control step |
//! |---|---|---|---|---|---|---|---|---|
//! | `hard` | 1 × 16 (1.56 ms) | 1.5 cm | 1.1° | – | 0.2° | 5 | 2.86 m | 6.88 M |
//! | `hard` | 1 × 4 (6.25 ms) | 1.4 cm | 4.9° | – | 2.4° | 9 | **8.96 m** | 1.87 M |
//! | `hard` | 4 × 1 (6.25 ms) | 1.4 cm | 6.2° | 7.5° | 2.4° | 8 | **8.76 m** | 2.24 M |
//! | `fade`, once per 25 ms | 1 × 4 (6.25 ms) | 1.4 cm | **7.0°** | – | **3.4°** | 1 | 0.31 m | 1.87 M |
//! | `fade` | 2 × 1 (12.5 ms) | 1.4 cm | **13.7°** | 20.9° | 1.3° | 0 | – | 1.18 M |
//! | `fade` | 3 × 1 (8.3 ms) | 1.4 cm | **7.8°** | 21.4° | 1.3° | 0 | – | 1.71 M |
//! | **`fade`** | **4 × 1 (6.25 ms; default)** | 1.4 cm | 5.2° | 17.8° | 1.3° | 0 | – | **2.25 M** |
//! | `fade` | 5 × 1 (5 ms) | 1.4 cm | **6.0°** | 12.7° | 1.2° | 0 | – | 2.78 M |
//! | `fade` | 8 × 1 (3.1 ms) | 1.4 cm | 1.3° | 8.5° | 1.2° | 0 | – | 4.36 M |
//! | `soft` | 4 × 1 (6.25 ms) | 1.4 cm | **12.5°** | 12.5° | **5.7°** | 0 | – | 2.26 M |
//!
//! Columns: the PD-standing test (`tests/standing.rs`); the joint-limit test
//! (`tests/joint_limits.rs`: actuated joints swung at full effort through their whole range
//! with the torso held in the air, sampled once per control period as the environment
//! observes them, plus the peak over every Rapier step); the limit-pressing stance
//! (`tests/rigid_stance.rs`: action `[1, −1, a, 1, −1, a]` held 60 s, 5 ankle actions × 3
//! reset seeds × armature 0.1 and 0.5; a stance that stays up must travel less than
//! 0.05 m/s). Bold: a failed requirement. In 1 × N rows the solver's substeps are not
//! observable, so only the per-control-step value exists.
//!
//! What decided the default:
//!
//! - **`hard` limits are a brace.** A stance with hips and knees pressed into their limits at
//!   full effort stays up and ratchets 9 m a minute across the floor at a 6.25 ms step: the
//!   pressed joints chatter (0.55 rad/s) and the feet walk the rigid body along. Learned
//!   policies found this (`results/README.md`). Only a 1.56 ms step (16 iterations, 3× the
//!   cost of the default) brings it under 0.05 m/s.
//! - **`fade` removes it at the coarse step.** No actuator torque presses a stop, so nothing
//!   chatters: every one of the 30 stances falls (the brace is gone) instead of creeping, at
//!   every step size tried.
//! - **The fade must act every Rapier step.** Applied once per 25 ms control period (1 × 4)
//!   it is a spring of stiffness `τmax/band` ≈ 4300 N·m/rad sampled at 25 ms, far beyond the
//!   `2I/T²` a sampled spring tolerates on a 0.1–0.4 kg·m² joint: it limit-cycles, holding
//!   joints 3.4° off their limits and overshooting 7°. Every 6.25 ms it holds 1.3°.
//! - **4 Rapier steps are the fewest that keep limits.** With fewer, the joints swung at full
//!   effort are seen 7.8° (3 steps) and 13.7° (2 steps) past their limits. A Rapier limit
//!   acts only once a joint is past it, so a joint arriving at `v` goes `≈ v·h` through it
//!   before being pushed back: the peak between control steps, 17.8° at the default, is a
//!   knee whipped to 30 rad/s by the hip stopping at its own limit, for a few milliseconds.
//!   The per-control-step overshoot is not monotonic in the step (5 × 1 sees 6.0°), because
//!   whips land at different phases of the control period; 8 × 1 brings both under 8.5°.
//! - **`soft` limits are not limits** at full effort: 12.5° past and held 5.7° off.
//! - An in-solver fade (a Rapier motor with stiffness `τ/band` towards the limit, force
//!   clamped to `τ`, at 1 × 4) held 0.7° and overshot 5.2° at 1.94 M instructions, but motor
//!   impulses are constraint impulses, which Rapier does not integrate as momentum-exactly
//!   as external torques: the humanoid's centre of mass drifted 23.5 mm in 4 s of zero-gravity
//!   joint motion instead of 1.2 mm (`tests/momentum.rs` allows 3 mm). Rejected.
//!
//! **Throughput.** `esrl bench env` (random actions, resets included) side by side with
//! MuJoCo stepping the same URDF at 5 ms × 5 per control step
//! (`python ../shared/peers/mujoco_urdf.py assets/humanoid.urdf`), on a 2-core machine shared
//! with other builds and trainings (load average 5–7), both pinned to the same core:
//!
//! - wall clock, alternating runs: at load average 6–7, esrl 3.1–4.1k control steps/s,
//!   MuJoCo 5.5–6.3k (0.61 on the means), `hard` at 1 × 16 1.2k; at load
//!   average 4–5, esrl 4.5–4.7k, MuJoCo 8.3–8.4k (0.54–0.56);
//! - CPU time (`perf stat -e task-clock`, long run minus short run, so start-up and
//!   descheduling drop out; five alternating rounds in two sessions): esrl 4.8–4.9k control
//!   steps per CPU-second, MuJoCo 8.3–8.8k, ratio 0.56–0.59;
//! - instructions (callgrind): esrl 2.25 M per control step, MuJoCo 0.82 M (0.79 M in
//!   `mj_step`, the rest the Python loop). MuJoCo retires fewer instructions per step but at a
//!   lower rate, so the instruction ratio (0.37) understates esrl's speed.
//!
//! MuJoCo runs 10.8–11.3k steps/s on an idle core of this kind of machine
//! (`../shared/peers/README.md`); at the measured ratio that puts esrl near 6k there, while
//! this shared machine gave 4.8–4.9k per CPU-second. Where a control step's 2.25 M instructions go
//! (callgrind, default settings, inclusive, so the rows overlap): Rapier's reduced-coordinate
//! multibody dynamics dominate, every Rapier step: assembling the 16 × 16 joint-space mass
//! matrix (`Multibody::update_mass_matrix`, dense nalgebra `quadform` and `gemm` per link,
//! twice: with and without gyroscopic terms) 58 %, its two LU factorisations and the solves
//! against them (joint-limit and contact rows each solve `M⁻¹Jᵀ`) 11 %, forward kinematics
//! 8 %, link Jacobians 5 %, accelerations 4 %; building the contact constraints 6 %, the
//! solver's sweeps over all constraints 2 %; collision detection 3 %, continuous collision
//! detection 1.5 %; everything of this crate (torques, fade, observation, reward) 1 %;
//! resets (a new world per episode, about every 22 steps under random actions) 1 %. The cost
//! is linear in the Rapier steps (0.56 M instructions each), and 70–80 % of it is Rapier's
//! multibody dynamics, which this crate cannot change: 5k steps/s per CPU-second on this
//! machine's shared cores would need fewer than 4 Rapier steps, which the joint limits do not
//! allow (table), or a cheaper mass matrix inside Rapier.
//!
//! (`cargo run --release -p esrl-sim --example bench_env -- STEPS SUBSTEPS ITERATIONS
//! [hard|fade|soft] [torque|target]` times single settings; `target` mode costs 2.34 M
//! instructions per control step.)
//!
//! The armature: a joint that reaches a limit at speed `v` overshoots by about `v·h`, and one
//! pushed into it by torque `τ` through inertia `I` chatters by about `½(τ/I)h²`. The foot is
//! the worst case: 1 kg with 0.012 kg·m² about the ankle against 120 N·m. A reflected actuator
//! inertia (MuJoCo's `armature`, standard for geared actuators and used by MuJoCo's humanoids)
//! of 0.1 kg·m² on the actuated joints keeps it within the bounds above. The `quick` preset
//! uses 0.5 (a 40 Hz torque loop balances the body more easily: `examples/pd_stand.rs` stands
//! 60 s for 6 of 30 PD gain pairs at 0.5, 1 at 0.1, at the default physics as before): its
//! limit-pressing stances fall too (`tests/rigid_stance.rs` runs both), but the heavier hip
//! swung at full effort is seen 6.4° past its limit at control rate (peak 8.9° between; 4.5°
//! at 5 Rapier steps), just over the 6° the default meets. Set
//! [`PhysicsConfig::actuator_armature`] to 0 for none.
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
//! # Speed, and where it is bound
//!
//! `esrl bench env` runs 5,166–5,222 control steps per second on one core of the 2-core AMD
//! EPYC machine of `results/speed/` (random torques, resets included), against 11,681 for
//! MuJoCo stepping the same URDF at the same 4 × 6.25 ms measured beside it: **0.45×**. A
//! `perf` profile of the benchmark puts 40 % of a control step in Rapier's
//! `Multibody::update_mass_matrix` and nalgebra's `quadform` (each link's 6 × 16 Jacobian
//! turned into its contribution JᵀMJ to the 16 × 16 mass matrix, at each of the 4 substeps)
//! and 12 % in the dense LU factorisation and solves of that matrix; forward kinematics,
//! contacts and the constraint solver share the rest. The settings this crate controls are
//! at their floor (one solver iteration; the 6.25 ms step the physics tests and every result
//! were measured at), and nothing computed per substep here can move to once per control step
//! without changing the dynamics. The bound is inside Rapier, which this project uses as a
//! dependency. The upstream proposal: a link's Jacobian is non-zero only in the columns of its
//! ancestors' degrees of freedom (the 6 of the floating base and at most 3 of its own chain
//! for the humanoid), so `update_mass_matrix` could restrict each `quadform` to those column
//! ranges (about 3× less work for this tree), and the mass matrix could be factored with the
//! sparsity of the kinematic tree (Featherstone's LTL/LᵀDL factorisation of the composite-
//! rigid-body matrix) instead of a dense LU: the same numbers up to rounding, with the cost
//! growing with the tree's depth instead of the square of its size.
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
//! - Rapier's joint motors (the `target` action mode's servos, [`RobotSim::set_joint_motor`])
//!   act through constraint impulses, which conserve momentum less exactly than external
//!   torques: floating in zero gravity with servos swinging hips, knee and ankle at up to
//!   5 rad/s, the centre of mass drifts 9 cm in 4 s at the default step (3 cm at a 1.56 ms
//!   step), where torques at 3 rad/s move it 2 mm. On the ground friction and contact forces
//!   (hundreds of N) dwarf the spurious force (≈ 1 N). Rapier's implicit joint springs
//!   ([`RobotSim::set_joint_servo`]) drift 4 mm in the same test, but their torque cannot be
//!   clamped to the effort limit.
//! - A Rapier joint limit acts only once the joint is past it: between two control steps a
//!   joint slammed into its stop can be up to `v·h` beyond it (17.8° for a 30 rad/s whip).
//! - Only revolute, continuous and fixed joints, and box, cylinder and sphere collision shapes.
//!   Self-collisions are off by default ([`PhysicsConfig::self_collisions`]).
#![forbid(unsafe_code)]

pub mod bench;
mod env;
mod episode;
mod error;
mod math;
mod model;
pub mod pendulum;
mod sim;
pub mod walk;

pub use env::{Env, GaitSample, MakeEnv, Step, StepInfo};
pub use episode::{hooks, run_episode, EpisodeEnd, EpisodeHook, Hooks};
pub use error::{SimError, UrdfError};
pub use model::{
    read_text_file, JointKind, JointModel, LinkGeometry, LinkModel, LinkPose, RobotModel, Shape,
    ShapeGeometry, HUMANOID_URDF, MAX_LINKS, MAX_URDF_BYTES, MAX_XML_DEPTH,
};
pub use pendulum::Pendulum;
pub use sim::{Base, LimitModel, PhysicsConfig, RobotSim, RobotState, SimSetup};
pub use walk::{
    ActionMode, FallConfig, GaitClock, InitNoise, Mirror, ObsLayout, OrientationFrame, Perturb,
    PushDirection, ResetConfig, ResetPose, RewardConfig, TargetServo, UprightGate, WalkConfig,
    WalkEnv,
};
