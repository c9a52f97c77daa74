//! Mean ± sample standard deviation across seeds (paper Table 1: "μ ± SD").

use serde::{Deserialize, Serialize};

use crate::error::{check_finite_nonempty, Result};

/// Mean and sample standard deviation of `n` values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanSd {
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation √(Σ(x−mean)²/(n−1)); `None` for a single value, where the
    /// sample SD is undefined (reporting 0 would claim a spread that was never measured).
    pub sd: Option<f64>,
    /// Number of values.
    pub n: usize,
}

/// Mean ± sample SD (Bessel-corrected, n − 1) of finite values, computed in two passes.
///
/// ```
/// let s = esrl_metrics::mean_sd(&[1.0, 2.0, 3.0, 4.0]).unwrap();
/// assert_eq!(s.mean, 2.5);
/// assert!((s.sd.unwrap() - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
/// assert_eq!(esrl_metrics::mean_sd(&[7.0]).unwrap().sd, None);
/// ```
pub fn mean_sd(values: &[f64]) -> Result<MeanSd> {
    check_finite_nonempty(values, "values")?;
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = (n > 1).then(|| {
        let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
        (ss / (n - 1) as f64).sqrt()
    });
    Ok(MeanSd { mean, sd, n })
}
