//! A training session: a [`Learner`] driven row by row into its run folder. Each
//! [`Training::step`] runs one row and writes what it produced — the metrics row, the best
//! policy, the summary, a checkpoint every `checkpoint_every` rows — and
//! [`Training::finish`] writes the last checkpoint. Whoever drives it (the `esrl` binary)
//! decides when to stop and what to print.

use crate::check::{CheckRecord, CheckState, Checker, Trigger};
use crate::checkpoint::{self, BestInfo, RunState, FIRST_WALK};
use crate::config::{EnvKind, TrainConfig};
use crate::error::{Context, Error, Result};
use crate::restart::{self, Restart};
use crate::run_dir::{append_jsonl, truncate_jsonl, write_atomic, RunDir};
use crate::summary::Summary;
use esrl_agents::{Agent, AgentError, Learner, Row};
use esrl_metrics::CurveSummary;
use esrl_sim::MakeEnv;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// How a session found its run folder.
#[derive(Debug, Clone, PartialEq)]
pub enum Opening {
    /// A new run in a new folder.
    New,
    /// Continued from a checkpoint.
    Resumed {
        /// The checkpoint folder.
        checkpoint: PathBuf,
        /// Rows it covers.
        rows: usize,
        /// Environment steps it had taken.
        env_steps: u64,
    },
    /// A run stopped before its first checkpoint, started over in its own folder.
    StartedOver,
}

/// What one row did, for whoever prints progress.
#[derive(Debug, Clone, PartialEq)]
pub struct RowDone {
    /// Rows done, this one included.
    pub rows: usize,
    /// Its learning-curve value.
    pub curve: f64,
    /// The best curve value so far, this row included.
    pub best: f64,
    /// Its one-line description.
    pub summary: String,
    /// The walking checks that finished while this row ran: of the policy of the row before,
    /// when that one was due a check (and of the ES mean after it, with `check.mean`).
    pub checks: Vec<CheckRecord>,
    /// The attempt abandoned before this row, when `[restart]` started the run over
    /// ([`crate::Session::step`]; a [`Training`] alone leaves it `None`).
    pub restarted: Option<Restart>,
    /// The time the session has left, on the row that first gives a pace
    /// ([`crate::Session::step`]; a [`Training`] alone leaves it `None`).
    pub estimate: Option<crate::pace::Estimate>,
}

/// A learner and the run folder it trains into.
pub struct Training<L: Learner> {
    cfg: TrainConfig,
    root: PathBuf,
    learner: L,
    envs: Arc<MakeEnv>,
    run: RunDir,
    state: RunState,
    /// The threads the learner computes on (`cfg.threads`).
    pool: rayon::ThreadPool,
    started: Instant,
    /// Training seconds before this session (resumed runs).
    wall0: f64,
    /// The walking check, for runs with a `[check]` on the walking task.
    checker: Option<Checker>,
    /// `RUN/.lock`, held while the session lives: one process trains a run folder at a time.
    _lock: std::fs::File,
    /// The check due after the last row, run beside the next one.
    due: Option<Due>,
    /// Which attempt of the run this is (`[restart]`).
    attempt: Attempt,
}

/// Which attempt of a run a [`Training`] trains (module [`crate::restart`]): its seed and the
/// attempts abandoned before it.
#[derive(Debug, Clone, PartialEq)]
pub struct Attempt {
    /// The seed the learner and the checks were built from.
    pub seed: u64,
    /// The abandoned attempts, oldest first.
    pub earlier: Vec<Restart>,
}

impl Attempt {
    /// The run's first attempt, of its own seed.
    pub fn first(seed: u64) -> Self {
        Self {
            seed,
            earlier: Vec::new(),
        }
    }

    /// The attempt after `earlier` of a run of `seed` ([`restart::attempt_seed`]).
    pub fn after(seed: u64, earlier: Vec<Restart>) -> Result<Self> {
        Ok(Self {
            seed: restart::attempt_seed(seed, earlier.len())?,
            earlier,
        })
    }

    /// Environment steps and seconds of the abandoned attempts.
    pub fn spent(&self) -> (u64, f64) {
        self.earlier
            .iter()
            .fold((0, 0.0), |(s, w), r| (s + r.env_steps, w + r.wall_s))
    }
}

