//! Contract: `WalkEnv` follows SPEC §2. The observation has the documented layout (43 values
//! for the humanoid, computed from the model) and agrees with the gait data and with finite
//! differences of the simulated motion; the reward is eq. 12 with its terms reported;
//! episodes end on a fall, at the end of the track and at 60 s; bad configs are refused with
//! the field named; the recording data (link poses, geometry) put the feet on the ground.

// Index loops read like the vector formulas they implement.
#![allow(clippy::needless_range_loop)]

use esrl_sim::{Env, GaitSample, LimitModel, SimError, Step, WalkConfig, WalkEnv};

/// The raw (SI) observation: the layout tests below check units and frames.
fn env() -> WalkEnv {
    WalkEnv::new(WalkConfig {
        normalize_obs: false,
        ..WalkConfig::default()
    })
    .unwrap()
}

fn rotate(q: &[f32], v: [f32; 3]) -> [f32; 3] {
    // v' = q v q*, quaternion [x, y, z, w].
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    let t = [
        2.0 * (y * v[2] - z * v[1]),
        2.0 * (z * v[0] - x * v[2]),
        2.0 * (x * v[1] - y * v[0]),
    ];
    [
        v[0] + w * t[0] + (y * t[2] - z * t[1]),
        v[1] + w * t[1] + (z * t[0] - x * t[2]),
        v[2] + w * t[2] + (x * t[1] - y * t[0]),
    ]
}

fn gait(s: &Step) -> &GaitSample {
    s.info.gait.as_ref().unwrap()
}

#[test]
fn dimensions_and_names_come_from_the_model() {
    let env = env();
    assert_eq!(env.obs_dim(), 43);
    assert_eq!(env.act_dim(), 6);
    assert_eq!(env.obs_layout().len, 43);
    assert_eq!(env.obs_names().len(), 43);
    assert_eq!(env.control_period(), 0.025);
    assert_eq!(env.max_episode_steps(), 2400);
    assert_eq!(
        env.actuated_joint_names(),
        [
            "left_hip",
            "left_knee",
            "left_ankle",
            "right_hip",
            "right_knee",
            "right_ankle"
        ]
    );
    assert_eq!(
        env.passive_joint_names(),
        [
            "left_shoulder_pitch",
            "left_shoulder_roll",
            "right_shoulder_pitch",
            "right_shoulder_roll"
        ]
    );
    let l = env.obs_layout();
    assert_eq!(
        (
            l.joint_angles.start,
            l.passive_angles.start,
            l.foot_forces.start,
            l.previous_action.start
        ),
        (15, 27, 35, 37)
    );
    assert_eq!(env.obs_names()[16], "joint_angle/left_knee");
    assert_eq!(
        env.effort_limits(),
        [150.0, 150.0, 120.0, 150.0, 150.0, 120.0]
    );
    fn is_send<T: Send>() {}
    is_send::<WalkEnv>();
    let _boxed: Box<dyn Env> = Box::new(env);
}

