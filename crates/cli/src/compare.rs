//! `esrl compare`: trains (or collects) several agents × seeds, evaluates every run and writes
//! the paper's Table 1 with the gait metrics as Markdown and CSV.
//!
//! ```text
//! DIR/
//!   <agent>-s<seed>/   one run folder per agent and seed (see run_dir), plus its eval.json
//!   table.md           Table 1, the per-actuator torque/power table (paper Fig. 5d) and the
//!                      per-joint range of motion / time at a limit
//!   table.csv          Table 1 for machines (mean, SD and count per metric)
//! ```
//!
//! A run folder that already holds a finished run (`summary.json` with `"finished": true`) is
//! reused as it is; an unfinished one with a checkpoint is resumed; one with metrics but no
//! checkpoint (killed before its first checkpoint) is moved aside to `<name>.stale` and
//! retrained — its rows are reproduced exactly, as training is deterministic. A folder
//! trained with a different configuration (other than the thread count) is an error, never
//! silently mixed into the table.
//!
//! Up to `--jobs` runs train at once, each on its own thread with its own rollout pool; the
//! results do not depend on either number. Episodes-to-Target is computed against each
//! agent's own target (80% of the median Best-Win-50 over its seeds), from the `curve` column
//! of each run's `metrics.jsonl`; Q0 is the mean of its `q0` column; the gait columns come
//! from `eval.json` (`mean.gait` of `--eval-episodes` deterministic episodes, seeds 0, 1, …).
//!
//! `--equal-steps` measures the budget: the environment steps actually taken by one finished
//! ES run of the preset (the first hybrid agent listed, seed 0; `es-sac` seed 0, trained as an
//! extra run, when no hybrid agent is listed). That run is trained first, unchanged; every
//! other run gets `max_env_steps` = that budget, and enough generations/episodes to spend it
//! (ES runs stop at the first generation boundary past the budget, plain runs at the first
//! episode end past it). Measuring rather than estimating (generations × population × episode
//! steps) matters because falls end most early episodes: the estimate is an upper bound that
//! ES runs never spend.
//!
//! Ctrl-C stops every training at its next generation/episode boundary with a checkpoint,
//! starts no other run and writes no table; run the same command again to resume them.

use crate::args::{AgentKind, CompareArgs};
use anyhow::{bail, Context, Result};
use esrl_eval::{EvalReport, EVAL_FILE};
use esrl_metrics::{
    actuator_markdown, joint_markdown, q0_mean, summarize_method, table1, table1_csv,
    table1_markdown, AgentRuns, SeedResult,
};
use esrl_run::checkpoint;
use esrl_run::config::config_differences;
use esrl_run::run_dir::write_atomic;
use esrl_run::{RunDir, Summary, TrainConfig};
use serde_json::Value;
use std::collections::VecDeque;
use std::fs;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// The Markdown table file.
pub const TABLE_MD: &str = "table.md";
/// The CSV table file.
pub const TABLE_CSV: &str = "table.csv";

/// Parses `es-sac,sac,…`: every name must be an agent; repeats are dropped.
pub fn parse_agents(list: &str) -> Result<Vec<AgentKind>> {
    let valid = AgentKind::ALL.map(AgentKind::name).join(", ");
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let Some(agent) = AgentKind::parse(name) else {
            bail!("--agents: unknown agent `{name}`; valid agents are {valid}");
        };
        if !out.contains(&agent) {
            out.push(agent);
        }
    }
    if out.is_empty() {
        bail!("--agents `{list}` names no agent; valid agents are {valid}");
    }
    Ok(out)
}

/// One agent × seed of the comparison.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The agent.
    pub agent: AgentKind,
    /// The seed.
    pub seed: u64,
    /// Its run folder, `DIR/<agent>-s<seed>`.
    pub dir: PathBuf,
    /// The configuration it is (or must be) trained with.
    pub config: TrainConfig,
}

impl Plan {
    /// The run's name: its folder's (`<agent>-s<seed>`; a study's `<arm>-s<seed>`).
    pub fn name(&self) -> String {
        self.dir.file_name().map_or_else(
            || run_name(self.agent, self.seed),
            |n| n.to_string_lossy().into_owned(),
        )
    }
}

