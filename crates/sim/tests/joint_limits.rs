//! Contract: joint limits hold under maximum torque. With the torso held in the air, every
//! actuated joint is driven at its full `<limit effort>` into its lower limit, its upper
//! limit, and its lower limit again (1.5 s each, full-range swings). At the default physics
//! settings, sampled once per control period (what the environment observes), a joint driven
//! towards a limit ends within 3° of it (last 0.5 s of each phase), and no joint is ever seen
//! more than 6° past a limit when it slams into it at full speed.
//!
//! Rapier's multibody limits act once a joint is past them: a joint reaching a limit at speed
//! `v` overshoots by about `v·h` (`h` the integrator step) for a moment inside the control
//! period, and one pushed by torque `τ` through inertia `I` chatters by about `½ (τ/I) h²`
//! (`fade` limits take that torque away near the limit). The crate docs list the measured
//! values, the transient peaks between control steps included.

mod common;

use esrl_sim::{RobotSim, RobotState, WalkConfig};

#[test]
fn actuated_joints_hold_their_limits_at_full_effort() {
    let config = WalkConfig::default();
    let (model, actuated, setup) = common::held_humanoid(&config);
    let mut q = vec![0.0; model.joints().len()];
    for &j in &actuated {
        let [lo, hi] = model.joints()[j].limits.unwrap();
        q[j] = 0.5 * (lo + hi);
    }
    let state = RobotState {
        base_position: [0.0, 0.0, 1.5],
        q,
        qd: vec![],
    };
    let mut sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
    let substeps = config.physics.substeps as usize;
    let steps = (1.5 / config.control_period).round() as usize;
    let hold_from = steps - (0.5 / config.control_period).round() as usize;
    for direction in [-1.0f32, 1.0, -1.0] {
        let mut transient = vec![0.0f64; actuated.len()];
        let mut held = vec![0.0f64; actuated.len()];
        for step in 0..steps {
            for &j in &actuated {
                sim.set_joint_torque(j, direction * model.joints()[j].effort as f32);
            }
            for _ in 0..substeps {
                sim.step();
            }
            for (k, &j) in actuated.iter().enumerate() {
                let [lo, hi] = model.joints()[j].limits.unwrap();
                let q = sim.joint_position(j) as f64;
                let past = (lo - q).max(q - hi).to_degrees();
                transient[k] = transient[k].max(past);
                if step >= hold_from {
                    let limit = if direction < 0.0 { lo } else { hi };
                    held[k] = held[k].max((q - limit).abs().to_degrees());
                }
            }
        }
        for (k, &j) in actuated.iter().enumerate() {
            let name = &model.joints()[j].name;
            assert!(
                held[k] < 3.0,
                "{name}: {:.2}° from its limit while held (direction {direction})",
                held[k]
            );
            assert!(
                transient[k] < 6.0,
                "{name}: overshot its limit by {:.2}° (direction {direction})",
                transient[k]
            );
        }
    }
}