/// The policies due a walking check, and the row they come from.
struct Due {
    /// Checked in order: with `check.mean` the ES mean θ after the row, then the row's own
    /// policy ([`crate::check`] module docs, "Checking the ES mean").
    candidates: Vec<Candidate>,
    row: usize,
    env_steps: u64,
    curve: f64,
    trigger: Trigger,
    /// Whether the check may stop once the bar is out of reach (nothing reads its full
    /// distance any more: [`Training::restart_settled`]).
    may_stop: bool,
    /// The check of the policy `RUN/best/` holds when this one was due (the same when it
    /// runs: checks are recorded in order). A check that stops but ranks above it runs in
    /// full ([`crate::check`] module docs, "Stopping early").
    kept: Option<crate::check::CheckResult>,
    /// Whether the run still seeks its first walk without the margin of speed
    /// ([`crate::check::Checker::check_seeking`]).
    seeking: bool,
}

/// One policy of a [`Due`].
struct Candidate {
    agent: esrl_agents::Agent,
    /// Whether it is the ES mean θ ([`crate::check::CheckConfig::mean`]).
    mean: bool,
}

/// A check done.
struct Checked {
    candidate: Candidate,
    result: crate::check::CheckResult,
    seconds: f64,
}

/// Runs the checks of `due`'s candidates in order (on the calling rayon pool), each told the
/// kept policy as the ones before it leave it; returns `due` without its candidates and the
/// checks.
fn run_checks(checker: Option<&Checker>, mut due: Due) -> Result<(Due, Vec<Checked>)> {
    let checker = checker.ok_or_else(|| Error::Msg("a check is due without a checker".into()))?;
    let (mut kept, mut seeking) = (due.kept.clone(), due.seeking);
    let mut done = Vec::new();
    for candidate in std::mem::take(&mut due.candidates) {
        let t = Instant::now();
        let result =
            checker.check_seeking(&candidate.agent, due.may_stop, kept.as_ref(), seeking)?;
        if kept.as_ref().is_none_or(|k| result.beats(k)) {
            kept = Some(result.clone());
        }
        seeking &= !(result.walking.unwrap_or(false) || result.at_bar);
        done.push(Checked {
            candidate,
            result,
            seconds: t.elapsed().as_secs_f64(),
        });
    }
    Ok((due, done))
}

/// The lock file of a run folder ([`lock_run`]).
pub const LOCK_FILE: &str = ".lock";

/// Creates `root` if needed and takes its lock (`RUN/.lock`, an advisory lock the operating
/// system drops when the process ends, however it ends), refusing a folder another process
/// is training.
pub fn lock_run(root: &Path) -> Result<std::fs::File> {
    std::fs::create_dir_all(root).with_context(|| format!("creating {}", root.display()))?;
    let p = root.join(LOCK_FILE);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&p)
        .with_context(|| format!("opening {}", p.display()))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(Error::Msg(format!(
            "{} is being trained by another process (it holds {}); wait for it to end, or \
             stop it first",
            root.display(),
            p.display()
        ))),
        Err(std::fs::TryLockError::Error(e)) => {
            Err(Error::from(e)).with_context(|| format!("locking {}", p.display()))
        }
    }
}

/// Whether a process trains the run in `root` now: whether another open file holds its lock
/// ([`lock_run`]). Asking takes the lock for an instant (shared, so a second asker does not
/// see a training) and releases it; a folder without a lock file was never trained.
pub fn is_training(root: &Path) -> bool {
    let Ok(file) = std::fs::File::open(root.join(LOCK_FILE)) else {
        return false;
    };
    match file.try_lock_shared() {
        Ok(()) => false,
        Err(std::fs::TryLockError::WouldBlock) => true,
        Err(std::fs::TryLockError::Error(_)) => false,
    }
}

/// The file of a run's walking checks, one [`CheckRecord`] per line.
pub const CHECKS_FILE: &str = "checks.jsonl";

