//! Contract: the gait-cycle metrics and the gait class of synthetic contact traces equal their
//! hand-computed values — an alternating walk with 20 % double support is a `walk` with
//! alternation 1, a synchronous two-footed hop a `hop`, an alternating run with 30 % flight a
//! `run`, a standing trace `stand` — both from contact flags and through `gait_metrics` on a
//! full trace with foot forces and positions; the range of motion and time at a limit of a
//! joint are hand-checked too, and bad inputs are refused naming the field.

use std::collections::BTreeMap;

use esrl_metrics::{
    classify_gait, gait_metrics, gait_phases, joint_motion, majority_class, mean_cycle, percentile,
    step_lengths, GaitClass, GaitClassInput, GaitOptions, GaitStep, GaitThresholds, GaitTrace,
    MetricsError,
};

const DT: f64 = 0.01;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + b.abs())
}

/// Contact of a foot that is down for the first `stance` samples of every `period`, shifted
/// by `offset` samples (down when `(i + offset) % period < stance`).
fn foot(n: usize, period: usize, stance: usize, offset: usize) -> Vec<bool> {
    (0..n).map(|i| (i + offset) % period < stance).collect()
}

fn class_of(left: &[bool], right: &[bool]) -> GaitClass {
    let t = GaitThresholds::default();
    let p = gait_phases(left, right, DT, t.sync_window).unwrap();
    classify_gait(&GaitClassInput::from_phases(&p), &t)
}

/// Left down 60 % of each 1 s cycle from sample 0, right the same half a cycle later:
/// double support 2 × 10 % = 20 %, single support 80 %, no flight.
fn walk(n: usize) -> (Vec<bool>, Vec<bool>) {
    (foot(n, 100, 60, 0), foot(n, 100, 60, 50))
}

#[test]
fn alternating_walk_with_20_percent_double_support() {
    let (l, r) = walk(500);
    let p = gait_phases(&l, &r, DT, 0.05).unwrap();
    assert!(close(p.double_support, 0.2));
    assert!(close(p.single_support, 0.8));
    assert_eq!(p.flight, 0.0);
    assert!(close(p.duty_factor[0], 0.6) && close(p.duty_factor[1], 0.6));
    // Left is down from the start: touchdowns at 100, 200, 300, 400; right at 50, …, 450.
    assert_eq!(p.touchdowns, [4, 5]);
    assert_eq!(p.step_count, 9);
    assert!(
        close(p.touchdown_times[1][0], 0.51),
        "sample 50 ends at 0.51 s"
    );
    // 9 steps in 5 s.
    assert!(close(p.cadence, 108.0));
    assert_eq!(p.alternation, Some(1.0));
    assert_eq!(p.synchronous, Some(0.0));
    assert_eq!(p.landings, 0);
    assert!(close(p.stride_time_mean.unwrap(), 1.0));
    assert!(p.stride_time_sd.unwrap() < 1e-12);
    assert!(p.stride_time_cv.unwrap() < 1e-12);
    assert_eq!(class_of(&l, &r), GaitClass::Walk);
}

#[test]
fn synchronous_two_footed_hop() {
    // Both feet down 30 of every 50 samples, together: 40 % flight.
    let c = foot(300, 50, 30, 0);
    let p = gait_phases(&c, &c, DT, 0.05).unwrap();
    assert!(close(p.double_support, 0.6));
    assert!(close(p.flight, 0.4));
    assert_eq!(p.single_support, 0.0);
    assert_eq!(p.touchdowns, [5, 5]);
    assert_eq!(p.landings, 5);
    assert_eq!(p.synchronous, Some(1.0));
    assert_eq!(p.alternation, Some(0.0), "landings never switch foot");
    assert!(close(p.cadence, 200.0));
    assert_eq!(class_of(&c, &c), GaitClass::Hop);
    // Still a hop when one foot lands up to the sync window (5 samples) after the other.
    let late = foot(300, 50, 30, 45);
    let p = gait_phases(&c, &late, DT, 0.05).unwrap();
    assert_eq!(p.landings, 5);
    assert_eq!(class_of(&c, &late), GaitClass::Hop);
    // Six samples (0.06 s) apart, beyond the window, they are separate steps, and in time
    // order R L R L … they alternate: the window is where a staggered landing becomes a step.
    let later = foot(300, 50, 30, 44);
    let p = gait_phases(&c, &later, DT, 0.05).unwrap();
    assert_eq!(p.landings, 0);
    assert_eq!(p.alternation, Some(1.0));
}