fn run_name(agent: AgentKind, seed: u64) -> String {
    format!("{}-s{seed}", agent.name())
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
    if checkpoint::find(dir).is_some() {
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

/// Trains the pending plans, up to `jobs` at once. Returns one result per plan, in order.
pub(crate) fn train_all(plans: &[Plan], jobs: usize, progress: bool) -> Vec<Result<()>> {
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
                    ensure_trained(plan, progress, &label)
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

/// What one finished run spent: its length, environment steps and wall time.
#[derive(Debug, Clone, PartialEq)]
pub struct BudgetRow {
    /// `<agent>-s<seed>`.
    pub run: String,
    /// Generations (ES agents) or episodes (plain agents) in its curve.
    pub length: usize,
    /// Whether `length` counts generations.
    pub generations: bool,
    /// Environment steps taken, from `summary.json`.
    pub env_steps: u64,
    /// Training wall time in seconds, from `summary.json` (summed over resumes).
    pub wall_s: f64,
}

fn budget_row(plan: &Plan, length: usize) -> Result<BudgetRow> {
    let summary = Summary::read(&plan.dir)?
        .with_context(|| format!("{}: no summary.json", plan.dir.display()))?;
    Ok(BudgetRow {
        run: plan.name(),
        length,
        generations: plan.agent.is_hybrid(),
        env_steps: summary.env_steps,
        wall_s: summary.wall_s,
    })
}

/// The per-run budget table: how many generations/episodes, environment steps and seconds
/// each run of the comparison took, so that unequal budgets are visible next to Table 1.
pub fn budget_markdown(rows: &[BudgetRow]) -> String {
    let mut out = String::from(
        "| Run | Generations / episodes | Env steps | Wall (s) |\n|---|---:|---:|---:|\n",
    );
    for r in rows {
        let unit = if r.generations {
            "generations"
        } else {
            "episodes"
        };
        out.push_str(&format!(
            "| {} | {} {unit} | {} | {:.0} |\n",
            r.run, r.length, r.env_steps, r.wall_s
        ));
    }
    out.push_str(
        "\nWall times are as measured on the machine that trained each run, with `--jobs` runs \
         sharing it; a reused run keeps the time of its own training.\n",
    );
    out
}

/// The `curve` column of a run's `metrics.jsonl` and its mean Q₀ ([`q0_mean`]).
pub fn read_curve(dir: &Path) -> Result<(Vec<f64>, Option<f64>)> {
    let p = dir.join(RunDir::JSONL);
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    let (mut curve, mut q0) = (Vec::new(), Vec::new());
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let row: Value = serde_json::from_str(line)
            .with_context(|| format!("{} line {}: not JSON", p.display(), i + 1))?;
        let c = row["curve"]
            .as_f64()
            .with_context(|| format!("{} line {}: no numeric `curve`", p.display(), i + 1))?;
        curve.push(c);
        q0.extend(row["q0"].as_f64());
    }
    if curve.is_empty() {
        bail!("{} has no rows", p.display());
    }
    Ok((curve, q0_mean(&q0)))
}

/// What `--eval-best` evaluates of a run: its kept policy `RUN/best/` when the run has one
/// (ES runs), else the run folder (its last checkpoint).
fn evaluated_policy(dir: &Path, best: bool) -> PathBuf {
    let kept = dir.join(checkpoint::BEST);
    if best && kept.join(checkpoint::BEST_INFO).is_file() {
        kept
    } else {
        dir.to_path_buf()
    }
}

/// The `eval.json` of `policy` (a run folder: its current checkpoint; or a run's `best/`) if
/// it covers `episodes` episodes from seed 0 of that policy as it is now and has the
/// gait-cycle metrics; else evaluates and writes it.
fn evaluation(policy: &Path, episodes: usize) -> Result<EvalReport> {
    let p = policy.join(EVAL_FILE);
    let mtime = |p: &Path| fs::metadata(p).and_then(|m| m.modified()).ok();
    if let (Some((_, ckpt)), Ok(text)) = (esrl_eval::locate(policy).ok(), fs::read_to_string(&p)) {
        if let Ok(r) = serde_json::from_str::<EvalReport>(&text) {
            // A checkpoint's state.json, a kept policy's best.json: written with the weights.
            let written = [ckpt.join("state.json"), ckpt.join(checkpoint::BEST_INFO)]
                .into_iter()
                .find(|f| f.is_file());
            let fresh = match (mtime(&p), written.as_deref().and_then(mtime)) {
                (Some(e), Some(c)) => e >= c,
                _ => false,
            };
            // An eval.json written before the gait-cycle metrics existed lacks them.
            let has_cycle = r.mean.gait.as_ref().is_none_or(|g| g.cycle.is_some());
            if fresh
                && has_cycle
                && r.seed == 0
                && r.episodes.len() == episodes
                && Path::new(&r.checkpoint) == ckpt
            {
                return Ok(r);
            }
        }
    }
    let loaded = esrl_eval::load_run(policy)?;
    Ok(esrl_eval::evaluate_and_write(&loaded, 0, episodes, None)?)
}

/// Sets `max_env_steps = budget` and enough generations/episodes to spend it.
fn apply_budget(cfg: &mut TrainConfig, budget: u64) {
    cfg.max_env_steps = Some(budget);
    let b = usize::try_from(budget).unwrap_or(usize::MAX);
    if cfg.agent.is_hybrid() {
        let per_generation = cfg.es.population.max(1);
        cfg.generations = cfg.generations.max(b.div_ceil(per_generation));
    } else {
        cfg.episodes = cfg.episodes.max(b);
    }
}

fn env_steps_of(dir: &Path) -> Result<u64> {
    Summary::read(dir)?
        .map(|s| s.env_steps)
        .with_context(|| format!("{}: no summary.json", dir.display()))
}

/// Runs `esrl compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    let agents = parse_agents(&args.agents)?;
    if args.seeds == 0 {
        bail!("--seeds 0: compare needs at least one seed per agent");
    }
    if args.eval_episodes == 0 {
        bail!("--eval-episodes 0: evaluate at least one episode per run");
    }
    if args.jobs == Some(0) {
        bail!("--jobs 0: run at least one training at a time");
    }
    if args.opts.threads == Some(0) {
        bail!("--threads 0: use at least one thread per run");
    }
    if args.equal_steps && args.opts.steps.is_some() {
        bail!("--equal-steps measures the step budget itself; drop --steps or --equal-steps");
    }
    let out = &args.out;
    fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    // Ctrl-C stops every training at its next boundary with a checkpoint; running the same
    // command again resumes them.
    crate::signals::install();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());

    let mut plans = Vec::new();
    for &agent in &agents {
        for seed in 0..args.seeds {
            let config = TrainConfig::resolve(agent, &args.opts.overrides(), Some(seed))?;
            plans.push(Plan {
                agent,
                seed,
                dir: out.join(run_name(agent, seed)),
                config,
            });
        }
    }

    let mut budget_note = None;
    // The run that set the --equal-steps budget (already reported above).
    let mut budget_run: Option<PathBuf> = None;
    if args.equal_steps {
        let reference_agent = agents
            .iter()
            .copied()
            .find(|a| a.is_hybrid())
            .unwrap_or(AgentKind::EsSac);
        let mut reference = Plan {
            agent: reference_agent,
            seed: 0,
            dir: out.join(run_name(reference_agent, 0)),
            config: TrainConfig::resolve(reference_agent, &args.opts.overrides(), Some(0))?,
        };
        reference.config.threads = args.opts.threads.unwrap_or(cores);
        ensure_trained(&reference, !args.opts.no_progress, "[budget]")
            .with_context(|| "training the ES run that sets the --equal-steps budget")?;
        let budget = env_steps_of(&reference.dir)?;
        budget_run = Some(reference.dir.clone());
        eprintln!(
            "equal steps: every run gets {budget} environment steps, measured on {}",
            reference.dir.display()
        );
        budget_note = Some(format!(
            "Equal environment-step budget: {budget} steps per run, measured as the steps taken \
             by `{}` (one ES run of the preset); runs stop at the first generation/episode \
             boundary past it.",
            reference.name()
        ));
        for p in &mut plans {
            if !(p.agent == reference.agent && p.seed == 0) {
                apply_budget(&mut p.config, budget);
            }
        }
    }

    let mut pending = Vec::new();
    for p in &plans {
        if run_state(&p.dir)? == RunState::Finished {
            check_config(p)?;
            if Some(&p.dir) != budget_run.as_ref() {
                eprintln!("reusing finished run {}", p.dir.display());
            }
        } else {
            pending.push(p.clone());
        }
    }
    let jobs = args
        .jobs
        .unwrap_or_else(|| (cores / args.opts.threads.unwrap_or(1)).max(1))
        .clamp(1, pending.len().max(1));
    let threads = args.opts.threads.unwrap_or((cores / jobs).max(1));
    for p in &mut pending {
        p.config.threads = threads;
    }
    let mut failures: Vec<String> = Vec::new();
    if !pending.is_empty() {
        eprintln!(
            "compare: {} run(s) to train, {jobs} at a time, {threads} rollout thread(s) each",
            pending.len()
        );
        let progress = jobs == 1 && !args.opts.no_progress;
        for (p, r) in pending.iter().zip(train_all(&pending, jobs, progress)) {
            if let Err(e) = r {
                failures.push(format!("{}: {e:#}", p.name()));
            }
        }
    }

    if crate::signals::requested().is_some() {
        bail!(
            "stopped by a signal before every run finished:\n  {}\nthe same command resumes \
             the comparison",
            failures.join("\n  ")
        );
    }

    // Evaluate every finished run and collect its table entries.
    let mut table_agents = Vec::new();
    let mut budgets = Vec::new();
    for &agent in &agents {
        let mut curves = Vec::new();
        let mut extras = Vec::new();
        for p in plans.iter().filter(|p| p.agent == agent) {
            if run_state(&p.dir)? != RunState::Finished {
                continue;
            }
            let collected = read_curve(&p.dir).and_then(|(curve, q0)| {
                let policy = evaluated_policy(&p.dir, args.eval_best);
                let report = evaluation(&policy, args.eval_episodes)
                    .with_context(|| format!("evaluating {}", policy.display()))?;
                Ok((curve, q0, report))
            });
            match collected {
                Ok((curve, q0, report)) => {
                    budgets.push(budget_row(p, curve.len())?);
                    curves.push(curve);
                    extras.push((q0, report.mean.gait));
                }
                Err(e) => failures.push(format!("{}: {e:#}", p.name())),
            }
        }
        if curves.is_empty() {
            continue;
        }
        let summaries = summarize_method(&curves)
            .with_context(|| format!("summarising the curves of {}", agent.name()))?;
        let seeds = summaries
            .into_iter()
            .zip(extras)
            .map(|(summary, (q0_mean, gait))| SeedResult {
                summary,
                gait,
                q0_mean,
            })
            .collect();
        table_agents.push(AgentRuns {
            agent: agent.name().into(),
            seeds,
        });
    }

    if !table_agents.is_empty() {
        let rows = table1(&table_agents).context("building Table 1")?;
        let table = table1_markdown(&rows);
        let actuators = actuator_markdown(&rows);
        let joints = joint_markdown(&rows);
        let has_gait = rows.iter().any(|r| r.gait_runs > 0);
        let has_joints = rows.iter().any(|r| !r.joint_names.is_empty());
        let preset = args.opts.preset.name();
        let mut md = format!(
            "# esrl compare: {} (preset {preset}, seeds 0 to {})\n\n",
            agents
                .iter()
                .map(|a| a.name())
                .collect::<Vec<_>>()
                .join(", "),
            args.seeds - 1
        );
        md.push_str("## Table 1\n\n");
        md.push_str(&table);
        if has_gait {
            md.push_str("\n## Mean |torque| and |power| per actuator\n\n");
            md.push_str(&actuators);
        }
        if has_joints {
            md.push_str(
                "\n## Range of motion (5th–95th percentile) and time within 1° of a limit per \
                 joint\n\n",
            );
            md.push_str(&joints);
        }
        md.push_str(&format!(
            "\nMean ± sample SD across seeds. Episodes-to-Target: first generation/episode whose \
             trailing 50-value mean reaches 80% of the agent's median Best-Win-50. Gait columns: \
             mean of {} deterministic evaluation episode(s) per run (seeds 0, 1, …); a run counts \
             as finishing the track only if every episode did, and as falling if any did. Gait: \
             the evaluation episodes of all seeds per gait class (rules and thresholds: \
             `esrl_metrics::GaitThresholds`); Double Support, Flight: fractions of the time; \
             Alternation: share of successive touchdowns that switch foot; Stride CV: \
             stride-time SD / mean; At Limit: share of the time the actuated joints spend \
             within 1° of a limit.\n",
            args.eval_episodes
        ));
        md.push_str(if args.eval_best {
            "Evaluated policies: each ES run's kept policy (`RUN/best/`, the best individual of \
             training; `RUN/best/eval.json`), each plain run's last policy (`RUN/eval.json`).\n"
        } else {
            "Evaluated policies: each run's last checkpoint (`RUN/eval.json`; for ES runs the \
             last RL actor, not the kept `RUN/best/`).\n"
        });
        if let Some(note) = &budget_note {
            md.push_str(&format!("\n{note}\n"));
        }
        md.push_str("\n## Budget per run\n\n");
        md.push_str(&budget_markdown(&budgets));
        write_atomic(&out.join(TABLE_MD), md.as_bytes())?;
        write_atomic(&out.join(TABLE_CSV), table1_csv(&rows).as_bytes())?;
        print!("{table}");
        if has_gait {
            println!();
            print!("{actuators}");
        }
        eprintln!(
            "wrote {} and {}",
            out.join(TABLE_MD).display(),
            out.join(TABLE_CSV).display()
        );
    }
    if !failures.is_empty() {
        bail!(
            "{} run(s) failed (the table leaves them out):\n  {}",
            failures.len(),
            failures.join("\n  ")
        );
    }
    if table_agents.is_empty() {
        bail!("no finished run to tabulate in {}", out.display());
    }
    Ok(())
}
