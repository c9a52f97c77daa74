//! The walking check: a deterministic evaluation of a policy from several starts, judged by
//! the walking bar, run during training to choose the policy a run keeps (`RUN/best/`) and to
//! time the first policy that walks.
//!
//! One check runs `starts` deterministic episodes (tanh μ, no exploration) of the run's own
//! walking task. Start `k` resets with the seed of [`Stream::CheckReset`]`(k)` and, when the
//! task has a gait clock, at clock phase `(k + ½) / starts`, so the starts cover the gait
//! cycle evenly (a policy that falls when started mid-swing shows it). Each episode is
//! classified by the gait metrics of `esrl-metrics` (walk, run, hop, shuffle, stand, fall);
//! the check counts the episodes that reach the end of the track, that fall, and of each
//! class, and the mean forward speed and distance.
//!
//! **The walking bar** ([`CheckConfig::finish_share`], [`CheckConfig::walk_share`]): at least
//! 80 % of the starts reach the 50 m line and more than half of the episodes are classified
//! `walk` (the bar the walking recipe is judged by: `walk` in most episodes, 50 m from ≥ 8 of
//! 10 starts).
//!
//! **Confirming a walk** ([`CheckConfig::confirm_starts`], off by default). Ten starts are a
//! small sample: a policy that finishes 8 of 10 may finish 14 of 20 fresh ones. With
//! `confirm_starts = m`, a policy at the bar on its `starts` is run from `m` more (reset seeds
//! of [`Stream::CheckReset`]`(starts + j)`, clock phases `(j + ¼) / m`, between the first
//! ones' when `m = starts`), and the bar is judged again on all `starts + m` episodes; only a
//! policy that still meets it counts as at the bar (for `RUN/best/`, the first walk and
//! `--until walk`). A policy below the bar on its first starts costs nothing more.
//!
//! **A margin of speed** ([`CheckConfig::max_track_time`], off by default). The bar asks for
//! the line within the episode (60 s: 0.83 m/s), and a run that stops at its first walk
//! stops at one barely that fast; on a second engine such a walk, a few per cent slower,
//! misses the line (`results/strict`, MuJoCo). With `max_track_time = T`, only starts that
//! reach the line within `T` seconds count as finished for the bar; the reported counts and
//! the ranking's shares are unchanged.
//!
//! **A margin of symmetry** ([`CheckConfig::max_knee_asymmetry`], off by default). A walk
//! may limp: one knee working harder than the other (knee-torque asymmetry, |L − R| over
//! their mean, of each episode's mean |torque|; `esrl-metrics`). With `max_knee_asymmetry =
//! a`, a policy meets the bar only if its episodes' mean knee-torque asymmetry is at most
//! `a` (0.1: 10 %), judged on every start it ran, the confirmation's included; the reported
//! counts and the ranking's shares are unchanged, and the mean is in `checks.jsonl`
//! ([`CheckResult::knee_asymmetry`]). The default preset, `walker-even`, sets 0.1: on ten
//! seeds it turned `walker-mirror`'s five lopsided walks (11.5–17.5 %) into even ones
//! (2.6–9.8 %) for 0–0.41 M env steps more and left the other five runs as they were
//! (`results/unseen-starts/README.md`, "A margin of symmetry").
//!
//! **The first walk of a run that asks for more** ([`Checker::check_seeking`]). With a
//! margin of speed or of symmetry, the run's bar comes later than the first walk a user
//! could have: a walk that reaches the line within the episode but not within `T`, or
//! limps. Until a run has found one, its checks also judge the bar without the margins
//! ([`CheckResult::walking`]): on the same
//! starts and confirmation starts, each start run once, the ones the check itself stopped
//! before run for the verdict (stopping, with `stop_early`, once that bar is out of reach
//! too). The check's own counts, rank and bar are what they are without the verdict, so the
//! policy `RUN/best/` keeps and the stop do not change; its seconds include the verdict's
//! episodes.
//!
//! **Choosing the kept policy.** Checks are ranked by ([`CheckResult::score`]): at the bar
//! first, then the share of starts finished, then fewer falls (as a share), then the share
//! classified `walk`, then mean distance (shares, so a confirmed check of `starts + m`
//! episodes ranks beside unconfirmed ones of `starts`; with equal counts, the order of the
//! counts). With a check configured, `RUN/best/` holds the best-ranked policy checked so far
//! instead of the one with the highest learning-curve value: a policy that scores one sampled
//! rollout higher but falls from more starts, or shuffles, is not kept over one that walks.
//! Candidates are each row whose learning-curve value is the highest so far
//! ([`CheckConfig::new_best`]; for the hybrid loop the generation's best individual) and,
//! every [`CheckConfig::every_steps`] environment steps, the policy of the latest row (so a
//! walk that appears after an early high score is still seen).
//!
//! **The policy a run starts from.** A run started from a trained policy (`init`: fine-tuning,
//! `--preset walker-robust`) checks that policy too, beside its first row (`"trigger":
//! "start"`, row 0, 0 env steps), as a candidate for `RUN/best/` only: a policy the run
//! trained must rank above it to be kept, so the run never hands back one its own check
//! ranks below its start (the stage under disturbances on seed 8 of the default kept an
//! early, worse policy when none it trained finished a disturbed start;
//! `results/robustness/README.md`). The start is not the run's first walk (a start at the
//! bar neither stops the run nor times a walk) and its distance does not settle the
//! `[restart]` rule; `best.json` of a kept start says `"start": true`.
//!
//! **Stopping early** ([`CheckConfig::stop_early`], off by default). Most checks are of
//! policies far from the bar, and a policy that must finish every start is out of reach at
//! its first start that does not. With `stop_early`, a check stops at the start, in start
//! order, after which the bar can no longer be met on its `starts` (or, confirming, on all
//! `starts + confirm_starts`): too many starts missed the line (in time), or too many were
//! not classified `walk`. Such a check is `stopped`, below the bar, and its counts and means
//! are over the starts it ran (the rank's shares too). It never changes whether a policy is
//! at the bar, so the first walk, `--until walk` and the policy a run that walks keeps stay
//! what a full check finds. A policy is kept on its full record only: a check that stops
//! with its starts so far ranking it above the kept policy (or with none kept yet) runs its
//! remaining starts after all (it is `completed`), so `RUN/best/` never holds a policy ranked
//! on the few starts of a stopped check, and a stopped check is one that its first starts
//! already rank below the kept policy. Which starts a stopped check ran does not depend on
//! the thread count: starts run in parallel, the ones past a start already known to end the
//! check are skipped, and the record keeps the starts up to the one that put the bar out of
//! reach. While `[restart]` may still start the run over, checks run in full (the rule reads
//! their mean distance); [`Checker::check`]'s `may_stop` says when it no longer can.
//!
//! **Checking the ES mean** ([`CheckConfig::mean`], off by default). The hybrid loop's
//! candidates are individuals: the generation's best perturbation θ + σε (or the RL actor),
//! chosen by one sampled rollout each. With `mean`, each policy due a check is checked
//! beside the ES mean θ after the same generation (the elites' weighted mean, eq. 10), first,
//! with the same starts, and both are ranked as candidates of their own: the mean is kept,
//! is the first walk, or stops the run wherever it ranks as a row's policy would, and a
//! row's policy that only ties with it does not replace it. The learner is the same run
//! either way, so the first walk can only come at the same row or earlier. The checks cost
//! more than twice as much where the mean walks and the rows' policies do not: a walking
//! mean runs every start where [`CheckConfig::stop_early`] stops most individuals' checks at
//! their first miss (`walker-fast`'s seeds 0, 8, 3 and 7: 1.2–4.6 times the check seconds
//! per checked row, 10–17 % of the run's wall time against 4–8 %). `checks.jsonl` marks the mean's checks (`"mean": true`) and
//! `best.json` a kept mean. (The motive, measured on eleven `walker-fast` runs, three as the
//! preset is and eight trained from wider starts: each run's ES mean at its stop, evaluated
//! from 200 unseen starts beside the individual it kept a generation or two before, fell
//! from 17 of 2,200 starts against the individuals' 32 and walked with less knee-torque
//! asymmetry in ten of the eleven; `results/unseen-starts/README.md`, "The ES mean".)
//!
//! **Cost.** A check simulates up to `starts` whole episodes (24,000 steps for 10 walking
//! starts of 60 s). It runs beside the next row on the run's thread pool (the training
//! session joins the two), so on two threads it mostly takes the core the rollouts leave
//! idle while the updates run; on one thread it adds its time. Before a checkpoint, the
//! check still due runs first, so a checkpoint covers every check of its rows and a resumed
//! run repeats them exactly. `checks.jsonl` gives each check's seconds and the summary their
//! total (`check_s`).
//!
//! The check draws nothing from the run's other streams and changes nothing the learner
//! does: a run learns the same with or without it, and only which policy `RUN/best/` keeps,
//! the rows of `checks.jsonl` and the summary's `steps_to_walk` differ.

