//! Contract: at the default physics step the humanoid, held in its standing pose by a PD
//! controller, stays up for 60 s (2400 control steps) with its torso origin never more than
//! 5 cm from where it started, and the ground carries its weight.
//!
//! The PD law `τ = kp (q* − q) − kd q̇` runs inside Rapier as an implicit joint
//! spring-damper ([`RobotSim::set_joint_servo`]), evaluated at every solver substep. A PD
//! evaluated once per 25 ms control period cannot hold this body (crate docs, "Standing"),
//! and that would test the controller rather than contact and integration.

mod common;

use esrl_sim::Env;

#[test]
fn pd_held_standing_pose_stays_up_for_a_minute() {
    let mut env = common::pd_held_standing();
    let start = env.sim().link_pose(env.model().root()).translation;
    let zero = vec![0.0; env.act_dim()];
    let mut max_drift = 0.0f32;
    let mut load = 0.0f64;
    let mut load_steps = 0;
    for step in 0..2400 {
        let s = env.step(&zero);
        let gait = s.info.gait.unwrap();
        assert!(!s.terminated, "fell at step {step} (t = {} s)", gait.time);
        let p = gait.torso_position;
        let d =
            ((p[0] - start.x).powi(2) + (p[1] - start.y).powi(2) + (p[2] - start.z).powi(2)).sqrt();
        max_drift = max_drift.max(d);
        if step >= 400 {
            load += (gait.foot_force[0] + gait.foot_force[1]) as f64;
            load_steps += 1;
        }
        if step + 1 == 2400 {
            assert!(s.truncated, "60 s should truncate the episode");
        }
    }
    assert!(max_drift < 0.05, "torso drifted {max_drift:.4} m");
    let mean_load = load / load_steps as f64 / env.body_weight() as f64;
    assert!(
        (mean_load - 1.0).abs() < 0.02,
        "feet carry {mean_load:.4} × body weight"
    );
}
