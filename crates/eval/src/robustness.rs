//! How a policy holds up under disturbances it was not trained for: pushes, ground friction,
//! mass, motor strength, slopes, observation noise and action delay (the disturbance set of
//! legged_gym's domain randomisation and of humanoid-gym's sim-to-sim checks), each at a few
//! magnitudes, each from the same deterministic starts as `esrl eval`.
//!
//! A [`Disturbance`] changes the run's walking task (`[walk.perturb]` and the physics'
//! `friction`, `mass_scale`, `slope`; `esrl_sim::Perturb`); [`card`] evaluates the policy
//! under the standard set ([`standard_set`]) and reports per disturbance and magnitude the
//! share of episodes that stay up to the end (no fall in the whole episode: on a track that
//! goes on past its line, a fall after the line counts), the share that reach the line, the
//! share that do either (the line or 60 s without a fall: the robustness goal's measure of
//! surviving), and the gait.
//!
//! **The robustness goal** ([`goal_set`], [`goal_rows`]): pushes of 0.5 m/s every 5 s each
//! way, ground friction 0.4–1.2, ±20 % mass and motor strength and ±5° slopes, each row
//! finished or stayed up in at least 9 of 10 episodes ([`GOAL_SHARE`]). The card says which
//! of these rows a policy meets and which it misses; a study with `[eval] robustness_episodes` counts
//! the runs that meet each, and all of them, with intervals.

use crate::disturbance::{CardRow, Disturbance};
use crate::load::LoadedRun;
use crate::report::{evaluate_with, EvalOptions};
use esrl_metrics::{gait_classes_text, GaitClass};
use esrl_run::{bail, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The robustness card's disturbances: pushes of 0.25–1 m/s every 5 s each way, friction
/// 0.4–1.2, ±20 % mass and strength, slopes of ±2.5° and ±5°, observation noise of 0.02–0.1
/// and one or two steps of delay.
pub fn standard_set() -> Vec<Disturbance> {
    use Disturbance::*;
    let mut set = Vec::new();
    for v in [0.25, 0.5, 0.75, 1.0] {
        set.push(PushSagittal(v));
    }
    for v in [0.25, 0.5, 0.75, 1.0] {
        set.push(PushLateral(v));
    }
    for v in [0.4, 0.6, 0.8, 1.2] {
        set.push(Friction(v));
    }
    set.extend([Mass(0.8), Mass(1.2), Strength(0.8), Strength(1.2)]);
    for v in [-5.0, -2.5, 2.5, 5.0] {
        set.push(Slope(v));
    }
    for v in [0.02, 0.05, 0.1] {
        set.push(ObsNoise(v));
    }
    set.extend([Delay(1), Delay(2)]);
    set
}

/// The robustness goal's disturbances, all on the card ([`standard_set`]): pushes of 0.5 m/s
/// every 5 s each way, ground friction 0.4, 0.6, 0.8 and 1.2, mass and strength × 0.8 and
/// × 1.2, and slopes of −5° and +5°.
pub fn goal_set() -> Vec<Disturbance> {
    use Disturbance::*;
    vec![
        PushSagittal(0.5),
        PushLateral(0.5),
        Friction(0.4),
        Friction(0.6),
        Friction(0.8),
        Friction(1.2),
        Mass(0.8),
        Mass(1.2),
        Strength(0.8),
        Strength(1.2),
        Slope(-5.0),
        Slope(5.0),
    ]
}

/// The share of a goal row's episodes that must finish or stay up, as (numerator,
/// denominator): 9 of 10.
pub const GOAL_SHARE: (usize, usize) = (9, 10);

/// Which of the robustness goal's rows a card meets.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoalRows {
    /// Goal disturbances the card has a row for (12 on a card of the standard set).
    pub rows: usize,
    /// Of them, the rows whose episodes finished or stayed up in at least [`GOAL_SHARE`].
    pub met: usize,
    /// The rows missed, in the goal's order.
    pub missed: Vec<GoalMiss>,
    /// Goal disturbances the card has no row for (a card of another set).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub absent: Vec<String>,
}

/// A goal row a card misses.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoalMiss {
    /// The row's label (`"slope -5 °"`, [`Disturbance::label`]).
    pub row: String,
    /// Its episodes that finished or stayed up.
    pub up: usize,
    /// Its episodes.
    pub episodes: usize,
}