#[test]
fn alternating_run_with_30_percent_flight() {
    // Each foot down 35 % of the cycle, half a cycle apart: flight 1 − 2 × 0.35.
    let (l, r) = (foot(500, 100, 35, 0), foot(500, 100, 35, 50));
    let p = gait_phases(&l, &r, DT, 0.05).unwrap();
    assert!(close(p.flight, 0.3));
    assert_eq!(p.double_support, 0.0);
    assert!(close(p.single_support, 0.7));
    assert_eq!(p.alternation, Some(1.0));
    assert_eq!(class_of(&l, &r), GaitClass::Run);
}

#[test]
fn standing_still_and_sliding() {
    let down = vec![true; 400];
    let p = gait_phases(&down, &down, DT, 0.05).unwrap();
    assert_eq!(
        p.step_count, 0,
        "feet down from reset have not touched down"
    );
    assert_eq!(p.alternation, None);
    assert_eq!(p.synchronous, None);
    assert_eq!(p.double_support, 1.0);
    let t = GaitThresholds::default();
    let mut input = GaitClassInput::from_phases(&p);
    assert_eq!(classify_gait(&input, &t), GaitClass::Stand);
    input.foot_speed = Some(0.009);
    assert_eq!(classify_gait(&input, &t), GaitClass::Stand);
    input.foot_speed = Some(0.03);
    assert_eq!(
        classify_gait(&input, &t),
        GaitClass::Shuffle,
        "sliding feet"
    );
    input.fell = true;
    assert_eq!(classify_gait(&input, &t), GaitClass::Fall);
}

#[test]
fn falls_shuffles_and_slow_steps() {
    let t = GaitThresholds::default();
    // A walk that ends in a fall is still a walk once it has taken two strides …
    let (l, r) = walk(500);
    let p = gait_phases(&l, &r, DT, 0.05).unwrap();
    let fell = GaitClassInput {
        fell: true,
        ..GaitClassInput::from_phases(&p)
    };
    assert_eq!(classify_gait(&fell, &t), GaitClass::Walk);
    // … but not after three touchdowns (samples 0..=150: right at 50, left at 100, right 150).
    let p = gait_phases(&l[..151], &r[..151], DT, 0.05).unwrap();
    assert_eq!(p.step_count, 3);
    let fell = GaitClassInput {
        fell: true,
        ..GaitClassInput::from_phases(&p)
    };
    assert_eq!(classify_gait(&fell, &t), GaitClass::Fall);
    // … nor within 2 s: the same 9 touchdowns at 0.3 s per cycle last 1.5 s.
    let p = gait_phases(&l, &r, 0.003, 0.015).unwrap();
    assert_eq!(p.step_count, 9);
    let mut fast = GaitClassInput::from_phases(&p);
    assert!(close(fast.duration, 1.5));
    assert_eq!(classify_gait(&fast, &t), GaitClass::Walk, "up: a walk");
    fast.fell = true;
    assert_eq!(classify_gait(&fast, &t), GaitClass::Fall);
    // One foot tapping while the other stays down: no alternation, no flight.
    let tap = foot(400, 20, 10, 0);
    assert_eq!(class_of(&vec![true; 400], &tap), GaitClass::Shuffle);
    // Alternating steps (108 a minute, 1.8 a second) that advance the feet 0.09 m/s, 5 cm a
    // step: stepping in place. At 0.9 m/s, 0.5 m a step: a walk.
    let mut input = GaitClassInput::from_phases(&gait_phases(&l, &r, DT, 0.05).unwrap());
    input.foot_speed = Some(0.09);
    assert_eq!(classify_gait(&input, &t), GaitClass::Shuffle);
    input.foot_speed = Some(0.9);
    assert_eq!(classify_gait(&input, &t), GaitClass::Walk);
    // The same walk at a tenth of the speed: 10.8 steps/min is below 60.
    let p = gait_phases(&l, &r, 10.0 * DT, 0.05).unwrap();
    assert!(close(p.cadence, 10.8));
    assert_eq!(
        classify_gait(&GaitClassInput::from_phases(&p), &t),
        GaitClass::Stand
    );
}

