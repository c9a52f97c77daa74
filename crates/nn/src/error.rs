//! Typed errors of the crate.

use std::path::PathBuf;

/// Everything that can go wrong in `esrl-nn` without being a programming error.
///
/// Shape mismatches between graph ops are programming errors and panic with the shapes in the
/// message; anything that comes from a file, a config or a flat vector is reported here.
#[derive(Debug, thiserror::Error)]
pub enum NnError {
    /// Reading or writing a checkpoint file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a valid safetensors file.
    #[error("{path}: not a valid safetensors file: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        reason: String,
    },
    /// A tensor the network needs is absent from the file.
    #[error("{path}: tensor `{name}` is missing")]
    MissingTensor {
        /// The file.
        path: PathBuf,
        /// The tensor name.
        name: String,
    },
    /// A tensor has the wrong shape.
    #[error("{path}: tensor `{name}` has shape {found:?}, expected {expected:?}")]
    ShapeMismatch {
        /// The file.
        path: PathBuf,
        /// The tensor name.
        name: String,
        /// Shape the network needs.
        expected: Vec<usize>,
        /// Shape in the file.
        found: Vec<usize>,
    },
    /// A tensor has a dtype other than F32.
    #[error("{path}: tensor `{name}` has dtype {found}, expected F32")]
    DtypeMismatch {
        /// The file.
        path: PathBuf,
        /// The tensor name.
        name: String,
        /// Dtype in the file.
        found: String,
    },
    /// A tensor in the file holds NaN or infinity.
    #[error("{path}: tensor `{name}` holds a non-finite value")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The tensor name.
        name: String,
    },
    /// A flat parameter or gradient vector has the wrong length.
    #[error("{what}: length {found}, expected {expected}")]
    LengthMismatch {
        /// What the vector is (e.g. "flat parameters of actor").
        what: String,
        /// Expected length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// A gradient holds NaN or infinity; the optimiser refused to step.
    #[error("non-finite gradient in {what}")]
    NonFiniteGradient {
        /// Which parameters.
        what: String,
    },
    /// An optimiser was asked to step on parameters the backward pass did not reach (unused,
    /// frozen, or a no-grad graph).
    #[error(
        "no gradient for the parameter set ({len} parameters): unused, frozen or no-grad graph"
    )]
    NoGradient {
        /// Size of the parameter set.
        len: usize,
    },
    /// A configuration value is out of range.
    #[error("invalid config `{field}` = {value}: {reason}")]
    Config {
        /// The field name, e.g. `actor.lstm_hidden`.
        field: String,
        /// The offending value as text.
        value: String,
        /// Why it is invalid.
        reason: String,
    },
}
