//! Gait-cycle metrics from foot contacts, and the gait class of a rollout.
//!
//! The input is one contact flag per foot per sample (left, right), sampled every `dt`
//! seconds; sample `i` describes the state after `i + 1` control steps, so an episode of `n`
//! samples lasts `n·dt`. A foot is in contact when its ground normal force exceeds
//! [`GaitThresholds::contact_force`].
//!
//! # Events
//!
//! - **Touchdown**: a sample in contact whose previous sample was not. A foot already down at
//!   the first sample has not touched down (a robot standing from reset takes no step).
//! - **Simultaneous touchdowns**: going through the touchdowns in time order, a touchdown of
//!   one foot and the next touchdown, if it is of the other foot and at most
//!   [`GaitThresholds::sync_window`] later, form one two-footed *landing*. Every other
//!   touchdown is a one-footed *step*. Landings and steps together are the *beats* of the gait.
//! - **Alternation**: the share of successive beats that are two steps of different feet
//!   (L→R or R→L). A landing never counts as a switch, so a two-footed hop has alternation 0 and
//!   a walk 1. `None` with fewer than two beats.
//! - **Synchronous share**: the share of touchdowns that belong to a landing (`None` without
//!   touchdowns).
//! - **Steps** (the step count) = all touchdowns of both feet (a landing counts 2);
//!   **cadence** = steps / (n·dt) × 60, steps per minute.
//! - **Stride time**: the time between successive touchdowns of the same foot, both feet
//!   pooled; its variability is the coefficient of variation SD/mean (sample SD), the usual
//!   stride-time variability of gait studies (Hausdorff 2005, "Gait variability: methods,
//!   modeling and meaning", J NeuroEng Rehabil 2:19). `None` with fewer than two strides.
//! - **Step length**: for successive beats that are steps of different feet, the forward (x)
//!   position of the new foot at its touchdown minus that of the other foot at its own, the
//!   preceding, touchdown (the distance between successive footprints; negative = backwards).
//!   Mean and sample SD; needs foot positions.
//!
//! # Phases (fractions of the samples)
//!
//! Double support: both feet in contact; single support: exactly one; flight: neither. They
//! sum to 1. Duty factor of a foot: the fraction of samples it is in contact (Alexander 1984).
//! Note `duty_left + duty_right − 1 = double support − flight`.
//!
//! # Gait class ([`classify_gait`]), rules in order
//!
//! 1. **`fall`**: the episode ended in a fall before [`GaitThresholds::min_touchdowns`]
//!    touchdowns or within [`GaitThresholds::min_duration`]: it fell before it could show a
//!    gait (the bounces of a toppling robot are no steps). A rollout that falls later is
//!    classified by what it did before (its `fell` is reported beside the class).
//! 2. **`stand`** / **`shuffle`**: fewer than `min_touchdowns` touchdowns or a cadence below
//!    [`GaitThresholds::min_cadence`] (60 steps/min): not stepping. `shuffle` when the feet
//!    still travel ([`GaitThresholds::still_speed`], sliding across the floor), else `stand`
//!    (also when foot positions are unknown).
//! 3. **`hop`**: at least [`GaitThresholds::min_synchronous`] of the touchdowns are
//!    simultaneous (both feet land together), or the touchdowns do not alternate
//!    (alternation not above [`GaitThresholds::min_alternation`]) and the robot leaves the
//!    ground with both feet (flight at least [`GaitThresholds::min_flight`]). Alexander
//!    1984: a hop has the feet in phase, a walk or run half a cycle apart.
//! 4. **`shuffle`**: touchdowns that do not alternate without flight (one foot tapping or
//!    sliding while the other stays down), or alternating steps that advance the feet less
//!    than [`GaitThresholds::min_advance`] each: foot speed / step rate, the mean step length
//!    of a steady gait (stepping in place, foot chatter). The advance is used rather than the
//!    step length because a staggered landing (one foot 60 ms after the other) makes a short
//!    step inside every long one.
//! 5. **`run`**: alternating steps with flight (at least `min_flight` of the time), else
//!    **`walk`**: alternating steps, flight ≈ 0, so the body is handed from foot to foot
//!    in double support. A human walk has about 20 % double support and no flight (Perry &
//!    Burnfield 2010, *Gait Analysis: Normal and Pathological Function*, 2nd ed.: stance
//!    60 % and two double-support periods of 10 % of the cycle at normal speed); only
//!    running has flight (Novacheck 1998, "The biomechanics of running", Gait & Posture
//!    7:77–95). Flight decides, not Alexander's duty factor alone: a stiff-legged bound with
//!    46 % double support and 40 % flight has a mean duty factor above 0.5 but is no walk.
//!
//! Sources of the thresholds are on each field of [`GaitThresholds`]. Alexander 1984:
//! R. McN. Alexander, "The gaits of bipedal and quadrupedal animals", Int. J. Robotics
//! Research 3(2):49–59.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{MetricsError, Result};