impl<L: Learner> Training<L> {
    /// Opens `root` for `learner`, built fresh from `cfg`: a new folder, or, when `resume`,
    /// the run continued from its newest checkpoint — checked against its manifest, the
    /// configuration and the metric logs before anything is truncated — or started over
    /// when it stopped before its first checkpoint. Then runs the learner's preparation
    /// (the hybrid loop's warm start) with environments from `envs`.
    pub fn open(
        cfg: &TrainConfig,
        root: &Path,
        learner: L,
        envs: Arc<MakeEnv>,
        resume: bool,
    ) -> Result<(Self, Opening)> {
        Self::open_attempt(cfg, root, learner, envs, resume, Attempt::first(cfg.seed))
    }

    /// [`Training::open`] for `attempt` of the run, its `learner` built from the attempt's
    /// seed ([`crate::Session`] does this for runs with `[restart]`).
    pub fn open_attempt(
        cfg: &TrainConfig,
        root: &Path,
        mut learner: L,
        envs: Arc<MakeEnv>,
        resume: bool,
        mut attempt: Attempt,
    ) -> Result<(Self, Opening)> {
        let pool = crate::build::pool(cfg.threads)?;
        let lock = lock_run(root)?;
        if resume {
            // A restart killed before its files were moved is finished now, under the lock.
            let written = restart::read(root)?;
            if written.len() != attempt.earlier.len() {
                crate::bail!(
                    "{} started over {} time(s) ({}); this training was built for attempt {}. \
                     Resume it with `esrl train --resume`, which builds the attempt's learner",
                    root.display(),
                    written.len(),
                    restart::RESTARTS_FILE,
                    attempt.earlier.len()
                );
            }
            restart::settle(root, &mut attempt.earlier)?;
        }
        let mut state = RunState::fresh();
        let (run, opening) = match (resume, checkpoint::find(root)) {
            (true, Some(dir)) => {
                let (run_state, learner_state) = checkpoint::load_state::<L::LoopState>(&dir)?;
                checkpoint::check_config(&dir, &run_state, cfg)?;
                checkpoint::check_state(root, &dir, &learner, &run_state, &learner_state)?;
                let env_steps = learner_state.env_steps;
                checkpoint::restore(&dir, &mut learner, &run_state, learner_state)?;
                state = run_state;
                let run = RunDir::resume(root, state.rows)?;
                let opening = Opening::Resumed {
                    checkpoint: dir,
                    rows: state.rows,
                    env_steps,
                };
                (run, opening)
            }
            (true, None) => {
                // Killed before its first checkpoint: nothing to lose but the rows of an
                // unfinished first stretch, so the run starts over in its own folder.
                checkpoint::remove_best(root)?;
                let run = RunDir::resume(root, 0)?;
                write_atomic(&root.join(RunDir::CONFIG), cfg.to_toml()?.as_bytes())?;
                (run, Opening::StartedOver)
            }
            (false, _) => (RunDir::create(root, &cfg.to_toml()?)?, Opening::New),
        };
        let checker = Self::checker(cfg, attempt.seed)?;
        if checker.is_some() {
            let state = state.check.get_or_insert_with(CheckState::default);
            truncate_jsonl(&root.join(CHECKS_FILE), state.records)?;
        }
        let started = Instant::now();
        let start = Self::start_policy(cfg, &state, checker.as_ref(), &learner);
        learner.prepare(envs.as_ref())?;
        let wall0 = state.wall_s;
        let mut training = Self {
            cfg: cfg.clone(),
            root: root.to_path_buf(),
            learner,
            envs,
            run,
            state,
            pool,
            started,
            wall0,
            checker,
            _lock: lock,
            due: None,
            attempt,
        };
        training.due = start.map(|agent| training.start_due(agent));
        Ok((training, opening))
    }

    /// The policy a fresh run started from (`init`) with a walking check: checked beside the
    /// first row ([`crate::check`] module docs, "The policy a run starts from").
    fn start_policy(
        cfg: &TrainConfig,
        state: &RunState,
        checker: Option<&Checker>,
        learner: &L,
    ) -> Option<Agent> {
        (cfg.init.is_some() && checker.is_some() && state.rows == 0)
            .then(|| learner.agent().clone())
    }

    /// The check of the start policy `agent`, due beside the first row.
    fn start_due(&self, agent: Agent) -> Due {
        Due {
            candidates: vec![Candidate { agent, mean: false }],
            row: 0,
            env_steps: 0,
            curve: 0.0,
            trigger: Trigger::Start,
            may_stop: self.restart_settled(),
            kept: None,
            seeking: false,
        }
    }

