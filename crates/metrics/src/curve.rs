//! Learning-curve metrics of paper §5 / Table 1 (SPEC §6).
//!
//! A *curve* is one value per generation (ES-X: the return of the policy kept after the ES
//! step) or per episode (plain X: the training episode's return). With `w` the window
//! ([`WINDOW`] = 50) and `c[0..n]` the curve:
//!
//! - AUC = Σ c\[i\]; nAUC = AUC / n (the paper divides by its 1500 generations, i.e. n).
//! - Final-50 = mean of the last `min(w, n)` values.
//! - Best-Win-50 = max over windows of `w` consecutive values of their mean; a curve shorter
//!   than `w` has one (shorter) window: the whole curve.
//! - trailing mean m\[i\] = mean of c\[max(0, i+1−w) ..= i\]: the first `w−1` entries average
//!   the values available so far (MATLAB's `movmean(c, [w-1 0])` with its default
//!   `"shrink"` endpoints, which is what the paper's MATLAB tooling computes).
//! - Episodes-to-Target = the first 0-based index i with m\[i\] ≥ target (the number of
//!   generations/episodes consumed is i + 1), `None` when never reached.
//! - target of a method = [`TARGET_FRACTION`] (0.8) × the median of its seeds' Best-Win-50
//!   (median of an even count: mean of the two middle values). The fraction multiplies the
//!   median as is, so a negative median gives a target above it (closer to zero).
//!
//! Every function refuses an empty curve ([`MetricsError::Empty`]) and NaN or ±inf values
//! ([`MetricsError::NonFinite`]) rather than returning a silently wrong number.

use serde::{Deserialize, Serialize};

use crate::error::{check_finite_nonempty, MetricsError, Result};

/// The window of Final-50, Best-Win-50 and the trailing mean of Episodes-to-Target.
pub const WINDOW: usize = 50;

/// Fraction of the median Best-Win-50 that defines a method's target (paper: 80%).
pub const TARGET_FRACTION: f64 = 0.8;

fn check_window(window: usize) -> Result<()> {
    if window == 0 {
        return Err(MetricsError::InvalidParameter {
            what: "window".into(),
            value: "0".into(),
            why: "must be at least 1".into(),
        });
    }
    Ok(())
}

fn mean_of(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// AUC: the sum of the curve.
///
/// ```
/// assert_eq!(esrl_metrics::auc(&[1.0, 2.0, 3.0]).unwrap(), 6.0);
/// ```
pub fn auc(curve: &[f64]) -> Result<f64> {
    check_finite_nonempty(curve, "curve")?;
    Ok(curve.iter().sum())
}

/// nAUC: AUC divided by the curve's length, i.e. the average return per generation/episode.
pub fn nauc(curve: &[f64]) -> Result<f64> {
    Ok(auc(curve)? / curve.len() as f64)
}

/// Mean of the last `window` values; the mean of all values when the curve is shorter.
pub fn final_mean(curve: &[f64], window: usize) -> Result<f64> {
    check_window(window)?;
    check_finite_nonempty(curve, "curve")?;
    let start = curve.len().saturating_sub(window);
    Ok(mean_of(&curve[start..]))
}

/// Mean Q₀ of a run (SPEC §6): the mean of the finite values of its `q0` column, `None` when
/// there are none. A diverged critic's NaN or ±inf is left out rather than averaged in; the
/// one rule for `summary.json`, `esrl compare` and the Python report.
///
/// ```
/// assert_eq!(esrl_metrics::q0_mean(&[1.0, f64::NAN, 3.0]), Some(2.0));
/// assert_eq!(esrl_metrics::q0_mean(&[f64::INFINITY]), None);
/// ```
pub fn q0_mean(q0: &[f64]) -> Option<f64> {
    let finite: Vec<f64> = q0.iter().copied().filter(|q| q.is_finite()).collect();
    (!finite.is_empty()).then(|| mean_of(&finite))
}

/// Final-50: [`final_mean`] with the paper's window of 50.
pub fn final_50(curve: &[f64]) -> Result<f64> {
    final_mean(curve, WINDOW)
}

/// Best mean of `window` consecutive values; the mean of all values when the curve is shorter.
///
/// Each window is summed afresh (O(n·w)) so that no running-sum rounding drifts in.
pub fn best_window_mean(curve: &[f64], window: usize) -> Result<f64> {
    check_window(window)?;
    check_finite_nonempty(curve, "curve")?;
    if curve.len() <= window {
        return Ok(mean_of(curve));
    }
    Ok(curve
        .windows(window)
        .map(mean_of)
        .fold(f64::NEG_INFINITY, f64::max))
}

/// Best-Win-50: [`best_window_mean`] with the paper's window of 50.
pub fn best_win_50(curve: &[f64]) -> Result<f64> {
    best_window_mean(curve, WINDOW)
}

/// Trailing means m\[i\] = mean of c\[max(0, i+1−window) ..= i\], one per curve value; the first
/// `window − 1` entries average the values available so far.
pub fn trailing_means(curve: &[f64], window: usize) -> Result<Vec<f64>> {
    check_window(window)?;
    check_finite_nonempty(curve, "curve")?;
    Ok((0..curve.len())
        .map(|i| mean_of(&curve[(i + 1).saturating_sub(window)..=i]))
        .collect())
}

/// First 0-based index whose trailing `window`-value mean (see [`trailing_means`]) is ≥
/// `target`; `None` when the curve never gets there.
pub fn episodes_to_target_window(
    curve: &[f64],
    target: f64,
    window: usize,
) -> Result<Option<usize>> {
    if !target.is_finite() {
        return Err(MetricsError::InvalidParameter {
            what: "target".into(),
            value: target.to_string(),
            why: "must be finite".into(),
        });
    }
    Ok(trailing_means(curve, window)?
        .iter()
        .position(|&m| m >= target))
}

/// Episodes-to-Target with the paper's window of 50: the first 0-based index where the trailing
/// 50-value mean reaches `target` (usually [`method_target`] of the method's seeds).
///
/// ```
/// // trailing means: 0, 5, 6.67, ... -> the mean first reaches 5 at index 1
/// let e = esrl_metrics::episodes_to_target(&[0.0, 10.0, 10.0], 5.0).unwrap();
/// assert_eq!(e, Some(1));
/// ```
pub fn episodes_to_target(curve: &[f64], target: f64) -> Result<Option<usize>> {
    episodes_to_target_window(curve, target, WINDOW)
}

/// Median of finite values (mean of the two middle values for an even count).
pub fn median(values: &[f64]) -> Result<f64> {
    check_finite_nonempty(values, "values")?;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    Ok(if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    })
}

