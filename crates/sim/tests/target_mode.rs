//! Contract: `walk.action = "target"` (module docs of `walk`, "Action"). An action maps onto
//! a joint angle target piecewise linearly (0 → the standing angle, ±1 → the limits); a zero
//! action holds the standing pose for 20 s on the ground from several reset seeds; `range`
//! and a joint's `joint_range` make the targets a residual around standing; with the
//! torso held in the air, a step of the target to half range is reached within 2° in the
//! documented times (ankle and knee 0.15 s, hip 0.6 s); the gait data report the servo's
//! torque and its work.

// Index loops read like the vector formulas they implement.
#![allow(clippy::needless_range_loop)]

mod common;

use esrl_sim::{ActionMode, Env, RobotSim, RobotState, WalkConfig, WalkEnv};

fn config() -> WalkConfig {
    WalkConfig {
        action: ActionMode::Target,
        ..WalkConfig::default()
    }
}

#[test]
fn actions_map_onto_the_joint_ranges_through_the_standing_pose() {
    let env = WalkEnv::new(config()).unwrap();
    // Left hip: standing −2°, range −90°…+30°; knee: 10°, 5°…90°; ankle: −8°, −20°…+20°.
    let cases = [
        (0, 0.0, -2.0),
        (0, 1.0, 30.0),
        (0, -1.0, -90.0),
        (0, 0.5, 14.0),
        (0, -0.5, -46.0),
        (1, 0.5, 50.0),
        (1, -0.5, 7.5),
        (2, 0.25, -1.0),
        (2, -0.25, -11.0),
        (2, 7.0, 20.0),
        (2, f32::NAN, -8.0),
    ];
    assert_targets(&env, &cases);
}

#[test]
fn a_range_makes_the_targets_a_residual_around_standing() {
    let mut cfg = config();
    cfg.target.range = Some(0.2);
    let env = WalkEnv::new(cfg).unwrap();
    // q* = q_stand + a·0.2 rad (11.46°), clamped to the limits.
    let cases = [
        (0, 0.0, -2.0),
        (0, 1.0, -2.0 + 11.459_156),
        (0, -0.5, -2.0 - 5.729_578),
        (1, -1.0, 5.0),
        (2, 1.0, -8.0 + 11.459_156),
        (2, -1.0, -19.459_156),
    ];
    assert_targets(&env, &cases);
}

#[test]
fn a_joint_range_replaces_the_range_for_that_joint_only() {
    let mut cfg = config();
    cfg.target.range = Some(0.2);
    cfg.target.joint_range = [("left_knee".to_string(), 0.6)].into_iter().collect();
    let env = WalkEnv::new(cfg.clone()).unwrap();
    let knee = env.standing_pose()[1].to_degrees();
    // The left knee spans ±0.6 rad (34.38°) around standing, the right one ±0.2 (11.46°).
    assert_targets(
        &env,
        &[
            (1, 1.0, knee + 34.377_47),
            (1, 0.5, knee + 17.188_734),
            (4, 1.0, knee + 11.459_156),
            (0, 1.0, -2.0 + 11.459_156),
        ],
    );
    cfg.target.joint_range = [("knee".to_string(), 0.6)].into_iter().collect();
    let err = WalkEnv::new(cfg.clone()).err().unwrap().to_string();
    assert!(
        err.contains("target.joint_range") && err.contains("`knee` is not an actuated joint"),
        "{err}"
    );
    cfg.target.joint_range = [("left_knee".to_string(), -0.1)].into_iter().collect();
    let err = WalkEnv::new(cfg).err().unwrap().to_string();
    assert!(err.contains("target.joint_range.left_knee"), "{err}");
}

#[test]
fn a_zero_action_holds_the_standing_pose_for_20_s() {
    let mut env = WalkEnv::new(config()).unwrap();
    for seed in [0, 1, 2] {
        env.reset(seed);
        let stand = env.standing_pose();
        let start = env.sim().link_pose(env.model().root()).translation;
        for step in 0..800 {
            let s = env.step(&[0.0; 6]);
            let g = s.info.gait.as_ref().unwrap();
            assert!(!s.terminated, "seed {seed}: fell at step {step}");
            let p = g.torso_position;
            let drift = (p[0] - start.x).hypot(p[1] - start.y);
            assert!(drift < 0.05, "seed {seed}, step {step}: drifted {drift} m");
            for k in 0..6 {
                let dev = (g.joint_angle[k] - stand[k]).abs().to_degrees();
                assert!(dev < 2.0, "seed {seed}, step {step}, joint {k}: {dev}° off");
            }
        }
    }
}

