//! Contract: Table 1 aggregates seeds into mean ± sample SD (counting seeds that lack a value)
//! and renders exactly the documented Markdown and CSV text.

use std::collections::BTreeMap;

use esrl_metrics::{
    actuator_markdown, format_number, joint_markdown, table1, table1_csv, table1_markdown,
    AgentRuns, CurveSummary, GaitClass, GaitCycle, GaitMetrics, JointMotion, MetricsError,
    SeedResult,
};

fn summary(nauc: f64, auc: f64, final_50: f64, best: f64, ett: Option<usize>) -> CurveSummary {
    CurveSummary {
        auc,
        nauc,
        final_50,
        best_win_50: best,
        episodes_to_target: ett,
    }
}

/// Gait metrics with the overall values given and per-actuator values derived from them.
#[allow(clippy::too_many_arguments)]
fn gait(
    track_time: Option<f64>,
    vel: f64,
    lat: f64,
    vert: f64,
    abs_vert: f64,
    torque: f64,
    power: f64,
    asym: f64,
    distance: f64,
    fell: bool,
) -> GaitMetrics {
    GaitMetrics {
        track_length: 50.0,
        track_time,
        mean_forward_velocity: vel,
        mean_abs_lateral: lat,
        mean_vertical: vert,
        mean_abs_vertical: abs_vert,
        actuator_names: vec!["left_knee".into(), "right_knee".into()],
        mean_abs_torque: vec![torque - 1.0, torque + 1.0],
        mean_abs_power: vec![power, power],
        mean_abs_torque_overall: torque,
        mean_abs_power_overall: power,
        knee_torque_asymmetry: asym,
        foot_names: vec![],
        mean_foot_force: vec![],
        distance,
        fell,
        steps: 100,
        duration: 2.5,
        cycle: None,
        joints: vec![],
        torso_pitch: None,
    }
}

/// Gait-cycle metrics with the table's columns given; the rest fixed.
fn cycle(
    ds: f64,
    flight: f64,
    alternation: Option<f64>,
    cadence: f64,
    step: Option<f64>,
    cv: Option<f64>,
    classes: &[(GaitClass, usize)],
) -> GaitCycle {
    GaitCycle {
        contact_force: 10.0,
        touchdowns: [5.0, 5.0],
        step_count: 10.0,
        cadence,
        alternation,
        synchronous: Some(0.0),
        double_support: ds,
        single_support: 1.0 - ds - flight,
        flight,
        duty_factor: [0.6, 0.6],
        step_length_mean: step,
        step_length_sd: None,
        stride_time_mean: Some(1.0),
        stride_time_cv: cv,
        foot_speed: Some(1.0),
        gait_class: classes[0].0,
        gait_classes: classes.iter().copied().collect::<BTreeMap<_, _>>(),
    }
}

fn knee(range: f64, at_limit: Option<f64>) -> Vec<JointMotion> {
    vec![JointMotion {
        name: "left_knee".into(),
        p5: 0.1,
        p95: 0.1 + range,
        range,
        limits: at_limit.map(|_| [0.0, 1.0]),
        at_lower: at_limit,
        at_upper: at_limit.map(|_| 0.0),
        at_limit,
    }]
}

/// `gait` with a gait cycle and joint motions.
fn with_cycle(mut g: GaitMetrics, c: GaitCycle, joints: Vec<JointMotion>) -> GaitMetrics {
    g.cycle = Some(c);
    g.joints = joints;
    g
}

fn agents() -> Vec<AgentRuns> {
    vec![
        AgentRuns {
            agent: "es-sac".into(),
            seeds: vec![
                SeedResult {
                    summary: summary(1.0, 1500.0, 10.0, 20.0, Some(100)),
                    gait: Some(with_cycle(
                        gait(
                            Some(40.0),
                            1.25,
                            0.05,
                            -0.02,
                            0.06,
                            40.0,
                            100.0,
                            0.1,
                            50.0,
                            false,
                        ),
                        cycle(
                            0.2,
                            0.0,
                            Some(1.0),
                            100.0,
                            Some(0.6),
                            Some(0.02),
                            &[(GaitClass::Walk, 2), (GaitClass::Fall, 1)],
                        ),
                        knee(0.1, Some(0.5)),
                    )),
                    q0_mean: Some(50.0),
                },
                SeedResult {
                    summary: summary(2.0, 3000.0, 10.0, 22.0, Some(200)),
                    gait: Some(with_cycle(
                        gait(None, 0.75, 0.15, -0.04, 0.10, 44.0, 120.0, 0.3, 20.0, true),
                        cycle(
                            0.4,
                            0.1,
                            Some(0.5),
                            120.0,
                            None,
                            None,
                            &[(GaitClass::Hop, 3)],
                        ),
                        knee(0.3, None),
                    )),
                    q0_mean: Some(60.0),
                },
                SeedResult {
                    summary: summary(3.0, 4500.0, 10.0, 24.0, None),
                    gait: None,
                    q0_mean: Some(70.0),
                },
            ],
        },
        AgentRuns {
            agent: "sac".into(),
            seeds: vec![(summary(1.23, 0.0, -5.5, 1e6, None), None).into()],
        },
    ]
}

