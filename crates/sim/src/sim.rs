//! A [`RobotModel`] instantiated in a Rapier world: one reduced-coordinate multibody, a flat
//! ground, torque inputs and state read-out.

use std::sync::Arc;

use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{SimError, UrdfError};
use crate::math::{self, Iso};
use crate::model::{JointKind, LinkPose, RobotModel, Shape};

/// How a joint behaves at the ends of its range (crate docs, "Physics step and joint limits").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LimitModel {
    /// Rapier's rigid one-sided limit constraint, torques applied unchanged: a torque pushing
    /// into a limit is held there for free, and a coarse integrator step makes the joint
    /// chatter against it.
    Hard,
    /// The rigid limit, plus: a torque `τ` that pushes a joint towards a limit is scaled by
    /// `clamp(d/band, 0, 1)`, `d` the distance to that limit (band
    /// [`PhysicsConfig::limit_band`]), at the start of every physics (Rapier) step: full
    /// torque until `band` before the limit, zero at and past it. Torques pulling away from
    /// a limit are untouched. An actuator cannot press a joint into its stop; loads from the
    /// rest of the body still rest on it. Evaluated once per Rapier step, the fade is a
    /// sampled spring of stiffness `|τ|/band`: it needs Rapier steps of a few milliseconds
    /// (crate docs, "Physics step and joint limits").
    Fade,
    /// No rigid stop: the limit is a one-sided implicit spring-damper acting past the limit
    /// (Rapier's soft constraint, natural frequency [`PhysicsConfig::limit_frequency`] and
    /// damping ratio [`PhysicsConfig::limit_damping_ratio`] about the joint's effective
    /// inertia), as Simscape models joint limits. Torques are applied unchanged.
    Soft,
}

/// Physics settings of a world: the integrator step, the solver, the contact model and the
/// joint limits.
///
/// The defaults are the fastest settings that pass the physics tests (standing, joint limits,
/// rigid-stance creep, pendulum, momentum); see the crate docs for the measurements behind
/// them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhysicsConfig {
    /// Rapier steps per control period; the physics step is `control_period / substeps`.
    /// Default 4, a physics step of 6.25 ms (crate docs, "Physics step and joint limits":
    /// the `fade` limits act once per Rapier step and need steps this short; with fewer,
    /// joints are seen more than 6° past their limits).
    pub substeps: u32,
    /// Rapier `num_solver_iterations`. In Rapier 0.36 each iteration is also an integration
    /// substep of `dt / solver_iterations`. Default 1 (crate docs, "Physics step and joint
    /// limits": with four Rapier steps per control period one iteration each is enough).
    pub solver_iterations: u32,
    /// Gravitational acceleration, m/s², along −z. Default 9.81 (standard gravity).
    pub gravity: f32,
    /// Coulomb friction coefficient of robot and ground colliders (Rapier averages the two).
    /// Default 1.0 (SPEC §2: "flat, friction about 1").
    pub friction: f32,
    /// Armature (reflected actuator inertia, kg·m², MuJoCo's `armature`) that `WalkEnv` adds
    /// to each torque-controlled joint. Default 0.1: see the crate docs ("Physics step and
    /// joint limits").
    pub actuator_armature: f32,
    /// Whether links of the robot collide with each other. Default false: with sagittal
    /// legs and limited shoulders the segments cannot meet in a meaningful way, and the
    /// paper's Simscape model only has foot/body–ground contact.
    pub self_collisions: bool,
    /// How joint limits act: `hard`, `fade` or `soft` ([`LimitModel`]). Default `fade`
    /// (crate docs, "Physics step and joint limits": the cheapest model that passes the
    /// physics tests, the limit-pressing one included).
    pub joint_limits: LimitModel,
    /// `fade`: width of the band before a limit over which a torque pushing into it fades
    /// to zero, rad. Default 2° = 0.0349 (`notes/walking-probes.md`; the narrowest that keeps
    /// joints within 6° of their limits at the default step, crate docs).
    pub limit_band: f32,
    /// `soft`: natural frequency of the limit spring about the joint's effective inertia, Hz.
    /// Default 20 (our choice, between Rapier's rigid 10⁶ Hz and a limit that sags under the
    /// body's weight; the crate docs' table measures it).
    pub limit_frequency: f32,
    /// `soft`: damping ratio of the limit spring. Default 1 (critical).
    pub limit_damping_ratio: f32,
    /// Every link's mass and inertia times this (a payload spread over the body, or a
    /// lighter build): a disturbance for robustness tests. Default 1 (the URDF's).
    #[serde(skip_serializing_if = "is_one")]
    pub mass_scale: f32,
    /// Ground slope, rad, positive uphill along +x: gravity is tilted by this angle about
    /// the lateral (y) axis, `g·(−sin s, 0, −cos s)`, so the flat ground acts as a slope.
    /// Default 0 (flat).
    #[serde(skip_serializing_if = "is_zero")]
    pub slope: f32,
    /// Natural frequency of the robot–ground contacts, Hz: Rapier's contacts are springs
    /// of this frequency (damping ratio 10) that correct a penetration beyond 5 mm, so it
    /// sets how far and how fast a loaded foot sinks in. Default 60, Rapier 0.36's own for
    /// contacts with a fixed body (`SpringCoefficients::contact_static_defaults`); lower is
    /// softer ground. A disturbance for robustness tests and training.
    #[serde(skip_serializing_if = "is_default_contact_frequency")]
    pub contact_frequency: f32,
}

