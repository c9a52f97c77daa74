//! A training run on disk: its configuration, the learner built from it, its folder, its
//! checkpoints, and the session that trains it.
//!
//! - [`config`]: [`TrainConfig`], resolved from a preset, a TOML file and [`Overrides`]; it
//!   is the run folder's `config.toml`.
//! - [`build`]: the one place that loads the URDF and builds the environments, the agent
//!   and the learner ([`AnyLearner`]: a plain [`esrl_agents::Trainer`] or an
//!   [`esrl_es::Hybrid`]) of a config.
//! - [`plan`](mod@plan): a `train` command's arguments ([`TrainRequest`]) turned into a configuration
//!   and a folder, new or resumed, for every front end.
//! - [`training`]: [`Training`] drives any [`esrl_agents::Learner`] row by row into its
//!   folder: metrics, summary, `RUN/best/`, checkpoints; [`session`]: [`Session`], the
//!   training of either kind of learner, for front ends.
//! - [`check`]: the walking check, a deterministic multi-start evaluation against the
//!   walking bar that chooses `RUN/best/` and times the first walk; [`restart`]: a run
//!   started over from another seed when its checks show it has not got going; [`init`]: a
//!   run that starts from a trained policy's weights (fine-tuning).
//! - [`checkpoint`], [`run_dir`], [`summary`]: the files, written atomically and verified
//!   before they are trusted.
//!
//! ```no_run
//! use esrl_run::{build, AgentKind, Overrides, Session, TrainConfig};
//! use std::path::Path;
//!
//! let cfg = TrainConfig::resolve(AgentKind::EsSac, &Overrides::default(), Some(0))?;
//! let envs = build::envs(cfg.env, &cfg.walk)?;
//! let evaluator = build::local_evaluator(&envs);
//! let dir = Path::new("runs/es-sac-s0");
//! let (mut session, _) = Session::open(&cfg, dir, &envs, evaluator, false)?;
//! while !session.done() {
//!     println!("{}", session.step()?.summary);
//! }
//! session.finish(true)?;
//! # Ok::<(), esrl_run::Error>(())
//! ```
//!
//! Errors are [`Error`]s that name the file, field or value at fault; nothing here prints.
//!
//! # Limitations
//!
//! - A run folder belongs to one process at a time: it is locked (`RUN/.lock`) while trained.
//! - A checkpoint is written every `checkpoint_every` rows and at the end: a kill loses the
//!   rows since the last one (they are recomputed, bit for bit, on resume).
//! - Checkpoints are bit-exact only on the machine kind that wrote them (see `esrl-nn`'s
//!   limitations on SIMD widths).

pub mod build;
pub mod check;
pub mod checkpoint;
mod compat;
pub mod config;
mod error;
pub mod init;
pub mod pace;
pub mod plan;
pub mod restart;
pub mod run_dir;
pub mod session;
pub mod summary;
pub mod training;

/// How messages tell a user to run the `esrl` command (`esrl`, `target/release/esrl`, …):
/// `esrl` until a front end says otherwise ([`set_command`]).
pub fn command() -> &'static str {
    COMMAND.get().map_or("esrl", String::as_str)
}

/// Sets, once per process, how messages name the `esrl` command (the binary sets the path it
/// was started by when `esrl` on the `PATH` is not itself).
pub fn set_command(name: impl Into<String>) {
    let _ = COMMAND.set(name.into());
}

static COMMAND: std::sync::OnceLock<String> = std::sync::OnceLock::new();

pub use build::{AnyLearner, Envs};
pub use config::{AgentKind, EnvKind, Overrides, Preset, TrainConfig};
pub use error::{Context, Error, Result};
pub use pace::{human_duration, Estimate, Pace};
pub use plan::{default_out, plan, TrainPlan, TrainRequest};
pub use run_dir::RunDir;
pub use session::Session;
pub use summary::Summary;
pub use training::{Opening, RowDone, Training};