#[test]
fn aggregation_by_hand() {
    let rows = table1(&agents()).unwrap();
    let r = &rows[0];
    assert_eq!(r.seeds, 3);
    let nauc = r.nauc.stat.unwrap();
    assert_eq!((nauc.mean, nauc.sd, nauc.n), (2.0, Some(1.0), 3));
    let ett = r.episodes_to_target.stat.unwrap();
    assert_eq!(ett.mean, 150.0);
    assert!((ett.sd.unwrap() - 5000f64.sqrt()).abs() < 1e-9);
    assert_eq!(ett.n, 2);
    assert_eq!(r.track_time.stat.unwrap().n, 1);
    assert_eq!(r.track_time.stat.unwrap().sd, None);
    assert_eq!((r.falls, r.gait_runs), (1, 2));
    assert_eq!(r.mean_abs_torque_per_actuator[1].stat.unwrap().mean, 43.0);
    assert_eq!(rows[1].track_time.stat, None);
    assert_eq!(rows[1].nauc.stat.unwrap().sd, None, "one seed has no SD");
}

#[test]
fn markdown_text() {
    let md = table1_markdown(&table1(&agents()).unwrap());
    let expected = "\
| Agent | Seeds | nAUC | AUC | Final-50 | Best-Win-50 | Episodes-to-Target | 50 m Track Time (s) | Fwd Velocity (m/s) | Mean \\|Lateral\\| (m) | Mean Vertical (m) | Mean \\|Vertical\\| (m) | Mean \\|Torque\\| (N·m) | Mean \\|Power\\| (W) | Knee Asymmetry | Distance (m) | Falls | Gait (episodes) | Double Support | Flight | Alternation | Cadence (steps/min) | Step Length (m) | Stride CV | At Limit | Q0 |
|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|
| es-sac | 3 | 2.00 ± 1.00 | 3000.00 ± 1500.00 | 10.00 ± 0.00 | 22.00 ± 2.00 | 150.00 ± 70.71 (2/3) | 40.00 (1/3) | 1.00 ± 0.35 (2/3) | 0.1000 ± 0.0707 (2/3) | -0.0300 ± 0.0141 (2/3) | 0.0800 ± 0.0283 (2/3) | 42.00 ± 2.83 (2/3) | 110.00 ± 14.14 (2/3) | 0.2000 ± 0.1414 (2/3) | 35.00 ± 21.21 (2/3) | 1/2 | hop 3, walk 2, fall 1 | 0.3000 ± 0.1414 (2/3) | 0.0500 ± 0.0707 (2/3) | 0.7500 ± 0.3536 (2/3) | 110.00 ± 14.14 (2/3) | 0.6000 (1/3) | 0.0200 (1/3) | 0.5000 (1/3) | 60.00 ± 10.00 |
| sac | 1 | 1.23 | 0.00 | -5.50 | 1.000e6 | - | - | - | - | - | - | - | - | - | - | - | - | - | - | - | - | - | - | - | - |
";
    assert_eq!(md, expected);
}

#[test]
fn actuator_markdown_text() {
    let md = actuator_markdown(&table1(&agents()).unwrap());
    let expected = "\
| Agent | left_knee \\|τ\\| (N·m) | right_knee \\|τ\\| (N·m) | left_knee \\|P\\| (W) | right_knee \\|P\\| (W) |
|---|---:|---:|---:|---:|
| es-sac | 41.00 ± 2.83 (2/3) | 43.00 ± 2.83 (2/3) | 110.00 ± 14.14 (2/3) | 110.00 ± 14.14 (2/3) |
| sac | - | - | - | - |
";
    assert_eq!(md, expected);
}