/// Rapier 0.36's natural frequency of contacts with a fixed body, Hz.
pub const DEFAULT_CONTACT_FREQUENCY: f32 = 60.0;

fn is_default_contact_frequency(v: &f32) -> bool {
    *v == DEFAULT_CONTACT_FREQUENCY
}

fn is_one(v: &f32) -> bool {
    *v == 1.0
}

/// Whether a setting is 0, its default (serde's `skip_serializing_if` of optional terms).
pub(crate) fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

impl Default for PhysicsConfig {
    fn default() -> Self {
        Self {
            substeps: 4,
            solver_iterations: 1,
            gravity: 9.81,
            friction: 1.0,
            actuator_armature: 0.1,
            self_collisions: false,
            joint_limits: LimitModel::Fade,
            limit_band: 2.0f32.to_radians(),
            limit_frequency: 20.0,
            limit_damping_ratio: 1.0,
            mass_scale: 1.0,
            slope: 0.0,
            contact_frequency: DEFAULT_CONTACT_FREQUENCY,
        }
    }
}

impl PhysicsConfig {
    /// Checks the values, naming the field at fault (`prefix` is prepended to field names).
    pub fn validate(&self, prefix: &str) -> Result<(), SimError> {
        let bad = |field: &str, value: String, reason: &str| {
            Err(SimError::Config {
                field: format!("{prefix}{field}"),
                value,
                reason: reason.to_owned(),
            })
        };
        if self.substeps == 0 || self.substeps > 1000 {
            return bad("substeps", self.substeps.to_string(), "must be in 1..=1000");
        }
        if self.solver_iterations == 0 || self.solver_iterations > 1000 {
            return bad(
                "solver_iterations",
                self.solver_iterations.to_string(),
                "must be in 1..=1000",
            );
        }
        if !(self.gravity.is_finite() && self.gravity >= 0.0) {
            return bad(
                "gravity",
                self.gravity.to_string(),
                "must be finite and ≥ 0",
            );
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return bad(
                "friction",
                self.friction.to_string(),
                "must be finite and ≥ 0",
            );
        }
        if !(self.actuator_armature.is_finite() && self.actuator_armature >= 0.0) {
            return bad(
                "actuator_armature",
                self.actuator_armature.to_string(),
                "must be finite and ≥ 0",
            );
        }
        if !(self.limit_band.is_finite() && self.limit_band > 0.0 && self.limit_band < 1.0) {
            return bad(
                "limit_band",
                self.limit_band.to_string(),
                "must be in (0, 1) rad",
            );
        }
        if !(self.limit_frequency.is_finite() && self.limit_frequency > 0.0) {
            return bad(
                "limit_frequency",
                self.limit_frequency.to_string(),
                "must be finite and > 0",
            );
        }
        if !(self.mass_scale.is_finite() && self.mass_scale > 0.0 && self.mass_scale <= 100.0) {
            return bad(
                "mass_scale",
                self.mass_scale.to_string(),
                "must be in (0, 100]",
            );
        }
        if !(self.slope.is_finite() && self.slope.abs() < std::f32::consts::FRAC_PI_4) {
            return bad("slope", self.slope.to_string(), "must be within ±π/4 rad");
        }
        if !(self.limit_damping_ratio.is_finite() && self.limit_damping_ratio >= 0.0) {
            return bad(
                "limit_damping_ratio",
                self.limit_damping_ratio.to_string(),
                "must be finite and ≥ 0",
            );
        }
        if !(self.contact_frequency.is_finite()
            && (1.0..=10_000.0).contains(&self.contact_frequency))
        {
            return bad(
                "contact_frequency",
                self.contact_frequency.to_string(),
                "must be in [1, 10000] Hz",
            );
        }
        Ok(())
    }
}

/// How the root link is attached to the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Base {
    /// Free-floating (6 degrees of freedom), e.g. the humanoid's torso.
    Floating,
    /// Welded to the world, e.g. a pendulum's pivot.
    Fixed,
}

/// Everything needed to build a world around a model.
#[derive(Clone, Debug)]
pub struct SimSetup {
    /// Rapier step, s.
    pub dt: f32,
    /// Physics settings (all read here but `substeps`, which is the caller's business).
    pub physics: PhysicsConfig,
    /// Floating or fixed root.
    pub base: Base,
    /// Whether to add the flat ground (top surface at z = 0).
    pub ground: bool,
    /// Armature (reflected actuator inertia, kg·m², MuJoCo's `armature`) per joint in URDF
    /// order; missing entries are 0.
    pub armature: Vec<f32>,
}