/// A method's target: `fraction` × the median over its seeds' curves of the best
/// `window`-value mean.
pub fn method_target_with<C: AsRef<[f64]>>(
    curves: &[C],
    window: usize,
    fraction: f64,
) -> Result<f64> {
    if !fraction.is_finite() {
        return Err(MetricsError::InvalidParameter {
            what: "fraction".into(),
            value: fraction.to_string(),
            why: "must be finite".into(),
        });
    }
    if curves.is_empty() {
        return Err(MetricsError::Empty {
            what: "curves (no seeds)".into(),
        });
    }
    let best = curves
        .iter()
        .enumerate()
        .map(|(seed, c)| {
            best_window_mean(c.as_ref(), window)
                .map_err(|e| rename(e, &format!("curve of seed {seed}")))
        })
        .collect::<Result<Vec<f64>>>()?;
    Ok(fraction * median(&best)?)
}

/// The paper's per-method target: 80% of the median Best-Win-50 over the method's seeds.
///
/// ```
/// // Best-Win-50 of each (short) curve is its mean: 1, 2, 4 -> median 2 -> target 1.6
/// let t = esrl_metrics::method_target(&[vec![1.0], vec![2.0], vec![4.0]]).unwrap();
/// assert!((t - 1.6).abs() < 1e-12);
/// ```
pub fn method_target<C: AsRef<[f64]>>(curves: &[C]) -> Result<f64> {
    method_target_with(curves, WINDOW, TARGET_FRACTION)
}

/// Replaces the generic `what` of an error by a more precise one (e.g. which seed).
fn rename(e: MetricsError, what: &str) -> MetricsError {
    match e {
        MetricsError::Empty { .. } => MetricsError::Empty { what: what.into() },
        MetricsError::NonFinite { index, value, .. } => MetricsError::NonFinite {
            what: what.into(),
            index,
            value,
        },
        other => other,
    }
}

/// The per-run learning-curve summary; its field names are the keys of a run's `summary.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurveSummary {
    /// Sum of the curve.
    pub auc: f64,
    /// AUC / curve length.
    pub nauc: f64,
    /// Mean of the last 50 values (all values if fewer).
    pub final_50: f64,
    /// Best mean of 50 consecutive values (mean of all values if fewer).
    pub best_win_50: f64,
    /// First 0-based index where the trailing 50-value mean reaches the method's target;
    /// `None` (JSON `null`) when never reached or when no target was given.
    pub episodes_to_target: Option<usize>,
}

impl CurveSummary {
    /// Summarises one curve. `target` is the method's target ([`method_target`]); with `None`
    /// the run's Episodes-to-Target is `None` (a single run cannot know its method's median).
    pub fn from_curve(curve: &[f64], target: Option<f64>) -> Result<Self> {
        Ok(Self {
            auc: auc(curve)?,
            nauc: nauc(curve)?,
            final_50: final_50(curve)?,
            best_win_50: best_win_50(curve)?,
            episodes_to_target: match target {
                Some(t) => episodes_to_target(curve, t)?,
                None => None,
            },
        })
    }
}

/// Summarises all seeds of one method: computes the method's target from every curve
/// ([`method_target`]) and then each seed's [`CurveSummary`] against it (same order as `curves`).
pub fn summarize_method<C: AsRef<[f64]>>(curves: &[C]) -> Result<Vec<CurveSummary>> {
    let target = method_target(curves)?;
    curves
        .iter()
        .enumerate()
        .map(|(seed, c)| {
            CurveSummary::from_curve(c.as_ref(), Some(target))
                .map_err(|e| rename(e, &format!("curve of seed {seed}")))
        })
        .collect()
}