use crate::error::{Context, Result};
use esrl_agents::{ActMode, Agent};
use esrl_metrics::{gait_metrics, pitch_of, GaitClass, GaitOptions, GaitStep, GaitTrace};
use esrl_sim::{run_episode, Env, GaitSample, RobotModel, Step, WalkConfig, WalkEnv};
use esrl_streams::Stream;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// How a run checks its policies against the walking bar (`[check]` in `config.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CheckConfig {
    /// Deterministic episodes per check, start `k` at gait-clock phase `(k + ½)/starts`.
    /// Default 10 (the walking bar's 10 starts).
    pub starts: usize,
    /// Check the policy of the latest row every this many environment steps. Default
    /// 100,000 (about a minute of training on 2 cores; the walking recipe's walks appear
    /// between 1.5 and 2.9 M steps).
    pub every_steps: u64,
    /// Also check the policy of every row whose learning-curve value is the highest so far.
    /// Default true.
    pub new_best: bool,
    /// The bar's share of starts that must reach the end of the track. Default 0.8 (8 of 10).
    pub finish_share: f64,
    /// The bar's share of episodes that must be classified `walk`: more than this. Default
    /// 0.5 (most episodes).
    pub walk_share: f64,
    /// Starts added to confirm a policy at the bar on its first `starts` (module docs); the
    /// bar is then judged on all of them. Default 0 (off).
    pub confirm_starts: usize,
    /// A start counts towards [`CheckConfig::finish_share`] only if it reaches the line within
    /// this many seconds (module docs, "A margin of speed"). Default none: within the
    /// episode.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_track_time: Option<f64>,
    /// The bar asks the episodes' mean knee-torque asymmetry to be at most this (a share:
    /// 0.1 is 10 %; module docs, "A margin of symmetry"). Default none: any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_knee_asymmetry: Option<f64>,
    /// Stop a check once the bar is out of its reach (module docs, "Stopping early").
    /// Default false: every start runs.
    #[serde(skip_serializing_if = "is_false")]
    pub stop_early: bool,
    /// Check the hybrid loop's ES mean θ beside each policy due a check, as a candidate of
    /// its own (module docs, "Checking the ES mean"). Default false.
    #[serde(skip_serializing_if = "is_false")]
    pub mean: bool,
}

impl Default for CheckConfig {
    fn default() -> Self {
        Self {
            starts: 10,
            every_steps: 100_000,
            new_best: true,
            finish_share: 0.8,
            walk_share: 0.5,
            confirm_starts: 0,
            max_track_time: None,
            max_knee_asymmetry: None,
            stop_early: false,
            mean: false,
        }
    }
}

/// Most starts a check may run (each is a whole episode).
pub const MAX_STARTS: usize = 1000;