    /// The walking check of `cfg`, its starts drawn from `seed`, for runs that check.
    fn checker(cfg: &TrainConfig, seed: u64) -> Result<Option<Checker>> {
        Ok(match (&cfg.check, cfg.env) {
            (Some(check), EnvKind::Walk) => Some(Checker::new(
                check.clone(),
                crate::build::load_model(&cfg.walk)?,
                cfg.walk.clone(),
                seed,
            )),
            _ => None,
        })
    }

    /// The run folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Which attempt of the run this is.
    pub fn attempt(&self) -> &Attempt {
        &self.attempt
    }

    /// The longest mean distance of this attempt's checks so far, metres.
    pub fn best_distance(&self) -> Option<f64> {
        self.state.check.as_ref()?.best_distance
    }

    /// Whether `[restart]` abandons this attempt before the next row ([`restart`] module
    /// docs). The check still due of the last row is run first, so the rule sees every
    /// check of the rows done, as a resumed run's does.
    pub fn restart_due(&mut self) -> Result<bool> {
        let Some(rule) = self.cfg.restart.clone() else {
            return Ok(false);
        };
        let due = |t: &Self| {
            rule.due(
                t.learner.env_steps(),
                t.attempt.earlier.len(),
                t.first_walk().is_some(),
                t.best_distance(),
            )
        };
        if !due(self) {
            return Ok(false);
        }
        self.flush_check()?;
        Ok(due(self))
    }

    /// Abandons this attempt: writes its summary, records it in `RUN/restarts.json` and moves
    /// its files into `RUN/restarts/seed-S/` ([`restart::abandon`]). Returns its record and
    /// the next attempt, which [`Training::start_over`] trains.
    pub fn abandon(&mut self) -> Result<(Restart, Attempt)> {
        self.flush_check()?;
        self.write_summary(false)?;
        let record = Restart {
            seed: self.attempt.seed,
            env_steps: self.learner.env_steps(),
            wall_s: self.wall_s(),
            rows: self.state.rows,
            checks: self.state.check.as_ref().map_or(0, |c| c.records),
            best_distance: self.best_distance(),
            folder: Restart::folder_of(self.attempt.seed),
            settled: false,
        };
        let mut earlier = self.attempt.earlier.clone();
        restart::abandon(&self.root, &mut earlier, record)?;
        let record = earlier
            .last()
            .cloned()
            .expect("abandon recorded the attempt");
        Ok((record, Attempt::after(self.cfg.seed, earlier)?))
    }

    /// Starts the run over in its folder with `learner` (built from `attempt`'s seed) after
    /// [`Training::abandon`]: a fresh run state, logs and checks, the same lock and threads.
    pub fn start_over(&mut self, learner: L, attempt: Attempt) -> Result<()> {
        self.due = None;
        checkpoint::remove_best(&self.root)?;
        self.run = RunDir::resume(&self.root, 0)?;
        self.state = RunState::fresh();
        self.checker = Self::checker(&self.cfg, attempt.seed)?;
        if self.checker.is_some() {
            self.state.check = Some(CheckState::default());
            truncate_jsonl(&self.root.join(CHECKS_FILE), 0)?;
        }
        let start = Self::start_policy(&self.cfg, &self.state, self.checker.as_ref(), &learner);
        self.learner = learner;
        self.attempt = attempt;
        self.started = Instant::now();
        self.wall0 = 0.0;
        self.learner.prepare(self.envs.as_ref())?;
        self.due = start.map(|agent| self.start_due(agent));
        Ok(())
    }

    /// The learner.
    pub fn learner(&self) -> &L {
        &self.learner
    }

    /// Rows done (resumed ones included).
    pub fn rows(&self) -> usize {
        self.state.rows
    }

    /// The rows the budget asks for: generations (hybrid) or episodes (plain).
    pub fn total(&self) -> usize {
        if self.cfg.agent.is_hybrid() {
            self.cfg.generations
        } else {
            self.cfg.episodes
        }
    }

    /// Training seconds so far, earlier sessions included.
    pub fn wall_s(&self) -> f64 {
        self.wall0 + self.started.elapsed().as_secs_f64()
    }

