//! Contract: gait metrics of a rollout equal hand-computed values on a 4-step trace, the track
//! time follows the documented precedence, and malformed traces are refused with an error
//! naming the field.

use esrl_metrics::{gait_metrics, GaitMetrics, GaitOptions, GaitStep, GaitTrace, MetricsError};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// 4 steps, actuators [left_hip, left_knee, right_hip, right_knee], two feet.
fn trace() -> GaitTrace {
    let mut t = GaitTrace::new(
        names(&["left_hip", "left_knee", "right_hip", "right_knee"]),
        names(&["left_foot", "right_foot"]),
    );
    let xs = [0.0, 20.0, 50.0, 60.0];
    let ys = [0.1, -0.3, 0.2, 0.0];
    let zs = [-0.1, 0.1, -0.2, 0.0];
    let torques = [
        [1.0, -2.0, 0.0, 4.0],
        [-1.0, 2.0, 0.0, -4.0],
        [3.0, -2.0, 0.0, 2.0],
        [-3.0, 2.0, 0.0, 2.0],
    ];
    let powers = [
        [1.0, 1.0, 1.0, 1.0],
        [-1.0, -1.0, -1.0, -1.0],
        [2.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, -2.0],
    ];
    let feet = [[100.0, 0.0], [50.0, 50.0], [0.0, 100.0], [0.0, 0.0]];
    for i in 0..4 {
        t.push(&GaitStep {
            time: 0.025 * (i + 1) as f64,
            torso_x: xs[i],
            torso_y: ys[i],
            torso_z_error: zs[i],
            forward_velocity: (i + 1) as f64,
            torques: &torques[i],
            powers: &powers[i],
            foot_forces: &feet[i],
            joint_angles: &[],
            foot_positions: &[],
            torso_pitch: None,
        });
    }
    t
}

#[test]
fn hand_computed_trace() {
    let g = gait_metrics(&trace(), &GaitOptions::default()).unwrap();
    assert_eq!(g.track_length, 50.0);
    assert_eq!(g.track_time, Some(0.025 * 3.0), "first sample with x ≥ 50");
    assert!(close(g.mean_forward_velocity, 2.5));
    assert!(close(g.mean_abs_lateral, 0.15));
    assert!(close(g.mean_vertical, -0.05));
    assert!(close(g.mean_abs_vertical, 0.1));
    assert_eq!(g.mean_abs_torque, vec![2.0, 2.0, 0.0, 3.0]);
    assert_eq!(g.mean_abs_power, vec![1.0, 0.5, 0.5, 1.0]);
    assert!(close(g.mean_abs_torque_overall, 1.75));
    assert!(close(g.mean_abs_power_overall, 0.75));
    // |2 − 3| / ((2 + 3)/2)
    assert!(close(g.knee_torque_asymmetry, 0.4));
    assert_eq!(g.mean_foot_force, vec![37.5, 37.5]);
    assert_eq!(g.distance, 60.0);
    assert!(!g.fell);
    assert_eq!(g.steps, 4);
    assert!(close(g.duration, 0.1));
    assert_eq!(g.actuator_names[3], "right_knee");
    // Contact (> 10 N): left [1, 1, 0, 0], right [0, 1, 1, 0]; the right touches down once.
    let c = g.cycle.expect("two feet with forces give a gait cycle");
    assert_eq!(
        (c.double_support, c.single_support, c.flight),
        (0.25, 0.5, 0.25)
    );
    assert_eq!(c.touchdowns, [0.0, 1.0]);
    assert_eq!(c.gait_class, esrl_metrics::GaitClass::Stand);
    assert_eq!(c.foot_speed, None, "no foot positions logged");
    assert!(g.joints.is_empty(), "no joint angles logged");
    assert_eq!(g.torso_pitch, None, "no torso pitch logged");
}

