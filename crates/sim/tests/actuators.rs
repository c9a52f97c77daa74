//! Contract: the actuator laws deliver the torques their docs give, checked on a single
//! pendulum (bob 1.5 kg at 0.8 m, hinge about y) against hand-computed dynamics and statics:
//! - `fade` limits: far from a limit the commanded torque `τ` accelerates the pendulum as `τ`
//!   itself would, `I ω̇ = τ − c ω` (the motor that carries it saturates at exactly `τ`); near the limit it pushes towards, the torque is
//!   `τ·d/band` (`d` the distance to the limit), so a torque that beats gravity comes to
//!   rest where `τ·d/band = m g l sin q`, inside the band, off the stop;
//! - the position servo (`target` action mode): holds `q*` against gravity with the static
//!   error `m g l sin q / kp`, and its torque is clamped to its maximum;
//! - `RobotSim::delivered_torque` reports those torques;
//! - servos in a state that blows up to NaN within a step do not panic it (Rapier's motor
//!   clamps with the joint position): the world is marked broken and reads NaN.

mod common;

use common::{I_COM, L, M};
use std::sync::Arc;

use esrl_sim::{Base, LimitModel, PhysicsConfig, RobotModel, RobotSim, RobotState, SimSetup};

/// Upper limit of the hinge, rad.
const HI: f64 = 0.5;
/// Joint damping, N·m·s/rad.
const DAMPING: f64 = 2.0;

fn urdf() -> String {
    common::pendulum_urdf(
        "revolute",
        &format!(
            "\n    <limit lower=\"-2.5\" upper=\"{HI}\" effort=\"50\" velocity=\"30\"/>\n    \
             <dynamics damping=\"{DAMPING}\"/>"
        ),
        false,
    )
}

fn sim(physics: PhysicsConfig, q0: f64) -> RobotSim {
    let model = Arc::new(RobotModel::from_urdf_str(&urdf()).unwrap());
    let setup = SimSetup {
        dt: 0.025 / physics.substeps as f32,
        physics,
        base: Base::Fixed,
        ground: false,
        armature: vec![0.0],
    };
    let state = RobotState {
        base_position: [0.0; 3],
        q: vec![q0],
        qd: vec![0.0],
    };
    RobotSim::new(model, &setup, &state).unwrap()
}

fn i_pivot() -> f64 {
    I_COM + M * L * L
}

/// Runs `seconds` of simulated time.
fn run(sim: &mut RobotSim, seconds: f64) {
    while sim.time() < seconds - 1e-9 {
        sim.step();
    }
}