impl CheckConfig {
    /// Checks every field, naming the first that cannot work.
    pub fn validate(&self) -> Result<()> {
        if self.starts == 0 || self.starts > MAX_STARTS {
            crate::bail!(
                "check.starts = {}: must be in 1..={MAX_STARTS}",
                self.starts
            );
        }
        if self.confirm_starts > MAX_STARTS {
            crate::bail!(
                "check.confirm_starts = {}: must be in 0..={MAX_STARTS}",
                self.confirm_starts
            );
        }
        if self.every_steps == 0 {
            crate::bail!("check.every_steps = 0: must be ≥ 1");
        }
        if let Some(t) = self.max_track_time {
            if !(t.is_finite() && t > 0.0) {
                crate::bail!("check.max_track_time = {t}: must be a time > 0 s");
            }
        }
        if let Some(a) = self.max_knee_asymmetry {
            if !(a.is_finite() && a >= 0.0) {
                crate::bail!("check.max_knee_asymmetry = {a}: must be a share ≥ 0 (0.1 is 10 %)");
            }
        }
        for (name, v) in [
            ("finish_share", self.finish_share),
            ("walk_share", self.walk_share),
        ] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                crate::bail!("check.{name} = {v}: must be in [0, 1]");
            }
        }
        Ok(())
    }

    /// Whether the bar has a margin of speed or of symmetry, so that a run seeks its first
    /// walk without them as well (module docs).
    pub fn has_margin(&self) -> bool {
        self.max_track_time.is_some() || self.max_knee_asymmetry.is_some()
    }

    /// "the 40 s margin", "the 10 % knee-asymmetry margin", or both joined by "and" (`None`
    /// without a margin).
    pub fn margins(&self) -> Option<String> {
        let speed = self.max_track_time.map(|t| format!("the {t} s margin"));
        let symmetry = self
            .max_knee_asymmetry
            .map(|a| format!("the {} % knee-asymmetry margin", percent(a)));
        match (speed, symmetry) {
            (Some(a), Some(b)) => Some(format!("{a} and {b}")),
            (a, b) => a.or(b),
        }
    }

    /// The gait-clock phase of start `k`: `(k + ½) / starts` for the first `starts`, then
    /// `(j + ¼) / confirm_starts` for confirmation start `j = k − starts`.
    pub fn phase(&self, k: usize) -> f32 {
        if k < self.starts {
            ((k as f64 + 0.5) / self.starts as f64) as f32
        } else {
            let j = (k - self.starts) as f64;
            ((j + 0.25) / self.confirm_starts.max(1) as f64) as f32
        }
    }
}

/// What one check found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckResult {
    /// Episodes run (the confirmation's included).
    pub starts: usize,
    /// Of `starts`, the episodes run to confirm a policy at the bar on its first ones (0: no
    /// confirmation ran; then absent from `checks.jsonl`).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub confirm_starts: usize,
    /// Episodes that reached the end of the track.
    pub finished: usize,
    /// Episodes that fell.
    pub falls: usize,
    /// Episodes per gait class.
    pub classes: BTreeMap<GaitClass, usize>,
    /// Mean forward speed of the torso over the episodes, m/s.
    pub mean_forward_velocity: f64,
    /// Mean distance covered along the track, m.
    pub mean_distance: f64,
    /// Mean track time of the episodes that reached the end of the track, s.
    pub track_time: Option<f64>,
    /// With [`CheckConfig::max_knee_asymmetry`], the episodes' mean knee-torque asymmetry (a
    /// share); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub knee_asymmetry: Option<f64>,
    /// Whether the policy meets the walking bar.
    pub at_bar: bool,
    /// Whether it meets the walking bar without the margins of speed and symmetry
    /// ([`CheckConfig::max_track_time`], [`CheckConfig::max_knee_asymmetry`]), on all its
    /// starts, confirmation included: judged only while a run with a margin seeks its first
    /// walk ([`Checker::check_seeking`]); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walking: Option<bool>,
    /// Environment steps of the episodes the result counts (a stopped check's skipped and
    /// discarded starts are not).
    pub check_steps: u64,
    /// Whether the check stopped once the bar was out of reach ([`CheckConfig::stop_early`]);
    /// its counts are then over the `starts` it ran. Absent from `checks.jsonl` when false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub stopped: bool,
    /// Whether the check stopped once the bar was out of reach but ranked above the kept
    /// policy on the starts it had run, and so ran its remaining starts (module docs,
    /// "Stopping early"); its counts are over every start. Absent from `checks.jsonl` when
    /// false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub completed: bool,
}

impl CheckResult {
    /// Episodes classified `class`.
    pub fn count(&self, class: GaitClass) -> usize {
        self.classes.get(&class).copied().unwrap_or(0)
    }

    /// The rank key (module docs): at the bar, then the shares of starts finished, not
    /// fallen and classified `walk`, then mean distance.
    pub fn score(&self) -> (bool, f64, f64, f64, f64) {
        let n = self.starts.max(1) as f64;
        let share = |k: usize| k as f64 / n;
        (
            self.at_bar,
            share(self.finished),
            -share(self.falls),
            share(self.count(GaitClass::Walk)),
            self.mean_distance,
        )
    }

    /// Whether this result ranks above `other` (ties keep `other`).
    pub fn beats(&self, other: &CheckResult) -> bool {
        self.score().partial_cmp(&other.score()) == Some(std::cmp::Ordering::Greater)
    }

    /// "walk 9, run 1; 10/10 finished, 0 falls, 1.09 m/s".
    pub fn describe(&self) -> String {
        let mut classes: Vec<(GaitClass, usize)> =
            self.classes.iter().map(|(c, n)| (*c, *n)).collect();
        classes.sort_by(|a, b| b.1.cmp(&a.1).then(b.0.cmp(&a.0)));
        let classes = classes
            .iter()
            .map(|(c, n)| format!("{} {n}", c.name()))
            .collect::<Vec<_>>()
            .join(", ");
        let confirmed = if self.confirm_starts > 0 {
            format!(", {} of the starts confirming", self.confirm_starts)
        } else {
            String::new()
        };
        format!(
            "{classes}; {}/{} finished, {} falls, {:.2} m/s{}{confirmed}{}{}",
            self.finished,
            self.starts,
            self.falls,
            self.mean_forward_velocity,
            if self.at_bar { " (at the bar)" } else { "" },
            if !self.at_bar && self.walking == Some(true) {
                " (at the bar without the margins, on all its starts)"
            } else {
                ""
            },
            match (self.stopped, self.walking) {
                (false, _) => "",
                (true, None) => " (stopped: the bar out of reach)",
                (true, Some(_)) => " (stopped: the bar with its margins out of reach)",
            }
        )
    }
}

/// Runs checks of policies on one walking task.
#[derive(Clone)]
pub struct Checker {
    config: CheckConfig,
    model: Arc<RobotModel>,
    walk: WalkConfig,
    seed: u64,
}

impl Checker {
    /// A checker for the walking task `walk` on `model`, in the run with seed `seed`.
    pub fn new(config: CheckConfig, model: Arc<RobotModel>, walk: WalkConfig, seed: u64) -> Self {
        Self {
            config,
            model,
            walk,
            seed,
        }
    }

    /// Its settings.
    pub fn config(&self) -> &CheckConfig {
        &self.config
    }

