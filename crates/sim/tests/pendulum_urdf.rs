//! Contract: a single pendulum described in URDF behaves as the textbook answer says.
//! Its small-oscillation period is `2π√(I/(m g l))` within 1 %, and a joint torque `τ`
//! produces the angular acceleration `τ/I` within 1 % (`τ/(I + armature)` with an armature),
//! at the default physics step. A torque between two free-floating bodies produces the
//! relative acceleration `τ(1/I₁ + 1/I₂')` that rigid-body mechanics gives, so the torque
//! pair acts on the joint alone.

mod common;

use common::{I_COM, L, M};
use std::sync::Arc;

use esrl_sim::{Base, PhysicsConfig, RobotModel, RobotSim, RobotState, SimSetup};

fn pendulum_urdf() -> String {
    common::pendulum_urdf("continuous", "", true)
}

/// Moment of inertia about the pivot (parallel-axis theorem).
fn i_pivot() -> f64 {
    I_COM + M * L * L
}

fn sim(physics: PhysicsConfig, q0: f64, armature: f32) -> RobotSim {
    let model = Arc::new(RobotModel::from_urdf_str(&pendulum_urdf()).unwrap());
    let control_period = 0.025;
    let setup = SimSetup {
        dt: control_period / physics.substeps as f32,
        physics,
        base: Base::Fixed,
        ground: false,
        armature: vec![armature],
    };
    let state = RobotState {
        base_position: [0.0; 3],
        q: vec![q0],
        qd: vec![0.0],
    };
    RobotSim::new(model, &setup, &state).unwrap()
}

#[test]
fn small_oscillation_period_matches_the_compound_pendulum_formula() {
    let physics = PhysicsConfig::default();
    let g = physics.gravity as f64;
    let mut sim = sim(physics, 0.02, 0.0);
    // Downward zero crossings, linearly interpolated inside the step.
    let mut crossings = Vec::new();
    let mut prev = sim.joint_position(0) as f64;
    while sim.time() < 30.0 {
        sim.step();
        let q = sim.joint_position(0) as f64;
        if prev > 0.0 && q <= 0.0 {
            crossings.push(sim.time() - sim.dt() as f64 * q / (q - prev));
        }
        prev = q;
    }
    assert!(crossings.len() >= 10, "only {} periods", crossings.len());
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let expected = 2.0 * std::f64::consts::PI * (i_pivot() / (M * g * L)).sqrt();
    let err = (measured / expected - 1.0).abs();
    assert!(
        err < 0.01,
        "period {measured:.5} s vs {expected:.5} s ({:.3} %)",
        100.0 * err
    );
}

#[test]
fn torque_gives_tau_over_inertia() {
    for armature in [0.0f32, 0.1] {
        let physics = PhysicsConfig {
            gravity: 0.0,
            ..PhysicsConfig::default()
        };
        let mut sim = sim(physics, 0.3, armature);
        let tau = 3.0f32;
        sim.set_joint_torque(0, tau);
        for _ in 0..8 {
            sim.step();
        }
        let alpha = sim.joint_velocity(0) as f64 / sim.time();
        let expected = tau as f64 / (i_pivot() + armature as f64);
        let err = (alpha / expected - 1.0).abs();
        assert!(
            err < 0.01,
            "armature {armature}: α = {alpha} vs τ/I = {expected}"
        );
    }
}

#[test]
fn torque_with_gravity_adds_to_the_gravity_torque() {
    // From rest at angle q0: α = (τ − m g l sin q0) / I at the first instant. One short step.
    let physics = PhysicsConfig {
        substeps: 25,
        ..PhysicsConfig::default()
    };
    let g = physics.gravity as f64;
    let q0 = 0.4f64;
    let mut sim = sim(physics, q0, 0.0);
    let tau = 2.0f32;
    sim.set_joint_torque(0, tau);
    sim.step();
    let alpha = sim.joint_velocity(0) as f64 / sim.time();
    let expected = (tau as f64 - M * g * L * q0.sin()) / i_pivot();
    let err = (alpha / expected - 1.0).abs();
    assert!(err < 0.01, "α = {alpha} vs {expected}");
}

#[test]
fn torque_pair_between_free_bodies_acts_on_the_joint_only() {
    // Body a (pivot at its COM) and body b (COM 0.5 m below the pivot), floating, no gravity.
    // Rigid-body mechanics: a spins with −τ/I_a (the pin force has no moment about a's COM);
    // b spins with τ/(I_b + μ l²), μ = m_a m_b/(m_a + m_b) the reduced mass.
    let model = Arc::new(RobotModel::from_urdf_str(&common::two_bodies_urdf(0.0)).unwrap());
    let setup = common::weightless(0.001);
    let state = RobotState {
        base_position: [0.0, 0.0, 1.0],
        q: vec![0.0],
        qd: vec![0.0],
    };
    let mut sim = RobotSim::new(model, &setup, &state).unwrap();
    sim.set_joint_torque(0, 1.0);
    sim.step();
    let t = sim.time();
    let (ma, mb, ia, ib, l) = (2.0f64, 1.0, 0.3, 0.1, 0.5);
    let mu = ma * mb / (ma + mb);
    let alpha_a = -1.0 / ia;
    let alpha_b = 1.0 / (ib + mu * l * l);
    let rel = sim.joint_velocity(0) as f64 / t;
    assert!(
        (rel / (alpha_b - alpha_a) - 1.0).abs() < 0.01,
        "relative α {rel}"
    );
    let wa = sim.link_angular_velocity(0).y as f64 / t;
    let wb = sim.link_angular_velocity(1).y as f64 / t;
    assert!((wa / alpha_a - 1.0).abs() < 0.01, "α_a {wa} vs {alpha_a}");
    assert!((wb / alpha_b - 1.0).abs() < 0.01, "α_b {wb} vs {alpha_b}");
}
