//! Interval estimates across seeds, as the field now reports them (Agarwal et al. 2021, "Deep
//! Reinforcement Learning at the Edge of the Statistical Precipice", and their `rliable`
//! library): the interquartile mean (IQM) with a percentile-bootstrap 95 % interval, the
//! probability of improvement of one method over another, and the Wilson 95 % interval of a
//! success rate.
//!
//! The estimators follow `rliable`'s definitions: the IQM is `scipy.stats.trim_mean(x, 0.25)`
//! (drop ⌊n/4⌋ values from each end, average the rest); the bootstrap resamples runs with
//! replacement (stratified by task; esrl's studies have one task, so runs are resampled as
//! one stratum) and takes the 2.5th and 97.5th percentiles of the statistic; the probability
//! of improvement is P(X > Y) + ½·P(X = Y) over every pair of runs (the Mann–Whitney U
//! statistic over n·m). The bootstrap draws from a SplitMix64 stream of a given seed, so a
//! report is the same every time it is written.

use serde::{Deserialize, Serialize};

use crate::error::{check_finite_nonempty, MetricsError, Result};

/// z of a two-sided 95 % normal interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// Bootstrap resamples by default (`rliable` uses 2,000 for its figures' intervals).
pub const BOOTSTRAP_REPS: usize = 2000;

/// A point estimate and its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// The estimate.
    pub estimate: f64,
    /// Lower end of the 95 % interval.
    pub lo: f64,
    /// Upper end of the 95 % interval.
    pub hi: f64,
}

/// The Wilson score interval of `successes` in `n` trials at normal quantile `z` (1.96 for
/// 95 %): centre (k + z²/2)/(n + z²), half-width z/(n + z²)·√(k(n−k)/n + z²/4). Unlike the
/// normal ("Wald") interval it stays inside [0, 1] and is not empty at 0 or n successes.
///
/// ```
/// let w = esrl_metrics::wilson(2, 5, esrl_metrics::Z95).unwrap();
/// assert!((w.estimate - 0.4).abs() < 1e-12);
/// assert!((w.lo - 0.1176).abs() < 1e-4 && (w.hi - 0.7693).abs() < 1e-4);
/// ```
pub fn wilson(successes: usize, n: usize, z: f64) -> Result<Interval> {
    if n == 0 || successes > n || !(z.is_finite() && z > 0.0) {
        return Err(MetricsError::InvalidParameter {
            what: "wilson".into(),
            value: format!("{successes} successes of {n} at z = {z}"),
            why: "needs n ≥ 1, at most n successes and z > 0".into(),
        });
    }
    let (k, n) = (successes as f64, n as f64);
    let z2 = z * z;
    let centre = (k + z2 / 2.0) / (n + z2);
    let half = z / (n + z2) * (k * (n - k) / n + z2 / 4.0).sqrt();
    // At k = 0 the lower bound is 0 and at k = n the upper is 1 exactly (centre = half
    // there); the subtraction would leave a rounding error above the estimate.
    Ok(Interval {
        estimate: k / n,
        lo: if successes == 0 {
            0.0
        } else {
            (centre - half).max(0.0)
        },
        hi: if k == n {
            1.0
        } else {
            (centre + half).min(1.0)
        },
    })
}

/// The interquartile mean: the mean after dropping ⌊n/4⌋ values from each end of the sorted
/// values (`scipy.stats.trim_mean(x, 0.25)`, `rliable`'s IQM).
///
/// ```
/// let x: Vec<f64> = (1..=10).map(f64::from).collect();
/// assert_eq!(esrl_metrics::iqm(&x).unwrap(), 5.5); // the mean of 3..=8
/// ```
pub fn iqm(values: &[f64]) -> Result<f64> {
    check_finite_nonempty(values, "values")?;
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let cut = v.len() / 4;
    let kept = &v[cut..v.len() - cut];
    Ok(kept.iter().sum::<f64>() / kept.len() as f64)
}

/// SplitMix64: the bootstrap's stream.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (Lemire's multiply-shift; the bias is below 2⁻⁵⁰ for any n a
    /// study has).
    fn below(&mut self, n: usize) -> usize {
        ((u128::from(self.next()) * n as u128) >> 64) as usize
    }
}

/// The 2.5th and 97.5th percentiles (linear interpolation between order statistics, numpy's
/// default) of `stats`.
fn percentile_interval(mut stats: Vec<f64>) -> (f64, f64) {
    stats.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let pos = q * (stats.len() - 1) as f64;
        let (i, frac) = (pos.floor() as usize, pos - pos.floor());
        let next = stats[(i + 1).min(stats.len() - 1)];
        stats[i] + frac * (next - stats[i])
    };
    (at(0.025), at(0.975))
}

/// `statistic` of `values` with its percentile-bootstrap 95 % interval from `reps`
/// resamples of the runs (with replacement), drawn from a stream seeded with `seed`.
pub fn bootstrap(
    values: &[f64],
    statistic: impl Fn(&[f64]) -> Result<f64>,
    reps: usize,
    seed: u64,
) -> Result<Interval> {
    check_finite_nonempty(values, "values")?;
    let estimate = statistic(values)?;
    let mut rng = SplitMix(seed);
    let mut sample = vec![0.0; values.len()];
    let mut stats = Vec::with_capacity(reps.max(1));
    for _ in 0..reps.max(1) {
        for s in sample.iter_mut() {
            *s = values[rng.below(values.len())];
        }
        stats.push(statistic(&sample)?);
    }
    let (lo, hi) = percentile_interval(stats);
    Ok(Interval { estimate, lo, hi })
}

/// The IQM of `values` with its bootstrap 95 % interval ([`BOOTSTRAP_REPS`] resamples).
pub fn iqm_interval(values: &[f64], seed: u64) -> Result<Interval> {
    bootstrap(values, iqm, BOOTSTRAP_REPS, seed)
}

/// P(X > Y) + ½·P(X = Y) for a run X of `x` and a run Y of `y`, over every pair.
///
/// ```
/// // 3 > 1, 3 > 2, 2 > 1, 2 = 2: (3 + ½) / 4.
/// assert_eq!(esrl_metrics::probability_of_improvement(&[3.0, 2.0], &[1.0, 2.0]).unwrap(), 0.875);
/// ```
pub fn probability_of_improvement(x: &[f64], y: &[f64]) -> Result<f64> {
    check_finite_nonempty(x, "x")?;
    check_finite_nonempty(y, "y")?;
    let mut wins = 0.0;
    for a in x {
        for b in y {
            wins += if a > b {
                1.0
            } else if a == b {
                0.5
            } else {
                0.0
            };
        }
    }
    Ok(wins / (x.len() * y.len()) as f64)
}

/// [`probability_of_improvement`] with a 95 % interval from resampling the runs of each
/// side independently ([`BOOTSTRAP_REPS`] times).
pub fn probability_of_improvement_interval(x: &[f64], y: &[f64], seed: u64) -> Result<Interval> {
    let estimate = probability_of_improvement(x, y)?;
    let mut rng = SplitMix(seed);
    let (mut sx, mut sy) = (vec![0.0; x.len()], vec![0.0; y.len()]);
    let mut stats = Vec::with_capacity(BOOTSTRAP_REPS);
    for _ in 0..BOOTSTRAP_REPS {
        for s in sx.iter_mut() {
            *s = x[rng.below(x.len())];
        }
        for s in sy.iter_mut() {
            *s = y[rng.below(y.len())];
        }
        stats.push(probability_of_improvement(&sx, &sy)?);
    }
    let (lo, hi) = percentile_interval(stats);
    Ok(Interval { estimate, lo, hi })
}