    /// Checks `agent`'s deterministic policy from every start (and, when it meets the bar
    /// and [`CheckConfig::confirm_starts`] asks, from the confirmation's), in parallel on the
    /// calling rayon pool (the result does not depend on the thread count). With
    /// [`CheckConfig::stop_early`] and `may_stop` (the caller's word that nothing reads the
    /// full check's distance: module docs, "Stopping early"), it stops once the bar is out
    /// of reach, unless the starts it ran rank it above `kept` (the kept policy's check;
    /// `None`: none kept yet), in which case it runs the rest and is `completed`.
    pub fn check(
        &self,
        agent: &Agent,
        may_stop: bool,
        kept: Option<&CheckResult>,
    ) -> Result<CheckResult> {
        self.check_seeking(agent, may_stop, kept, false)
    }

    /// [`Checker::check`], and with `seeking` (the run has not found its first walk yet)
    /// and a margin ([`CheckConfig::has_margin`]), the verdict [`CheckResult::walking`] on
    /// the bar without the margins (module docs, "The first walk of a run that asks for
    /// more").
    pub fn check_seeking(
        &self,
        agent: &Agent,
        may_stop: bool,
        kept: Option<&CheckResult>,
        seeking: bool,
    ) -> Result<CheckResult> {
        let (starts, confirm) = (self.config.starts, self.config.confirm_starts);
        let stop = self.config.stop_early && may_stop;
        let mut episodes = Vec::new();
        let first = self.run_phase(agent, 0..starts, &mut episodes, stop, kept)?;
        let mut result = if !first.at_bar || confirm == 0 {
            first
        } else {
            self.run_phase(agent, starts..starts + confirm, &mut episodes, stop, kept)?
        };
        if seeking && self.config.has_margin() {
            result.walking = Some(self.walking(agent, episodes, stop)?);
        }
        Ok(result)
    }

    /// Whether the policy meets the bar without the margins of speed and symmetry, on its
    /// starts and (when it does on those) its confirmation's, given the `episodes` a check
    /// of it ran (in start order); the starts the check did not run are run here, stopping
    /// once that bar is out of reach when `stop`.
    fn walking(&self, agent: &Agent, mut episodes: Vec<Start>, stop: bool) -> Result<bool> {
        let untimed = Checker {
            config: CheckConfig {
                max_track_time: None,
                max_knee_asymmetry: None,
                ..self.config.clone()
            },
            ..self.clone()
        };
        let (starts, confirm) = (self.config.starts, self.config.confirm_starts);
        let confirming = episodes.split_off(episodes.len().min(starts));
        let stopped = untimed.run_starts(agent, episodes.len()..starts, &mut episodes, stop)?;
        let first = judge(&untimed.config, &episodes, 0, stopped);
        if !first.at_bar || confirm == 0 {
            return Ok(first.at_bar);
        }
        episodes.extend(confirming);
        let ks = episodes.len()..starts + confirm;
        let stopped = untimed.run_starts(agent, ks, &mut episodes, stop)?;
        Ok(judge(&untimed.config, &episodes, confirm, stopped).at_bar)
    }

    /// Runs the phase `ks` of a check (its first starts, or the confirmation's) after the
    /// earlier phase's `episodes`, and judges all of them; a phase that stops but ranks
    /// above `kept` on the starts it ran runs the rest ([`Checker::check`]).
    fn run_phase(
        &self,
        agent: &Agent,
        ks: std::ops::Range<usize>,
        episodes: &mut Vec<Start>,
        stop: bool,
        kept: Option<&CheckResult>,
    ) -> Result<CheckResult> {
        // The confirmation's episodes are those past the first `starts`.
        let judged = |episodes: &[Start], stopped: bool| {
            let confirming = episodes.len().saturating_sub(self.config.starts);
            judge(&self.config, episodes, confirming, stopped)
        };
        let stopped = self.run_starts(agent, ks.clone(), episodes, stop)?;
        let result = judged(episodes, stopped);
        if !stopped || kept.is_some_and(|k| !result.beats(k)) {
            return Ok(result);
        }
        self.run_starts(agent, episodes.len()..ks.end, episodes, false)?;
        Ok(CheckResult {
            completed: true,
            ..judged(episodes, false)
        })
    }

    /// Runs starts `ks` in parallel and appends them to `episodes` (the earlier starts of the
    /// same check), in start order. With `stop`, the starts after the one that puts the bar
    /// out of reach on `ks.end` episodes are left out (skipped when not yet begun); returns
    /// whether that happened.
    fn run_starts(
        &self,
        agent: &Agent,
        ks: std::ops::Range<usize>,
        episodes: &mut Vec<Start>,
        stop: bool,
    ) -> Result<bool> {
        if !stop {
            let run: Result<Vec<Start>> =
                ks.into_par_iter().map(|k| self.episode(agent, k)).collect();
            episodes.extend(run?);
            return Ok(false);
        }
        let reach = Reach::new(&self.config, ks.end, episodes);
        // The last start that can still matter: a start past the first one known to put the
        // bar out of reach is skipped (module docs). Misses seen so far, by kind.
        let last = AtomicUsize::new(usize::MAX);
        let seen = Mutex::new([Vec::new(), Vec::new()]);
        let results: Vec<Option<Result<Start>>> = ks
            .clone()
            .into_par_iter()
            .map(|k| {
                if k > last.load(Ordering::Acquire) {
                    return None;
                }
                let start = self.episode(agent, k);
                if let Ok(start) = &start {
                    let mut seen = seen.lock().unwrap_or_else(|e| e.into_inner());
                    if let Some(end) = reach.known_end(&mut seen, ks.start, k, start) {
                        last.fetch_min(end, Ordering::AcqRel);
                    }
                }
                Some(start)
            })
            .collect();
        // Every start up to the one that ends the check ran: a start is skipped only past a
        // start known to end it, which is at or after the one that does.
        let ran: Vec<Start> = results
            .into_iter()
            .map_while(|r| r)
            .collect::<Result<_>>()?;
        let end = reach.end(&ran);
        if end.is_none() && ran.len() < ks.len() {
            crate::bail!(
                "a walking check skipped start {} before a start that ended it",
                ks.start + ran.len()
            );
        }
        episodes.extend(ran.into_iter().take(end.map_or(usize::MAX, |e| e + 1)));
        Ok(end.is_some())
    }