    /// Whether the budget is spent: every row done, the environment-step budget reached, or,
    /// with `stop_at_walk`, a policy at the walking bar found.
    pub fn done(&self) -> bool {
        self.state.rows >= self.total() || self.budget_left() == Some(0) || self.walked_and_stops()
    }

    /// Environment steps counted against `max_env_steps`: this attempt's, and with
    /// `restart.whole_budget` those of the attempts abandoned before it too.
    pub fn budget_steps(&self) -> u64 {
        let abandoned = match &self.cfg.restart {
            Some(rule) if rule.whole_budget => self.attempt.spent().0,
            _ => 0,
        };
        self.learner.env_steps() + abandoned
    }

    /// Environment steps `max_env_steps` still allows (`None`: no such budget).
    pub fn budget_left(&self) -> Option<u64> {
        let spent = self.budget_steps();
        self.cfg.max_env_steps.map(|b| b.saturating_sub(spent))
    }

    /// Whether the run stops because a policy met the walking bar (`stop_at_walk`).
    pub fn walked_and_stops(&self) -> bool {
        self.cfg.stop_at_walk && self.first_walk().is_some()
    }

    /// The first check that met the walking bar, if any.
    pub fn first_walk(&self) -> Option<&CheckRecord> {
        self.state.check.as_ref()?.first_walk.as_ref()
    }

    /// With a margin of speed or symmetry (`check.max_track_time`,
    /// `check.max_knee_asymmetry`), the first check that met the walking bar without the
    /// margins (its policy in `RUN/first-walk/`), if any.
    pub fn first_any_walk(&self) -> Option<&CheckRecord> {
        self.state.check.as_ref()?.first_any_walk.as_ref()
    }

    /// The walking check of the policy `RUN/best/` holds, if the run checks its policies.
    pub fn kept_check(&self) -> Option<&CheckRecord> {
        self.state.check.as_ref()?.kept.as_ref()
    }

    /// Runs one row and writes it: the metrics row (with `wall_s`), `RUN/best/` when the row
    /// beat every earlier one, a copy of it for each multiple of `best_every_steps` the row's
    /// steps passed, the summary, and a checkpoint when one is due. A learner that
    /// diverges (a non-finite loss or return) ends the session with an error that keeps the
    /// last good checkpoint.
    pub fn step(&mut self) -> Result<RowDone> {
        let steps_before = self.learner.env_steps();
        // The check due after the last row runs beside this one (module docs of `check`).
        let due = self.due.take();
        let (learner, envs, checker) = (&mut self.learner, self.envs.as_ref(), &self.checker);
        let (row, checked) = self.pool.install(|| {
            rayon::join(
                || learner.run_row(envs),
                || due.map(|d| run_checks(checker.as_ref(), d)),
            )
        });
        let checks = match checked {
            Some(c) => self.record_checks(c?)?,
            None => Vec::new(),
        };
        let row = match row {
            Ok(row) if !row.curve().is_finite() => Err(AgentError::NonFinite {
                what: "return",
                update: self.learner.agent().updates(),
            }),
            other => other,
        };
        let row = row.map_err(|e| {
            Error::Msg(format!(
                "training stopped at row {}: {e}. The last good checkpoint in {} is kept; \
                 lower the learning rates or the gradient clip and resume or restart.",
                self.state.rows,
                self.root.join(RunDir::CHECKPOINT).display()
            ))
        })?;
        let curve = row.curve();
        let mut value = serde_json::to_value(&row)?;
        if let Some(m) = value.as_object_mut() {
            m.insert("wall_s".into(), serde_json::json!(self.wall_s()));
        }
        self.run.append(&value)?;
        let previous_best = self.best();
        match &self.checker {
            Some(_) => self.due = self.check_due(curve > previous_best, curve)?,
            None => {
                if curve > previous_best {
                    if let Some(agent) = self.learner.scored_agent()? {
                        let info = BestInfo {
                            generation: self.learner.rows() - 1,
                            fitness: curve,
                            env_steps: self.learner.env_steps(),
                            mean: false,
                            start: false,
                            check: None,
                        };
                        checkpoint::save_best(&self.root, &self.cfg, &agent, &info)?;
                    }
                }
            }
        }
        if let Some(every) = self.cfg.best_every_steps {
            // Each multiple of `every` this row's steps reached: `best/` as it stands now.
            let steps = self.learner.env_steps();
            for k in steps_before / every + 1..=steps / every {
                checkpoint::snapshot_best(&self.root, k * every)?;
            }
        }
        self.state.rows += 1;
        self.state.curve.push(curve);
        self.state.q0.push(row.q0());
        self.write_summary(false)?;
        if self.state.rows.is_multiple_of(self.cfg.checkpoint_every) {
            self.checkpoint()?;
        }
        Ok(RowDone {
            rows: self.state.rows,
            curve,
            best: previous_best.max(curve),
            summary: row.summary(),
            checks,
            estimate: None,
            restarted: None,
        })
    }

