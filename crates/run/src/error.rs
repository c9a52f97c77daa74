//! The error of the run and evaluation libraries: a message that names the file, field or
//! value at fault, with the causes behind it ([`std::error::Error::source`]), and
//! [`Context`] to say what was being done when a cause struck.

use std::error::Error as StdError;
use std::fmt::Display;

/// What went wrong with a run, its files or its settings.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A message naming the file, field or value at fault.
    #[error("{0}")]
    Msg(String),
    /// What was being done, and what went wrong.
    #[error("{context}")]
    Context {
        /// What was being done ("reading RUN/config.toml").
        context: String,
        /// The cause.
        #[source]
        source: Box<Error>,
    },
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// JSON that does not parse or serialise.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// TOML that does not parse.
    #[error(transparent)]
    TomlRead(#[from] toml::de::Error),
    /// A config that does not serialise to TOML.
    #[error(transparent)]
    TomlWrite(#[from] toml::ser::Error),
    /// A URDF, environment or physics setting that cannot work.
    #[error(transparent)]
    Sim(#[from] esrl_sim::SimError),
    /// A URDF that cannot be loaded.
    #[error(transparent)]
    Urdf(#[from] esrl_sim::UrdfError),
    /// A network, optimiser or tensor file.
    #[error(transparent)]
    Nn(#[from] esrl_nn::NnError),
    /// The agent, or a learner's state.
    #[error(transparent)]
    Agent(#[from] esrl_agents::AgentError),
    /// An `[rl]` setting that cannot work.
    #[error(transparent)]
    Rl(#[from] esrl_agents::ConfigError),
    /// An `[es]` setting that cannot work.
    #[error(transparent)]
    Es(#[from] esrl_es::ConfigError),
    /// A metric that cannot be computed.
    #[error(transparent)]
    Metrics(#[from] esrl_metrics::MetricsError),
    /// Any other library's error.
    #[error(transparent)]
    Other(Box<dyn StdError + Send + Sync>),
}

impl Error {
    /// An error of any other library.
    pub fn other(e: impl StdError + Send + Sync + 'static) -> Self {
        Self::Other(Box::new(e))
    }

    /// The message and every cause on one line, `outer: inner: …`, leaving out a cause whose
    /// text the line already holds (library errors often repeat their source in their own
    /// message).
    pub fn chain(&self) -> String {
        let mut line = String::new();
        let mut next: Option<&dyn StdError> = Some(self);
        while let Some(e) = next {
            let text = e.to_string();
            if !line.contains(&text) {
                if !line.is_empty() {
                    line.push_str(": ");
                }
                line.push_str(&text);
            }
            next = e.source();
        }
        line
    }
}

/// Says what was being done when an error struck (`anyhow`'s `context`, typed).
pub trait Context<T> {
    /// Wraps the error in `context`.
    fn context(self, context: impl Display) -> Result<T, Error>;
    /// Wraps the error in the context `f` makes (only on error).
    fn with_context<C: Display>(self, f: impl FnOnce() -> C) -> Result<T, Error>;
}

impl<T, E: Into<Error>> Context<T> for Result<T, E> {
    fn context(self, context: impl Display) -> Result<T, Error> {
        self.map_err(|e| Error::Context {
            context: context.to_string(),
            source: Box::new(e.into()),
        })
    }

    fn with_context<C: Display>(self, f: impl FnOnce() -> C) -> Result<T, Error> {
        self.map_err(|e| Error::Context {
            context: f().to_string(),
            source: Box::new(e.into()),
        })
    }
}

impl<T> Context<T> for Option<T> {
    fn context(self, context: impl Display) -> Result<T, Error> {
        self.ok_or_else(|| Error::Msg(context.to_string()))
    }

    fn with_context<C: Display>(self, f: impl FnOnce() -> C) -> Result<T, Error> {
        self.ok_or_else(|| Error::Msg(f().to_string()))
    }
}

/// Returns early with an [`Error::Msg`] made by `format!`.
#[macro_export]
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err($crate::Error::Msg(format!($($arg)*)))
    };
}

/// The result of the run and evaluation libraries.
pub type Result<T, E = Error> = std::result::Result<T, E>;