/// Initial state of a robot: root position (upright), joint positions and velocities, one per
/// joint in URDF order (entries of fixed joints are ignored).
#[derive(Clone, Debug, Default)]
pub struct RobotState {
    /// Root link origin in the world, m. Orientation is the identity.
    pub base_position: [f64; 3],
    /// Joint positions, rad.
    pub q: Vec<f64>,
    /// Joint velocities, rad/s.
    pub qd: Vec<f64>,
}

/// An in-solver position servo on one joint ([`RobotSim::set_joint_motor`]).
#[derive(Clone, Copy, Debug)]
struct Servo {
    target: f32,
    stiffness: f32,
    damping: f32,
    max_torque: f32,
}

const ROBOT_GROUP: Group = Group::GROUP_1;
const GROUND_GROUP: Group = Group::GROUP_2;

/// One robot in one Rapier world.
pub struct RobotSim {
    world: PhysicsWorld,
    model: Arc<RobotModel>,
    bodies: Vec<RigidBodyHandle>,
    colliders: Vec<Vec<ColliderHandle>>,
    ground: Option<ColliderHandle>,
    multibody: Option<MultibodyIndex>,
    /// Per joint: multibody link id of its child.
    link_ids: Vec<usize>,
    /// Translation from the root link frame to the root body frame (its centre of mass).
    root_shift: Vector,
    /// Per joint: unit axis in the parent link frame.
    axis_in_parent: Vec<Vector>,
    /// Per joint: the torque last commanded ([`RobotSim::set_joint_torque`]).
    torques: Vec<f32>,
    /// Per joint: the external torque applied in the last step, after the limit model.
    applied: Vec<f32>,
    /// Per joint: limits, rad (None for fixed, continuous and unlimited joints).
    limits: Vec<Option<[f32; 2]>>,
    limit_model: LimitModel,
    limit_band: f32,
    servos: Vec<Option<Servo>>,
    /// A step panicked inside Rapier ([`RobotSim::is_broken`]).
    broken: bool,
    dt: f32,
    time: f64,
}

impl RobotSim {
    /// Builds a world holding `model` in the initial `state`.
    pub fn new(
        model: Arc<RobotModel>,
        setup: &SimSetup,
        state: &RobotState,
    ) -> Result<Self, SimError> {
        setup.physics.validate("physics.")?;
        if let Some(a) = setup
            .armature
            .iter()
            .find(|a| !(a.is_finite() && **a >= 0.0))
        {
            return Err(SimError::Config {
                field: "armature".into(),
                value: a.to_string(),
                reason: "must be finite and ≥ 0".into(),
            });
        }
        if !(setup.dt.is_finite() && setup.dt > 0.0) {
            return Err(SimError::Config {
                field: "dt".into(),
                value: setup.dt.to_string(),
                reason: "must be finite and > 0".into(),
            });
        }
        let root = model.root();
        if setup.base == Base::Floating && model.links()[root].mass <= 0.0 {
            return Err(UrdfError::MasslessFloatingRoot {
                link: model.links()[root].name.clone(),
            }
            .into());
        }
        Ok(Self::build(model, setup, state))
    }

    /// [`Self::new`] without the checks, for setups that already passed them. The world is
    /// built in Rapier insertion order, step by step: the ground, the links (bodies with
    /// their mass properties, then their colliders), the joints, the joint state, and a
    /// zero-length step that applies it all.
    pub(crate) fn build(model: Arc<RobotModel>, setup: &SimSetup, state: &RobotState) -> Self {
        let (g, slope) = (setup.physics.gravity, setup.physics.slope);
        // Flat ground exactly as before slopes existed (no −0 along x).
        let gravity = if slope == 0.0 {
            Vector::new(0.0, 0.0, -g)
        } else {
            Vector::new(-g * slope.sin(), 0.0, -g * slope.cos())
        };
        let mut world = PhysicsWorld {
            gravity,
            ..PhysicsWorld::default()
        };
        world.integration_parameters.dt = setup.dt;
        world.integration_parameters.num_solver_iterations =
            setup.physics.solver_iterations as usize;
        // The ground is a fixed body: its contacts take the "static" softness.
        world
            .integration_parameters
            .static_contact_softness
            .natural_frequency = setup.physics.contact_frequency;
        let ground = setup
            .ground
            .then(|| add_ground(&mut world, setup.physics.friction));
        // Rapier 0.36 treats the linear velocity of a free multibody root as the velocity of
        // its centre of mass but integrates it as the velocity of the body frame origin, so a
        // root whose centre of mass is off its frame origin does not conserve momentum. The
        // root body's frame is therefore placed at its centre of mass; `root_shift` converts.
        let shift = model.links()[model.root()].com;
        let (bodies, colliders) = add_links(&mut world, &model, setup, state, shift);
        let axis_in_parent = add_joints(&mut world, &model, setup, &bodies, shift);
        let (multibody, link_ids) = set_joint_state(&mut world, &model, setup, state, &bodies);

        // A zero-length step applies the pending changes (mass properties, collision pairs)
        // so that the world can be queried before its first real step.
        world.integration_parameters.dt = 0.0;
        world.step();
        world.integration_parameters.dt = setup.dt;

        let n_joints = model.joints().len();
        Self {
            root_shift: Vector::new(shift[0] as f32, shift[1] as f32, shift[2] as f32),
            world,
            bodies,
            colliders,
            ground,
            multibody,
            link_ids,
            axis_in_parent,
            torques: vec![0.0; n_joints],
            applied: vec![0.0; n_joints],
            limits: model
                .joints()
                .iter()
                .map(|j| match (j.kind, j.limits) {
                    (JointKind::Fixed, _) | (_, None) => None,
                    (_, Some([lo, hi])) => Some([lo as f32, hi as f32]),
                })
                .collect(),
            limit_model: setup.physics.joint_limits,
            limit_band: setup.physics.limit_band,
            servos: vec![None; n_joints],
            broken: false,
            dt: setup.dt,
            time: 0.0,
            model,
        }
    }