    /// Whether the row just run is due a walking check (module docs of [`crate::check`]):
    /// it set a new best curve value (`new_best`) or passed a multiple of `every_steps`. Then
    /// its policy — the one that scored its curve value, or the agent itself — is taken to be
    /// checked beside the next row.
    fn check_due(&mut self, new_best: bool, curve: f64) -> Result<Option<Due>> {
        let Some(checker) = &self.checker else {
            return Ok(None);
        };
        let cfg = checker.config();
        let steps = self.learner.env_steps();
        let state = self.state.check.get_or_insert_with(CheckState::default);
        let periodic = steps / cfg.every_steps > state.periodic;
        let new_best = new_best && cfg.new_best;
        let trigger = match (new_best, periodic) {
            (true, true) => Trigger::Both,
            (true, false) => Trigger::NewBest,
            (false, true) => Trigger::Periodic,
            (false, false) => return Ok(None),
        };
        if periodic {
            state.periodic = steps / cfg.every_steps;
        }
        let agent = match self.learner.scored_agent()? {
            Some(agent) => agent,
            None => self.learner.agent().clone(),
        };
        let mut candidates = Vec::new();
        if cfg.mean {
            if let Some(agent) = self.learner.mean_agent()? {
                candidates.push(Candidate { agent, mean: true });
            }
        }
        candidates.push(Candidate { agent, mean: false });
        Ok(Some(Due {
            candidates,
            row: self.learner.rows() - 1,
            env_steps: steps,
            curve,
            trigger,
            may_stop: self.restart_settled(),
            kept: self.kept_check().map(|k| k.result.clone()),
            seeking: cfg.has_margin()
                && self
                    .state
                    .check
                    .as_ref()
                    .is_none_or(|c| c.first_any_walk.is_none()),
        }))
    }

    /// Whether `[restart]` can no longer start this attempt over, whatever later checks
    /// find: there is no rule, the attempt is the last it allows, or it has walked or has a
    /// check past the rule's distance (both stay true). Until then a check runs every start,
    /// since the rule reads its mean distance ([`crate::check`] module docs, "Stopping
    /// early").
    fn restart_settled(&self) -> bool {
        let Some(rule) = &self.cfg.restart else {
            return true;
        };
        self.attempt.earlier.len() >= rule.max
            || self.first_walk().is_some()
            || self.best_distance().is_some_and(|d| d >= rule.min_distance)
    }

    /// Logs the finished checks of `due` in order ([`Training::record_check`]).
    fn record_checks(&mut self, (due, checks): (Due, Vec<Checked>)) -> Result<Vec<CheckRecord>> {
        checks
            .into_iter()
            .map(|c| self.record_check(&due, c))
            .collect()
    }