    /// Start `k`: one deterministic episode, judged.
    fn episode(&self, agent: &Agent, k: usize) -> Result<Start> {
        let mut env = WalkEnv::from_model(self.model.clone(), self.walk.clone())
            .context("building the walking environment of the check")?;
        env.set_start_phase(Some(self.config.phase(k)));
        let seed = Stream::CheckReset(k as u64).seed(self.seed);
        let mut policy = agent.policy();
        policy.reset();
        // Deterministic actions draw nothing; the stream only satisfies the signature.
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut log = GaitLog::new(&env);
        let mut hook = esrl_sim::hooks(
            |obs: &[f32], action: &mut [f32]| {
                policy.act(obs, ActMode::Deterministic, &mut rng, action)
            },
            |env: &WalkEnv, _: &[f32], _: &[f32], step: &Step| {
                log.observe(env, step);
                Ok::<(), std::convert::Infallible>(())
            },
        );
        let limit = env.max_episode_steps().max(1);
        let end = match run_episode(&mut env, seed, Some(limit), &mut hook) {
            Ok(end) => end,
            Err(never) => match never {},
        };
        let trace = log.finish();
        let steps = end.steps as u64;
        if trace.is_empty() {
            // Not one finite sample: the simulation failed at once, which the task calls a
            // fall.
            return Ok(Start {
                class: GaitClass::Fall,
                track_time: None,
                knee_asymmetry: None,
                fell: true,
                speed: 0.0,
                distance: 0.0,
                steps,
            });
        }
        let track = f64::from(self.walk.track_length);
        let g = gait_metrics(&trace, &gait_options(&trace.actuator_names, track))
            .context("computing the gait metrics of a check")?;
        Ok(Start {
            class: g.cycle.as_ref().map_or(GaitClass::Fall, |c| c.gait_class),
            track_time: g.track_time,
            knee_asymmetry: Some(g.knee_torque_asymmetry),
            fell: g.fell,
            speed: g.mean_forward_velocity,
            distance: g.distance,
            steps,
        })
    }
}