    /// The model this world was built from.
    pub fn model(&self) -> &Arc<RobotModel> {
        &self.model
    }

    /// Rapier step, s.
    pub fn dt(&self) -> f32 {
        self.dt
    }

    /// Simulated time since construction, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    fn mb(&self) -> Option<&Multibody> {
        self.multibody
            .and_then(|i| self.world.multibody_joints.get_multibody(i))
    }

    /// Position of joint `j` (URDF order), rad; 0 for fixed joints, NaN once broken
    /// ([`Self::is_broken`]).
    pub fn joint_position(&self, j: usize) -> f32 {
        if self.model.joints()[j].kind == JointKind::Fixed {
            return 0.0;
        }
        if self.broken {
            return f32::NAN;
        }
        self.mb()
            .and_then(|mb| mb.link(self.link_ids[j]))
            .map_or(0.0, |l| l.joint().coords()[3])
    }

    /// Velocity of joint `j` (URDF order), rad/s; 0 for fixed joints.
    pub fn joint_velocity(&self, j: usize) -> f32 {
        if self.model.joints()[j].kind == JointKind::Fixed {
            return 0.0;
        }
        self.mb()
            .and_then(|mb| {
                mb.link(self.link_ids[j])
                    .map(|l| mb.generalized_velocity()[l.assembly_id()])
            })
            .unwrap_or(0.0)
    }

    /// Sets the torque commanded at joint `j` (URDF order), N·m, positive about the joint axis
    /// on the child (and its reaction on the parent). It is applied at every following
    /// [`Self::step`] until set again, through the limit model ([`LimitModel::Fade`] scales
    /// it near a limit it pushes into; [`Self::applied_torque`] says what went in). No
    /// clamping to effort here: callers do that.
    pub fn set_joint_torque(&mut self, j: usize, torque: f32) {
        self.torques[j] = if torque.is_finite() { torque } else { 0.0 };
    }

    /// The factor in [0, 1] the limit model applies to a torque `torque` commanded at joint
    /// `j` in position `q`: for [`LimitModel::Fade`] on a limited joint,
    /// `clamp((hi − q)/band, 0, 1)` for a torque pushing up, `clamp((q − lo)/band, 0, 1)` for
    /// one pushing down; 1 otherwise.
    pub fn limit_factor(&self, j: usize, q: f32, torque: f32) -> f32 {
        match (self.limit_model, self.limits[j]) {
            (LimitModel::Fade, Some([lo, hi])) if torque != 0.0 => {
                let room = if torque > 0.0 { hi - q } else { q - lo };
                (room / self.limit_band).clamp(0.0, 1.0)
            }
            _ => 1.0,
        }
    }

    /// The external torque applied at joint `j` during the last [`Self::step`], N·m: the
    /// commanded torque times [`Self::limit_factor`] at the start of the step (without any
    /// servo's torque).
    pub fn applied_torque(&self, j: usize) -> f32 {
        self.applied[j]
    }

    /// The torque of joint `j`'s servo ([`Self::set_joint_motor`]) in the current state, N·m:
    /// `clamp(kp·(q* − q) − kd·q̇, ±τ_max)`; 0 without one. Rapier integrates the servo
    /// implicitly, so after a step this is the torque of its last solver substep.
    pub fn servo_torque(&self, j: usize) -> f32 {
        self.servos[j].map_or(0.0, |s| {
            let (q, qd) = (self.joint_position(j), self.joint_velocity(j));
            (s.stiffness * (s.target - q) - s.damping * qd).clamp(-s.max_torque, s.max_torque)
        })
    }

    /// The torque joint `j`'s actuator delivers, N·m: [`Self::applied_torque`] plus
    /// [`Self::servo_torque`].
    pub fn delivered_torque(&self, j: usize) -> f32 {
        self.applied[j] + self.servo_torque(j)
    }

    /// Drives joint `j` towards `target` (rad) with a position servo run inside Rapier's
    /// solver at every solver substep: a `MotorModel::ForceBased` motor of stiffness
    /// `stiffness` (N·m/rad) and damping `damping` (N·m·s/rad) whose torque Rapier clamps to
    /// `±max_torque` (N·m), i.e. `τ = clamp(kp·(q* − q) − kd·q̇, ±τ_max)` evaluated
    /// implicitly. Replaces any previous servo on the joint; `max_torque = 0` removes it.
    /// [`Self::servo_torque`] says what it delivers.
    pub fn set_joint_motor(
        &mut self,
        j: usize,
        target: f32,
        stiffness: f32,
        damping: f32,
        max_torque: f32,
    ) {
        if self.model.joints()[j].kind == JointKind::Fixed {
            return;
        }
        let servo = Servo {
            target: if target.is_finite() { target } else { 0.0 },
            stiffness: stiffness.max(0.0),
            damping: damping.max(0.0),
            max_torque: max_torque.max(0.0),
        };
        self.servos[j] = (servo.max_torque > 0.0).then_some(servo);
        self.set_motor(j, self.servos[j]);
    }

    /// Installs (`Some`) or removes (`None`) the Rapier motor of joint `j`.
    fn set_motor(&mut self, j: usize, servo: Option<Servo>) {
        let link_id = self.link_ids[j];
        let Some(link) = self
            .multibody
            .and_then(|i| self.world.multibody_joints.get_multibody_mut(i))
            .and_then(|mb| mb.link_mut(link_id))
        else {
            return;
        };
        match servo {
            Some(s) => {
                link.joint
                    .data
                    .set_motor(JointAxis::AngX, s.target, 0.0, s.stiffness, s.damping)
                    .set_motor_model(JointAxis::AngX, MotorModel::ForceBased)
                    .set_motor_max_force(JointAxis::AngX, s.max_torque);
            }
            None => link.joint.data.motor_axes.remove(JointAxesMask::ANG_X),
        }
    }

    /// Holds joint `j` at `target` (rad) with an implicit spring-damper of stiffness `kp`
    /// (N·m/rad) and damping `kd` (N·m·s/rad, added to the URDF damping), integrated by Rapier
    /// inside every solver substep: a PD position servo that is stable at any gain, unlike a PD
    /// evaluated once per control period. `kp = kd = 0` removes it. Not used by the RL
    /// environments (their joints are torque-controlled); meant for holding poses and tests.
    pub fn set_joint_servo(&mut self, j: usize, target: f32, kp: f32, kd: f32) {
        let joint = &self.model.joints()[j];
        if joint.kind == JointKind::Fixed {
            return;
        }
        let (kp, kd) = (kp.max(0.0), kd.max(0.0));
        let base_damping = joint.damping as f32;
        let link_id = self.link_ids[j];
        if let Some(mb) = self
            .multibody
            .and_then(|i| self.world.multibody_joints.get_multibody_mut(i))
        {
            let Some(link) = mb.link_mut(link_id) else {
                return;
            };
            // Axis 3 of the 6-DoF layout is the angular x axis, our revolute axis.
            link.joint.set_spring(3, kp, target);
            let dof = link.assembly_id();
            mb.damping_mut()[dof] = base_damping + kd;
        }
    }

    /// The torque currently commanded at joint `j`, N·m.
    pub fn joint_torque(&self, j: usize) -> f32 {
        self.torques[j]
    }

    /// Advances the world by one Rapier step of [`Self::dt`].
    ///
    /// Torques go in as a pair of equal and opposite external torques `±τ·a` on the child and
    /// parent links, `a` the joint axis in the world at the start of the step. Rapier maps link
    /// wrenches to generalised forces through the link Jacobians: the pair contributes exactly
    /// `τ` to the joint's own coordinate and cancels on every other one. Under
    /// [`LimitModel::Fade`] the torque is first scaled by [`Self::limit_factor`] at the
    /// joint's position at the start of the step.
    pub fn step(&mut self) {
        for &h in &self.bodies {
            if let Some(rb) = self.world.bodies.get_mut(h) {
                rb.reset_torques(false);
            }
        }
        let model = self.model.clone();
        for (ji, j) in model.joints().iter().enumerate() {
            let mut tau = self.torques[ji];
            if tau != 0.0 && self.limit_model == LimitModel::Fade {
                tau *= self.limit_factor(ji, self.joint_position(ji), tau);
            }
            self.applied[ji] = tau;
            if tau == 0.0 || j.kind == JointKind::Fixed {
                continue;
            }
            let Some(parent_rot) = self
                .world
                .bodies
                .get(self.bodies[j.parent])
                .map(|b| *b.rotation())
            else {
                continue;
            };
            let t = parent_rot * self.axis_in_parent[ji] * tau;
            if let Some(rb) = self.world.bodies.get_mut(self.bodies[j.child]) {
                rb.add_torque(t, false);
            }
            if let Some(rb) = self.world.bodies.get_mut(self.bodies[j.parent]) {
                if rb.is_dynamic() {
                    rb.add_torque(-t, false);
                }
            }
        }
        if !self.broken {
            // Rapier's motor constraint (the servos of `set_joint_motor`) clamps with the
            // joint position, which panics once a state has blown up to NaN (absurd models,
            // e.g. a link 1e30 m away). Such a world is lost anyway: it is marked broken,
            // reads NaN from then on, and the environment ends the episode as a fall.
            let world = &mut self.world;
            let stepped =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| world.step())).is_ok();
            self.broken = !stepped;
        }
        self.time += self.dt as f64;
    }

    /// Adds `dv` (m/s, world frame) to the linear velocity of the root link's centre of mass
    /// (a floating base's first three generalised velocities): a push, an impulse of
    /// `m_root·dv` to the root. Nothing for a fixed base.
    pub fn push_root(&mut self, dv: [f32; 3]) {
        let Some(index) = self.multibody else { return };
        let root_free = self
            .world
            .multibody_joints
            .get_multibody(index)
            .is_some_and(|mb| {
                mb.ndofs()
                    >= 6 + self
                        .model
                        .joints()
                        .iter()
                        .filter(|j| j.is_movable())
                        .count()
            });
        if !root_free {
            return;
        }
        if let Some(mb) = self.world.multibody_joints.get_multibody_mut(index) {
            let mut v = mb.generalized_velocity_mut();
            for (k, d) in dv.iter().enumerate() {
                v[k] += d;
            }
        }
    }

    /// Whether a step failed inside Rapier (a state that blew up to NaN); the world then
    /// stands still and [`Self::joint_position`] reads NaN.
    pub fn is_broken(&self) -> bool {
        self.broken
    }

    /// World pose of link `l`'s frame.
    pub fn link_pose(&self, l: usize) -> Pose {
        let pose = self
            .world
            .bodies
            .get(self.bodies[l])
            .map_or(Pose::IDENTITY, |b| *b.position());
        if l == self.model.root() {
            pose * Pose::from_translation(-self.root_shift)
        } else {
            pose
        }
    }

    /// World position of link `l`'s centre of mass, m.
    pub fn link_center_of_mass(&self, l: usize) -> Vector {
        self.world
            .bodies
            .get(self.bodies[l])
            .map_or(Vector::ZERO, |b| {
                b.position().transform_point(b.local_center_of_mass())
            })
    }

    /// World velocity of link `l`: (linear velocity of its centre of mass, angular velocity).
    ///
    /// Read from the multibody's generalised velocities through the link Jacobian: Rapier
    /// refreshes the rigid-body velocities of multibody links only at the start of each solver
    /// substep, so after a step they lag by one substep.
    pub fn link_velocity(&self, l: usize) -> (Vector, Vector) {
        let id = if l == self.model.root() {
            Some(0)
        } else {
            self.model.parent_joint(l).map(|j| self.link_ids[j])
        };
        if let (Some(mb), Some(id)) = (self.mb(), id) {
            let v = mb.body_jacobian(id) * mb.generalized_velocity();
            return (Vector::new(v[0], v[1], v[2]), Vector::new(v[3], v[4], v[5]));
        }
        self.world
            .bodies
            .get(self.bodies[l])
            .map_or((Vector::ZERO, Vector::ZERO), |b| (b.linvel(), b.angvel()))
    }

    /// World linear velocity of link `l`'s frame origin, m/s.
    pub fn link_origin_velocity(&self, l: usize) -> Vector {
        let (v, w) = self.link_velocity(l);
        v + w.cross(self.link_pose(l).translation - self.link_center_of_mass(l))
    }

    /// World angular velocity of link `l`, rad/s.
    pub fn link_angular_velocity(&self, l: usize) -> Vector {
        self.link_velocity(l).1
    }

    /// All link frames in the world, URDF link order.
    pub fn link_poses(&self) -> Vec<LinkPose> {
        self.model
            .links()
            .iter()
            .enumerate()
            .map(|(l, link)| {
                let p = self.link_pose(l);
                LinkPose {
                    name: link.name.clone(),
                    translation: p.translation.to_array(),
                    rotation: p.rotation.to_array(),
                }
            })
            .collect()
    }

    /// Total mass as Rapier sees it (sum of rigid-body masses), kg.
    pub fn total_mass(&self) -> f32 {
        self.bodies
            .iter()
            .filter_map(|&h| self.world.bodies.get(h))
            .map(|b| b.mass())
            .sum()
    }

    /// Whole-body centre of mass as Rapier sees it, world frame, m.
    pub fn center_of_mass(&self) -> Vector {
        let mut m = 0.0;
        let mut c = Vector::ZERO;
        for (l, b) in self.bodies.iter().enumerate() {
            let Some(b) = self.world.bodies.get(*b) else {
                continue;
            };
            m += b.mass();
            c += self.link_center_of_mass(l) * b.mass();
        }
        if m > 0.0 {
            c / m
        } else {
            c
        }
    }

    /// Normal force the ground exerts on link `l` (all its colliders), N, averaged over the
    /// last Rapier step. Zero without ground or contact.
    pub fn ground_normal_force(&self, l: usize) -> f32 {
        let Some(ground) = self.ground else {
            return 0.0;
        };
        let mut impulse = 0.0;
        for &c in &self.colliders[l] {
            if let Some(pair) = self.world.narrow_phase.contact_pair(c, ground) {
                impulse += pair.total_impulse().z.abs();
            }
        }
        // Rapier reports the impulse accumulated over the whole step (all solver substeps).
        impulse / self.dt
    }

    /// The Rapier world, for inspection.
    pub fn world(&self) -> &PhysicsWorld {
        &self.world
    }
}