#[test]
fn observation_reward_and_gait_agree() {
    // Hard limits: the applied torque is exactly action × effort (no fade), so the power can
    // be checked against the joint angles alone.
    let mut config = WalkConfig {
        normalize_obs: false,
        ..WalkConfig::default()
    };
    config.physics.joint_limits = LimitModel::Hard;
    let mut env = WalkEnv::new(config).unwrap();
    let layout = env.obs_layout().clone();
    let weight = env.body_weight();
    let mut prev_obs = env.reset(5);
    let actions = [
        [0.2, -0.1, 0.05, -0.3, 0.25, 2.0],
        [-0.4, 0.3, -0.2, 0.1, -0.1, f32::NAN],
    ];
    let mut prev_world_v: Option<[f32; 3]> = None;
    for (k, action) in actions.iter().cycle().take(12).enumerate() {
        let s = env.step(action);
        let g = gait(&s).clone();
        let o = &s.obs;
        assert_eq!(o[layout.height_error], g.height_error);
        assert_eq!(o[layout.lateral_offset], g.lateral_offset);
        assert_eq!(&o[layout.orientation.clone()], &g.torso_rotation);
        assert_eq!(&o[layout.joint_angles.clone()], g.joint_angle.as_slice());
        assert_eq!(
            &o[layout.joint_velocities.clone()],
            g.joint_velocity.as_slice()
        );
        for f in 0..2 {
            assert!((o[layout.foot_forces.start + f] - g.foot_force[f] / weight).abs() < 1e-6);
        }
        // Previous action: the clamped action (NaN → 0).
        let clamped: Vec<f32> = action
            .iter()
            .map(|a| {
                if a.is_finite() {
                    a.clamp(-1.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect();
        assert_eq!(&o[layout.previous_action.clone()], clamped.as_slice());
        let efforts = env.effort_limits();
        for j in 0..6 {
            assert_eq!(g.joint_torque[j], clamped[j] * efforts[j]);
            // A constant torque's mean power over the period is τ·Δq/T (the physics steps'
            // works telescope), Δq from this and the previous observation.
            let dq = o[layout.joint_angles.start + j] - prev_obs[layout.joint_angles.start + j];
            let p = g.joint_torque[j] * dq / env.control_period();
            assert!(
                (g.joint_power[j] - p).abs() <= 1e-3 * p.abs().max(1.0),
                "joint {j}: power {} vs τ Δq / T = {p}",
                g.joint_power[j]
            );
            assert!(g.joint_abs_power[j] >= g.joint_power[j].abs() * (1.0 - 1e-6));
        }
        // Body-frame velocity rotated back to the world gives the forward velocity.
        let v_body: Vec<f32> = o[layout.linear_velocity.clone()].to_vec();
        let v_world = rotate(&g.torso_rotation, [v_body[0], v_body[1], v_body[2]]);
        assert!(
            (v_world[0] - g.forward_velocity).abs() < 1e-4,
            "{v_world:?} vs {}",
            g.forward_velocity
        );
        // Acceleration is the finite difference of the world velocity, in the body frame.
        if let Some(pv) = prev_world_v {
            let a_body: Vec<f32> = o[layout.acceleration.clone()].to_vec();
            let a_world = rotate(&g.torso_rotation, [a_body[0], a_body[1], a_body[2]]);
            for c in 0..3 {
                let fd = (v_world[c] - pv[c]) / env.control_period();
                assert!(
                    (a_world[c] - fd).abs() < 1e-2 * fd.abs().max(1.0),
                    "step {k} axis {c}: {} vs {fd}",
                    a_world[c]
                );
            }
        }
        prev_world_v = Some(v_world);
        // Eq. 12 from the gait data, term by term.
        let p = g.joint_abs_power.iter().sum::<f32>() / 6.0;
        let expect = [
            ("forward", g.forward_velocity),
            ("lateral", -5.0 * g.lateral_offset.powi(2)),
            ("height", -25.0 * g.height_error.powi(2)),
            ("power", -0.0005 * p),
            ("alive", 0.025),
        ];
        assert_eq!(s.info.reward_terms.len(), expect.len());
        for ((name, got), (want_name, want)) in s.info.reward_terms.iter().zip(expect) {
            assert_eq!(*name, want_name);
            assert!((got - want).abs() < 1e-5, "{name}: {got} vs {want}");
        }
        let sum: f32 = s.info.reward_terms.iter().map(|t| t.1).sum();
        assert!((sum - s.reward).abs() < 1e-6);
        assert!((g.time - (k + 1) as f32 * 0.025).abs() < 1e-5);
        prev_obs = s.obs.clone();
    }
    assert_eq!(prev_obs.len(), 43);
}

#[test]
fn velocities_match_finite_differences_of_positions() {
    // In flight (no contact, no limit reached) with one solver iteration per step, Rapier moves
    // the coordinates by exactly velocity × dt, so the velocities the observation reports can be
    // checked against finite differences of positions.
    use esrl_sim::{Base, RobotSim, RobotState, SimSetup};
    let config = WalkConfig::default();
    let model = std::sync::Arc::new(esrl_sim::RobotModel::humanoid().unwrap());
    let mut physics = config.physics.clone();
    physics.solver_iterations = 1;
    let setup = SimSetup {
        dt: 0.01,
        physics,
        base: Base::Floating,
        ground: false,
        armature: vec![],
    };
    let mut q0 = vec![0.0; model.joints().len()];
    for j in 0..q0.len() {
        if let Some([lo, hi]) = model.joints()[j].limits {
            q0[j] = 0.5 * (lo + hi);
        }
    }
    let state = RobotState {
        base_position: [0.0, 0.0, 2.0],
        q: q0,
        qd: vec![],
    };
    let mut sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
    let torso = model.root();
    let n = model.joints().len();
    let mut q_prev: Vec<f32> = (0..n).map(|j| sim.joint_position(j)).collect();
    let mut c_prev = sim.link_center_of_mass(torso);
    for k in 0..10 {
        for j in 0..n {
            sim.set_joint_torque(j, if (j + k) % 2 == 0 { 4.0 } else { -3.0 });
        }
        sim.step();
        for j in 0..n {
            let q = sim.joint_position(j);
            let fd = (q - q_prev[j]) / 0.01;
            let v = sim.joint_velocity(j);
            assert!(
                (fd - v).abs() < 1e-3 * v.abs().max(1.0),
                "{}: Δq/dt {fd} vs q̇ {v}",
                model.joints()[j].name
            );
            q_prev[j] = q;
        }
        let c = sim.link_center_of_mass(torso);
        let fd = (c - c_prev) / 0.01;
        let v = sim.link_velocity(torso).0;
        assert!(
            (fd - v).length() < 1e-3 * v.length().max(1.0),
            "torso COM: Δc/dt {fd:?} vs v {v:?}"
        );
        c_prev = c;
    }
}

#[test]
fn an_unpowered_robot_falls_and_the_episode_terminates() {
    let mut env = env();
    env.reset(0);
    let zero = [0.0; 6];
    for k in 0..200 {
        let s = env.step(&zero);
        assert!(!s.truncated);
        if s.terminated {
            let g = gait(&s);
            assert!(g.fell && !g.success);
            assert!(
                g.height_error < -0.3 || g.torso_rotation[3] < (std::f32::consts::FRAC_PI_8).cos(),
                "{g:?}"
            );
            assert!(k > 4, "fell too early ({k})");
            return;
        }
    }
    panic!("the unpowered robot did not fall within 5 s");
}

#[test]
fn the_episode_truncates_at_its_time_limit() {
    let config = WalkConfig {
        episode_seconds: 0.25,
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(config).unwrap();
    assert_eq!(env.max_episode_steps(), 10);
    env.reset(0);
    let stand = env.standing_pose();
    let names: Vec<String> = env.actuated_joint_names().to_vec();
    for (k, n) in names.iter().enumerate() {
        let j = env.model().joint_index(n).unwrap();
        env.sim_mut().set_joint_servo(j, stand[k], 2000.0, 100.0);
    }
    for k in 1..=10 {
        let s = env.step(&[0.0; 6]);
        assert!(!s.terminated);
        assert_eq!(s.truncated, k == 10);
    }
}

/// An env reset with seed 0 whose hips and knees are held stiff at standing, so that
/// dorsiflexing both ankles (action `[0, 0, −0.6, 0, 0, −0.6]`) tips the body forward.
fn tipping_forward(config: WalkConfig) -> WalkEnv {
    let mut env = WalkEnv::new(config).unwrap();
    env.reset(0);
    let stand = env.standing_pose();
    for (k, n) in env.actuated_joint_names().to_vec().iter().enumerate() {
        if !n.ends_with("ankle") {
            let j = env.model().joint_index(n).unwrap();
            env.sim_mut().set_joint_servo(j, stand[k], 2000.0, 100.0);
        }
    }
    env
}

#[test]
fn passing_the_end_of_the_track_is_a_success() {
    let config = WalkConfig {
        track_length: 0.03,
        ..WalkConfig::default()
    };
    let mut env = tipping_forward(config);
    for _ in 0..80 {
        let s = env.step(&[0.0, 0.0, -0.6, 0.0, 0.0, -0.6]);
        if s.terminated {
            let g = gait(&s);
            assert!(g.success && !g.fell, "{g:?}");
            assert!(g.torso_position[0] >= 0.03);
            return;
        }
    }
    panic!("never reached x = 0.03 m");
}

#[test]
fn with_end_at_finish_off_the_episode_runs_past_the_line() {
    // The forward tip of the test above, with the line at 0.03 m not ending the episode.
    let config = WalkConfig {
        track_length: 0.03,
        end_at_finish: false,
        ..WalkConfig::default()
    };
    let mut env = tipping_forward(config);
    let mut crossed = None;
    for k in 0..80 {
        let s = env.step(&[0.0, 0.0, -0.6, 0.0, 0.0, -0.6]);
        let g = gait(&s);
        assert_eq!(
            g.success,
            g.torso_position[0] >= 0.03 && !g.fell,
            "step {k}"
        );
        if g.success {
            assert!(!s.terminated, "success ended the episode at step {k}");
            crossed.get_or_insert(k);
        }
        if s.terminated {
            break;
        }
    }
    let k = crossed.expect("never reached x = 0.03 m");
    assert!(
        k < 79,
        "crossed on the last step: nothing after it was checked"
    );
}

#[test]
fn bad_configs_name_the_field() {
    let cases: Vec<(WalkConfig, &str)> = vec![
        (
            WalkConfig {
                control_period: 0.0,
                ..WalkConfig::default()
            },
            "control_period",
        ),
        (
            WalkConfig {
                episode_seconds: f32::NAN,
                ..WalkConfig::default()
            },
            "episode_seconds",
        ),
        (
            WalkConfig {
                track_length: -1.0,
                ..WalkConfig::default()
            },
            "track_length",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.physics.substeps = 0;
                c
            },
            "physics.substeps",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.physics.solver_iterations = 0;
                c
            },
            "physics.solver_iterations",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.reward.power = f32::INFINITY;
                c
            },
            "reward.power",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.fall.max_tilt = 0.0;
                c
            },
            "fall.max_tilt",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.init_noise.joint_angle = -0.1;
                c
            },
            "init_noise.joint_angle",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.physics.actuator_armature = -1.0;
                c
            },
            "physics.actuator_armature",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.physics.limit_band = 0.0;
                c
            },
            "physics.limit_band",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.physics.limit_frequency = f32::NAN;
                c
            },
            "physics.limit_frequency",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.reward.action_sq = -0.1;
                c
            },
            "reward.action_sq",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.reward.torque_sq = f32::NAN;
                c
            },
            "reward.torque_sq",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.reward.tilt_sq = -1.0;
                c
            },
            "reward.tilt_sq",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.reward.forward_gate = Some(esrl_sim::UprightGate {
                    max_tilt: 0.0,
                    max_height_drop: 0.1,
                });
                c
            },
            "reward.forward_gate.max_tilt",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.fall.max_lateral = Some(0.0);
                c
            },
            "fall.max_lateral",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.fall.max_yaw = Some(f32::INFINITY);
                c
            },
            "fall.max_yaw",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.reset.crouch = -0.1;
                c
            },
            "reset.crouch",
        ),
        (
            {
                let mut c = WalkConfig::default();
                c.target.stiffness = -1.0;
                c
            },
            "target.stiffness",
        ),
    ];
    for (config, field) in cases {
        match WalkEnv::new(config) {
            Err(SimError::Config { field: f, .. }) => assert_eq!(f, field),
            Err(e) => panic!("{field}: wrong error {e}"),
            Ok(_) => panic!("{field}: accepted"),
        }
    }
    let mut c = WalkConfig::default();
    c.standing_pose.insert("left_elbow".into(), 0.3);
    assert!(
        matches!(WalkEnv::new(c), Err(SimError::Model { field, .. }) if field == "standing_pose.left_elbow")
    );
    let c = WalkConfig {
        foot_links: ["left_foot".into(), "right_hand".into()],
        ..WalkConfig::default()
    };
    assert!(matches!(WalkEnv::new(c), Err(SimError::Model { field, .. }) if field == "foot_links"));
    let mut c = WalkConfig {
        actuated_joints: vec!["left_hip".into(), "left_knee".into()],
        ..WalkConfig::default()
    };
    c.reset.pose = esrl_sim::ResetPose::Crouch;
    assert!(matches!(WalkEnv::new(c), Err(SimError::Model { field, .. }) if field == "reset.pose"));
    // `target` needs a range to map actions onto.
    let urdf = esrl_sim::HUMANOID_URDF.replace(
        r#"<joint name="left_knee" type="revolute">"#,
        r#"<joint name="left_knee" type="continuous">"#,
    );
    let model = std::sync::Arc::new(esrl_sim::RobotModel::from_urdf_str(&urdf).unwrap());
    let c = WalkConfig {
        action: esrl_sim::ActionMode::Target,
        ..WalkConfig::default()
    };
    match WalkEnv::from_model(model, c) {
        Err(SimError::Model { field, reason }) => {
            assert_eq!(field, "action");
            assert!(reason.contains("left_knee"), "{reason}");
        }
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn config_is_serde_with_defaults_and_no_unknown_fields() {
    let default = WalkConfig::default();
    let text = serde_json::to_string(&default).unwrap();
    let back: WalkConfig = serde_json::from_str(&text).unwrap();
    assert_eq!(back, default);
    let partial: WalkConfig =
        serde_json::from_str(r#"{"control_period": 0.02, "physics": {"substeps": 2}}"#).unwrap();
    assert_eq!(partial.control_period, 0.02);
    assert_eq!(partial.physics.substeps, 2);
    assert_eq!(
        partial.physics.solver_iterations,
        default.physics.solver_iterations
    );
    assert_eq!(partial.reward, default.reward);
    assert!(serde_json::from_str::<WalkConfig>(r#"{"contol_period": 0.02}"#).is_err());
    assert!(serde_json::from_str::<WalkConfig>(r#"{"reward": {"alive_bonus": 1}}"#).is_err());
    let options: WalkConfig = serde_json::from_str(
        r#"{"action": "target", "physics": {"joint_limits": "soft"}, "reset": {"pose": "split"},
            "reward": {"forward_gate": {"max_tilt": 0.3}}, "fall": {"max_yaw": 0.5}}"#,
    )
    .unwrap();
    assert_eq!(options.action, esrl_sim::ActionMode::Target);
    assert_eq!(options.physics.joint_limits, LimitModel::Soft);
    assert_eq!(options.reset.pose, esrl_sim::ResetPose::Split);
    let gate = options.reward.forward_gate.clone().unwrap();
    assert_eq!(gate.max_tilt, 0.3);
    assert_eq!(gate.max_height_drop, 0.15);
    assert_eq!(options.fall.max_yaw, Some(0.5));
    assert_eq!(options.fall.max_lateral, None);
    let back: WalkConfig = serde_json::from_str(&serde_json::to_string(&options).unwrap()).unwrap();
    assert_eq!(back, options);
    for bad in [
        r#"{"action": "torques"}"#,
        r#"{"physics": {"joint_limits": "brace"}}"#,
        r#"{"reset": {"pose": "standing", "depth": 1}}"#,
        r#"{"target": {"kp": 1}}"#,
        r#"{"reward": {"forward_gate": {"tilt": 1}}}"#,
    ] {
        assert!(serde_json::from_str::<WalkConfig>(bad).is_err(), "{bad}");
    }
}

#[test]
fn recording_data_put_the_feet_on_the_ground() {
    let mut env = env();
    env.reset(3);
    let poses = env.link_poses();
    let geometry = env.geometry();
    let names: Vec<&str> = env
        .model()
        .links()
        .iter()
        .map(|l| l.name.as_str())
        .collect();
    assert_eq!(
        poses.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
        names
    );
    assert_eq!(
        geometry.iter().map(|g| g.link.as_str()).collect::<Vec<_>>(),
        names
    );
    let torso = geometry.iter().find(|g| g.link == "torso").unwrap();
    assert_eq!(torso.shapes.len(), 3);
    let mut lowest = f32::INFINITY;
    for (pose, geom) in poses.iter().zip(&geometry) {
        for shape in &geom.shapes {
            if let esrl_sim::Shape::Box { size } = shape.shape {
                for corner in 0..8 {
                    let local = [
                        if corner & 1 == 0 { -0.5 } else { 0.5 } * size[0],
                        if corner & 2 == 0 { -0.5 } else { 0.5 } * size[1],
                        if corner & 4 == 0 { -0.5 } else { 0.5 } * size[2],
                    ];
                    let in_link = rotate(&shape.rotation, local);
                    let in_link = [
                        in_link[0] + shape.translation[0],
                        in_link[1] + shape.translation[1],
                        in_link[2] + shape.translation[2],
                    ];
                    let w = rotate(&pose.rotation, in_link);
                    lowest = lowest.min(w[2] + pose.translation[2]);
                }
            }
        }
    }
    assert!(lowest.abs() < 2e-3, "lowest box corner at z = {lowest}");
    let _ = serde_json::to_string(&geometry).unwrap();
    let _ = serde_json::to_string(&poses).unwrap();
}

#[test]
fn normalized_observation_is_the_raw_one_times_the_documented_factors() {
    // The table of the module docs, written out index by index for the humanoid.
    let mut want = vec![10.0, 10.0]; // height error, lateral offset: 1 = 0.1 m
    want.extend([1.0; 4]); // quaternion
    want.extend([1.0; 3]); // linear velocity, m/s
    want.extend([0.5; 3]); // angular velocity: 1 = 2 rad/s
    want.extend([0.1; 3]); // acceleration: 1 = 10 m/s²
    want.extend([1.0; 6]); // joint angles, rad
    want.extend([0.1; 6]); // joint velocities: 1 = 10 rad/s
    want.extend([1.0; 4]); // passive angles, rad
    want.extend([0.5; 4]); // passive velocities: 1 = 2 rad/s
    want.extend([1.0; 2]); // foot forces / weight
    want.extend([1.0; 6]); // previous action
    assert_eq!(want.len(), 43);
    let mut scaled = WalkEnv::new(WalkConfig::default()).unwrap();
    assert!(scaled.config().normalize_obs, "on by default");
    assert_eq!(scaled.obs_scale(), want.as_slice());
    let mut raw = env();
    assert!(raw.obs_scale().iter().all(|&f| f == 1.0));
    let check = |o_raw: &[f32], o_scaled: &[f32]| {
        for i in 0..43 {
            assert_eq!(o_scaled[i], o_raw[i] * want[i], "index {i}");
        }
    };
    check(&raw.reset(3), &scaled.reset(3));
    let mut seen_large = false;
    for k in 0..20 {
        let a = [0.8, -0.6, 0.4, -0.8, 0.6, -0.4].map(|v| if k % 2 == 0 { v } else { -v });
        let (r, s) = (raw.step(&a), scaled.step(&a));
        check(&r.obs, &s.obs);
        assert_eq!(
            r.reward, s.reward,
            "the reward does not depend on the scaling"
        );
        seen_large |= r.obs.iter().any(|v| v.abs() > 5.0);
        if r.terminated {
            break;
        }
    }
    assert!(
        seen_large,
        "raw entries beyond 5 exist for the scaling to tame"
    );
}
