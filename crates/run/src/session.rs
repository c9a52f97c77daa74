//! A training session of either kind: [`Session`] holds the [`Training`] of a plain trainer or
//! of the hybrid loop and dispatches to it, so a front end (the `esrl` binary, the Python
//! driver) drives both with the same code and no generics. It also times the session: once
//! the first rows give a pace, the row that establishes it carries an [`Estimate`] of the
//! time left ([`RowDone::estimate`]), which every front end prints the same way.

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

/// The time a session has left, estimated from the pace of its first rows (at least 3 rows
/// and 10 s: the first rows are no guide, as a plain agent's warm start does no updates and
/// a smoke run ends at once).
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Seconds left.
    pub seconds: f64,
    /// Rows the pace was measured over.
    pub measured: usize,
    /// What the estimate extrapolates.
    pub by: Pace,
}

/// The pace an [`Estimate`] extrapolates.
#[derive(Debug, Clone, PartialEq)]
pub enum Pace {
    /// The environment-step budget ends the run first: the steps left at the step rate.
    Steps {
        /// Environment steps per second so far.
        rate: f64,
        /// Steps left of the budget.
        left: u64,
    },
    /// The rows left at the seconds per row so far.
    Rows {
        /// Seconds per row so far.
        per_row: f64,
        /// Rows left.
        left: usize,
    },
}

impl Estimate {
    /// The time left after `measured` rows and `steps` environment steps in `elapsed`
    /// seconds, with `rows_left` rows and (under a step budget) `steps_left` steps to go:
    /// `None` before 3 rows and 10 s; the step budget's time when it ends the run first.
    pub fn from_pace(
        elapsed: f64,
        measured: usize,
        rows_left: usize,
        steps: u64,
        steps_left: Option<u64>,
    ) -> Option<Estimate> {
        if measured < 3 || elapsed < 10.0 {
            return None;
        }
        let per_row = elapsed / measured as f64;
        let by_rows = per_row * rows_left as f64;
        let rate = steps as f64 / elapsed;
        let by_steps = steps_left.and_then(|left| {
            let seconds = left as f64 / rate;
            (rate > 0.0 && seconds < by_rows).then_some(Estimate {
                seconds,
                measured,
                by: Pace::Steps { rate, left },
            })
        });
        Some(by_steps.unwrap_or(Estimate {
            seconds: by_rows,
            measured,
            by: Pace::Rows {
                per_row,
                left: rows_left,
            },
        }))
    }

    /// One line for a log: the pace, the time left and how far to trust it; `unit` is what
    /// a row is.
    pub fn describe(&self, unit: &str) -> String {
        let (measured, time) = (self.measured, human_duration(self.seconds));
        match self.by {
            Pace::Steps { rate, left } => format!(
                "pace: {rate:.0} env steps/s over the first {measured} {unit}s: about {time} for \
                 the {left} env steps left of the step budget (episodes lengthen as the policy \
                 learns to stay up; the step rate varies less)"
            ),
            Pace::Rows { per_row, left } => format!(
                "pace: {per_row:.1} s per {unit} over the first {measured}: about {time} for the \
                 {left} left (episodes lengthen as the policy learns to stay up, so likely more)"
            ),
        }
    }
}

/// "1 h 05 min", "4 min 10 s", "12 s".
pub fn human_duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..=59 => format!("{s} s"),
        60..=3599 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, (s % 3600) / 60),
    }
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
        let mut session = Session {
            training,
            start: (0, 0, Instant::now()),
            estimated: false,
            step_budget: cfg.max_env_steps,
        };
        session.start = (session.rows(), session.env_steps(), Instant::now());
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_by_hand() {
        // Too early: 2 rows, or under 10 s.
        assert_eq!(Estimate::from_pace(30.0, 2, 10, 100, None), None);
        assert_eq!(Estimate::from_pace(9.0, 5, 10, 100, None), None);
        // 4 rows in 20 s: 5 s a row, 10 rows left = 50 s.
        let e = Estimate::from_pace(20.0, 4, 10, 1000, None).unwrap();
        assert_eq!(
            e.by,
            Pace::Rows {
                per_row: 5.0,
                left: 10
            }
        );
        assert!((e.seconds - 50.0).abs() < 1e-9);
        // 1000 steps in 20 s = 50 steps/s; 500 steps left = 10 s < 50 s: the budget ends it.
        let e = Estimate::from_pace(20.0, 4, 10, 1000, Some(500)).unwrap();
        assert_eq!(
            e.by,
            Pace::Steps {
                rate: 50.0,
                left: 500
            }
        );
        assert!((e.seconds - 10.0).abs() < 1e-9);
        assert!(e.describe("generation").starts_with(
            "pace: 50 env steps/s over the first 4 generations: about 10 s for the 500 env steps"
        ));
        // 5000 steps left = 100 s > 50 s: the rows end it first.
        let e = Estimate::from_pace(20.0, 4, 10, 1000, Some(5000)).unwrap();
        assert!(matches!(e.by, Pace::Rows { .. }));
        assert_eq!(human_duration(3900.0), "1 h 05 min");
        assert_eq!(human_duration(250.0), "4 min 10 s");
    }
}
