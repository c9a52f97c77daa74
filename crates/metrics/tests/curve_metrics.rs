//! Contract: the learning-curve metrics (AUC, nAUC, Final-50, Best-Win-50, trailing means,
//! Episodes-to-Target, per-method target, mean ± SD) equal hand-computed values, including the
//! documented edge cases, and refuse empty or non-finite input.

use esrl_metrics::{
    auc, best_win_50, best_window_mean, episodes_to_target, episodes_to_target_window, final_50,
    final_mean, mean_sd, median, method_target, method_target_with, nauc, summarize_method,
    trailing_means, CurveSummary, MetricsError,
};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

#[test]
fn short_curve_uses_all_values() {
    let c = [1.0, 2.0, 3.0, 4.0];
    assert_eq!(auc(&c).unwrap(), 10.0);
    assert_eq!(nauc(&c).unwrap(), 2.5);
    assert_eq!(final_50(&c).unwrap(), 2.5);
    assert_eq!(best_win_50(&c).unwrap(), 2.5);
}

#[test]
fn sixty_values_final_and_best_window() {
    // 50 zeros then 10 × 100: AUC 1000, the last 50 hold 40 zeros and the ten 100s.
    let mut c = vec![0.0; 50];
    c.extend([100.0; 10]);
    assert_eq!(auc(&c).unwrap(), 1000.0);
    assert!(close(nauc(&c).unwrap(), 1000.0 / 60.0));
    assert_eq!(final_50(&c).unwrap(), 20.0);
    assert_eq!(best_win_50(&c).unwrap(), 20.0);
}

#[test]
fn best_window_finds_an_interior_plateau() {
    // 1.0 on [70, 120): exactly one 50-window is all ones; its neighbours hold 49 of them.
    let mut c = vec![0.0; 200];
    for v in &mut c[70..120] {
        *v = 1.0;
    }
    assert_eq!(best_win_50(&c).unwrap(), 1.0);
    assert_eq!(final_50(&c).unwrap(), 0.0);
    // Cut the curve at 119: the best window is [69, 119) with 49 ones.
    assert!(close(best_win_50(&c[..119]).unwrap(), 49.0 / 50.0));
}

#[test]
fn small_window_by_hand() {
    let c = [1.0, 5.0, 2.0, 8.0, 3.0];
    // windows of 3: 8/3, 15/3, 13/3
    assert_eq!(best_window_mean(&c, 3).unwrap(), 5.0);
    assert!(close(final_mean(&c, 3).unwrap(), 13.0 / 3.0));
    let m = trailing_means(&c, 3).unwrap();
    let expected = [1.0, 3.0, 8.0 / 3.0, 5.0, 13.0 / 3.0];
    assert_eq!(m.len(), expected.len());
    for (a, b) in m.iter().zip(expected) {
        assert!(close(*a, b), "{m:?}");
    }
    assert_eq!(episodes_to_target_window(&c, 4.5, 3).unwrap(), Some(3));
    assert_eq!(
        episodes_to_target_window(&c, 5.0, 3).unwrap(),
        Some(3),
        "reaching = ≥"
    );
    assert_eq!(episodes_to_target_window(&c, 1.0, 3).unwrap(), Some(0));
    assert_eq!(episodes_to_target_window(&c, 5.1, 3).unwrap(), None);
}

#[test]
fn trailing_mean_at_the_start_uses_available_values() {
    // A lucky first episode reaches the target at once under the documented "shrink" choice.
    let mut c = vec![100.0];
    c.extend([0.0; 80]);
    assert_eq!(episodes_to_target(&c, 50.0).unwrap(), Some(0));
    // Linear ramp c[i] = i: trailing mean (i < 50) is i/2, then i − 24.5.
    let ramp: Vec<f64> = (0..100).map(f64::from).collect();
    assert_eq!(episodes_to_target(&ramp, 20.0).unwrap(), Some(40));
    assert_eq!(episodes_to_target(&ramp, 30.0).unwrap(), Some(55));
    assert_eq!(episodes_to_target(&ramp, 74.5).unwrap(), Some(99));
    assert_eq!(
        episodes_to_target(&ramp, 74.6).unwrap(),
        None,
        "never reached"
    );
}