/// A share as a percentage, rounded to 0.01 (0.07 → 7, not 7.000000000000001).
fn percent(share: f64) -> f64 {
    (share * 10_000.0).round() / 100.0
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// Judges a check's episodes by the bar of `config` (`confirm` of them confirming;
/// `stopped`: the check stopped once the bar was out of reach, so it is below it).
fn judge(config: &CheckConfig, episodes: &[Start], confirm: usize, stopped: bool) -> CheckResult {
    let mut classes = BTreeMap::new();
    for e in episodes {
        *classes.entry(e.class).or_insert(0) += 1;
    }
    let times: Vec<f64> = episodes.iter().filter_map(|e| e.track_time).collect();
    let finished = times.len();
    let in_time = match config.max_track_time {
        Some(limit) => times.iter().filter(|&&t| t <= limit).count(),
        None => finished,
    };
    let starts = episodes.len();
    let n = starts as f64;
    let walks = classes.get(&GaitClass::Walk).copied().unwrap_or(0);
    // The mean over every episode: one without gait metrics (a simulation that failed at
    // once) is no even walk, and leaves the mean undefined.
    let knee_asymmetry = config.max_knee_asymmetry.map(|_| {
        episodes
            .iter()
            .map(|e| e.knee_asymmetry.unwrap_or(f64::NAN))
            .sum::<f64>()
            / n
    });
    let even = match (config.max_knee_asymmetry, knee_asymmetry) {
        (Some(limit), Some(a)) => a <= limit,
        _ => true,
    };
    CheckResult {
        starts,
        confirm_starts: confirm,
        finished,
        falls: episodes.iter().filter(|e| e.fell).count(),
        mean_forward_velocity: episodes.iter().map(|e| e.speed).sum::<f64>() / n,
        mean_distance: episodes.iter().map(|e| e.distance).sum::<f64>() / n,
        track_time: (!times.is_empty()).then(|| times.iter().sum::<f64>() / times.len() as f64),
        knee_asymmetry,
        at_bar: !stopped
            && in_time as f64 >= config.finish_share * n - 1e-9
            && walks as f64 > config.walk_share * n
            && even,
        walking: None,
        check_steps: episodes.iter().map(|e| e.steps).sum(),
        stopped,
        completed: false,
        classes,
    }
}

/// How far a check with stopping early is from losing the bar: the misses of each kind (a
/// start that did not reach the line in time; one not classified `walk`) it can still take
/// on its `n` episodes, after the earlier phase's.
struct Reach {
    /// More misses of each kind than this put the bar out of reach (may be negative: out of
    /// reach at the first start).
    spare: [i64; 2],
    /// [`CheckConfig::max_track_time`].
    limit: Option<f64>,
}

impl Reach {
    /// The spare misses of a check judged on `n` episodes, `earlier` of them already run.
    fn new(config: &CheckConfig, n: usize, earlier: &[Start]) -> Self {
        let nf = n as f64;
        // The fewest finishes and walks `judge` accepts on `n` episodes.
        let finishes = (0..=n)
            .find(|&k| k as f64 >= config.finish_share * nf - 1e-9)
            .unwrap_or(n + 1);
        let walks = (0..=n)
            .find(|&k| k as f64 > config.walk_share * nf)
            .unwrap_or(n + 1);
        let mut reach = Self {
            spare: [n as i64 - finishes as i64, n as i64 - walks as i64],
            limit: config.max_track_time,
        };
        for start in earlier {
            let missed = reach.missed(start);
            for (s, hit) in reach.spare.iter_mut().zip(missed) {
                *s -= i64::from(hit);
            }
        }
        reach
    }

    /// Whether `start` missed the line (in time), and whether it is not a walk.
    fn missed(&self, start: &Start) -> [bool; 2] {
        let in_time = start
            .track_time
            .is_some_and(|t| self.limit.is_none_or(|limit| t <= limit));
        [!in_time, start.class != GaitClass::Walk]
    }

    /// The start of `phase` (this phase's starts, in order) after which the bar is out of
    /// reach, if it is: where a check stops.
    fn end(&self, phase: &[Start]) -> Option<usize> {
        let mut misses = [0i64; 2];
        phase.iter().position(|start| {
            for (m, hit) in misses.iter_mut().zip(self.missed(start)) {
                *m += i64::from(hit);
            }
            misses.iter().zip(self.spare).any(|(&m, spare)| m > spare)
        })
    }

    /// Records start `k`'s misses in `seen` (the misses so far of this phase's completed
    /// starts, by kind, sorted) and returns the start at or after which the check surely
    /// ends, once known: for a kind with `spare + 1` misses among the completed starts, the
    /// latest of the first `spare + 1` (the check ends there or, if a start not yet done
    /// misses too, earlier). `first` is the phase's first start.
    fn known_end(
        &self,
        seen: &mut [Vec<usize>; 2],
        first: usize,
        k: usize,
        start: &Start,
    ) -> Option<usize> {
        let missed = self.missed(start);
        let mut end = None::<usize>;
        for ((list, hit), spare) in seen.iter_mut().zip(missed).zip(self.spare) {
            if hit {
                let at = list.partition_point(|&i| i < k);
                list.insert(at, k);
            }
            let need = (spare + 1).max(0) as usize;
            let here = if need == 0 {
                Some(first)
            } else {
                list.get(need - 1).copied()
            };
            if let Some(here) = here {
                end = Some(end.map_or(here, |e| e.min(here)));
            }
        }
        end
    }
}

/// One start of a check, judged.
struct Start {
    class: GaitClass,
    track_time: Option<f64>,
    /// The episode's knee-torque asymmetry (none when it has no gait metrics).
    knee_asymmetry: Option<f64>,
    fell: bool,
    speed: f64,
    distance: f64,
    steps: u64,
}

/// Every step's [`GaitSample`] of a walking episode gathered into a [`GaitTrace`], with the
/// feet's link-origin positions and the model's joint limits: what the gait metrics read.
/// Samples with a non-finite value (a simulation that blew up on its last step; the
/// environment then reports a fall) are left out.
pub struct GaitLog {
    trace: GaitTrace,
    feet: Vec<usize>,
}

impl GaitLog {
    /// An empty log for episodes of `env`.
    pub fn new(env: &WalkEnv) -> Self {
        let mut trace = GaitTrace::new(
            env.actuated_joint_names().to_vec(),
            env.config().foot_links.to_vec(),
        );
        let model = env.model();
        trace.joint_limits = trace
            .actuator_names
            .iter()
            .map(|n| model.joint_index(n).and_then(|j| model.joints()[j].limits))
            .collect();
        // `WalkEnv` refuses foot links the model lacks, so both are found.
        let feet = env
            .config()
            .foot_links
            .iter()
            .filter_map(|n| model.link_index(n))
            .collect();
        Self { trace, feet }
    }

    /// Logs the step just taken (`env` after it). Returns whether a sample was kept.
    pub fn observe(&mut self, env: &WalkEnv, step: &Step) -> bool {
        let Some(g) = &step.info.gait else {
            return false;
        };
        if g.fell {
            self.trace.fell = true;
        }
        let poses = env.link_poses();
        let foot_positions: Vec<[f64; 2]> = self
            .feet
            .iter()
            .map(|&l| poses[l].translation.map(f64::from))
            .map(|p| [p[0], p[1]])
            .collect();
        let feet_finite = foot_positions.iter().flatten().all(|v| v.is_finite());
        if !(finite_sample(g) && feet_finite) {
            return false;
        }
        let f64s = |v: &[f32]| v.iter().map(|&x| f64::from(x)).collect::<Vec<f64>>();
        self.trace.push(&GaitStep {
            time: f64::from(g.time),
            torso_x: f64::from(g.torso_position[0]),
            torso_y: f64::from(g.lateral_offset),
            torso_z_error: f64::from(g.height_error),
            forward_velocity: f64::from(g.forward_velocity),
            torques: &f64s(&g.joint_torque),
            powers: &f64s(&g.joint_abs_power),
            foot_forces: &f64s(&g.foot_force),
            joint_angles: &f64s(&g.joint_angle),
            foot_positions: &foot_positions,
            torso_pitch: Some(pitch_of(g.torso_rotation.map(f64::from))),
        });
        if g.success && self.trace.success_time.is_none() {
            self.trace.success_time = Some(f64::from(g.time));
        }
        true
    }

    /// The trace.
    pub fn finish(self) -> GaitTrace {
        self.trace
    }
}

fn finite_sample(g: &GaitSample) -> bool {
    let scalars = [
        g.time,
        g.forward_velocity,
        g.lateral_offset,
        g.height_error,
        g.torso_position[0],
    ];
    scalars
        .iter()
        .chain(&g.joint_torque)
        .chain(&g.joint_power)
        .chain(&g.foot_force)
        .chain(&g.joint_angle)
        .chain(&g.torso_rotation)
        .all(|v| v.is_finite())
}

/// Gait options for these actuators on a track of `track_length` m: the default knee names
/// if present, else the actuators whose names contain `knee` and `left` / `right`.
pub fn gait_options(actuators: &[String], track_length: f64) -> GaitOptions {
    let mut o = GaitOptions {
        track_length,
        ..GaitOptions::default()
    };
    let find = |side: &str| {
        actuators
            .iter()
            .find(|n| {
                let n = n.to_ascii_lowercase();
                n.contains("knee") && n.contains(side)
            })
            .cloned()
    };
    if !actuators.contains(&o.left_knee) {
        if let Some(n) = find("left") {
            o.left_knee = n;
        }
    }
    if !actuators.contains(&o.right_knee) {
        if let Some(n) = find("right") {
            o.right_knee = n;
        }
    }
    o
}

/// Why a policy was checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Trigger {
    /// Its row's learning-curve value was the highest so far.
    NewBest,
    /// The run passed a multiple of [`CheckConfig::every_steps`].
    Periodic,
    /// Both at once.
    Both,
    /// The policy the run started from (`init`), checked beside the first row: a candidate
    /// for `RUN/best/` only ([`crate::check`] module docs, "The policy a run starts from").
    Start,
}

/// One line of `RUN/checks.jsonl`: which policy was checked, when, why, what the check found
/// and whether `RUN/best/` took it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckRecord {
    /// The row (generation or episode, from 0) whose policy was checked.
    pub row: usize,
    /// Training environment steps by the end of that row.
    pub env_steps: u64,
    /// Training seconds by the end of that row (earlier checks included).
    pub wall_s: f64,
    /// Why it was checked.
    pub trigger: Trigger,
    /// What the check found.
    #[serde(flatten)]
    pub result: CheckResult,
    /// Whether `RUN/best/` took this policy (it ranked above every policy checked before).
    pub kept: bool,
    /// Whether the checked policy is the ES mean θ after the row ([`CheckConfig::mean`]), not
    /// the row's own policy. Absent from `checks.jsonl` when false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub mean: bool,
    /// Seconds the check took.
    pub seconds: f64,
}