/// The flat ground: a fixed box whose top face is z = 0, colliding with the robot only.
fn add_ground(world: &mut PhysicsWorld, friction: f32) -> ColliderHandle {
    let body = world.insert_body(RigidBodyBuilder::fixed());
    let collider = ColliderBuilder::cuboid(1000.0, 1000.0, 0.5)
        .translation(Vector::new(0.0, 0.0, -0.5))
        .friction(friction)
        .collision_groups(InteractionGroups::new(
            GROUND_GROUP,
            ROBOT_GROUP,
            InteractionTestMode::And,
        ));
    world.insert_collider(collider, Some(body))
}

/// One rigid body per link, root first then in joint order, posed by forward kinematics of
/// `state` with the URDF's mass, centre of mass and inertia, and its collision shapes.
/// The root body's frame sits at its centre of mass (`shift` from its link frame). Returns
/// the body and the colliders of each link, in URDF link order.
fn add_links(
    world: &mut PhysicsWorld,
    model: &RobotModel,
    setup: &SimSetup,
    state: &RobotState,
    shift: [f64; 3],
) -> (Vec<RigidBodyHandle>, Vec<Vec<ColliderHandle>>) {
    let root = model.root();
    let base = Iso::from_translation(state.base_position);
    let poses = model.forward_kinematics(&base, &state.q);
    let root_body = Iso::from_translation(shift);
    let unshift = Iso::from_translation(math::scale(shift, -1.0));
    let robot_filter = if setup.physics.self_collisions {
        ROBOT_GROUP | GROUND_GROUP
    } else {
        GROUND_GROUP
    };
    let mut bodies = vec![RigidBodyHandle::invalid(); model.links().len()];
    let mut colliders = vec![Vec::new(); model.links().len()];
    let mut link_order = vec![root];
    link_order.extend(model.joint_order().iter().map(|&j| model.joints()[j].child));
    for &l in &link_order {
        let link = &model.links()[l];
        let mut builder = if l == root && setup.base == Base::Fixed {
            RigidBodyBuilder::fixed()
        } else {
            RigidBodyBuilder::dynamic()
        }
        .pose(
            if l == root {
                poses[l].mul(&root_body)
            } else {
                poses[l]
            }
            .to_pose(),
        )
        .can_sleep(false);
        if link.mass > 0.0 {
            let c = if l == root { [0.0; 3] } else { link.com };
            let mut inertia = [[0.0f32; 3]; 3];
            for (r, row) in inertia.iter_mut().enumerate() {
                for (k, v) in row.iter_mut().enumerate() {
                    *v = link.inertia[r][k] as f32;
                }
            }
            // glam matrices are column-major; the tensor is symmetric, so either reading works.
            let scale = setup.physics.mass_scale;
            let m = Matrix::from_cols_array_2d(&inertia) * scale;
            builder = builder.additional_mass_properties(MassProperties::with_inertia_matrix(
                Vector::new(c[0] as f32, c[1] as f32, c[2] as f32),
                link.mass as f32 * scale,
                m,
            ));
        }
        let handle = world.insert_body(builder);
        bodies[l] = handle;
        for (origin, shape) in &link.shapes {
            let mut pose = origin.mul(&Iso::from_rotation(shape_frame(shape)));
            if l == root {
                pose = unshift.mul(&pose);
            }
            let collider = collider_of(shape)
                .position(pose.to_pose())
                .density(0.0)
                .friction(setup.physics.friction)
                .collision_groups(InteractionGroups::new(
                    ROBOT_GROUP,
                    robot_filter,
                    InteractionTestMode::And,
                ));
            colliders[l].push(world.insert_collider(collider, Some(handle)));
        }
    }
    (bodies, colliders)
}

