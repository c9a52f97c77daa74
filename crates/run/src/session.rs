//! A training session of either kind: [`Session`] holds the [`Training`] of a plain trainer or
//! of the hybrid loop and dispatches to it, so a front end (the `esrl` binary, the Python
//! driver) drives both with the same code and no generics. It also times the session: once
//! the first rows give a pace, the row that establishes it carries an [`Estimate`] of the
//! time left ([`RowDone::estimate`]), which every front end prints the same way.

use crate::build::AnyLearner;
use crate::check::CheckRecord;
use crate::config::TrainConfig;
use crate::error::Result;
use crate::pace::Estimate;
use crate::training::{Opening, RowDone, Training};
use esrl_agents::{Learner, Trainer};
use esrl_es::Hybrid;
use esrl_sim::MakeEnv;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// The training session of a plain agent or of the hybrid loop.
pub struct Session {
    training: Either,
    /// Rows, environment steps and the clock when the session opened.
    start: (usize, u64, Instant),
    /// Whether the estimate was given.
    estimated: bool,
    /// The environment-step budget, if any.
    step_budget: Option<u64>,
}

/// The training inside a [`Session`].
enum Either {
    /// SAC / TD3 / DDPG: a row is an episode.
    Plain(Box<Training<Trainer>>),
    /// ES-SAC / ES-TD3 / ES-DDPG: a row is a generation.
    Hybrid(Box<Training<Hybrid>>),
}

/// `$body` with `$t` the session's [`Training`], whatever the learner.
macro_rules! each {
    ($session:expr, $t:ident => $body:expr) => {
        match $session {
            Either::Plain($t) => $body,
            Either::Hybrid($t) => $body,
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
        let (training, opening) = match learner {
            AnyLearner::Plain(t) => {
                let (t, o) = Training::open(cfg, root, *t, envs, resume)?;
                (Either::Plain(Box::new(t)), o)
            }
            AnyLearner::Hybrid(h) => {
                let (t, o) = Training::open(cfg, root, *h, envs, resume)?;
                (Either::Hybrid(Box::new(t)), o)
            }
        };
        let (rows, steps) = each!(&training, t => (t.rows(), t.learner().env_steps()));
        let session = Session {
            training,
            start: (rows, steps, Instant::now()),
            estimated: false,
            step_budget: cfg.max_env_steps,
        };
        Ok((session, opening))
    }

    /// What a row is: `"episode"` or `"generation"`.
    pub fn unit(&self) -> &'static str {
        match self.training {
            Either::Plain(_) => <Trainer as Learner>::UNIT,
            Either::Hybrid(_) => <Hybrid as Learner>::UNIT,
        }
    }

    /// [`Training::step`]: runs one row and writes it; the row that first gives a pace
    /// carries the [`Estimate`] of the time left.
    pub fn step(&mut self) -> Result<RowDone> {
        let mut row = each!(&mut self.training, t => t.step())?;
        if !self.estimated {
            row.estimate = self.estimate();
            self.estimated = row.estimate.is_some();
        }
        Ok(row)
    }

    /// The time left from the pace since the session opened ([`Estimate::from_pace`]).
    fn estimate(&self) -> Option<Estimate> {
        let (rows0, steps0, started) = self.start;
        let steps = self.env_steps();
        Estimate::from_pace(
            started.elapsed().as_secs_f64(),
            self.rows() - rows0,
            self.total().saturating_sub(self.rows()),
            steps.saturating_sub(steps0),
            self.step_budget.map(|b| b.saturating_sub(steps)),
        )
    }

    /// [`Training::finish`]: the last checkpoint (`finished`: the budget was completed).
    pub fn finish(&mut self, finished: bool) -> Result<()> {
        each!(&mut self.training, t => t.finish(finished))
    }

    /// [`Training::done`]: whether the budget is spent.
    pub fn done(&self) -> bool {
        each!(&self.training, t => t.done())
    }

    /// Rows done.
    pub fn rows(&self) -> usize {
        each!(&self.training, t => t.rows())
    }

    /// Rows the budget asks for.
    pub fn total(&self) -> usize {
        each!(&self.training, t => t.total())
    }

    /// Environment steps taken.
    pub fn env_steps(&self) -> u64 {
        each!(&self.training, t => t.learner().env_steps())
    }

    /// Training seconds so far, earlier sessions included.
    pub fn wall_s(&self) -> f64 {
        each!(&self.training, t => t.wall_s())
    }

    /// [`Training::first_walk`]: the first check that met the walking bar.
    pub fn first_walk(&self) -> Option<&CheckRecord> {
        each!(&self.training, t => t.first_walk())
    }

    /// [`Training::kept_check`]: the walking check of the policy `RUN/best/` holds.
    pub fn kept_check(&self) -> Option<&CheckRecord> {
        each!(&self.training, t => t.kept_check())
    }
}
