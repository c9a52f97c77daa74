//! The one error type of the crate.

use std::path::PathBuf;

use thiserror::Error;

/// Why a recording could not be written or read.
#[derive(Debug, Error)]
pub enum RecordError {
    /// The scene description is unusable (duplicate link, zero-size shape, NaN pose, ...).
    #[error("scene: {what}: {why}")]
    InvalidScene {
        /// The offending item, e.g. `links[3] "left_shank" shapes[1] radius`.
        what: String,
        /// What is wrong with it.
        why: String,
    },
    /// A scalar topic declaration is unusable (bad topic or field name, duplicate, ...).
    #[error("scalar topic `{topic}`: {why}")]
    InvalidTopic {
        /// The topic.
        topic: String,
        /// What is wrong with it.
        why: String,
    },
    /// A frame does not match the scene or the topics, holds NaN/inf, or goes back in time.
    #[error("frame {frame}: {what}: {why}")]
    InvalidFrame {
        /// 0-based index of the frame in the recording.
        frame: usize,
        /// The offending field, e.g. `link_poses[2].translation` or `/esrl/joints.left_knee`.
        what: String,
        /// What is wrong with it.
        why: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The MCAP library refused to write or read.
    #[error("mcap: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A message could not be encoded or decoded as JSON.
    #[error("json ({context}): {source}")]
    Json {
        /// Where, e.g. the topic.
        context: String,
        /// The underlying error.
        source: serde_json::Error,
    },
    /// A recording does not hold what the reader expects (missing topic, non-numeric field, ...).
    #[error("recording: {0}")]
    Read(String),
}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, RecordError>;