/// Thresholds of the gait-cycle metrics and of the gait class (defaults and sources below).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaitThresholds {
    /// A foot is in contact when its ground normal force exceeds this, N. Default 10: force
    /// plates detect toe-off reliably only at 10 N or less (Tirosh & Sparrow 2003,
    /// "Identifying heel contact and toe-off using forceplate thresholds with a range of
    /// digital-filter cutoff frequencies", J Appl Biomech 19:178–184), and 10 N is the cut-off
    /// of "Identifying gait events without a force plate during running: a comparison of
    /// methods" (Gait & Posture 33:130–132, 2011). About 1.5 % of the humanoid's weight.
    pub contact_force: f64,
    /// Touchdowns of opposite feet at most this far apart form one landing, s. Default 0.05
    /// (two control periods): a quarter of the shortest human step time (about 0.2 s when
    /// sprinting at 5 steps/s), so alternating steps are never paired, while simultaneous
    /// landings may differ by one sample.
    pub sync_window: f64,
    /// Fewer touchdowns than this (two strides) is no gait: `fall`, `stand` or `shuffle`.
    /// Default 4 (esrl's choice: one stride per foot is the least that shows a pattern, two
    /// the least that shows it repeat).
    pub min_touchdowns: usize,
    /// An episode that falls sooner than this has shown no gait (`fall`), s. Default 2: two
    /// strides of normal human walking (stride time about 1 s: Perry & Burnfield 2010).
    pub min_duration: f64,
    /// Below this cadence the robot is not stepping (`stand` or `shuffle`), steps/min.
    /// Default 60: the lower edge of the cadence bands in which free-living adults do their
    /// walking (60–79 steps/min and up; below 60 they accumulate hours of sporadic,
    /// non-walking steps: Tudor-Locke et al. 2011, "Patterns of adult stepping cadence in
    /// the 2005–2006 NHANES", Prev Med 53:178–181).
    pub min_cadence: f64,
    /// `hop` when at least this share of the touchdowns is simultaneous. Default 0.5 (most
    /// landings two-footed).
    pub min_synchronous: f64,
    /// Touchdowns alternate when the alternation is above this (strictly). Default 0.5: most
    /// successive steps switch foot (a walk or run alternates every step, alternation 1; a
    /// hop has 0).
    pub min_alternation: f64,
    /// Flight (both feet off the ground) of at least this fraction of the time makes an
    /// alternating gait a `run` and a non-alternating one a `hop`. Default 0.05 (esrl's
    /// choice): a walk has no flight, while in running each foot is down for less than half
    /// of the cycle and two float phases take up a sizeable part of it, growing with speed
    /// (Novacheck 1998); 5 % leaves room for the odd sample in which a walking robot's feet
    /// both bounce off the ground.
    pub min_flight: f64,
    /// `walk` and `run` need the feet to advance at least this per step (foot speed / step
    /// rate), m; unknown without foot positions, then not checked. Default 0.1 (esrl's
    /// choice): a seventh of a normal adult step (about 0.7 m, half the 1.4 m stride of Perry
    /// & Burnfield 2010) and a ninth of the humanoid's leg length (0.94 m); shorter steps are
    /// stepping in place or foot chatter.
    pub min_advance: f64,
    /// Feet whose net horizontal displacement over the episode, divided by its duration, is
    /// below this stand still; above, they slide (`shuffle`), m/s. Default 0.01 (0.6 m a
    /// minute, esrl's choice): below the 1.75 m a minute (0.03 m/s) that a limit-pressed
    /// rigid stance still creeps in the simulator (`esrl-sim` crate docs, physics table), so
    /// such creep reads as `shuffle`, not `stand`.
    pub still_speed: f64,
    /// A joint within this of a position limit counts as at the limit, rad. Default 1°: it
    /// shows the brace of a policy that rests on a joint stop.
    pub limit_margin: f64,
}

