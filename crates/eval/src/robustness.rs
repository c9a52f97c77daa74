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

use crate::disturbance::{CardRow, Disturbance};
use crate::load::LoadedRun;
use crate::report::{evaluate_with, EvalOptions};
use esrl_metrics::{gait_classes_text, GaitClass};
use esrl_run::{bail, Result};
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
}