#[test]
fn step_lengths_between_footprints() {
    // Left touches down at samples 100k at x = 1.4k, right at 50 + 100k at 0.7 + 1.4k: every
    // footprint 0.7 m ahead of the previous one.
    let (l, r) = walk(500);
    let mut x = [0.0, -0.7];
    let foot_x: Vec<[f64; 2]> = (0..500)
        .map(|i| {
            if i > 0 && i % 100 == 0 {
                x[0] = 1.4 * (i / 100) as f64;
            }
            if i % 100 == 50 {
                x[1] = 0.7 + 1.4 * (i / 100) as f64;
            }
            x
        })
        .collect();
    let steps = step_lengths(&l, &r, &foot_x, DT, 0.05).unwrap();
    assert_eq!(steps.len(), 8, "9 alternating touchdowns, 8 steps");
    assert!(steps.iter().all(|s| close(*s, 0.7)), "{steps:?}");

    // The same through `gait_metrics` on a full trace: forces 400 N down / 0 N up, the feet
    // at y = ±0.1.
    let mut trace = GaitTrace::new(
        vec!["left_knee".into(), "right_knee".into()],
        vec!["left_foot".into(), "right_foot".into()],
    );
    trace.joint_limits = vec![Some([0.0, 1.0]), None];
    for i in 0..500 {
        let f = |c: bool| if c { 400.0 } else { 0.0 };
        let q = [if i < 100 { 1.0 } else { 0.5 }, 0.2];
        trace.push(&GaitStep {
            time: (i + 1) as f64 * DT,
            torso_x: 0.0,
            torso_y: 0.0,
            torso_z_error: 0.0,
            forward_velocity: 1.26,
            torques: &[0.0, 0.0],
            powers: &[0.0, 0.0],
            foot_forces: &[f(l[i]), f(r[i])],
            joint_angles: &q,
            foot_positions: &[[foot_x[i][0], 0.1], [foot_x[i][1], -0.1]],
            torso_pitch: None,
        });
    }
    let g = gait_metrics(&trace, &GaitOptions::default()).unwrap();
    let c = g.cycle.unwrap();
    assert_eq!(c.gait_class, GaitClass::Walk);
    assert_eq!(c.gait_classes, BTreeMap::from([(GaitClass::Walk, 1)]));
    assert_eq!(c.touchdowns, [4.0, 5.0]);
    assert!(close(c.double_support, 0.2));
    assert!(close(c.cadence, 108.0));
    assert!(close(c.step_length_mean.unwrap(), 0.7));
    assert!(c.step_length_sd.unwrap() < 1e-12);
    // Left foot 0 → 5.6 m, right −0.7 → 6.3 m, in 5 s: (5.6 + 7.0) / 2 / 5.
    assert!(close(c.foot_speed.unwrap(), 1.26));
    assert_eq!(c.contact_force, 10.0);
    // Left knee at its upper limit (1.0) for the first 100 of 500 samples.
    let knee = &g.joints[0];
    assert_eq!(knee.at_upper, Some(0.2));
    assert_eq!(knee.at_lower, Some(0.0));
    assert_eq!(knee.at_limit, Some(0.2));
    // 5th percentile 0.5, 95th 1.0 (400 samples at 0.5, 100 at 1.0).
    assert_eq!((knee.p5, knee.p95, knee.range), (0.5, 1.0, 0.5));
    assert_eq!(g.joints[1].at_limit, None, "no limits, no time at a limit");
    assert_eq!(g.joints[1].range, 0.0);

    // A contact threshold above the 400 N load: no foot is ever down.
    let mut options = GaitOptions::default();
    options.thresholds.contact_force = 500.0;
    let c = gait_metrics(&trace, &options).unwrap().cycle.unwrap();
    assert_eq!((c.flight, c.step_count), (1.0, 0.0));
}