impl std::fmt::Display for GoalMiss {
    /// `slope -5 °: 7/10`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}/{}", self.row, self.up, self.episodes)
    }
}

/// Which of [`goal_set`]'s rows `card` meets. A row counts its episodes that finished or
/// stayed up (for a card written before that count was kept, the larger of the two, a
/// lower bound).
pub fn goal_rows(card: &[CardRow]) -> GoalRows {
    let (num, den) = GOAL_SHARE;
    let mut goal = GoalRows {
        rows: 0,
        met: 0,
        missed: Vec::new(),
        absent: Vec::new(),
    };
    for d in goal_set() {
        let Some(row) = card.iter().find(|r| r.disturbance == Some(d)) else {
            goal.absent.push(d.label());
            continue;
        };
        goal.rows += 1;
        let up = row.finished_or_up.max(row.survived).max(row.finished);
        if row.episodes > 0 && den * up >= num * row.episodes {
            goal.met += 1;
        } else {
            goal.missed.push(GoalMiss {
                row: row.label(),
                up,
                episodes: row.episodes,
            });
        }
    }
    goal
}

/// "Robustness goal: 10 of 12 rows met (…); missed: …".
pub fn goal_markdown(goal: &GoalRows) -> String {
    let (num, den) = GOAL_SHARE;
    let mut text = format!(
        "Robustness goal (pushes 0.5 m/s each way, friction 0.4–1.2, mass and strength ±20 %, \
         slopes ±5°; a row is met when at least {num} of {den} episodes finish or stay up): {} \
         of {} rows met",
        goal.met, goal.rows
    );
    if !goal.missed.is_empty() {
        let missed: Vec<String> = goal.missed.iter().map(GoalMiss::to_string).collect();
        text.push_str(&format!("; missed: {}", missed.join(", ")));
    }
    if !goal.absent.is_empty() {
        text.push_str(&format!("; not on this card: {}", goal.absent.join(", ")));
    }
    text.push('.');
    text
}

/// Evaluates `loaded` undisturbed and under each of `set`, `episodes` deterministic episodes
/// from reset seeds `seed, seed + 1, …` each (traces are not kept). The undisturbed task is
/// the run's own without its `[walk.perturb]` (training-time randomisation is left out).
pub fn card(
    loaded: &LoadedRun,
    seed: u64,
    episodes: usize,
    set: &[Disturbance],
    stop: Option<&(dyn Fn() -> bool + Sync)>,
) -> Result<Vec<CardRow>> {
    if loaded.config.env != esrl_run::EnvKind::Walk {
        bail!("the robustness card is for walking runs");
    }
    let mut rows = Vec::new();
    for d in std::iter::once(None).chain(set.iter().copied().map(Some)) {
        if stop.is_some_and(|s| s()) {
            break;
        }
        // From the undisturbed task: a run trained with randomised disturbances is carded
        // on the same task as any other.
        let mut walk = loaded.config.walk.clone();
        walk.perturb = esrl_sim::Perturb::default();
        if let Some(d) = d {
            d.apply(&mut walk);
        }
        let disturbed = loaded.with_walk(walk)?;
        let report = evaluate_with(
            &disturbed,
            seed,
            episodes,
            None,
            &EvalOptions { traces: 0, stop },
        )?;
        let gaits: Vec<_> = report
            .episodes
            .iter()
            .filter_map(|e| e.gait.as_ref())
            .collect();
        let mut classes = BTreeMap::new();
        for g in &gaits {
            let c = g.cycle.as_ref().map_or(GaitClass::Fall, |c| c.gait_class);
            *classes.entry(c).or_insert(0) += 1;
        }
        let (survived, finished, finished_or_up) =
            survival_counts(gaits.iter().map(|g| (g.fell, g.track_time.is_some())));
        rows.push(CardRow {
            disturbance: d,
            episodes: report.episodes.len(),
            survived,
            finished,
            finished_or_up,
            speed: gaits.iter().map(|g| g.mean_forward_velocity).sum::<f64>()
                / gaits.len().max(1) as f64,
            classes,
        });
    }
    Ok(rows)
}