impl Default for GaitThresholds {
    fn default() -> Self {
        Self {
            contact_force: 10.0,
            sync_window: 0.05,
            min_touchdowns: 4,
            min_duration: 2.0,
            min_cadence: 60.0,
            min_synchronous: 0.5,
            min_alternation: 0.5,
            min_flight: 0.05,
            min_advance: 0.1,
            still_speed: 0.01,
            limit_margin: 1f64.to_radians(),
        }
    }
}

impl GaitThresholds {
    /// Checks every threshold (finite, ≥ 0; shares ≤ 1), naming the field at fault.
    pub fn validate(&self) -> Result<()> {
        let fields = [
            ("contact_force", self.contact_force, f64::INFINITY),
            ("sync_window", self.sync_window, f64::INFINITY),
            ("min_duration", self.min_duration, f64::INFINITY),
            ("min_cadence", self.min_cadence, f64::INFINITY),
            ("min_synchronous", self.min_synchronous, 1.0),
            ("min_alternation", self.min_alternation, 1.0),
            ("min_flight", self.min_flight, 1.0),
            ("min_advance", self.min_advance, f64::INFINITY),
            ("still_speed", self.still_speed, f64::INFINITY),
            ("limit_margin", self.limit_margin, f64::INFINITY),
        ];
        for (what, value, max) in fields {
            if !(value.is_finite() && (0.0..=max).contains(&value)) {
                return Err(MetricsError::InvalidParameter {
                    what: format!("thresholds.{what}"),
                    value: value.to_string(),
                    why: if max.is_finite() {
                        format!("must be in [0, {max}]")
                    } else {
                        "must be finite and ≥ 0".into()
                    },
                });
            }
        }
        Ok(())
    }
}

/// What a rollout's gait is (rules in the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GaitClass {
    /// Fell before two strides.
    Fall,
    /// Feet still, no stepping.
    Stand,
    /// Feet sliding, tapping, or stepping in place.
    Shuffle,
    /// Both feet land together.
    Hop,
    /// Alternating steps with flight.
    Run,
    /// Alternating steps without flight.
    Walk,
}

impl GaitClass {
    /// Every class, from the least to the most locomotive (the order ties are broken in).
    pub const ALL: [GaitClass; 6] = [
        GaitClass::Fall,
        GaitClass::Stand,
        GaitClass::Shuffle,
        GaitClass::Hop,
        GaitClass::Run,
        GaitClass::Walk,
    ];

    /// The lower-case name used in JSON and tables (`walk`, `run`, …).
    pub fn name(self) -> &'static str {
        match self {
            GaitClass::Fall => "fall",
            GaitClass::Stand => "stand",
            GaitClass::Shuffle => "shuffle",
            GaitClass::Hop => "hop",
            GaitClass::Run => "run",
            GaitClass::Walk => "walk",
        }
    }
}

impl std::fmt::Display for GaitClass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The most frequent class of `counts`; a tie goes to the less locomotive class
/// ([`GaitClass::ALL`] order), so a tie never overstates a gait. `None` when empty.
pub fn majority_class(counts: &BTreeMap<GaitClass, usize>) -> Option<GaitClass> {
    let mut best: Option<(GaitClass, usize)> = None;
    for class in GaitClass::ALL {
        let n = counts.get(&class).copied().unwrap_or(0);
        if n > 0 && best.is_none_or(|(_, m)| n > m) {
            best = Some((class, n));
        }
    }
    best.map(|(c, _)| c)
}

/// Foot index: 0 left, 1 right.
type Foot = usize;

/// One beat of the gait: a one-footed step or a two-footed landing.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Beat {
    /// A touchdown of one foot at a sample index.
    Step { foot: Foot, index: usize },
    /// Touchdowns of both feet within the sync window.
    Landing,
}