/// The Rapier collider of a URDF primitive, in the primitive's frame after [`shape_frame`].
fn collider_of(shape: &Shape) -> ColliderBuilder {
    match *shape {
        Shape::Box { size } => ColliderBuilder::cuboid(size[0] / 2.0, size[1] / 2.0, size[2] / 2.0),
        Shape::Sphere { radius } => ColliderBuilder::ball(radius),
        Shape::Cylinder { radius, length } => ColliderBuilder::cylinder(length / 2.0, radius),
    }
}

/// The rotation from a URDF primitive's frame to its Rapier collider's: Rapier cylinders run
/// along y, URDF ones along z, so y is rotated onto z; boxes and spheres need none.
fn shape_frame(shape: &Shape) -> [[f64; 3]; 3] {
    match shape {
        Shape::Cylinder { .. } => math::axis_angle([1.0, 0.0, 0.0], std::f64::consts::FRAC_PI_2),
        Shape::Box { .. } | Shape::Sphere { .. } => math::IDENTITY,
    }
}

/// One multibody joint per URDF joint, in joint order: revolute (the URDF axis mapped onto
/// the joint's x) with its limits (and their softness under the `soft` limit model), or
/// fixed. Returns each joint's unit axis in its parent link frame.
fn add_joints(
    world: &mut PhysicsWorld,
    model: &RobotModel,
    setup: &SimSetup,
    bodies: &[RigidBodyHandle],
    shift: [f64; 3],
) -> Vec<Vector> {
    let root = model.root();
    let unshift = Iso::from_translation(math::scale(shift, -1.0));
    let mut axis_in_parent = vec![Vector::X; model.joints().len()];
    for &ji in model.joint_order() {
        let j = &model.joints()[ji];
        let (locked, frame_rot) = match j.kind {
            JointKind::Fixed => (JointAxesMask::LOCKED_FIXED_AXES, math::IDENTITY),
            _ => (JointAxesMask::LOCKED_REVOLUTE_AXES, math::x_onto(j.axis)),
        };
        let mut frame1 = j.origin.mul(&Iso::from_rotation(frame_rot));
        if j.parent == root {
            frame1 = unshift.mul(&frame1);
        }
        let frame2 = Iso::from_rotation(frame_rot);
        let mut builder = GenericJointBuilder::new(locked)
            .local_frame1(frame1.to_pose())
            .local_frame2(frame2.to_pose())
            .contacts_enabled(false);
        if let Some([lo, hi]) = j.limits {
            builder = builder.limits(JointAxis::AngX, [lo as f32, hi as f32]);
            if setup.physics.joint_limits == LimitModel::Soft {
                // For multibody joints the softness only acts on limits (and friction).
                builder = builder.softness(SpringCoefficients::new(
                    setup.physics.limit_frequency,
                    setup.physics.limit_damping_ratio,
                ));
            }
        }
        let a = math::mat_vec(&j.origin.r, j.axis);
        axis_in_parent[ji] = Vector::new(a[0] as f32, a[1] as f32, a[2] as f32);
        // Insertion only fails for a link that already has a parent or would close a loop,
        // which a validated (tree) model never asks for.
        let _ =
            world
                .multibody_joints
                .insert(bodies[j.parent], bodies[j.child], builder.build(), true);
    }
    axis_in_parent
}

