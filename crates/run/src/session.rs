//! A training session of either kind: [`Session`] holds the [`Training`] of a plain trainer or
//! of the hybrid loop and dispatches to it, so a front end (the `esrl` binary, the Python
//! driver) drives both with the same code and no generics.

use crate::build::AnyLearner;
use crate::check::CheckRecord;
use crate::config::TrainConfig;
use crate::error::Result;
use crate::training::{Opening, RowDone, Training};
use esrl_agents::{Learner, Trainer};
use esrl_es::Hybrid;
use esrl_sim::MakeEnv;
use std::path::Path;
use std::sync::Arc;

/// The training session of a plain agent or of the hybrid loop.
pub enum Session {
    /// SAC / TD3 / DDPG: a row is an episode.
    Plain(Box<Training<Trainer>>),
    /// ES-SAC / ES-TD3 / ES-DDPG: a row is a generation.
    Hybrid(Box<Training<Hybrid>>),
}

/// `$body` with `$t` the session's [`Training`], whatever the learner.
macro_rules! each {
    ($session:expr, $t:ident => $body:expr) => {
        match $session {
            Session::Plain($t) => $body,
            Session::Hybrid($t) => $body,
        }
    };
}

impl Session {
    /// [`Training::open`] for the learner inside `learner`.
    pub fn open(
        cfg: &TrainConfig,
        root: &Path,
        learner: AnyLearner,
        envs: Arc<MakeEnv>,
        resume: bool,
    ) -> Result<(Self, Opening)> {
        Ok(match learner {
            AnyLearner::Plain(t) => {
                let (t, o) = Training::open(cfg, root, *t, envs, resume)?;
                (Session::Plain(Box::new(t)), o)
            }
            AnyLearner::Hybrid(h) => {
                let (t, o) = Training::open(cfg, root, *h, envs, resume)?;
                (Session::Hybrid(Box::new(t)), o)
            }
        })
    }

    /// What a row is: `"episode"` or `"generation"`.
    pub fn unit(&self) -> &'static str {
        match self {
            Session::Plain(_) => <Trainer as Learner>::UNIT,
            Session::Hybrid(_) => <Hybrid as Learner>::UNIT,
        }
    }

    /// [`Training::step`]: runs one row and writes it.
    pub fn step(&mut self) -> Result<RowDone> {
        each!(self, t => t.step())
    }

    /// [`Training::finish`]: the last checkpoint (`finished`: the budget was completed).
    pub fn finish(&mut self, finished: bool) -> Result<()> {
        each!(self, t => t.finish(finished))
    }

    /// [`Training::done`]: whether the budget is spent.
    pub fn done(&self) -> bool {
        each!(self, t => t.done())
    }

    /// Rows done.
    pub fn rows(&self) -> usize {
        each!(self, t => t.rows())
    }

    /// Rows the budget asks for.
    pub fn total(&self) -> usize {
        each!(self, t => t.total())
    }

    /// Environment steps taken.
    pub fn env_steps(&self) -> u64 {
        each!(self, t => t.learner().env_steps())
    }

    /// Training seconds so far, earlier sessions included.
    pub fn wall_s(&self) -> f64 {
        each!(self, t => t.wall_s())
    }

    /// [`Training::first_walk`]: the first check that met the walking bar.
    pub fn first_walk(&self) -> Option<&CheckRecord> {
        each!(self, t => t.first_walk())
    }

    /// [`Training::kept_check`]: the walking check of the policy `RUN/best/` holds.
    pub fn kept_check(&self) -> Option<&CheckRecord> {
        each!(self, t => t.kept_check())
    }
}