/// Touchdown sample indices of each foot.
fn touchdowns(contact: &[bool]) -> Vec<usize> {
    (1..contact.len())
        .filter(|&i| contact[i] && !contact[i - 1])
        .collect()
}

/// The beats in time order (module docs), from each foot's touchdown indices.
fn beats(down: &[Vec<usize>; 2], dt: f64, sync_window: f64) -> Vec<Beat> {
    let mut events: Vec<(usize, Foot)> = down[0]
        .iter()
        .map(|&i| (i, 0))
        .chain(down[1].iter().map(|&i| (i, 1)))
        .collect();
    events.sort_unstable();
    let mut out = Vec::with_capacity(events.len());
    let mut k = 0;
    while k < events.len() {
        let (index, foot) = events[k];
        if let Some(&(next, other)) = events.get(k + 1) {
            // A small tolerance so that a window of exactly k samples pairs k samples apart
            // despite rounding in (next − index)·dt.
            if other != foot && (next - index) as f64 * dt <= sync_window * (1.0 + 1e-9) {
                out.push(Beat::Landing);
                k += 2;
                continue;
            }
        }
        out.push(Beat::Step { foot, index });
        k += 1;
    }
    out
}

/// Temporal gait-cycle metrics of two contact traces (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitPhases {
    /// Samples.
    pub samples: usize,
    /// Sample period, s.
    pub dt: f64,
    /// Duration `samples · dt`, s.
    pub duration: f64,
    /// Fraction of samples with both feet in contact.
    pub double_support: f64,
    /// Fraction with exactly one foot in contact.
    pub single_support: f64,
    /// Fraction with neither foot in contact.
    pub flight: f64,
    /// Fraction of samples each foot (left, right) is in contact.
    pub duty_factor: [f64; 2],
    /// Touchdowns of the left and right foot.
    pub touchdowns: [usize; 2],
    /// Times of the touchdowns, s since reset (`(i + 1)·dt` for sample `i`), left and right.
    pub touchdown_times: [Vec<f64>; 2],
    /// All touchdowns (a two-footed landing counts 2).
    pub step_count: usize,
    /// Steps per minute.
    pub cadence: f64,
    /// Beats that are two-footed landings.
    pub landings: usize,
    /// Share of successive beats that switch foot; `None` with fewer than two beats.
    pub alternation: Option<f64>,
    /// Share of touchdowns that belong to a two-footed landing; `None` without touchdowns.
    pub synchronous: Option<f64>,
    /// Mean time between successive touchdowns of the same foot (both feet pooled), s.
    pub stride_time_mean: Option<f64>,
    /// Sample SD of those stride times, s (two strides at least).
    pub stride_time_sd: Option<f64>,
    /// Stride-time variability: SD / mean (two strides at least).
    pub stride_time_cv: Option<f64>,
}

fn mean_and_sd(values: &[f64]) -> (Option<f64>, Option<f64>) {
    if values.is_empty() {
        return (None, None);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.len() > 1).then(|| {
        let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
        (ss / (n - 1.0)).sqrt()
    });
    (Some(mean), sd)
}

fn check_dt(dt: f64) -> Result<()> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(MetricsError::InvalidParameter {
            what: "dt".into(),
            value: dt.to_string(),
            why: "must be finite and > 0".into(),
        })
    }
}