/// Puts the joints at `state` (positions, then velocities) and sets each degree of freedom's
/// armature, damping and friction from the setup and the URDF (and nothing else: Rapier's
/// default damping is removed). Returns the multibody and, per joint, the multibody link id
/// of its child; a model without joints has no multibody (Rapier makes one only through
/// joints).
fn set_joint_state(
    world: &mut PhysicsWorld,
    model: &RobotModel,
    setup: &SimSetup,
    state: &RobotState,
    bodies: &[RigidBodyHandle],
) -> (Option<MultibodyIndex>, Vec<usize>) {
    let mut link_ids = vec![0usize; model.joints().len()];
    let Some(id) = world
        .multibody_joints
        .rigid_body_link(bodies[model.root()])
        .copied()
    else {
        return (None, link_ids);
    };
    let index = id.multibody;
    for (ji, j) in model.joints().iter().enumerate() {
        if let Some(link) = world.multibody_joints.rigid_body_link(bodies[j.child]) {
            link_ids[ji] = link.id;
        }
    }
    let world_bodies = &world.bodies;
    if let Some(mb) = world.multibody_joints.get_multibody_mut(index) {
        mb.set_self_contacts_enabled(setup.physics.self_collisions);
        for (ji, j) in model.joints().iter().enumerate() {
            if j.kind == JointKind::Fixed {
                continue;
            }
            let q = state.q.get(ji).copied().unwrap_or(0.0) as f32;
            if let Some(link) = mb.link_mut(link_ids[ji]) {
                link.joint.apply_displacement(&[q]);
            }
        }
        // Resolves the root type (fixed roots drop their 6 free DoFs) and poses.
        mb.forward_kinematics(world_bodies, true);
    }
    if let Some(mb) = world.multibody_joints.get_multibody(index) {
        mb.update_rigid_bodies(&mut world.bodies, true);
    }
    if let Some(mb) = world.multibody_joints.get_multibody_mut(index) {
        // Rapier gives every angular DoF (the free root's too) a default damping of 0.1; the
        // URDF's <dynamics> is the only damping we want.
        mb.damping_mut().fill(0.0);
        let mut dofs = Vec::new();
        for (ji, j) in model.joints().iter().enumerate() {
            if j.kind == JointKind::Fixed {
                continue;
            }
            if let Some(link) = mb.link(link_ids[ji]) {
                dofs.push((link.assembly_id(), ji));
            }
        }
        for &(dof, ji) in &dofs {
            let j = &model.joints()[ji];
            mb.armature_mut()[dof] = setup.armature.get(ji).copied().unwrap_or(0.0).max(0.0);
            mb.damping_mut()[dof] = j.damping as f32;
            mb.frictions_mut()[dof] = j.friction as f32;
            mb.generalized_velocity_mut()[dof] = state.qd.get(ji).copied().unwrap_or(0.0) as f32;
        }
    }
    (Some(index), link_ids)
}
