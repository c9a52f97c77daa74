//! How a policy holds up under disturbances it was not trained for: pushes, ground friction,
//! mass, motor strength, slopes, observation noise and action delay (the disturbance set of
//! legged_gym's domain randomisation and of humanoid-gym's sim-to-sim checks), each at a few
//! magnitudes, each from the same deterministic starts as `esrl eval`.
//!
//! A [`Disturbance`] changes the run's walking task (`[walk.perturb]` and the physics'
//! `friction`, `mass_scale`, `slope`; `esrl_sim::Perturb`); [`card`] evaluates the policy
//! under the standard set ([`standard_set`]) and reports per disturbance and magnitude the
//! share of episodes that stay up to the end (finish the track or walk the whole 60 s without
//! a fall), the share that reach the line, and the gait.

use crate::load::LoadedRun;
use crate::report::{evaluate_with, EvalOptions};
use esrl_metrics::{gait_classes_text, GaitClass};
use esrl_run::{bail, Result};
use esrl_sim::PushDirection;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One disturbance at one magnitude.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Disturbance {
    /// Sagittal pushes of this many m/s, every 5 s on average.
    PushSagittal(f32),
    /// Lateral pushes of this many m/s, every 5 s on average.
    PushLateral(f32),
    /// Ground friction coefficient (robot and ground; the task's default is 1).
    Friction(f32),
    /// Every link's mass and inertia times this.
    Mass(f32),
    /// Every actuator's effort limit times this.
    Strength(f32),
    /// Ground slope, degrees, positive uphill.
    Slope(f32),
    /// Gaussian noise of this SD on every (scaled) observation entry.
    ObsNoise(f32),
    /// The joints get the action of this many control steps before.
    Delay(u32),
}

impl Disturbance {
    /// The name used on the command line and in reports (`push_sagittal`, `friction`, …).
    pub fn name(self) -> &'static str {
        match self {
            Disturbance::PushSagittal(_) => "push_sagittal",
            Disturbance::PushLateral(_) => "push_lateral",
            Disturbance::Friction(_) => "friction",
            Disturbance::Mass(_) => "mass",
            Disturbance::Strength(_) => "strength",
            Disturbance::Slope(_) => "slope",
            Disturbance::ObsNoise(_) => "obs_noise",
            Disturbance::Delay(_) => "delay",
        }
    }

    /// Its magnitude and unit, for tables.
    pub fn magnitude(self) -> (f32, &'static str) {
        match self {
            Disturbance::PushSagittal(v) | Disturbance::PushLateral(v) => (v, "m/s"),
            Disturbance::Friction(v) => (v, "μ"),
            Disturbance::Mass(v) | Disturbance::Strength(v) => (v, "×"),
            Disturbance::Slope(v) => (v, "°"),
            Disturbance::ObsNoise(v) => (v, "SD"),
            Disturbance::Delay(v) => (v as f32, "steps"),
        }
    }

    /// Parses `KIND=VALUE` (`push_sagittal=0.5`, `friction=0.4`, `slope=-5`, `delay=1`).
    pub fn parse(text: &str) -> Result<Self> {
        let Some((kind, value)) = text.split_once('=') else {
            bail!("--perturb {text}: expected KIND=VALUE, e.g. push_sagittal=0.5");
        };
        let v: f32 = match value.trim().parse() {
            Ok(v) if f32::is_finite(v) => v,
            _ => bail!("--perturb {text}: `{value}` is not a number"),
        };
        Ok(match kind.trim() {
            "push_sagittal" => Disturbance::PushSagittal(v),
            "push_lateral" => Disturbance::PushLateral(v),
            "friction" => Disturbance::Friction(v),
            "mass" => Disturbance::Mass(v),
            "strength" => Disturbance::Strength(v),
            "slope" => Disturbance::Slope(v),
            "obs_noise" => Disturbance::ObsNoise(v),
            "delay" if v >= 0.0 && v.fract() == 0.0 => Disturbance::Delay(v as u32),
            "delay" => bail!("--perturb {text}: the delay counts whole control steps"),
            other => bail!(
                "--perturb {text}: unknown disturbance `{other}`; one of push_sagittal, \
                 push_lateral (m/s), friction (coefficient), mass, strength (scale), slope \
                 (degrees), obs_noise (SD), delay (control steps)"
            ),
        })
    }

    /// Lays the disturbance over a walking configuration (the result is validated when the
    /// environment is built).
    pub fn apply(self, walk: &mut esrl_sim::WalkConfig) {
        let p = &mut walk.perturb;
        match self {
            Disturbance::PushSagittal(v) => {
                p.push_speed = v;
                p.push_every = 5.0;
                p.push_direction = PushDirection::Sagittal;
            }
            Disturbance::PushLateral(v) => {
                p.push_speed = v;
                p.push_every = 5.0;
                p.push_direction = PushDirection::Lateral;
            }
            Disturbance::Friction(v) => walk.physics.friction = v,
            Disturbance::Mass(v) => walk.physics.mass_scale = v,
            Disturbance::Strength(v) => p.strength = v,
            Disturbance::Slope(v) => walk.physics.slope = v.to_radians(),
            Disturbance::ObsNoise(v) => p.obs_noise = v,
            Disturbance::Delay(v) => p.action_delay = v,
        }
    }
}

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

/// One line of the card.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CardRow {
    /// The disturbance (`null` for the undisturbed task).
    pub disturbance: Option<Disturbance>,
    /// Episodes run.
    pub episodes: usize,
    /// Episodes that did not fall (they finished the track or lasted the whole episode).
    pub survived: usize,
    /// Episodes that reached the end of the track.
    pub finished: usize,
    /// Mean forward speed, m/s.
    pub speed: f64,
    /// Episodes per gait class.
    pub classes: BTreeMap<GaitClass, usize>,
}

impl CardRow {
    /// "push_sagittal 0.5 m/s" (or "none").
    pub fn label(&self) -> String {
        match self.disturbance {
            None => "none".into(),
            Some(d) => {
                let (v, unit) = d.magnitude();
                format!("{} {v} {unit}", d.name())
            }
        }
    }
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
        rows.push(CardRow {
            disturbance: d,
            episodes: report.episodes.len(),
            survived: gaits.iter().filter(|g| !g.fell).count(),
            finished: gaits.iter().filter(|g| g.track_time.is_some()).count(),
            speed: gaits.iter().map(|g| g.mean_forward_velocity).sum::<f64>()
                / gaits.len().max(1) as f64,
            classes,
        });
    }
    Ok(rows)
}

/// The card as a Markdown table.
pub fn card_markdown(rows: &[CardRow]) -> String {
    let mut out = String::from(
        "| disturbance | stayed up | finished 50 m | speed (m/s) | gait classes |\n\
         |---|---:|---:|---:|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {}/{} | {}/{} | {:.2} | {} |\n",
            r.label(),
            r.survived,
            r.episodes,
            r.finished,
            r.episodes,
            r.speed,
            gait_classes_text(&r.classes)
        ));
    }
    out
}