/// Phases, touchdowns, alternation, cadence and stride times of two contact traces (left,
/// right) sampled every `dt` seconds; simultaneous touchdowns are those within `sync_window`
/// seconds (module docs).
///
/// Errors: traces of different lengths, empty traces, a non-positive `dt`, a negative
/// `sync_window`.
///
/// ```
/// // A walk: each foot down 60 % of a 1 s cycle, the right half a cycle later.
/// let left: Vec<bool> = (0..400).map(|i| i % 100 < 60).collect();
/// let right: Vec<bool> = (0..400).map(|i| (i + 50) % 100 < 60).collect();
/// let p = esrl_metrics::gait_phases(&left, &right, 0.01, 0.05).unwrap();
/// assert!((p.double_support - 0.2).abs() < 1e-12);
/// assert_eq!(p.alternation, Some(1.0));
/// ```
pub fn gait_phases(left: &[bool], right: &[bool], dt: f64, sync_window: f64) -> Result<GaitPhases> {
    check_dt(dt)?;
    if !(sync_window.is_finite() && sync_window >= 0.0) {
        return Err(MetricsError::InvalidParameter {
            what: "sync_window".into(),
            value: sync_window.to_string(),
            why: "must be finite and ≥ 0".into(),
        });
    }
    if left.is_empty() {
        return Err(MetricsError::Empty {
            what: "left contact".into(),
        });
    }
    if right.len() != left.len() {
        return Err(MetricsError::LengthMismatch {
            what: "right contact".into(),
            found: right.len(),
            expected: left.len(),
        });
    }
    let n = left.len();
    let nf = n as f64;
    let (mut both, mut one) = (0usize, 0usize);
    for (&l, &r) in left.iter().zip(right) {
        match (l, r) {
            (true, true) => both += 1,
            (true, false) | (false, true) => one += 1,
            (false, false) => {}
        }
    }
    let duty = |c: &[bool]| c.iter().filter(|&&b| b).count() as f64 / nf;
    let down = [touchdowns(left), touchdowns(right)];
    let beats = beats(&down, dt, sync_window);
    let step_count = down[0].len() + down[1].len();
    let landings = beats.iter().filter(|b| **b == Beat::Landing).count();
    let alternation = (beats.len() >= 2).then(|| {
        let switches = beats
            .windows(2)
            .filter(|w| match (w[0], w[1]) {
                (Beat::Step { foot: a, .. }, Beat::Step { foot: b, .. }) => a != b,
                _ => false,
            })
            .count();
        switches as f64 / (beats.len() - 1) as f64
    });
    let strides: Vec<f64> = down
        .iter()
        .flat_map(|d| d.windows(2).map(|w| (w[1] - w[0]) as f64 * dt))
        .collect();
    let (stride_time_mean, stride_time_sd) = mean_and_sd(&strides);
    let stride_time_cv = match (stride_time_mean, stride_time_sd) {
        (Some(m), Some(sd)) if m > 0.0 => Some(sd / m),
        _ => None,
    };
    let duration = nf * dt;
    Ok(GaitPhases {
        samples: n,
        dt,
        duration,
        double_support: both as f64 / nf,
        single_support: one as f64 / nf,
        flight: (n - both - one) as f64 / nf,
        duty_factor: [duty(left), duty(right)],
        touchdowns: [down[0].len(), down[1].len()],
        touchdown_times: [0, 1].map(|f| down[f].iter().map(|&i| (i + 1) as f64 * dt).collect()),
        step_count,
        cadence: step_count as f64 / duration * 60.0,
        landings,
        alternation,
        synchronous: (step_count > 0).then(|| 2.0 * landings as f64 / step_count as f64),
        stride_time_mean,
        stride_time_sd,
        stride_time_cv,
    })
}

/// Lengths of the steps (module docs) from the contact traces and each foot's forward
/// position `foot_x[sample] = [left x, right x]` (m): one value per pair of successive beats
/// that are steps of different feet.
///
/// Errors as [`gait_phases`], and a `foot_x` of another length or with NaN/inf.
pub fn step_lengths(
    left: &[bool],
    right: &[bool],
    foot_x: &[[f64; 2]],
    dt: f64,
    sync_window: f64,
) -> Result<Vec<f64>> {
    gait_phases(left, right, dt, sync_window)?;
    if foot_x.len() != left.len() {
        return Err(MetricsError::LengthMismatch {
            what: "foot_x".into(),
            found: foot_x.len(),
            expected: left.len(),
        });
    }
    if let Some(i) = foot_x.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(MetricsError::NonFinite {
            what: "foot_x".into(),
            index: i,
            value: foot_x[i]
                .into_iter()
                .find(|v| !v.is_finite())
                .unwrap_or(f64::NAN),
        });
    }
    let down = [touchdowns(left), touchdowns(right)];
    Ok(beats(&down, dt, sync_window)
        .windows(2)
        .filter_map(|w| match (w[0], w[1]) {
            (Beat::Step { foot: a, index: i }, Beat::Step { foot: b, index: j }) if a != b => {
                Some(foot_x[j][b] - foot_x[i][a])
            }
            _ => None,
        })
        .collect())
}