/// Root of `f` on `[a, b]` by bisection (f(a), f(b) of opposite signs).
fn bisect(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if (f(a) < 0.0) == (f(m) < 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[test]
fn fade_far_from_a_limit_is_the_commanded_torque() {
    let physics = PhysicsConfig {
        gravity: 0.0,
        joint_limits: LimitModel::Fade,
        ..PhysicsConfig::default()
    };
    for tau in [3.0f32, -3.0] {
        let mut sim = sim(physics.clone(), 0.0);
        sim.set_joint_torque(0, tau);
        run(&mut sim, 0.2);
        // I ω̇ = τ − c ω with the joint damping c: ω(t) = (τ/c)(1 − e^(−c t/I)).
        let (c, t) = (DAMPING, sim.time());
        let expected = tau as f64 / c * (1.0 - (-c * t / i_pivot()).exp());
        let omega = sim.joint_velocity(0) as f64;
        assert!(
            (omega / expected - 1.0).abs() < 0.01,
            "τ = {tau}: ω = {omega} vs {expected}"
        );
        assert!(
            (sim.delivered_torque(0) - tau).abs() < 1e-4,
            "delivered {} vs commanded {tau}",
            sim.delivered_torque(0)
        );
    }
}

#[test]
fn fade_balances_gravity_inside_the_band_not_on_the_stop() {
    let physics = PhysicsConfig {
        joint_limits: LimitModel::Fade,
        ..PhysicsConfig::default()
    };
    let band = physics.limit_band as f64;
    let g = physics.gravity as f64;
    let tau = 20.0f64;
    let mut sim = sim(physics, 0.0);
    sim.set_joint_torque(0, tau as f32);
    run(&mut sim, 8.0);
    // τ (HI − q)/band = m g l sin q, solved by hand (bisection) on [0, HI].
    let q_eq = bisect(|q| tau * (HI - q) / band - M * g * L * q.sin(), 0.0, HI);
    let q = sim.joint_position(0) as f64;
    assert!(
        (q - q_eq).abs() < 1e-3,
        "rests at {q:.5} rad, expected {q_eq:.5} ({:.2}° before the limit)",
        (HI - q_eq).to_degrees()
    );
    assert!(HI - q > 0.3 * (HI - q_eq), "resting on the stop");
    let delivered = sim.delivered_torque(0) as f64;
    let gravity = M * g * L * q.sin();
    assert!(
        (delivered / gravity - 1.0).abs() < 0.01,
        "delivered {delivered} vs gravity torque {gravity}"
    );
}

#[test]
fn hard_limits_rest_the_same_load_on_the_stop() {
    let physics = PhysicsConfig {
        joint_limits: LimitModel::Hard,
        ..PhysicsConfig::default()
    };
    let mut sim = sim(physics, 0.0);
    sim.set_joint_torque(0, 20.0);
    run(&mut sim, 8.0);
    let q = sim.joint_position(0) as f64;
    assert!(q > HI - 1e-3, "at {q}, the limit is {HI}");
    assert_eq!(sim.delivered_torque(0), 20.0);
}

#[test]
fn servo_holds_its_target_with_the_static_error_of_its_stiffness() {
    let physics = PhysicsConfig::default();
    let g = physics.gravity as f64;
    let (target, kp) = (0.3f64, 1500.0f64);
    let mut sim = sim(physics, 0.0);
    sim.set_joint_motor(0, target as f32, kp as f32, 60.0, 50.0);
    run(&mut sim, 3.0);
    // kp (q* − q) = m g l sin q.
    let q_eq = bisect(|q| kp * (target - q) - M * g * L * q.sin(), 0.0, target);
    let q = sim.joint_position(0) as f64;
    assert!((q - q_eq).abs() < 1e-4, "at {q:.6}, expected {q_eq:.6}");
    assert!(target - q_eq > 1e-3, "the static error is visible");
    let delivered = sim.delivered_torque(0) as f64;
    let gravity = M * g * L * q.sin();
    assert!(
        (delivered / gravity - 1.0).abs() < 0.01,
        "delivered {delivered} vs gravity torque {gravity}"
    );
}

#[test]
fn servo_torque_is_clamped_to_its_maximum() {
    let physics = PhysicsConfig::default();
    let g = physics.gravity as f64;
    let max = 5.0f64;
    let mut sim = sim(physics, 0.0);
    sim.set_joint_motor(0, 0.45, 1500.0, 60.0, max as f32);
    run(&mut sim, 5.0);
    // The servo saturates: m g l sin q = 5 N·m.
    let q_eq = (max / (M * g * L)).asin();
    let q = sim.joint_position(0) as f64;
    assert!((q - q_eq).abs() < 1e-3, "at {q:.5}, expected {q_eq:.5}");
    assert!(((sim.delivered_torque(0) as f64) - max).abs() < 1e-3);
}

#[test]
fn a_servo_in_a_blown_up_state_marks_the_world_broken_instead_of_panicking() {
    // Joint speeds of 1e30 rad/s turn the state into NaN within a solver substep; with several
    // substeps per Rapier step the servos' motor constraints then meet a NaN joint position,
    // on which Rapier panics.
    let model = Arc::new(RobotModel::humanoid().unwrap());
    let n = model.joints().len();
    let setup = SimSetup {
        dt: 0.025,
        physics: PhysicsConfig {
            substeps: 1,
            solver_iterations: 4,
            ..PhysicsConfig::default()
        },
        base: Base::Floating,
        ground: true,
        armature: vec![],
    };
    let state = RobotState {
        base_position: [0.0, 0.0, 1.2],
        q: vec![0.0; n],
        qd: vec![1e30; n],
    };
    let mut sim = RobotSim::new(model, &setup, &state).unwrap();
    for j in 0..n {
        sim.set_joint_motor(j, 0.2, 1500.0, 60.0, 100.0);
    }
    sim.step();
    assert!(sim.is_broken());
    assert!(sim.joint_position(0).is_nan());
    sim.step();
    assert!(sim.is_broken());
}