/// The checks of a run so far, as its checkpoint keeps them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CheckState {
    /// Lines of `checks.jsonl` (later ones are dropped on resume).
    pub records: usize,
    /// Seconds spent checking.
    pub seconds: f64,
    /// Environment steps the checks simulated (not counted in the run's budget).
    pub env_steps: u64,
    /// The multiple of [`CheckConfig::every_steps`] last checked.
    pub periodic: u64,
    /// The check of the policy `RUN/best/` holds.
    pub kept: Option<CheckRecord>,
    /// The first check that met the walking bar.
    pub first_walk: Option<CheckRecord>,
    /// With [`CheckConfig::max_track_time`], the first check that met the walking bar
    /// without that margin ([`CheckResult::walking`], or the bar itself), whose policy
    /// `RUN/first-walk/` holds. Absent without the margin (then it is `first_walk`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_any_walk: Option<CheckRecord>,
    /// The longest mean distance of a check so far, metres (`[restart]` judges it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best_distance: Option<f64>,
}

impl CheckState {
    /// Figures for `summary.json`: `steps_to_walk`, `time_to_walk_s` and `row_to_walk` (the
    /// first policy at the bar; absent before one), `steps_to_any_walk` and
    /// `time_to_any_walk_s` (the first at the bar without the margin of speed; only with
    /// one), `checks`, `check_s`, `check_env_steps`.
    pub fn figures(&self) -> Vec<(&'static str, Option<f64>)> {
        let first = self.first_walk.as_ref();
        let any = self.first_any_walk.as_ref();
        vec![
            ("steps_to_walk", first.map(|r| r.env_steps as f64)),
            ("time_to_walk_s", first.map(|r| r.wall_s)),
            ("row_to_walk", first.map(|r| r.row as f64)),
            ("steps_to_any_walk", any.map(|r| r.env_steps as f64)),
            ("time_to_any_walk_s", any.map(|r| r.wall_s)),
            ("checks", Some(self.records as f64)),
            ("check_s", Some(self.seconds)),
            ("check_env_steps", Some(self.env_steps as f64)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A start that walks to the line (or not) and falls (or not).
    fn start(finished: bool, fell: bool) -> Start {
        Start {
            class: if fell {
                GaitClass::Fall
            } else {
                GaitClass::Walk
            },
            track_time: finished.then_some(50.0),
            knee_asymmetry: Some(0.05),
            fell,
            speed: 1.0,
            distance: if finished { 50.0 } else { 10.0 },
            steps: 100,
        }
    }

    #[test]
    fn the_bar_is_judged_on_every_episode_of_a_confirmed_check() {
        let config = CheckConfig {
            confirm_starts: 20,
            ..CheckConfig::default()
        };
        // 9 of 10 first starts finish: at the bar.
        let mut episodes: Vec<Start> = (0..10).map(|k| start(k != 3, k == 3)).collect();
        let first = judge(&config, &episodes, 0, false);
        assert!(first.at_bar && first.finished == 9 && first.starts == 10);
        // 15 of 20 fresh ones: 24 of 30 in all, exactly 80 %: still at the bar.
        episodes.extend((0..20).map(|k| start(k >= 5, k < 5)));
        let all = judge(&config, &episodes, 20, false);
        assert_eq!((all.starts, all.confirm_starts, all.finished), (30, 20, 24));
        assert_eq!(all.falls, 6);
        assert!(all.at_bar);
        // One more fall among the fresh ones: 23 of 30 is below 80 %.
        episodes[10 + 5] = start(false, true);
        let below = judge(&config, &episodes, 20, false);
        assert_eq!(below.finished, 23);
        assert!(!below.at_bar);
        // Ranked by shares: the confirmed check at the bar above the one below; and an
        // unconfirmed 9/10 against a confirmed 27/30 is decided by the next key (falls).
        assert!(all.beats(&below) && !below.beats(&all));
        let confirmed = judge(
            &config,
            &(0..30)
                .map(|k| start(k % 10 != 3, false))
                .collect::<Vec<_>>(),
            20,
            false,
        );
        assert_eq!(confirmed.finished, 27);
        assert!(confirmed.beats(&first), "same finish share, fewer falls");
    }

    #[test]
    fn with_a_time_limit_only_starts_that_reach_the_line_in_time_count() {
        // 10 of 10 reach the line: 7 in 45 s, 3 in 55 s.
        let episodes: Vec<Start> = (0..10)
            .map(|k| Start {
                track_time: Some(if k < 7 { 45.0 } else { 55.0 }),
                ..start(true, false)
            })
            .collect();
        let plain = judge(&CheckConfig::default(), &episodes, 0, false);
        assert!(plain.at_bar && plain.finished == 10);
        let limit = |t: f64| CheckConfig {
            max_track_time: Some(t),
            ..CheckConfig::default()
        };
        // Within 50 s: 7 of 10, below 80 %; the count reported stays every finish.
        let slow = judge(&limit(50.0), &episodes, 0, false);
        assert!(!slow.at_bar);
        assert_eq!(slow.finished, 10);
        // Within 55 s (inclusive): all 10.
        assert!(judge(&limit(55.0), &episodes, 0, false).at_bar);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(limit(bad).validate().is_err(), "{bad}");
        }
    }

    #[test]
    fn with_a_symmetry_margin_the_mean_knee_asymmetry_of_every_episode_decides() {
        // 10 walks to the line: 6 even (4 %) and 4 limping (24 %): a mean of 12 %.
        let mut episodes: Vec<Start> = (0..10)
            .map(|k| Start {
                knee_asymmetry: Some(if k < 6 { 0.04 } else { 0.24 }),
                ..start(true, false)
            })
            .collect();
        let plain = judge(&CheckConfig::default(), &episodes, 0, false);
        assert!(plain.at_bar);
        assert_eq!(plain.knee_asymmetry, None, "reported only with the margin");
        let margin = |a: f64| CheckConfig {
            max_knee_asymmetry: Some(a),
            ..CheckConfig::default()
        };
        let limping = judge(&margin(0.10), &episodes, 0, false);
        assert!(!limping.at_bar);
        assert!((limping.knee_asymmetry.unwrap() - 0.12).abs() < 1e-12);
        // The counts and the rank's shares do not see the margin: below the bar, it ranks
        // below the same episodes judged without it, and beside them otherwise.
        assert_eq!(limping.finished, 10);
        assert!(plain.beats(&limping));
        let (l, p) = (limping.score(), plain.score());
        assert_eq!((l.1, l.2, l.3, l.4), (p.1, p.2, p.3, p.4));
        // At most the limit (inclusive): at the bar.
        assert!(judge(&margin(0.12 + 1e-12), &episodes, 0, false).at_bar);
        // Judged on the confirmation's episodes too: 10 more even ones bring the mean to 8 %.
        episodes.extend((0..10).map(|_| Start {
            knee_asymmetry: Some(0.04),
            ..start(true, false)
        }));
        let confirmed = judge(&margin(0.10), &episodes, 10, false);
        assert!(confirmed.at_bar);
        assert!((confirmed.knee_asymmetry.unwrap() - 0.08).abs() < 1e-12);
        // An episode without gait metrics leaves no mean, and no walk at the bar.
        episodes[0].knee_asymmetry = None;
        assert!(!judge(&margin(10.0), &episodes, 10, false).at_bar);
        for bad in [-0.1, f64::NAN, f64::INFINITY] {
            assert!(margin(bad).validate().is_err(), "{bad}");
        }
        assert_eq!(
            margin(0.07).margins().as_deref(),
            Some("the 7 % knee-asymmetry margin")
        );
        let both = CheckConfig {
            max_track_time: Some(40.0),
            ..margin(0.125)
        };
        assert_eq!(
            both.margins().as_deref(),
            Some("the 40 s margin and the 12.5 % knee-asymmetry margin")
        );
        assert!(margin(0.1).has_margin() && !CheckConfig::default().has_margin());
    }

    #[test]
    fn shares_rank_checks_of_equal_size_as_their_counts_did() {
        let config = CheckConfig::default();
        let results: Vec<CheckResult> = (0..=10)
            .flat_map(|finished| {
                (0..=10 - finished).map(move |falls| {
                    (0..10)
                        .map(|k| start(k < finished, k >= finished && k < finished + falls))
                        .collect::<Vec<_>>()
                })
            })
            .map(|e| judge(&config, &e, 0, false))
            .collect();
        for a in &results {
            for b in &results {
                let counts = |r: &CheckResult| {
                    (
                        r.at_bar,
                        r.finished,
                        std::cmp::Reverse(r.falls),
                        r.count(GaitClass::Walk),
                    )
                };
                let by_counts = counts(a)
                    .cmp(&counts(b))
                    .then(a.mean_distance.partial_cmp(&b.mean_distance).unwrap());
                assert_eq!(
                    a.beats(b),
                    by_counts == std::cmp::Ordering::Greater,
                    "{} vs {}",
                    a.describe(),
                    b.describe()
                );
            }
        }
    }

    #[test]
    fn a_check_stops_where_its_misses_put_the_bar_out_of_reach() {
        // The default bar on 10: 8 finishes and 6 walks, so 2 and 4 misses to spare.
        let config = CheckConfig::default();
        let reach = Reach::new(&config, 10, &[]);
        assert_eq!(reach.spare, [2, 4]);
        let finishes =
            |pattern: &[bool]| -> Vec<Start> { pattern.iter().map(|&f| start(f, false)).collect() };
        // The third start that misses the line ends the check.
        let e = finishes(&[
            true, false, true, false, true, true, false, true, true, true,
        ]);
        assert_eq!(reach.end(&e), Some(6));
        assert_eq!(reach.end(&e[..6]), None);
        // Fallen starts are misses of both kinds: the third fall ends it too.
        let falls: Vec<Start> = (0..10).map(|_| start(false, true)).collect();
        assert_eq!(reach.end(&falls), Some(2));
        // `walker`'s bar (all 10 finish, then 19 of 20): the first miss ends the first
        // phase; confirming, after 10 finishes, the second miss.
        let strict = CheckConfig {
            finish_share: 0.95,
            confirm_starts: 10,
            ..CheckConfig::default()
        };
        assert_eq!(Reach::new(&strict, 10, &[]).end(&e), Some(1));
        let first = finishes(&[true; 10]);
        let confirming = Reach::new(&strict, 20, &first);
        assert_eq!(confirming.spare, [1, 9]);
        assert_eq!(confirming.end(&e), Some(3));
        // A bar no count can meet (every episode a walk, more than all of them) ends the
        // check at its first start.
        let never = CheckConfig {
            walk_share: 1.0,
            ..CheckConfig::default()
        };
        assert_eq!(Reach::new(&never, 10, &[]).end(&first), Some(0));
        // A time limit makes a late finish a miss.
        let timed = CheckConfig {
            max_track_time: Some(50.0),
            ..strict
        };
        let late = Start {
            track_time: Some(55.0),
            ..start(true, false)
        };
        assert_eq!(Reach::new(&timed, 10, &[]).end(&[late]), Some(0));
    }

    #[test]
    fn starts_are_skipped_only_past_the_start_that_ends_the_check() {
        // Every pattern of 6 starts (finish or miss) under a bar with 2 misses to spare, each
        // completed in several orders: the start known to end the check, at any moment, is
        // never before the start that does end it, and once every start before that one is
        // done, it is that one.
        let config = CheckConfig {
            starts: 6,
            finish_share: 0.6,
            walk_share: 0.0,
            ..CheckConfig::default()
        };
        let reach = Reach::new(&config, 6, &[]);
        assert_eq!(reach.spare, [2, 5]);
        let orders: [[usize; 6]; 4] = [
            [0, 1, 2, 3, 4, 5],
            [5, 4, 3, 2, 1, 0],
            [3, 0, 5, 1, 4, 2],
            [1, 3, 5, 0, 2, 4],
        ];
        for bits in 0u32..64 {
            let e: Vec<Start> = (0..6).map(|k| start((bits >> k) & 1 == 1, false)).collect();
            let end = reach.end(&e);
            for order in orders {
                let mut seen = [Vec::new(), Vec::new()];
                let mut known = None::<usize>;
                for &k in &order {
                    if let Some(at) = reach.known_end(&mut seen, 0, k, &e[k]) {
                        known = Some(known.map_or(at, |x| x.min(at)));
                    }
                    if let Some(known) = known {
                        let end = end.expect("a known end is an end");
                        assert!(known >= end, "{bits:06b} {order:?}: {known} < {end}");
                    }
                }
                assert_eq!(known, end, "{bits:06b} {order:?}");
            }
        }
    }

    #[test]
    fn confirmation_starts_sit_between_the_first_ones_on_the_clock() {
        let config = CheckConfig {
            starts: 4,
            confirm_starts: 4,
            ..CheckConfig::default()
        };
        let phases: Vec<f32> = (0..8).map(|k| config.phase(k)).collect();
        assert_eq!(
            phases,
            [0.125, 0.375, 0.625, 0.875, 0.0625, 0.3125, 0.5625, 0.8125]
        );
        let off = CheckConfig::default();
        assert_eq!(off.phase(9), 0.95);
    }
}