/// What [`classify_gait`] looks at. Build it from [`GaitPhases`] with
/// [`GaitClassInput::from_phases`] and add what the contacts cannot tell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitClassInput {
    /// The episode ended in a fall.
    #[serde(default)]
    pub fell: bool,
    /// All touchdowns.
    pub step_count: usize,
    /// Steps per minute.
    pub cadence: f64,
    /// Duration of the episode, s.
    pub duration: f64,
    /// Share of touchdowns in two-footed landings.
    pub synchronous: Option<f64>,
    /// Share of successive beats that switch foot.
    pub alternation: Option<f64>,
    /// Fraction of time with both feet down.
    pub double_support: f64,
    /// Fraction of time with neither foot down.
    pub flight: f64,
    /// Mean over the feet of the net horizontal displacement / duration, m/s (`None`:
    /// unknown: not stepping then reads as `stand`, and the advance per step is not checked).
    #[serde(default)]
    pub foot_speed: Option<f64>,
}

impl GaitClassInput {
    /// The contact-based inputs of `phases`; `fell` false, foot speed unknown.
    pub fn from_phases(phases: &GaitPhases) -> Self {
        Self {
            fell: false,
            step_count: phases.step_count,
            cadence: phases.cadence,
            duration: phases.duration,
            synchronous: phases.synchronous,
            alternation: phases.alternation,
            double_support: phases.double_support,
            flight: phases.flight,
            foot_speed: None,
        }
    }
}

/// The gait class of a rollout (rules in the module docs).
///
/// ```
/// use esrl_metrics::{classify_gait, gait_phases, GaitClass, GaitClassInput, GaitThresholds};
/// // Both feet down 60 % of each 0.5 s cycle, together: a hop.
/// let c: Vec<bool> = (0..300).map(|i| i % 50 < 30).collect();
/// let p = gait_phases(&c, &c, 0.01, 0.05).unwrap();
/// let class = classify_gait(&GaitClassInput::from_phases(&p), &GaitThresholds::default());
/// assert_eq!(class, GaitClass::Hop);
/// ```
pub fn classify_gait(input: &GaitClassInput, t: &GaitThresholds) -> GaitClass {
    if input.fell && (input.step_count < t.min_touchdowns || input.duration < t.min_duration) {
        return GaitClass::Fall;
    }
    if input.step_count < t.min_touchdowns || input.cadence < t.min_cadence {
        return match input.foot_speed {
            Some(s) if s >= t.still_speed => GaitClass::Shuffle,
            _ => GaitClass::Stand,
        };
    }
    let alternating = input.alternation.is_some_and(|a| a > t.min_alternation);
    let flight = input.flight >= t.min_flight;
    if input.synchronous.is_some_and(|s| s >= t.min_synchronous) || (!alternating && flight) {
        return GaitClass::Hop;
    }
    let advance = input
        .foot_speed
        .filter(|_| input.cadence > 0.0)
        .map(|v| v * 60.0 / input.cadence);
    if !alternating || advance.is_some_and(|a| a < t.min_advance) {
        return GaitClass::Shuffle;
    }
    if flight {
        GaitClass::Run
    } else {
        GaitClass::Walk
    }
}

