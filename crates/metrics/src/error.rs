//! The one error type of the crate.

use thiserror::Error;

/// Why a metric could not be computed. Every variant names the input (`what`) it refers to,
/// e.g. `"curve"`, `"torques[12]"` or `"seed 2 best_win_50"`.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MetricsError {
    /// The input has no values, so the metric is undefined (a mean of nothing).
    #[error("{what}: empty input, the metric is undefined")]
    Empty {
        /// The input that was empty.
        what: String,
    },
    /// A NaN or infinite value: a metric over it would silently be NaN.
    #[error("{what}: non-finite value {value} at index {index}")]
    NonFinite {
        /// The input holding the value.
        what: String,
        /// Index of the first offending value.
        index: usize,
        /// The value itself (NaN or ±inf).
        value: f64,
    },
    /// Two inputs that must have one entry per step (or per actuator) disagree in length.
    #[error("{what}: length {found}, expected {expected}")]
    LengthMismatch {
        /// The input with the wrong length.
        what: String,
        /// Its length.
        found: usize,
        /// The length it must have.
        expected: usize,
    },
    /// An actuator name asked for (e.g. a knee for the asymmetry) is not among the trace's names.
    #[error("actuator `{name}` not found among {available:?}")]
    UnknownActuator {
        /// The name asked for.
        name: String,
        /// The names the trace has.
        available: Vec<String>,
    },
    /// A parameter outside its domain (window 0, negative track length, ...).
    #[error("{what}: invalid value {value}: {why}")]
    InvalidParameter {
        /// The parameter.
        what: String,
        /// Its value, as text.
        value: String,
        /// What it must satisfy.
        why: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, MetricsError>;

/// Checks that `values` is non-empty and finite; `what` names the input in the error.
pub(crate) fn check_finite_nonempty(values: &[f64], what: &str) -> Result<()> {
    if values.is_empty() {
        return Err(MetricsError::Empty {
            what: what.to_string(),
        });
    }
    check_finite(values, what)
}

/// Checks that every value in `values` is finite; `what` names the input in the error.
pub(crate) fn check_finite(values: &[f64], what: &str) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(MetricsError::NonFinite {
            what: what.to_string(),
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
