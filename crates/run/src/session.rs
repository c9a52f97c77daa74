//! A training session of either kind: [`Session`] holds the [`Training`] of a plain trainer or
//! of the hybrid loop and dispatches to it, so a front end (the `esrl` binary, the Python
//! driver) drives both with the same code and no generics. It also times the session: once
//! the first rows give a pace, the row that establishes it carries an [`Estimate`] of the
//! time left ([`RowDone::estimate`]), which every front end prints the same way. It builds
//! the learner itself, from the seed of the run's current attempt, so that `[restart]`
//! (module [`crate::restart`]) can start the run over with a new one.

use crate::build::{self, AnyLearner, Envs};
use crate::check::CheckRecord;
use crate::checkpoint;
use crate::config::TrainConfig;
use crate::error::{Error, Result};
use crate::init;
use crate::pace::Estimate;
use crate::restart::{self, Restart};
use crate::training::{Attempt, Opening, RowDone, Training};
use esrl_agents::{Learner, Trainer};
use esrl_es::{Evaluator, Hybrid};
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
    /// The run's configuration, its environments and the evaluator of its populations: what
    /// a restart builds the next learner from.
    cfg: TrainConfig,
    envs: Envs,
    evaluator: Arc<dyn Evaluator>,
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
    /// [`Training::open`] for the learner of `cfg` ([`build::learner_with`], its populations
    /// rolled out by `evaluator`): of the run's own seed, or, in a resumed run that
    /// `[restart]` started over, of its current attempt's.
    pub fn open(
        cfg: &TrainConfig,
        root: &Path,
        envs: &Envs,
        evaluator: Arc<dyn Evaluator>,
        resume: bool,
    ) -> Result<(Self, Opening)> {
        let earlier = if resume {
            restart::read(root)?
        } else {
            Vec::new()
        };
        // A run resumed from its checkpoint takes its weights from there, not from `init`
        // (whose folder need not exist any more); a restart still to be settled deletes the
        // checkpoint, and the next attempt starts from `init`.
        let from_checkpoint =
            resume && earlier.last().is_none_or(|r| r.settled) && checkpoint::find(root).is_some();
        let attempt = Attempt::after(cfg.seed, earlier)?;
        let mut attempt_cfg = cfg.with_seed(attempt.seed);
        let mut loaded = None;
        if from_checkpoint {
            attempt_cfg.init = None;
        } else if attempt_cfg.init.is_some() {
            // The run's own copy once it has one (a start over, a pending restart), else
            // the folder `init` names, hashed before it is read.
            match init::local(root).filter(|_| resume) {
                Some(copy) => attempt_cfg.init = Some(copy),
                None => loaded = attempt_cfg.init.as_deref().map(init::record).transpose()?,
            }
        }
        let learner = build::learner_with(&attempt_cfg, envs, evaluator.clone())?;
        let make = envs.make.clone();
        let (training, opening) = match learner {
            AnyLearner::Plain(t) => {
                let (t, o) = Training::open_attempt(cfg, root, *t, make, resume, attempt)?;
                (Either::Plain(Box::new(t)), o)
            }
            AnyLearner::Hybrid(h) => {
                let (t, o) = Training::open_attempt(cfg, root, *h, make, resume, attempt)?;
                (Either::Hybrid(Box::new(t)), o)
            }
        };
        if let (Some(record), Opening::New | Opening::StartedOver) = (&loaded, &opening) {
            init::snapshot(root, record)?;
        }
        let (rows, steps) = each!(&training, t => (t.rows(), t.learner().env_steps()));
        let session = Session {
            training,
            start: (rows, steps, Instant::now()),
            estimated: false,
            cfg: cfg.clone(),
            envs: envs.clone(),
            evaluator,
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
    /// Before the row, `[restart]` may abandon the attempt and start the run over
    /// ([`RowDone::restarted`]).
    pub fn step(&mut self) -> Result<RowDone> {
        let restarted = self.restart_if_due()?;
        let mut row = each!(&mut self.training, t => t.step())?;
        row.restarted = restarted;
        if !self.estimated {
            row.estimate = self.estimate();
            self.estimated = row.estimate.is_some();
        }
        Ok(row)
    }

    /// Abandons the attempt and starts the next one when `[restart]`'s rule says so
    /// ([`Training::restart_due`]); returns the abandoned attempt's record.
    fn restart_if_due(&mut self) -> Result<Option<Restart>> {
        if !each!(&mut self.training, t => t.restart_due())? {
            return Ok(None);
        }
        let (record, next) = each!(&mut self.training, t => t.abandon())?;
        let mut cfg = self.cfg.with_seed(next.seed);
        if cfg.init.is_some() {
            // Every attempt starts from the run's copy of the policy it started from.
            let root = each!(&self.training, t => t.root().to_path_buf());
            cfg.init = Some(init::local(&root).ok_or_else(|| {
                Error::Msg(format!(
                    "{}: the copy of the starting policy ({}/) is missing",
                    root.display(),
                    init::INIT_DIR
                ))
            })?);
        }
        let learner = build::learner_with(&cfg, &self.envs, self.evaluator.clone())?;
        match (&mut self.training, learner) {
            (Either::Plain(t), AnyLearner::Plain(l)) => t.start_over(*l, next)?,
            (Either::Hybrid(t), AnyLearner::Hybrid(h)) => t.start_over(*h, next)?,
            _ => {
                return Err(Error::Msg(
                    "a restart built a learner of another kind than the run's".into(),
                ))
            }
        }
        // The next rows give the new attempt's pace.
        self.start = (0, 0, Instant::now());
        self.estimated = false;
        Ok(Some(record))
    }

    /// The run's configuration.
    pub fn config(&self) -> &TrainConfig {
        &self.cfg
    }

    /// Which attempt of the run trains now (`[restart]`).
    pub fn attempt(&self) -> &Attempt {
        each!(&self.training, t => t.attempt())
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
            each!(&self.training, t => t.budget_left()),
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

    /// [`Training::budget_steps`]: environment steps counted against `max_env_steps`.
    pub fn budget_steps(&self) -> u64 {
        each!(&self.training, t => t.budget_steps())
    }

    /// Training seconds so far, earlier sessions included.
    pub fn wall_s(&self) -> f64 {
        each!(&self.training, t => t.wall_s())
    }

    /// [`Training::first_walk`]: the first check that met the walking bar.
    pub fn first_walk(&self) -> Option<&CheckRecord> {
        each!(&self.training, t => t.first_walk())
    }

    /// [`Training::first_any_walk`]: with a margin of speed or symmetry, the first check at
    /// the bar without the margins.
    pub fn first_any_walk(&self) -> Option<&CheckRecord> {
        each!(&self.training, t => t.first_any_walk())
    }

    /// [`Training::kept_check`]: the walking check of the policy `RUN/best/` holds.
    pub fn kept_check(&self) -> Option<&CheckRecord> {
        each!(&self.training, t => t.kept_check())
    }
}