#[test]
fn joint_markdown_text() {
    let md = joint_markdown(&table1(&agents()).unwrap());
    // Ranges 0.1 and 0.3 rad: mean 0.2 rad = 11.46°, SD √0.02 rad = 8.10°.
    let expected = "\
| Agent | left_knee ROM (°) | left_knee at limit |
|---|---:|---:|
| es-sac | 11.46 ± 8.10 (2/3) | 0.5000 (1/3) |
| sac | - | - |
";
    assert_eq!(md, expected);
}

#[test]
fn csv_text() {
    let mut input = agents();
    input[1].agent = "sac, \"v2\"".into();
    let csv = table1_csv(&table1(&input).unwrap());
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3);
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(header.len(), 2 + 23 * 3 + 4);
    assert_eq!(
        &header[..5],
        ["agent", "seeds", "nauc_mean", "nauc_sd", "nauc_n"]
    );
    assert_eq!(
        &header[14..17],
        [
            "episodes_to_target_mean",
            "episodes_to_target_sd",
            "episodes_to_target_n"
        ]
    );
    assert_eq!(
        &header[header.len() - 3..],
        ["falls", "gait_runs", "gait_classes"]
    );
    assert_eq!(
        &header[44..50],
        [
            "q0_mean_mean",
            "q0_mean_sd",
            "q0_mean_n",
            "double_support_mean",
            "double_support_sd",
            "double_support_n"
        ]
    );
    assert!(
        lines[1].starts_with("es-sac,3,2,1,3,3000,1500,3,10,0,3,22,2,3,150,70.71067811865476,2,"),
        "{}",
        lines[1]
    );
    assert!(lines[1].contains(",60,10,3,"), "{}", lines[1]);
    assert!(
        lines[1].ends_with(",0.5,,1,50,1,2,hop:3;walk:2;fall:1"),
        "{}",
        lines[1]
    );
    // Quoted name, one seed: empty SD, undefined cells empty with n = 0.
    assert!(
        lines[2].starts_with("\"sac, \"\"v2\"\"\",1,1.23,,1,0,,1,-5.5,,1,1000000,,1,,,0,"),
        "{}",
        lines[2]
    );
    assert!(lines[2].ends_with(",,,0,,0,0,"), "{}", lines[2]);
}

#[test]
fn number_format() {
    assert_eq!(format_number(4536.5), "4536.50");
    assert_eq!(format_number(0.0576), "0.0576");
    assert_eq!(format_number(-0.0285), "-0.0285");
    assert_eq!(format_number(6.8e6), "6.800e6");
    assert_eq!(format_number(0.0001), "1.000e-4");
    assert_eq!(format_number(0.0), "0.00");
    // A cell's SD takes the style of the larger of mean and SD.
    let cell = esrl_metrics::Cell {
        stat: Some(esrl_metrics::mean_sd(&[0.002 - 0.0073, 0.002 + 0.0073]).unwrap()),
        seeds: 2,
    };
    assert_eq!(cell.to_markdown(), "0.0020 ± 0.0103");
    let big = esrl_metrics::Cell {
        stat: Some(esrl_metrics::mean_sd(&[6.8e6 - 2.5e5, 6.8e6 + 2.5e5]).unwrap()),
        seeds: 2,
    };
    assert_eq!(big.to_markdown(), "6.800e6 ± 3.536e5");
}

#[test]
fn bad_aggregation_input() {
    let none = [AgentRuns {
        agent: "td3".into(),
        seeds: vec![],
    }];
    assert!(matches!(table1(&none), Err(MetricsError::Empty { .. })));

    let mut nan = agents();
    nan[0].seeds[1].summary.final_50 = f64::NAN;
    let e = table1(&nan).unwrap_err();
    assert!(matches!(e, MetricsError::NonFinite { index: 1, .. }));
    assert!(
        e.to_string().contains("es-sac") && e.to_string().contains("final_50"),
        "{e}"
    );

    let mut mixed = agents();
    if let Some(g) = mixed[0].seeds[1].gait.as_mut() {
        g.actuator_names.reverse();
    }
    assert!(matches!(
        table1(&mixed),
        Err(MetricsError::InvalidParameter { .. })
    ));
}
