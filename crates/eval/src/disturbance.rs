//! The disturbances of a robustness evaluation and the card's lines: what `esrl eval
//! --perturb KIND=VALUE` parses, how each changes the walking task, and what the card
//! reports per disturbance ([`crate::robustness`] runs them).

use esrl_metrics::GaitClass;
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
    /// Natural frequency of the robot–ground contacts, Hz (the task's default is 60: lower
    /// is softer ground).
    Contact(f32),
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
            Disturbance::Contact(_) => "contact",
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
            Disturbance::Contact(v) => (v, "Hz"),
        }
    }

    /// "push_sagittal 0.5 m/s": its name, magnitude and unit, for tables.
    pub fn label(self) -> String {
        let (v, unit) = self.magnitude();
        format!("{} {v} {unit}", self.name())
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
        let d = match kind.trim() {
            "push_sagittal" => Disturbance::PushSagittal(v),
            "push_lateral" => Disturbance::PushLateral(v),
            "friction" => Disturbance::Friction(v),
            "mass" => Disturbance::Mass(v),
            "strength" => Disturbance::Strength(v),
            "slope" => Disturbance::Slope(v),
            "obs_noise" => Disturbance::ObsNoise(v),
            "contact" => Disturbance::Contact(v),
            "delay" if v >= 0.0 && v.fract() == 0.0 => Disturbance::Delay(v as u32),
            "delay" => bail!("--perturb {text}: the delay counts whole control steps"),
            other => bail!(
                "--perturb {text}: unknown disturbance `{other}`; one of push_sagittal, \
                 push_lateral (m/s), friction (coefficient), mass, strength (scale), slope \
                 (degrees), obs_noise (SD), delay (control steps), contact (Hz)"
            ),
        };
        // Out of range: refused here, in the unit typed, before a policy is loaded.
        if let Disturbance::Slope(deg) = d {
            if deg.abs() >= 45.0 {
                bail!("--perturb {text}: the slope is in degrees, within ±45° (exclusive)");
            }
        }
        let mut walk = esrl_sim::WalkConfig::default();
        d.apply(&mut walk);
        if let Err(e) = walk.validate() {
            bail!("--perturb {text}: {e}");
        }
        Ok(d)
    }

    /// Lays the disturbance over a walking configuration (the result is validated when the
    /// environment is built). A training range of the same quantity (`friction_range`, …)
    /// is cleared, or every episode would draw it again over the value set here.
    pub fn apply(self, walk: &mut esrl_sim::WalkConfig) {
        let p = &mut walk.perturb;
        match self {
            Disturbance::Friction(_) => p.friction_range = None,
            Disturbance::Mass(_) => p.mass_range = None,
            Disturbance::Strength(_) => p.strength_range = None,
            Disturbance::Slope(_) => p.slope_range = None,
            Disturbance::Contact(_) => p.contact_frequency_range = None,
            _ => {}
        }
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
            Disturbance::Contact(v) => walk.physics.contact_frequency = v,
        }
    }
}

/// One line of the card.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CardRow {
    /// The disturbance (`null` for the undisturbed task).
    pub disturbance: Option<Disturbance>,
    /// Episodes run.
    pub episodes: usize,
    /// Episodes that did not fall in the whole episode (on a track that goes on past its line,
    /// `walk.end_at_finish = false`, a fall after the line counts).
    pub survived: usize,
    /// Episodes that reached the end of the track.
    pub finished: usize,
    /// Episodes that reached the end of the track or did not fall: the robustness goal's
    /// measure of surviving ("finish or stay up 60 s"). Cards written before it was kept read
    /// as 0.
    #[serde(default)]
    pub finished_or_up: usize,
    /// Mean forward speed, m/s.
    pub speed: f64,
    /// Episodes per gait class.
    pub classes: BTreeMap<GaitClass, usize>,
}

impl CardRow {
    /// "push_sagittal 0.5 m/s" (or "none").
    pub fn label(&self) -> String {
        self.disturbance
            .map_or_else(|| "none".into(), Disturbance::label)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disturbance_replaces_the_training_range_of_its_quantity() {
        let mut walk = esrl_sim::WalkConfig::default();
        walk.perturb.slope_range = Some([-5.0, 5.0]);
        walk.perturb.friction_range = Some([0.4, 1.2]);
        walk.perturb.mass_range = Some([0.8, 1.2]);
        Disturbance::Slope(5.0).apply(&mut walk);
        Disturbance::Friction(0.4).apply(&mut walk);
        assert_eq!(walk.perturb.slope_range, None);
        assert_eq!(walk.perturb.friction_range, None);
        assert!((walk.physics.slope - 5f32.to_radians()).abs() < 1e-7);
        assert_eq!(walk.physics.friction, 0.4);
        // Other quantities keep their ranges.
        assert_eq!(walk.perturb.mass_range, Some([0.8, 1.2]));
    }

    #[test]
    fn out_of_range_magnitudes_are_refused_in_the_unit_typed() {
        let err = |text: &str| Disturbance::parse(text).unwrap_err().to_string();
        let slope = err("slope=100");
        assert!(
            slope.contains("degrees") && slope.contains("±45°"),
            "{slope}"
        );
        assert!(err("slope=-45").contains("±45°"));
        assert_eq!(
            Disturbance::parse("slope=-44").unwrap(),
            Disturbance::Slope(-44.0)
        );
        for (text, field) in [
            ("friction=-1", "physics.friction"),
            ("mass=0", "physics.mass_scale"),
            ("strength=0", "perturb.strength"),
            ("push_lateral=100", "perturb.push_speed"),
            ("obs_noise=-1", "perturb.obs_noise"),
            ("contact=0", "physics.contact_frequency"),
            ("delay=1000", "perturb.action_delay"),
        ] {
            let e = err(text);
            assert!(
                e.starts_with(&format!("--perturb {text}:")) && e.contains(field),
                "{e}"
            );
        }
        for d in crate::standard_set() {
            let (v, _) = d.magnitude();
            assert_eq!(Disturbance::parse(&format!("{}={v}", d.name())).unwrap(), d);
        }
    }
}