#[test]
fn a_target_step_is_reached_within_2_degrees_in_the_documented_time() {
    let config = config();
    let env = WalkEnv::new(config.clone()).unwrap();
    let (model, actuated, setup) = common::held_humanoid(&config);
    let stand = env.standing_pose();
    let mut q = vec![0.0; model.joints().len()];
    for (k, &j) in actuated.iter().enumerate() {
        q[j] = stand[k] as f64;
    }
    let (kp, kd) = (config.target.stiffness, config.target.damping);
    // (joint, documented time to stay within 2°, s)
    for (k, limit_s) in [(0, 0.6), (1, 0.15), (2, 0.15)] {
        for a in [0.5f32, -0.5] {
            let state = RobotState {
                base_position: [0.0, 0.0, 1.5],
                q: q.clone(),
                qd: vec![],
            };
            let mut sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
            for (i, &j) in actuated.iter().enumerate() {
                let act = if i == k { a } else { 0.0 };
                sim.set_joint_motor(j, env.target_angle(i, act), kp, kd, env.effort_limits()[i]);
            }
            let target = env.target_angle(k, a);
            let mut settled_at = None;
            for step in 1..=(2.0 / setup.dt).round() as usize {
                sim.step();
                let err = (sim.joint_position(actuated[k]) - target)
                    .abs()
                    .to_degrees();
                if err <= 2.0 {
                    settled_at.get_or_insert(step as f32 * setup.dt);
                } else {
                    settled_at = None;
                }
            }
            let t = settled_at.unwrap_or(f32::INFINITY);
            assert!(
                t <= limit_s,
                "joint {k}, a = {a}: within 2° after {t} s (documented {limit_s} s)"
            );
        }
    }
}

#[test]
fn gait_data_report_the_servo_torque_and_its_work() {
    // Standing still on a zero action, the servos carry the body: the reported torques are
    // theirs (not the zero action's), equal to the servo law at the state each step ends in
    // to within the motion of the step, and the mechanical power is that of the small motion.
    let mut env = WalkEnv::new(config()).unwrap();
    let (kp, kd) = (env.config().target.stiffness, env.config().target.damping);
    let joints: Vec<usize> = env
        .actuated_joint_names()
        .iter()
        .map(|n| env.model().joint_index(n).unwrap())
        .collect();
    env.reset(3);
    let mut held = 0.0f32;
    for step in 0..200 {
        let s = env.step(&[0.0; 6]);
        if step < 120 {
            continue; // settle
        }
        let g = s.info.gait.as_ref().unwrap();
        for k in 0..6 {
            let (q, qd) = (g.joint_angle[k], g.joint_velocity[k]);
            let effort = env.effort_limits()[k];
            let law = (kp * (env.target_angle(k, 0.0) - q) - kd * qd).clamp(-effort, effort);
            assert!((env.sim().servo_torque(joints[k]) - law).abs() < 1e-3 * law.abs().max(1.0));
            assert!(
                (g.joint_torque[k] - law).abs() < 0.1 * law.abs().max(5.0),
                "step {step}, joint {k}: mean torque {} vs law {law}",
                g.joint_torque[k]
            );
            assert!(g.joint_abs_power[k] >= g.joint_power[k].abs() * (1.0 - 1e-6));
            assert!(g.joint_abs_power[k] < 0.05 * g.joint_torque[k].abs().max(1.0));
            held = held.max(g.joint_torque[k].abs());
        }
    }
    assert!(
        held > 10.0,
        "the servos should hold the body, largest torque {held} N·m"
    );
}

/// Asserts `env.target_angle(k, a)` in degrees for each `(k, a, want°)`.
fn assert_targets(env: &WalkEnv, cases: &[(usize, f32, f32)]) {
    let deg = std::f32::consts::PI / 180.0;
    for &(k, a, want) in cases {
        let got = env.target_angle(k, a) / deg;
        assert!(
            (got - want).abs() < 1e-3,
            "joint {k}, a = {a}: {got}° vs {want}°"
        );
    }
}
