//! How long a session has left: an [`Estimate`] from the pace of its first rows, the line
//! every front end prints from it, and [`human_duration`].

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
