//! Contract: joint torques are internal forces, so in zero gravity they cannot move the
//! centre of mass (linear momentum is conserved).
//!
//! - Two bodies whose root has its centre of mass 0.3 m off its frame origin, spun through
//!   several radians by a joint torque: the centre of mass stays within 5 mm. This caught
//!   Rapier 0.36 integrating a free root's centre-of-mass velocity as the velocity of its frame
//!   origin: 0.41 m of drift at any time step, before `RobotSim` put the root body's frame at
//!   its centre of mass.
//! - The humanoid driven by alternating hip, knee and ankle torques (joint speeds up to
//!   ~3 rad/s) for 4 s: within 3 mm while its segments move by centimetres. At faster joint
//!   motion Rapier's first-order multibody integrator drifts more (crate docs, "Known
//!   limitations").

mod common;

use std::sync::Arc;

use esrl_sim::{Base, PhysicsConfig, RobotModel, RobotSim, RobotState, SimSetup};

#[test]
fn a_spinning_root_with_an_offset_centre_of_mass_conserves_momentum() {
    let model = Arc::new(RobotModel::from_urdf_str(&common::two_bodies_urdf(0.3)).unwrap());
    let setup = common::weightless(0.01);
    let state = RobotState {
        base_position: [0.0, 0.0, 1.0],
        q: vec![0.0],
        qd: vec![],
    };
    let mut sim = RobotSim::new(model, &setup, &state).unwrap();
    let c0 = sim.center_of_mass();
    sim.set_joint_torque(0, 1.0);
    for _ in 0..100 {
        sim.step();
    }
    assert!(
        sim.joint_position(0) > 3.0,
        "the joint should have turned far"
    );
    let drift = (sim.center_of_mass() - c0).length();
    assert!(drift < 5e-3, "centre of mass moved {drift} m");
}

#[test]
fn internal_torques_do_not_move_the_centre_of_mass() {
    let model = Arc::new(RobotModel::humanoid().unwrap());
    let physics = PhysicsConfig {
        gravity: 0.0,
        ..PhysicsConfig::default()
    };
    let physics_substeps = physics.substeps as usize;
    let setup = SimSetup {
        dt: 0.025 / physics.substeps as f32,
        physics,
        base: Base::Floating,
        ground: false,
        armature: vec![],
    };
    let mut q = vec![0.0; model.joints().len()];
    for (name, v) in [
        ("left_hip", -0.3),
        ("left_knee", 0.5),
        ("right_hip", 0.2),
        ("right_knee", 0.3),
    ] {
        q[model.joint_index(name).unwrap()] = v;
    }
    let state = RobotState {
        base_position: [0.0, 0.0, 1.0],
        q,
        qd: vec![],
    };
    let mut sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
    let c0 = sim.center_of_mass();
    let torso0 = sim.link_pose(model.root()).translation;
    let drive = [
        ("left_hip", 5.0, 10),
        ("right_knee", 3.0, 7),
        ("left_ankle", 1.0, 5),
    ];
    let mut torso_moved = 0.0f32;
    // 4 s whatever the physics step.
    for k in 0..(4.0 / setup.dt).round() as usize {
        for (name, tau, period) in drive {
            // Periods in control steps of 25 ms.
            let sign = if (k / (period * physics_substeps)).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            sim.set_joint_torque(model.joint_index(name).unwrap(), sign * tau);
        }
        sim.step();
        let drift = (sim.center_of_mass() - c0).length();
        assert!(drift < 3e-3, "step {k}: centre of mass moved {drift} m");
        torso_moved = torso_moved.max((sim.link_pose(model.root()).translation - torso0).length());
    }
    assert!(
        torso_moved > 0.02,
        "the torques should move the torso ({torso_moved} m)"
    );
}