/// The gait-cycle metrics of one rollout (a field of `GaitMetrics`), or their mean over
/// episodes (then counts are means too and `gait_classes` counts every episode's class).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitCycle {
    /// Contact threshold used, N.
    pub contact_force: f64,
    /// Touchdowns of the left and right foot.
    pub touchdowns: [f64; 2],
    /// All touchdowns (steps).
    pub step_count: f64,
    /// Steps per minute.
    pub cadence: f64,
    /// Share of successive beats that switch foot (`None` with fewer than two beats).
    pub alternation: Option<f64>,
    /// Share of touchdowns in two-footed landings (`None` without touchdowns).
    pub synchronous: Option<f64>,
    /// Fraction of time with both feet down.
    pub double_support: f64,
    /// Fraction of time with one foot down.
    pub single_support: f64,
    /// Fraction of time with neither foot down.
    pub flight: f64,
    /// Fraction of time each foot (left, right) is down.
    pub duty_factor: [f64; 2],
    /// Mean step length, m (`None` without alternating steps or foot positions).
    pub step_length_mean: Option<f64>,
    /// Sample SD of the step lengths, m (two steps at least).
    pub step_length_sd: Option<f64>,
    /// Mean stride time, s.
    pub stride_time_mean: Option<f64>,
    /// Stride-time variability SD/mean.
    pub stride_time_cv: Option<f64>,
    /// Mean over the feet of the net horizontal displacement / duration, m/s (`None` without
    /// foot positions).
    pub foot_speed: Option<f64>,
    /// The gait class (of the episode; for a mean, the most frequent, ties to the less
    /// locomotive class).
    pub gait_class: GaitClass,
    /// Episodes per class (one entry for an episode).
    pub gait_classes: BTreeMap<GaitClass, usize>,
}

impl GaitCycle {
    /// The cycle metrics of one episode from its phases, step lengths and foot speed.
    pub fn from_parts(
        phases: &GaitPhases,
        steps: &[f64],
        foot_speed: Option<f64>,
        fell: bool,
        thresholds: &GaitThresholds,
    ) -> Self {
        let (step_length_mean, step_length_sd) = mean_and_sd(steps);
        let input = GaitClassInput {
            fell,
            foot_speed,
            ..GaitClassInput::from_phases(phases)
        };
        let gait_class = classify_gait(&input, thresholds);
        Self {
            contact_force: thresholds.contact_force,
            touchdowns: phases.touchdowns.map(|t| t as f64),
            step_count: phases.step_count as f64,
            cadence: phases.cadence,
            alternation: phases.alternation,
            synchronous: phases.synchronous,
            double_support: phases.double_support,
            single_support: phases.single_support,
            flight: phases.flight,
            duty_factor: phases.duty_factor,
            step_length_mean,
            step_length_sd,
            stride_time_mean: phases.stride_time_mean,
            stride_time_cv: phases.stride_time_cv,
            foot_speed,
            gait_class,
            gait_classes: BTreeMap::from([(gait_class, 1)]),
        }
    }
}

fn mean_of(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The mean of several episodes' cycle metrics: every number is the mean over the episodes
/// that have it (`None` if none does), `gait_classes` adds up the episodes' counts and
/// `gait_class` is their [`majority_class`]. `None` for no episodes.
pub fn mean_cycle(cycles: &[&GaitCycle]) -> Option<GaitCycle> {
    let first = cycles.first()?;
    let m = |f: fn(&GaitCycle) -> f64| mean_of(cycles.iter().map(|c| f(c))).unwrap_or(f64::NAN);
    let opt = |f: fn(&GaitCycle) -> Option<f64>| mean_of(cycles.iter().filter_map(|c| f(c)));
    let mut gait_classes = BTreeMap::new();
    for c in cycles {
        for (&class, &n) in &c.gait_classes {
            *gait_classes.entry(class).or_insert(0) += n;
        }
    }
    Some(GaitCycle {
        contact_force: first.contact_force,
        touchdowns: [m(|c| c.touchdowns[0]), m(|c| c.touchdowns[1])],
        step_count: m(|c| c.step_count),
        cadence: m(|c| c.cadence),
        alternation: opt(|c| c.alternation),
        synchronous: opt(|c| c.synchronous),
        double_support: m(|c| c.double_support),
        single_support: m(|c| c.single_support),
        flight: m(|c| c.flight),
        duty_factor: [m(|c| c.duty_factor[0]), m(|c| c.duty_factor[1])],
        step_length_mean: opt(|c| c.step_length_mean),
        step_length_sd: opt(|c| c.step_length_sd),
        stride_time_mean: opt(|c| c.stride_time_mean),
        stride_time_cv: opt(|c| c.stride_time_cv),
        foot_speed: opt(|c| c.foot_speed),
        gait_class: majority_class(&gait_classes).unwrap_or(first.gait_class),
        gait_classes,
    })
}
