//! Contract: the interval estimates of `esrl_metrics` (IQM, percentile bootstrap, probability
//! of improvement, Wilson) agree with values computed by hand and with the definitions of
//! `rliable` / SciPy they follow; the bootstrap is repeatable and covers the estimate.

use esrl_metrics::{
    bootstrap, iqm, iqm_interval, probability_of_improvement, probability_of_improvement_interval,
    wilson, Z95,
};

#[test]
fn wilson_by_hand() {
    // k = 2, n = 5, z² = 3.8415: centre (2 + 1.9207)/8.8415 = 0.44345, half-width
    // 1.96/8.8415 · √(2·3/5 + 0.96037) = 0.22168 · 1.46977 = 0.32582 → [0.11763, 0.76927].
    let w = wilson(2, 5, Z95).unwrap();
    assert!((w.lo - 0.117_63).abs() < 1e-4, "{w:?}");
    assert!((w.hi - 0.769_27).abs() < 1e-4, "{w:?}");
    // 0 of 10: [0, z²/(n + z²)] = [0, 0.27753]; 10 of 10 its mirror.
    let none = wilson(0, 10, Z95).unwrap();
    assert_eq!(none.lo, 0.0);
    assert!((none.hi - 3.841_459 / 13.841_459).abs() < 1e-6);
    let all = wilson(10, 10, Z95).unwrap();
    assert!((all.lo - 10.0 / 13.841_459).abs() < 1e-6 && all.hi == 1.0);
    // The bounds at 0 and n are exact for every n (at n = 3 the formula's subtraction leaves
    // 5.6e-17 above the estimate).
    for n in 1..=40 {
        assert_eq!(wilson(0, n, Z95).unwrap().lo, 0.0, "0 of {n}");
        assert_eq!(wilson(n, n, Z95).unwrap().hi, 1.0, "{n} of {n}");
    }
    // Impossible counts are errors.
    assert!(wilson(0, 0, Z95).is_err() && wilson(3, 2, Z95).is_err());
}

#[test]
fn iqm_trims_a_quarter_from_each_end_like_scipy() {
    // scipy.stats.trim_mean([1..10], 0.25): drops 2 from each end → mean(3..8) = 5.5.
    let x: Vec<f64> = (1..=10).map(f64::from).collect();
    assert_eq!(iqm(&x).unwrap(), 5.5);
    // n = 5: sorted [1, 2, 3, 100, 1000], drops 1 from each end → mean(2, 3, 100) = 35.
    assert_eq!(iqm(&[1000.0, 2.0, 100.0, 1.0, 3.0]).unwrap(), 35.0);
    // n = 3: ⌊3/4⌋ = 0, the plain mean.
    assert_eq!(iqm(&[1.0, 2.0, 6.0]).unwrap(), 3.0);
    assert!(iqm(&[]).is_err() && iqm(&[f64::NAN]).is_err());
}

#[test]
fn the_bootstrap_is_repeatable_and_brackets_the_estimate() {
    let x: Vec<f64> = (0..12).map(|i| f64::from(i * i % 7)).collect();
    let a = iqm_interval(&x, 7).unwrap();
    let b = iqm_interval(&x, 7).unwrap();
    assert_eq!(a, b, "same seed, same interval");
    assert!(a.lo <= a.estimate && a.estimate <= a.hi, "{a:?}");
    assert!(a.lo >= 0.0 && a.hi <= 6.0, "inside the data's range: {a:?}");
    // A constant sample has a zero-width interval.
    let c = bootstrap(&[4.0; 6], iqm, 500, 1).unwrap();
    assert_eq!((c.lo, c.estimate, c.hi), (4.0, 4.0, 4.0));
    // The mean of a two-point sample {0, 1} resampled 4 times: the interval spans most of
    // [0, 1] (resamples of all 0s or all 1s have probability 1/16 each).
    let mean = |v: &[f64]| Ok(v.iter().sum::<f64>() / v.len() as f64);
    let m = bootstrap(&[0.0, 1.0, 0.0, 1.0], mean, 4000, 3).unwrap();
    assert!(m.lo <= 0.25 && m.hi >= 0.75, "{m:?}");
}

#[test]
fn probability_of_improvement_by_hand() {
    // x = {3, 2}, y = {1, 2}: pairs (3,1) (3,2) (2,1) win, (2,2) ties → 3.5/4.
    assert_eq!(
        probability_of_improvement(&[3.0, 2.0], &[1.0, 2.0]).unwrap(),
        0.875
    );
    assert_eq!(probability_of_improvement(&[1.0], &[1.0]).unwrap(), 0.5);
    assert_eq!(
        probability_of_improvement(&[0.0, 0.0], &[5.0]).unwrap(),
        0.0
    );
    let p = probability_of_improvement_interval(&[3.0, 2.0, 4.0], &[1.0, 2.0], 5).unwrap();
    assert!(
        p.lo <= p.estimate && p.estimate <= p.hi && p.hi <= 1.0,
        "{p:?}"
    );
}