#[test]
fn median_and_method_target() {
    assert_eq!(median(&[3.0, 1.0, 2.0]).unwrap(), 2.0);
    assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]).unwrap(), 2.5);
    // Short curves: Best-Win-50 is the mean of each.
    let odd = [vec![1.0; 10], vec![3.0; 10], vec![10.0; 10]];
    assert!(close(method_target(&odd).unwrap(), 2.4));
    let even = [vec![1.0], vec![3.0], vec![10.0], vec![20.0]];
    assert!(close(method_target(&even).unwrap(), 0.8 * 6.5));
    // One seed: its own Best-Win-50. Negative medians are scaled as is.
    assert!(close(method_target(&[vec![-10.0]]).unwrap(), -8.0));
    assert!(close(
        method_target_with(&[vec![1.0, 5.0, 2.0]], 2, 0.5).unwrap(),
        1.75
    ));
}

#[test]
fn summarize_method_computes_the_target_from_all_seeds() {
    let a: Vec<f64> = (0..60).map(f64::from).collect();
    let b: Vec<f64> = (0..60).map(|i| 2.0 * f64::from(i)).collect();
    // Best-Win-50: 34.5 and 69; median 51.75; target 41.4.
    let s = summarize_method(&[&a, &b]).unwrap();
    assert_eq!(
        s[0],
        CurveSummary {
            auc: 1770.0,
            nauc: 29.5,
            final_50: 34.5,
            best_win_50: 34.5,
            // a's trailing mean: i/2 for i < 50 (max 24.5), then i − 24.5 ≥ 41.4 from i = 66: never.
            episodes_to_target: None,
        }
    );
    assert_eq!(s[1].episodes_to_target, Some(42));
    assert_eq!(s[1].best_win_50, 69.0);
    // A single seed always reaches 80% of its own best window.
    let one = summarize_method(&[&a]).unwrap();
    // target 27.6: trailing mean i − 24.5 ≥ 27.6 from i = 53 (i/2 peaks at 24.5 before).
    assert_eq!(one[0].episodes_to_target, Some(53));
}

#[test]
fn summary_json_keys_are_exact() {
    let s = CurveSummary::from_curve(&[1.0, 2.0], None).unwrap();
    let v: serde_json::Value = serde_json::to_value(s).unwrap();
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "auc",
            "best_win_50",
            "episodes_to_target",
            "final_50",
            "nauc"
        ]
    );
    assert!(v["episodes_to_target"].is_null());
    let back: CurveSummary = serde_json::from_value(v).unwrap();
    assert_eq!(back, s);
}

#[test]
fn mean_and_sample_sd() {
    let s = mean_sd(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]).unwrap();
    assert_eq!(s.mean, 5.0);
    assert!(close(s.sd.unwrap(), (32.0f64 / 7.0).sqrt()));
    assert_eq!(s.n, 8);
    let one = mean_sd(&[3.5]).unwrap();
    assert_eq!((one.mean, one.sd, one.n), (3.5, None, 1));
    assert_eq!(mean_sd(&[1.0, 1.0]).unwrap().sd, Some(0.0));
}

#[test]
fn empty_and_non_finite_inputs_are_errors() {
    let empty: [f64; 0] = [];
    for r in [
        auc(&empty),
        nauc(&empty),
        final_50(&empty),
        best_win_50(&empty),
        median(&empty),
    ] {
        assert!(matches!(r, Err(MetricsError::Empty { .. })), "{r:?}");
    }
    assert!(matches!(mean_sd(&empty), Err(MetricsError::Empty { .. })));
    assert!(matches!(
        episodes_to_target(&empty, 1.0),
        Err(MetricsError::Empty { .. })
    ));
    let no_seeds: [Vec<f64>; 0] = [];
    assert!(matches!(
        method_target(&no_seeds),
        Err(MetricsError::Empty { .. })
    ));

    let nan = [1.0, f64::NAN, 3.0];
    match auc(&nan) {
        Err(MetricsError::NonFinite { index, value, .. }) => {
            assert_eq!(index, 1);
            assert!(value.is_nan());
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        best_win_50(&[0.0, f64::INFINITY]),
        Err(MetricsError::NonFinite { index: 1, .. })
    ));
    assert!(matches!(mean_sd(&nan), Err(MetricsError::NonFinite { .. })));
    match method_target(&[vec![1.0], vec![f64::NAN]]) {
        Err(e @ MetricsError::NonFinite { .. }) => {
            assert!(e.to_string().contains("seed 1"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        episodes_to_target(&[1.0], f64::NAN),
        Err(MetricsError::InvalidParameter { .. })
    ));
    assert!(matches!(
        final_mean(&[1.0], 0),
        Err(MetricsError::InvalidParameter { .. })
    ));
}