#[test]
fn percentiles_and_joint_motion_by_hand() {
    let v: Vec<f64> = (1..=101).map(f64::from).collect();
    assert_eq!(percentile(&v, 0.05).unwrap(), 6.0);
    assert_eq!(percentile(&v, 0.95).unwrap(), 96.0);
    // h = 3 × 0.05 = 0.15: 1 + 0.15 × (2 − 1).
    assert!(close(
        percentile(&[4.0, 1.0, 3.0, 2.0], 0.05).unwrap(),
        1.15
    ));
    let m = joint_motion("ankle", &v, Some([0.0, 100.0]), 1.0).unwrap();
    assert_eq!((m.p5, m.p95, m.range), (6.0, 96.0, 90.0));
    // 1 ≤ 0 + 1 at the lower limit; 99, 100, 101 ≥ 100 − 1 at the upper one.
    assert!(close(m.at_lower.unwrap(), 1.0 / 101.0));
    assert!(close(m.at_upper.unwrap(), 3.0 / 101.0));
    assert!(close(m.at_limit.unwrap(), 4.0 / 101.0));
}

#[test]
fn majority_and_mean_over_episodes() {
    let (l, r) = walk(500);
    let t = GaitThresholds::default();
    let p = gait_phases(&l, &r, DT, 0.05).unwrap();
    let walk = esrl_metrics::GaitCycle::from_parts(&p, &[0.6, 0.8], Some(1.0), false, &t);
    let c = foot(300, 50, 30, 0);
    let q = gait_phases(&c, &c, DT, 0.05).unwrap();
    let hop = esrl_metrics::GaitCycle::from_parts(&q, &[], None, false, &t);
    assert_eq!(hop.gait_class, GaitClass::Hop);
    let m = mean_cycle(&[&walk, &hop, &hop]).unwrap();
    assert_eq!(m.gait_class, GaitClass::Hop);
    assert_eq!(
        m.gait_classes,
        BTreeMap::from([(GaitClass::Hop, 2), (GaitClass::Walk, 1)])
    );
    assert!(close(m.double_support, (0.2 + 0.6 + 0.6) / 3.0));
    assert!(close(m.touchdowns[0], (4.0 + 5.0 + 5.0) / 3.0));
    // Only the walk has step lengths: their mean 0.7 and SD √0.02.
    assert!(close(m.step_length_mean.unwrap(), 0.7));
    assert!(close(m.step_length_sd.unwrap(), 0.02f64.sqrt()));
    assert_eq!(m.foot_speed, Some(1.0));
    // A tie goes to the less locomotive class.
    let tie = BTreeMap::from([(GaitClass::Walk, 2), (GaitClass::Fall, 2)]);
    assert_eq!(majority_class(&tie), Some(GaitClass::Fall));
    assert_eq!(majority_class(&BTreeMap::new()), None);
    assert_eq!(mean_cycle(&[]), None);
}

#[test]
fn bad_inputs_name_the_field() {
    let (l, r) = walk(10);
    match gait_phases(&l, &r[..9], DT, 0.05) {
        Err(MetricsError::LengthMismatch { what, .. }) => assert_eq!(what, "right contact"),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        gait_phases(&[], &[], DT, 0.05),
        Err(MetricsError::Empty { .. })
    ));
    for dt in [0.0, -1.0, f64::NAN] {
        match gait_phases(&l, &r, dt, 0.05) {
            Err(MetricsError::InvalidParameter { what, .. }) => assert_eq!(what, "dt"),
            other => panic!("{other:?}"),
        }
    }
    match step_lengths(&l, &r, &[[0.0, f64::NAN]; 10], DT, 0.05) {
        Err(MetricsError::NonFinite { what, index, .. }) => {
            assert_eq!((what.as_str(), index), ("foot_x", 0))
        }
        other => panic!("{other:?}"),
    }
    let bad = GaitThresholds {
        min_flight: 1.5,
        ..GaitThresholds::default()
    };
    match bad.validate() {
        Err(MetricsError::InvalidParameter { what, .. }) => {
            assert_eq!(what, "thresholds.min_flight")
        }
        other => panic!("{other:?}"),
    }
    match joint_motion("knee", &[0.0, 1.0], Some([1.0, 0.0]), 0.01) {
        Err(MetricsError::InvalidParameter { what, .. }) => {
            assert_eq!(what, "joint_limits[knee]")
        }
        other => panic!("{other:?}"),
    }
    assert!(percentile(&[1.0], 1.5).is_err());
}