/// Of episodes given as `(fell, reached the line)`, how many stayed up (no fall in the whole
/// episode), reached the line, and did either.
fn survival_counts(episodes: impl Iterator<Item = (bool, bool)>) -> (usize, usize, usize) {
    let (mut up, mut finished, mut either) = (0, 0, 0);
    for (fell, reached) in episodes {
        up += usize::from(!fell);
        finished += usize::from(reached);
        either += usize::from(!fell || reached);
    }
    (up, finished, either)
}

/// The card as a Markdown table.
pub fn card_markdown(rows: &[CardRow]) -> String {
    let mut out = String::from(
        "| disturbance | stayed up | finished 50 m | finished or stayed up | speed (m/s) | gait classes |\n\
         |---|---:|---:|---:|---:|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {}/{} | {}/{} | {}/{} | {:.2} | {} |\n",
            r.label(),
            r.survived,
            r.episodes,
            r.finished,
            r.episodes,
            r.finished_or_up,
            r.episodes,
            r.speed,
            gait_classes_text(&r.classes)
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fall_after_the_line_is_finished_not_stayed_up() {
        // (fell, reached the line): walked 60 s past the line; fell after the line; fell
        // before it; stood the 60 s short of it.
        let episodes = [(false, true), (true, true), (true, false), (false, false)];
        assert_eq!(survival_counts(episodes.into_iter()), (2, 2, 3));
        assert_eq!(survival_counts(std::iter::empty()), (0, 0, 0));
    }

    /// A card row of `d` with `up` of `episodes` finished or stayed up.
    fn row(d: Disturbance, up: usize, episodes: usize) -> CardRow {
        CardRow {
            disturbance: Some(d),
            episodes,
            survived: up,
            finished: 0,
            finished_or_up: up,
            speed: 1.0,
            classes: BTreeMap::new(),
        }
    }

    #[test]
    fn a_goal_row_is_met_at_nine_of_ten_and_missed_rows_are_named() {
        let mut card: Vec<CardRow> = goal_set().into_iter().map(|d| row(d, 10, 10)).collect();
        card[1] = row(Disturbance::PushLateral(0.5), 0, 10);
        card[10] = row(Disturbance::Slope(-5.0), 8, 10);
        card[11] = row(Disturbance::Slope(5.0), 9, 10);
        // Rows off the goal change nothing.
        card.push(row(Disturbance::PushSagittal(1.0), 0, 10));
        let goal = goal_rows(&card);
        assert_eq!((goal.rows, goal.met), (12, 10));
        let missed: Vec<String> = goal.missed.iter().map(GoalMiss::to_string).collect();
        assert_eq!(missed, ["push_lateral 0.5 m/s: 0/10", "slope -5 °: 8/10"]);
        assert!(goal.absent.is_empty());
        // 18 of 20 meets the share, 17 of 20 does not.
        card[10] = row(Disturbance::Slope(-5.0), 18, 20);
        assert_eq!(goal_rows(&card).met, 11);
        card[10] = row(Disturbance::Slope(-5.0), 17, 20);
        assert_eq!(goal_rows(&card).met, 10);
        let text = goal_markdown(&goal);
        assert!(text.contains("10 of 12 rows met"), "{text}");
        assert!(
            text.contains("missed: push_lateral 0.5 m/s: 0/10"),
            "{text}"
        );
    }

    #[test]
    fn a_card_without_the_goal_rows_names_them_and_an_old_card_counts_a_lower_bound() {
        let goal = goal_rows(&[row(Disturbance::Friction(0.4), 10, 10)]);
        assert_eq!((goal.rows, goal.met, goal.absent.len()), (1, 1, 11));
        assert!(goal_markdown(&goal).contains("not on this card: push_sagittal 0.5 m/s"));
        // A card written before `finished_or_up` was kept reads it as 0: the larger of
        // stayed up and finished stands in for it.
        let mut old = row(Disturbance::Mass(1.2), 0, 10);
        (old.survived, old.finished) = (7, 9);
        assert_eq!(goal_rows(&[old]).met, 1);
        // No episodes meet no goal.
        assert_eq!(goal_rows(&[row(Disturbance::Mass(0.8), 0, 0)]).met, 0);
    }
}