/// `a ⊗ b` for quaternions `[x, y, z, w]`.
fn qmul([ax, ay, az, aw]: [f64; 4], [bx, by, bz, bw]: [f64; 4]) -> [f64; 4] {
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

#[test]
fn torso_pitch_is_the_lean_seen_from_the_side() {
    // Each step's torso rolled 0.2 rad about its forward axis, then pitched by θ about +y
    // (q = q_y(θ) ⊗ q_x(0.2)): its up axis is (cos 0.2 · sin θ, −sin 0.2, cos 0.2 · cos θ),
    // whose angle from the vertical in the x–z plane is θ.
    let roll = [0.1f64.sin(), 0.0, 0.0, 0.1f64.cos()];
    let thetas: [f64; 4] = [0.1, 0.3, -0.1, 0.5];
    let mut t = trace();
    for &theta in &thetas {
        let pitch = [0.0, (theta / 2.0).sin(), 0.0, (theta / 2.0).cos()];
        t.torso_pitch
            .push(esrl_metrics::pitch_of(qmul(pitch, roll)));
    }
    for (got, want) in t.torso_pitch.iter().zip(thetas) {
        assert!(close(*got, want), "pitch {got} for θ = {want}");
    }
    // A forward lean is positive: the top of a torso turned about +y moves towards +x.
    assert!(esrl_metrics::pitch_of([0.0, 0.1f64.sin(), 0.0, 0.1f64.cos()]) > 0.0);
    let p = gait_metrics(&t, &GaitOptions::default())
        .unwrap()
        .torso_pitch
        .expect("a logged torso pitch gives its summary");
    // Sorted −0.1, 0.1, 0.3, 0.5: h = 3·0.05 = 0.15 and 3·0.95 = 2.85.
    assert!(close(p.mean, 0.2), "mean {}", p.mean);
    assert!(close(p.p5, -0.1 + 0.15 * 0.2), "p5 {}", p.p5);
    assert!(close(p.p95, 0.3 + 0.85 * 0.2), "p95 {}", p.p95);

    t.torso_pitch.pop();
    assert!(matches!(
        gait_metrics(&t, &GaitOptions::default()),
        Err(MetricsError::LengthMismatch { what, .. }) if what == "torso_pitch"
    ));
}

#[test]
fn track_time_precedence_and_absence() {
    let mut t = trace();
    t.success_time = Some(0.07);
    let g = gait_metrics(&t, &GaitOptions::default()).unwrap();
    assert_eq!(
        g.track_time,
        Some(0.07),
        "the environment's success time wins"
    );

    let mut short = trace();
    short.torso_x = vec![0.0, 1.0, 2.0, 3.0];
    short.fell = true;
    let g = gait_metrics(&short, &GaitOptions::default()).unwrap();
    assert_eq!(g.track_time, None);
    assert!(g.fell);
    assert_eq!(g.distance, 3.0);
    let opts = GaitOptions {
        track_length: 2.0,
        ..GaitOptions::default()
    };
    assert_eq!(
        gait_metrics(&short, &opts).unwrap().track_time,
        Some(0.025 * 3.0)
    );
}

#[test]
fn knee_names_come_from_the_caller() {
    let mut t = trace();
    t.actuator_names = names(&["lh", "lk", "rh", "rk"]);
    assert!(matches!(
        gait_metrics(&t, &GaitOptions::default()),
        Err(MetricsError::UnknownActuator { ref name, .. }) if name == "left_knee"
    ));
    // Swapping which knee is "left" leaves the symmetric index unchanged.
    let opts = GaitOptions {
        left_knee: "rk".into(),
        right_knee: "lk".into(),
        ..GaitOptions::default()
    };
    assert!(close(
        gait_metrics(&t, &opts).unwrap().knee_torque_asymmetry,
        0.4
    ));
    // Zero torque on both knees is symmetric, not 0/0.
    for row in &mut t.torques {
        row[1] = 0.0;
        row[3] = 0.0;
    }
    assert_eq!(gait_metrics(&t, &opts).unwrap().knee_torque_asymmetry, 0.0);
}

#[test]
fn malformed_traces_are_refused() {
    let opts = GaitOptions::default();
    let empty = GaitTrace::new(names(&["left_knee", "right_knee"]), vec![]);
    assert!(matches!(
        gait_metrics(&empty, &opts),
        Err(MetricsError::Empty { .. })
    ));

    let mut t = trace();
    t.torques[2].pop();
    let e = gait_metrics(&t, &opts).unwrap_err();
    assert!(matches!(
        e,
        MetricsError::LengthMismatch {
            found: 3,
            expected: 4,
            ..
        }
    ));
    assert!(e.to_string().contains("torques[2]"), "{e}");

    let mut t = trace();
    t.torso_y.pop();
    let e = gait_metrics(&t, &opts).unwrap_err();
    assert!(e.to_string().contains("torso_y"), "{e}");

    let mut t = trace();
    t.powers[1][2] = f64::NAN;
    let e = gait_metrics(&t, &opts).unwrap_err();
    assert!(matches!(e, MetricsError::NonFinite { index: 2, .. }));
    assert!(e.to_string().contains("powers[1]"), "{e}");

    let mut t = trace();
    t.forward_velocity[0] = f64::INFINITY;
    assert!(matches!(
        gait_metrics(&t, &opts),
        Err(MetricsError::NonFinite { .. })
    ));

    let bad = GaitOptions {
        track_length: 0.0,
        ..GaitOptions::default()
    };
    assert!(matches!(
        gait_metrics(&trace(), &bad),
        Err(MetricsError::InvalidParameter { .. })
    ));
}

#[test]
fn feet_are_optional_and_metrics_round_trip_json() {
    let mut t = trace();
    t.foot_names.clear();
    t.foot_forces.clear();
    t.success_time = None;
    t.torso_x = vec![0.0; 4];
    let g = gait_metrics(&t, &GaitOptions::default()).unwrap();
    assert!(g.mean_foot_force.is_empty());
    let json = serde_json::to_string(&g).unwrap();
    assert!(json.contains("\"track_time\":null"), "{json}");
    let back: GaitMetrics = serde_json::from_str(&json).unwrap();
    assert_eq!(back, g);
}
