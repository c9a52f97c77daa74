//! The runs of a study: what a run folder holds (empty, stale, resumable, finished), bringing
//! each to "finished" (reused, resumed from its checkpoint, or trained; a folder trained with
//! another configuration is an error, never mixed in), and training several at once.
//!
//! A folder with metrics but no checkpoint (killed before its first checkpoint) is moved aside
//! to `<name>.stale` and retrained: its rows are reproduced exactly, as training is
//! deterministic. Up to `jobs` runs train at once, each on its own thread with its own rollout
//! pool; the results depend on neither number. After a stop signal the runs in progress
//! checkpoint and no other starts.

use crate::args::AgentKind;
use anyhow::{bail, Context, Result};
use esrl_run::checkpoint;
use esrl_run::config::config_differences;
use esrl_run::{RunDir, Summary, TrainConfig};
use std::collections::VecDeque;
use std::fs;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// One run of a study: an agent, a seed, its folder and configuration.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The agent.
    pub agent: AgentKind,
    /// The seed.
    pub seed: u64,
    /// Its run folder, `DIR/runs/<arm>-s<seed>`.
    pub dir: PathBuf,
    /// The configuration it is (or must be) trained with.
    pub config: TrainConfig,
}

impl Plan {
    /// The run's name: its folder's (`<arm>-s<seed>`).
    pub fn name(&self) -> String {
        self.dir.file_name().map_or_else(
            || format!("{}-s{}", self.agent.name(), self.seed),
            |n| n.to_string_lossy().into_owned(),
        )
    }
}

/// What a run folder holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunState {
    /// Nothing (or only a config): train from scratch.
    Empty,
    /// Metrics but no checkpoint: moved aside, then trained from scratch.
    Stale,
    /// A checkpoint of an unfinished run: resume.
    Resumable,
    /// `summary.json` says finished: reuse.
    Finished,
}

/// Classifies a run folder.
pub fn run_state(dir: &Path) -> Result<RunState> {
    if Summary::read(dir)?.is_some_and(|s| s.finished) {
        return Ok(RunState::Finished);
    }
    // A run that started over (`[restart]`) resumes its current attempt, from its
    // checkpoint or, killed before the attempt's first one, from the attempt's start.
    if checkpoint::find(dir).is_some() || dir.join(esrl_run::restart::RESTARTS_FILE).exists() {
        return Ok(RunState::Resumable);
    }
    if dir.join(RunDir::JSONL).exists() {
        return Ok(RunState::Stale);
    }
    Ok(RunState::Empty)
}

/// Fails when the run folder's config differs from the plan's.
pub(crate) fn check_config(plan: &Plan) -> Result<()> {
    let (stored, _) = checkpoint::run_config(&plan.dir).with_context(|| {
        format!(
            "{} holds a run whose config cannot be read; move it away or choose another --out",
            plan.dir.display()
        )
    })?;
    let diff = config_differences(&stored, &plan.config)?;
    if !diff.is_empty() {
        bail!(
            "{} was trained with a different configuration ({}; stored vs wanted); choose another \
             --out, pass the same options as before, or delete the folder",
            plan.dir.display(),
            diff.join(", ")
        );
    }
    Ok(())
}

/// Moves a stale run folder aside to `<name>.stale` (or `.stale-2`, …).
fn move_aside(dir: &Path) -> Result<PathBuf> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    let parent = dir.parent().unwrap_or(Path::new("."));
    let mut target = parent.join(format!("{name}.stale"));
    let mut k = 2;
    while target.exists() {
        target = parent.join(format!("{name}.stale-{k}"));
        k += 1;
    }
    fs::rename(dir, &target)
        .with_context(|| format!("moving {} to {}", dir.display(), target.display()))?;
    Ok(target)
}

/// Brings one run to "finished": reuses, resumes or trains it. Returns whether it trained.
pub(crate) fn ensure_trained(plan: &Plan, progress: bool, label: &str) -> Result<bool> {
    let state = run_state(&plan.dir)?;
    if state != RunState::Empty {
        if state == RunState::Stale {
            let moved = move_aside(&plan.dir)?;
            eprintln!(
                "{label} {} has metrics but no checkpoint; moved to {} and retraining",
                plan.dir.display(),
                moved.display()
            );
        } else {
            check_config(plan)?;
        }
    }
    match state {
        RunState::Finished => {
            eprintln!("{label} reusing finished run {}", plan.dir.display());
            return Ok(false);
        }
        RunState::Resumable => eprintln!("{label} resuming {}", plan.dir.display()),
        RunState::Empty | RunState::Stale => {
            eprintln!("{label} training {}", plan.dir.display())
        }
    }
    let started = Instant::now();
    crate::train::train(
        &plan.config,
        &plan.dir,
        state == RunState::Resumable,
        if progress {
            crate::train::Display::Bar
        } else {
            crate::train::Display::Runs
        },
    )
    .with_context(|| format!("training {}", plan.dir.display()))?;
    if crate::signals::requested().is_some() {
        bail!(
            "stopped by a signal; {} has a checkpoint, and the same command resumes it",
            plan.dir.display()
        );
    }
    let Some(summary) = Summary::read(&plan.dir)?.filter(|s| s.finished) else {
        bail!(
            "training {} stopped before its budget was spent",
            plan.dir.display()
        );
    };
    let here = started.elapsed().as_secs_f64();
    if state == RunState::Resumable {
        // The run's own clock (summary.json) counts every command that trained it.
        eprintln!(
            "{label} finished {} in {here:.1} s ({:.1} s of training in all)",
            plan.dir.display(),
            summary.wall_s
        );
    } else {
        eprintln!("{label} finished {} in {here:.1} s", plan.dir.display());
    }
    Ok(true)
}

/// Trains the pending plans, up to `jobs` at once, and calls `then` on each as soon as it
/// has finished (a study writes its record there, so a stopped study keeps the records of
/// the runs it finished). Returns one result per plan, in order.
pub(crate) fn train_all(
    plans: &[Plan],
    jobs: usize,
    progress: bool,
    then: &(dyn Fn(&Plan) -> Result<()> + Sync),
) -> Vec<Result<()>> {
    let queue: Mutex<VecDeque<usize>> = Mutex::new((0..plans.len()).collect());
    let results: Mutex<Vec<Option<Result<()>>>> =
        Mutex::new((0..plans.len()).map(|_| None).collect());
    let total = plans.len();
    std::thread::scope(|s| {
        for _ in 0..jobs.min(plans.len()) {
            s.spawn(|| loop {
                // After a stop signal the runs in progress checkpoint; none starts.
                if crate::signals::requested().is_some() {
                    break;
                }
                let next = queue.lock().map(|mut q| q.pop_front()).unwrap_or(None);
                let Some(i) = next else { break };
                let plan = &plans[i];
                let label = format!("[{}/{total}]", i + 1);
                let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
                    ensure_trained(plan, progress, &label).and_then(|_| then(plan))
                }))
                .unwrap_or_else(|_| Err(anyhow::anyhow!("training {} panicked", plan.name())))
                .map(|_| ());
                if let Err(e) = &r {
                    eprintln!("{label} {} failed: {e:#}", plan.name());
                }
                if let Ok(mut all) = results.lock() {
                    all[i] = Some(r);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| {
            r.unwrap_or_else(|| {
                Err(anyhow::anyhow!(
                    "not started (stopped by a signal); the same command trains it"
                ))
            })
        })
        .collect()
}