    /// Logs a finished check to `checks.jsonl` and keeps its policy in `RUN/best/` if it
    /// ranks above the policy there.
    fn record_check(&mut self, due: &Due, checked: Checked) -> Result<CheckRecord> {
        let Checked {
            candidate,
            result,
            seconds,
        } = checked;
        let wall_s = self.wall_s();
        // The policy the run started from competes for `RUN/best/` only (module docs of
        // `check`, "The policy a run starts from").
        let start = due.trigger == Trigger::Start;
        let state = self.state.check.get_or_insert_with(CheckState::default);
        let kept = state.kept.as_ref().is_none_or(|k| result.beats(&k.result));
        state.seconds += seconds;
        state.env_steps += result.check_steps;
        if !start {
            let d = result.mean_distance;
            state.best_distance = Some(state.best_distance.map_or(d, |b| b.max(d)));
        }
        let record = CheckRecord {
            row: due.row,
            env_steps: due.env_steps,
            wall_s,
            trigger: due.trigger,
            result,
            kept,
            mean: candidate.mean,
            seconds,
        };
        let info = || BestInfo {
            generation: record.row,
            fitness: due.curve,
            env_steps: due.env_steps,
            mean: candidate.mean,
            start,
            check: Some(record.result.clone()),
        };
        if kept {
            checkpoint::save_best(&self.root, &self.cfg, &candidate.agent, &info())?;
            state.kept = Some(record.clone());
        }
        if record.result.at_bar && state.first_walk.is_none() && !start {
            state.first_walk = Some(record.clone());
        }
        let walking = record.result.walking.unwrap_or(false) || record.result.at_bar;
        if due.seeking && walking && state.first_any_walk.is_none() {
            checkpoint::save_policy(&self.root, FIRST_WALK, &self.cfg, &candidate.agent, &info())?;
            state.first_any_walk = Some(record.clone());
        }
        append_jsonl(&self.root.join(CHECKS_FILE), &record)?;
        state.records += 1;
        Ok(record)
    }

    /// Writes the last checkpoint and the summary, `finished` saying whether the budget was
    /// completed.
    pub fn finish(&mut self, finished: bool) -> Result<()> {
        self.checkpoint()?;
        self.write_summary(finished)
    }

    /// The best curve value so far (−∞ before the first row).
    fn best(&self) -> f64 {
        self.state
            .curve
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Runs the check still due, if any, now: a checkpoint covers every check of its rows.
    fn flush_check(&mut self) -> Result<Vec<CheckRecord>> {
        let Some(due) = self.due.take() else {
            return Ok(Vec::new());
        };
        let checker = &self.checker;
        let checked = self.pool.install(|| run_checks(checker.as_ref(), due))?;
        self.record_checks(checked)
    }

    fn checkpoint(&mut self) -> Result<()> {
        self.flush_check()?;
        self.state.wall_s = self.wall_s();
        checkpoint::save(&self.root, &self.cfg, &self.learner, &mut self.state)
            .with_context(|| format!("writing a checkpoint of {}", self.root.display()))
    }

    fn write_summary(&self, finished: bool) -> Result<()> {
        if self.state.curve.is_empty() {
            return Ok(());
        }
        let mut learner = Map::new();
        let checks = self.state.check.as_ref().map(CheckState::figures);
        for (name, value) in self
            .learner
            .summary_figures()
            .into_iter()
            .chain(checks.into_iter().flatten())
        {
            if let Some(v) = value {
                learner.insert(name.into(), Value::from(v));
            }
        }
        if self.cfg.restart.is_some() {
            // The walk's cost counts the abandoned attempts ([`restart`] module docs).
            let (steps, wall) = self.attempt.spent();
            let added = [
                ("steps_to_walk", steps as f64),
                ("time_to_walk_s", wall),
                ("steps_to_any_walk", steps as f64),
                ("time_to_any_walk_s", wall),
            ];
            for (name, add) in added {
                if let Some(v) = learner.get_mut(name) {
                    *v = Value::from(v.as_f64().unwrap_or(f64::NAN) + add);
                }
            }
            learner.insert("attempt_seed".into(), Value::from(self.attempt.seed));
            learner.insert("restarts".into(), Value::from(self.attempt.earlier.len()));
            learner.insert("restart_env_steps".into(), Value::from(steps));
            learner.insert("restart_wall_s".into(), Value::from(wall));
        }
        let summary = Summary {
            agent: self.cfg.agent.name().into(),
            env: self.cfg.env,
            seed: self.cfg.seed,
            curve: CurveSummary::from_curve(&self.state.curve, None)?,
            q0_mean: esrl_metrics::q0_mean(&self.state.q0),
            length: self.state.curve.len(),
            env_steps: self.learner.env_steps(),
            best: self.best(),
            wall_s: self.wall_s(),
            finished,
            learner,
        };
        self.run.write_summary(&summary)
    }
}
