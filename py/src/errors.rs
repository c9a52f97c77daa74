//! Rust errors → Python exceptions, with the Rust message unchanged.
//!
//! - bad values (metric inputs, configs, malformed run files) → `ValueError`;
//! - a missing file or folder → `FileNotFoundError` (other I/O failures → `OSError`);
//! - everything else (a recording the reader cannot use, a panic caught inside the
//!   simulator, misuse of an environment) → `esrl_rs.EsrlError`.

use std::path::Path;

use pyo3::exceptions::{
    PyException, PyFileNotFoundError, PyNotADirectoryError, PyOSError, PyPermissionError,
    PyValueError,
};
use pyo3::{create_exception, PyErr};

create_exception!(
    esrl_rs,
    EsrlError,
    PyException,
    "An error raised by the esrl Rust core that is neither a bad value nor a missing file."
);

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// An `esrl_rs.EsrlError` with `message`.
pub fn esrl_error(message: impl Into<String>) -> PyErr {
    EsrlError::new_err(message.into())
}

/// The Python exception for an I/O error on `path`: `FileNotFoundError`, `PermissionError`,
/// `NotADirectoryError` or `OSError`, with the message `"{path}: {error}"`.
pub fn io_error(path: &Path, error: &std::io::Error) -> PyErr {
    let message = format!("{}: {error}", path.display());
    match error.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        std::io::ErrorKind::NotADirectory => PyNotADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// `FileNotFoundError` with `message`.
pub fn not_found(message: impl Into<String>) -> PyErr {
    PyFileNotFoundError::new_err(message.into())
}

/// Metric errors are all about the values passed in.
pub fn metrics_error(error: esrl_metrics::MetricsError) -> PyErr {
    value_error(error.to_string())
}

/// Errors reading the recording at `path`: I/O keeps its kind; content the reader cannot use
/// (a missing topic, a non-numeric field, bad JSON) is a `ValueError`; a file the MCAP library
/// refuses is an `EsrlError`. Messages start with the file name.
pub fn record_error(path: &Path, error: esrl_record::RecordError) -> PyErr {
    use esrl_record::RecordError as E;
    match &error {
        E::Io { path, source } => io_error(path, source),
        E::Mcap(_) => esrl_error(format!("{}: {error}", path.display())),
        _ => value_error(format!("{}: {error}", path.display())),
    }
}

/// Simulator errors: an unreadable URDF keeps its I/O kind; configuration, model and URDF
/// problems are bad values.
pub fn sim_error(error: esrl_sim::SimError) -> PyErr {
    if let esrl_sim::SimError::Urdf(esrl_sim::UrdfError::Io { source, .. }) = &error {
        let message = error.to_string();
        return match source.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
            _ => PyOSError::new_err(message),
        };
    }
    value_error(error.to_string())
}

/// The message of a caught panic's payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

/// An error of the run library: I/O kinds are kept, the rest is a `ValueError` (bad config,
/// a checkpoint that does not match it), with the whole context chain.
pub fn run_error(error: esrl_run::Error) -> PyErr {
    let message = error.chain();
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(&error);
    let mut io_kind = None;
    while let Some(e) = cause {
        // A transparent `Error::Io` hands on its I/O error's source, not the error itself.
        let io = match e.downcast_ref::<esrl_run::Error>() {
            Some(esrl_run::Error::Io(io)) => Some(io),
            _ => e.downcast_ref::<std::io::Error>(),
        };
        if let Some(io) = io {
            io_kind = Some(io.kind());
            break;
        }
        cause = e.source();
    }
    match io_kind {
        Some(std::io::ErrorKind::NotFound) => PyFileNotFoundError::new_err(message),
        Some(std::io::ErrorKind::PermissionDenied) => PyPermissionError::new_err(message),
        _ => value_error(message),
    }
}
