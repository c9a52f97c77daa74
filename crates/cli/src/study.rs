//! `esrl study`: one TOML file describes an experiment — arms (an agent and its settings),
//! seeds, budget, which policy each run hands over and how it is evaluated — and the
//! command runs it, resumably and shardable, and reports it with interval estimates.
//!
//! ```toml
//! description = "the default command over ten seeds"
//! seeds = 10                      # 0, 1, …, 9; or a list: seeds = [3, 4]
//!
//! [eval]                          # the handed-over policy of every run
//! episodes = 20                   # deterministic episodes, reset seeds 1000, 1001, …
//! seed = 1000
//! policy = "kept"                 # RUN/best/ (the walking check's choice); "last": the checkpoint
//!
//! [[arm]]
//! name = "default"
//! agent = "es-sac"                # preset "walking" unless `preset` says otherwise
//!
//! [[arm]]
//! name = "mirror"
//! agent = "es-sac"
//! config = "overlays/mirror.toml" # a file laid over the preset (relative to this file)
//! set = { rl = { mirror = true } } # or keys inline
//! steps = 2000000                 # budget: steps, generations, episodes
//! ```
//!
//! ```text
//! DIR/
//!   study.toml              the study file as run (a folder holds one study)
//!   runs/<arm>-s<seed>/     the run folders (esrl train's; resumable, exact)
//!   records/<arm>-s<seed>/  what a run leaves for the report, small enough to commit:
//!                           config.toml, metrics.csv, summary.json, checks.jsonl, eval.json
//!                           (its handed-over policy from the study's starts) and policy/
//!                           (actor.safetensors, config.toml, best.json: `esrl eval` takes it)
//!   report.md, .csv, .json  `esrl study report DIR` (the figures: `python -m
//!                           esrl_rs.report --study DIR`)
//! ```
//!
//! `esrl study run` trains every run that is not finished (resuming interrupted ones from
//! their checkpoint; `--jobs N` at a time), evaluates its handed-over policy and writes its
//! record; finished runs and written records are reused, so the same command continues a
//! stopped study and gives the records an uninterrupted one would. `--shard i/n` takes the
//! runs whose index (arms in order, seeds within) is i modulo n: n machines each run one
//! shard into their own `DIR`, and the records folders merge by copying. The report reads
//! records only.

use crate::args::{AgentKind, Preset, StudyArgs, StudyCommand};
use crate::runs::{check_config, run_state, train_all, Plan, RunState};
use anyhow::{bail, Context, Result};
use esrl_eval::{evaluate_with, load_run_pick, EvalOptions, EvalReport, Pick};
use esrl_metrics::{
    actuator_markdown, gait_classes_text, iqm_interval, joint_markdown,
    probability_of_improvement_interval, summarize_method, table1, table1_markdown, wilson,
    AgentRuns, GaitClass, Interval, SeedResult, Z95,
};
use esrl_run::checkpoint::{BEST, BEST_INFO};
use esrl_run::run_dir::{write_atomic, write_json_atomic};
use esrl_run::{Overrides, RunDir, Summary, TrainConfig};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The study file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// What the study asks, for the report's heading.
    #[serde(default)]
    pub description: String,
    /// Seeds: a count n (0, 1, …, n − 1) or a list.
    pub seeds: Seeds,
    /// How each run's handed-over policy is evaluated.
    #[serde(default)]
    pub eval: StudyEval,
    /// The arms, in the report's order.
    #[serde(rename = "arm")]
    pub arms: Vec<Arm>,
}

/// The seeds of a study.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Seeds {
    /// 0, 1, …, n − 1.
    Count(u64),
    /// These.
    List(Vec<u64>),
}

impl Seeds {
    fn list(&self) -> Vec<u64> {
        match self {
            Seeds::Count(n) => (0..*n).collect(),
            Seeds::List(v) => v.clone(),
        }
    }
}

/// Which policy a run hands over.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Handover {
    /// `RUN/best/` when the run keeps one (the walking check's or the ES curve's choice),
    /// else the last checkpoint.
    #[default]
    Kept,
    /// The last checkpoint.
    Last,
}

/// How a study evaluates each run's handed-over policy.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct StudyEval {
    /// Deterministic episodes. Default 20.
    pub episodes: usize,
    /// Reset seed of the first (then +1 each). Default 1000: starts no training, check or
    /// `esrl eval` default (0–9) used.
    pub seed: u64,
    /// Which policy. Default `kept`.
    pub policy: Handover,
    /// Episodes whose per-step trace the record keeps (≈ 0.4 MB each). Default 1.
    pub traces: usize,
}

impl Default for StudyEval {
    fn default() -> Self {
        Self {
            episodes: 20,
            seed: 1000,
            policy: Handover::Kept,
            traces: 1,
        }
    }
}

/// One arm: an agent and its settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Arm {
    /// Its name in folders and the report (letters, digits, `-`, `_`).
    pub name: String,
    /// The agent.
    pub agent: AgentKind,
    /// The preset underneath (default `walking`).
    #[serde(default)]
    pub preset: Option<Preset>,
    /// A TOML file laid over the preset, relative to the study file.
    #[serde(default)]
    pub config: Option<PathBuf>,
    /// Keys laid over the preset and the file, as in `config.toml`.
    #[serde(default)]
    pub set: toml::Table,
    /// Environment-step budget.
    #[serde(default)]
    pub steps: Option<u64>,
    /// Generations (ES agents).
    #[serde(default)]
    pub generations: Option<usize>,
    /// Episodes (plain agents).
    #[serde(default)]
    pub episodes: Option<usize>,
}

/// A study read from its file, with every run's configuration resolved.
pub struct Study {
    /// The file's text.
    pub text: String,
    /// The parsed file.
    pub file: StudyFile,
    /// (arm index, seed, configuration), arms in order and seeds within.
    pub runs: Vec<(usize, u64, TrainConfig)>,
}

/// Name of the study file inside a study folder.
pub const STUDY_FILE: &str = "study.toml";

impl Study {
    /// Reads and resolves `path`; relative `config` paths are taken from its folder.
    pub fn load(path: &Path) -> Result<Self> {
        let text = esrl_sim::read_text_file(path, 1 << 20)
            .with_context(|| format!("reading {}", path.display()))?;
        let mut study = Self::parse(&text).with_context(|| format!("in {}", path.display()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        study
            .resolve(base)
            .with_context(|| format!("in {}", path.display()))?;
        Ok(study)
    }

    fn parse(text: &str) -> Result<Self> {
        let file: StudyFile = toml::from_str(text)?;
        if file.arms.is_empty() {
            bail!("the study has no [[arm]]");
        }
        let seeds = file.seeds.list();
        if seeds.is_empty() {
            bail!("seeds: the study has no seed");
        }
        let mut sorted = seeds.clone();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != seeds.len() {
            bail!("seeds: a seed is listed twice");
        }
        if file.eval.episodes == 0 {
            bail!("eval.episodes = 0: evaluate at least one episode");
        }
        let mut names = Vec::new();
        for arm in &file.arms {
            let ok = !arm.name.is_empty()
                && arm
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !ok {
                bail!(
                    "arm name `{}`: use letters, digits, `-` and `_` (it names folders)",
                    arm.name
                );
            }
            if names.contains(&&arm.name) {
                bail!("arm `{}` is listed twice", arm.name);
            }
            names.push(&arm.name);
            for key in ["agent", "seed", "preset"] {
                if arm.set.contains_key(key) {
                    bail!(
                        "arm `{}`: `set` may not set `{key}` (the study does)",
                        arm.name
                    );
                }
            }
        }
        Ok(Self {
            text: text.to_owned(),
            file,
            runs: Vec::new(),
        })
    }

    fn resolve(&mut self, base: &Path) -> Result<()> {
        let seeds = self.file.seeds.list();
        let mut runs = Vec::new();
        for (i, arm) in self.file.arms.iter().enumerate() {
            for &seed in &seeds {
                let overrides = Overrides {
                    preset: arm.preset.unwrap_or_default(),
                    config: arm.config.as_ref().map(|c| base.join(c)),
                    generations: arm.generations,
                    episodes: arm.episodes,
                    steps: arm.steps,
                    ..Overrides::default()
                };
                let mut cfg = TrainConfig::resolve(arm.agent, &overrides, Some(seed))
                    .with_context(|| format!("arm `{}`", arm.name))?;
                if !arm.set.is_empty() {
                    cfg = cfg
                        .merged_with_str(&toml::to_string(&arm.set)?)
                        .with_context(|| format!("arm `{}`: its `set` keys", arm.name))?;
                    cfg.validate()
                        .with_context(|| format!("arm `{}`: its `set` keys", arm.name))?;
                }
                runs.push((i, seed, cfg));
            }
        }
        self.runs = runs;
        Ok(())
    }

    /// `<arm>-s<seed>` of run `k`.
    pub fn run_name(&self, k: usize) -> String {
        let (arm, seed, _) = &self.runs[k];
        format!("{}-s{seed}", self.file.arms[*arm].name)
    }
}

/// Runs `esrl study`.
pub fn run(args: &StudyArgs) -> Result<()> {
    match &args.command {
        StudyCommand::Run {
            study,
            out,
            jobs,
            shard,
            threads,
            no_progress,
        } => run_study(
            study,
            out.as_deref(),
            *jobs,
            shard.as_deref(),
            *threads,
            *no_progress,
        ),
        StudyCommand::Status { dir } => status(dir),
        StudyCommand::Report { dir, json } => report(dir, *json),
    }
}

/// Parses `i/n` (0 ≤ i < n).
fn parse_shard(text: &str) -> Result<(usize, usize)> {
    let parsed = text
        .split_once('/')
        .and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)));
    match parsed {
        Some((i, n)) if n > 0 && i < n => Ok((i, n)),
        _ => bail!("--shard {text}: expected i/n with 0 ≤ i < n, e.g. 0/2"),
    }
}

pub(crate) fn run_study(
    path: &Path,
    out: Option<&Path>,
    jobs: Option<usize>,
    shard: Option<&str>,
    threads: Option<usize>,
    no_progress: bool,
) -> Result<()> {
    let study = Study::load(path)?;
    let out = match out {
        Some(o) => o.to_path_buf(),
        None => PathBuf::from("studies").join(
            path.file_stem()
                .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned()),
        ),
    };
    let (index, of) = match shard {
        Some(s) => parse_shard(s)?,
        None => (0, 1),
    };
    if jobs == Some(0) || threads == Some(0) {
        bail!("--jobs and --threads must be at least 1");
    }
    fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let held = out.join(STUDY_FILE);
    match fs::read_to_string(&held) {
        Ok(text) if text != study.text => bail!(
            "{} holds another study ({} differs from {}); give this one another --out",
            out.display(),
            held.display(),
            path.display()
        ),
        Ok(_) => {}
        Err(_) => write_atomic(&held, study.text.as_bytes())?,
    }
    crate::signals::install();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mine: Vec<usize> = (0..study.runs.len()).filter(|k| k % of == index).collect();
    let mut plans = Vec::new();
    for &k in &mine {
        let (arm, seed, cfg) = &study.runs[k];
        plans.push(Plan {
            agent: study.file.arms[*arm].agent,
            seed: *seed,
            dir: out.join("runs").join(study.run_name(k)),
            config: cfg.clone(),
        });
    }
    // A run is trained unless it has finished here or its record is already written (records
    // merged by copying from another shard or machine need no run folder).
    let recorded = |p: &Plan| {
        out.join("records")
            .join(p.name())
            .join(esrl_eval::EVAL_FILE)
            .is_file()
    };
    let mut pending = Vec::new();
    for p in &plans {
        if run_state(&p.dir)? == RunState::Finished {
            check_config(p)?;
        } else if !recorded(p) {
            pending.push(p.clone());
        }
    }
    let jobs = jobs
        .unwrap_or_else(|| (cores / threads.unwrap_or(1)).max(1))
        .clamp(1, pending.len().max(1));
    let threads = threads.unwrap_or((cores / jobs).max(1));
    for p in &mut pending {
        p.config.threads = threads;
    }
    let held_records = plans
        .iter()
        .filter(|p| run_state(&p.dir).ok() != Some(RunState::Finished) && recorded(p))
        .count();
    eprintln!(
        "study {}: {} run(s) in this shard ({index}/{of}), {} to train, {held_records} recorded \
         without a run folder, {jobs} at a time, {threads} thread(s) each → {}",
        path.display(),
        plans.len(),
        pending.len(),
        out.display()
    );
    // Each run's record is written as soon as it has finished.
    let record_of = |p: &Plan| -> Result<()> {
        let record = out.join("records").join(p.name());
        if !record.join(esrl_eval::EVAL_FILE).is_file() {
            write_record(&p.dir, &record, &study.file.eval)?;
            eprintln!("recorded {}", record.display());
        }
        Ok(())
    };
    let mut failures = Vec::new();
    if !pending.is_empty() {
        let progress = jobs == 1 && !no_progress;
        for (p, r) in pending
            .iter()
            .zip(train_all(&pending, jobs, progress, &record_of))
        {
            if let Err(e) = r {
                failures.push(format!("{}: {e:#}", p.name()));
            }
        }
    }
    if crate::signals::requested().is_some() {
        bail!(
            "stopped by a signal before every run finished:\n  {}\nthe runs in progress have \
             checkpoints and the same command continues the study",
            failures.join("\n  ")
        );
    }
    for p in &plans {
        if run_state(&p.dir)? != RunState::Finished {
            continue;
        }
        if pending.iter().any(|q| q.dir == p.dir) {
            continue; // recorded (or failed) as it finished
        }
        if let Err(e) = record_of(p) {
            failures.push(format!("{}: {e:#}", p.name()));
        }
    }
    if !failures.is_empty() {
        bail!(
            "{} run(s) failed:\n  {}",
            failures.len(),
            failures.join("\n  ")
        );
    }
    eprintln!(
        "done; `{} study report {}` tabulates the records",
        esrl_run::command(),
        out.display()
    );
    Ok(())
}

/// Copies what the report needs of the finished run `run` into `record` (written to a
/// temporary folder, renamed into place last): its files, the evaluation of its handed-over
/// policy, and the policy's actor.
fn write_record(run: &Path, record: &Path, eval: &StudyEval) -> Result<()> {
    let pick = match eval.policy {
        Handover::Kept => Pick::Kept,
        Handover::Last => Pick::Last,
    };
    let loaded = load_run_pick(run, pick)?;
    let report = evaluate_with(
        &loaded,
        eval.seed,
        eval.episodes,
        None,
        &EvalOptions {
            traces: eval.traces,
            stop: None,
        },
    )?;
    let tmp = record.with_extension("tmp");
    if tmp.exists() {
        fs::remove_dir_all(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
    }
    let policy = tmp.join("policy");
    fs::create_dir_all(&policy).with_context(|| format!("creating {}", policy.display()))?;
    for name in [
        RunDir::CONFIG,
        RunDir::CSV,
        RunDir::SUMMARY,
        esrl_run::training::CHECKS_FILE,
    ] {
        let from = run.join(name);
        if from.is_file() {
            fs::copy(&from, tmp.join(name))
                .with_context(|| format!("copying {}", from.display()))?;
        }
    }
    for name in ["actor.safetensors", RunDir::CONFIG, BEST_INFO] {
        let from = loaded.checkpoint.join(name);
        if from.is_file() {
            fs::copy(&from, policy.join(name))
                .with_context(|| format!("copying {}", from.display()))?;
        }
    }
    if !policy.join(RunDir::CONFIG).is_file() {
        fs::copy(run.join(RunDir::CONFIG), policy.join(RunDir::CONFIG))?;
    }
    let mut value = serde_json::to_value(&report)?;
    // The record's own policy folder, not the machine-specific paths of the run.
    value["run"] = json!(run.file_name().map(|n| n.to_string_lossy()));
    value["checkpoint"] = json!(if loaded.checkpoint.ends_with(BEST) {
        "policy (RUN/best/)"
    } else {
        "policy (RUN/checkpoint/)"
    });
    write_json_atomic(&tmp.join(esrl_eval::EVAL_FILE), &value)?;
    if record.exists() {
        fs::remove_dir_all(record).with_context(|| format!("removing {}", record.display()))?;
    }
    fs::rename(&tmp, record)
        .with_context(|| format!("renaming {} into place", record.display()))?;
    Ok(())
}

/// The study of a study folder (its `study.toml`, as run).
fn held_study(dir: &Path) -> Result<Study> {
    let p = dir.join(STUDY_FILE);
    if !p.is_file() {
        bail!(
            "{} is not a study folder (no {STUDY_FILE}); `esrl study run STUDY.toml --out {}` \
             makes one",
            dir.display(),
            dir.display()
        );
    }
    Study::load(&p)
}

fn status(dir: &Path) -> Result<()> {
    let study = held_study(dir)?;
    let mut counts = BTreeMap::<&str, usize>::new();
    println!("| run | state | rows | env steps | kept policy |\n|---|---|---:|---:|---|");
    for k in 0..study.runs.len() {
        let name = study.run_name(k);
        let run = dir.join("runs").join(&name);
        let record = dir.join("records").join(&name);
        let summary = Summary::read(&run).ok().flatten();
        let state = if record.join(esrl_eval::EVAL_FILE).is_file() {
            "recorded"
        } else {
            match run_state(&run)? {
                RunState::Finished => "trained",
                RunState::Resumable => "stopped (resumable)",
                RunState::Stale => "stopped before its first checkpoint",
                RunState::Empty => "not started",
            }
        };
        *counts.entry(state).or_default() += 1;
        let kept = read_eval(&record)?
            .map(|r| describe_eval(&r))
            .unwrap_or_else(|| "-".into());
        println!(
            "| {name} | {state} | {} | {} | {kept} |",
            summary
                .as_ref()
                .map_or("-".into(), |s| s.length.to_string()),
            summary
                .as_ref()
                .map_or("-".into(), |s| s.env_steps.to_string()),
        );
    }
    let line = counts
        .iter()
        .map(|(s, n)| format!("{n} {s}"))
        .collect::<Vec<_>>()
        .join(", ");
    eprintln!("{}: {} runs: {line}", dir.display(), study.runs.len());
    Ok(())
}

/// The evaluation of a record: `None` while the record is not written; an error naming the
/// file when it is there but cannot be read.
fn read_eval(record: &Path) -> Result<Option<EvalReport>> {
    let p = record.join(esrl_eval::EVAL_FILE);
    if !p.is_file() {
        return Ok(None);
    }
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    let report = serde_json::from_str(&text)
        .with_context(|| format!("{}: not an evaluation report", p.display()))?;
    Ok(Some(report))
}

/// "walk 19, run 1; 20/20 finished, 0 falls".
fn describe_eval(r: &EvalReport) -> String {
    let classes = r
        .mean
        .gait
        .as_ref()
        .and_then(|g| g.cycle.as_ref())
        .map_or("-".into(), |c| gait_classes_text(&c.gait_classes));
    format!(
        "{classes}; {}/{} finished, {} falls",
        r.mean.finished, r.mean.episodes, r.mean.falls
    )
}

/// The walking bar on an evaluation: more than half of the episodes `walk` and at least
/// 80 % reach the line.
fn at_bar(r: &EvalReport) -> bool {
    let n = r.mean.episodes as f64;
    let walks = r
        .mean
        .gait
        .as_ref()
        .and_then(|g| g.cycle.as_ref())
        .map_or(0, |c| {
            c.gait_classes.get(&GaitClass::Walk).copied().unwrap_or(0)
        });
    r.mean.finished as f64 >= 0.8 * n - 1e-9 && walks as f64 > 0.5 * n
}

/// One recorded run, as the report reads it.
struct Record {
    arm: usize,
    seed: u64,
    curve: Vec<f64>,
    q0: Option<f64>,
    summary: Summary,
    eval: EvalReport,
}

/// The per-run row of the report.
#[derive(Debug, Clone, Serialize)]
struct RunRow {
    arm: String,
    seed: u64,
    at_bar: bool,
    classes: String,
    finished: usize,
    falls: usize,
    episodes: usize,
    track_time: Option<f64>,
    speed: f64,
    sway: f64,
    knee_asymmetry: f64,
    knee_flexion_deg: Option<f64>,
    double_support: Option<f64>,
    /// Whether the run checked policies against the walking bar while it trained.
    checked: bool,
    steps_to_walk: Option<f64>,
    time_to_walk_s: Option<f64>,
    env_steps: u64,
    wall_s: f64,
    best_win_50: f64,
}

/// Largest 95th-percentile knee angle of the two knees, degrees: how far the swing knee
/// flexes.
fn knee_flexion(r: &EvalReport) -> Option<f64> {
    let g = r.mean.gait.as_ref()?;
    g.joints
        .iter()
        .filter(|j| j.name.contains("knee"))
        .map(|j| j.p95.to_degrees())
        .reduce(f64::max)
}

fn run_row(study: &Study, rec: &Record) -> RunRow {
    let g = rec.eval.mean.gait.as_ref();
    let finishers: Vec<f64> = rec
        .eval
        .episodes
        .iter()
        .filter_map(|e| e.gait.as_ref()?.track_time)
        .collect();
    let figure = |k: &str| rec.summary.learner.get(k).and_then(Value::as_f64);
    RunRow {
        arm: study.file.arms[rec.arm].name.clone(),
        seed: rec.seed,
        at_bar: at_bar(&rec.eval),
        classes: g
            .and_then(|g| g.cycle.as_ref())
            .map_or("-".into(), |c| gait_classes_text(&c.gait_classes)),
        finished: rec.eval.mean.finished,
        falls: rec.eval.mean.falls,
        episodes: rec.eval.mean.episodes,
        track_time: (!finishers.is_empty())
            .then(|| finishers.iter().sum::<f64>() / finishers.len() as f64),
        speed: g.map_or(f64::NAN, |g| g.mean_forward_velocity),
        sway: g.map_or(f64::NAN, |g| g.mean_abs_lateral),
        knee_asymmetry: g.map_or(f64::NAN, |g| g.knee_torque_asymmetry),
        knee_flexion_deg: knee_flexion(&rec.eval),
        double_support: g.and_then(|g| g.cycle.as_ref()).map(|c| c.double_support),
        checked: figure("checks").is_some_and(|c| c > 0.0),
        steps_to_walk: figure("steps_to_walk"),
        time_to_walk_s: figure("time_to_walk_s"),
        env_steps: rec.summary.env_steps,
        wall_s: rec.summary.wall_s,
        best_win_50: rec.summary.curve.best_win_50,
    }
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite())
        .map_or("–".into(), |x| format!("{x:.digits$}"))
}

fn interval_text(i: &Interval, digits: usize, scale: f64) -> String {
    format!(
        "{:.digits$} [{:.digits$}, {:.digits$}]",
        i.estimate * scale,
        i.lo * scale,
        i.hi * scale
    )
}

pub(crate) fn report(dir: &Path, json_out: bool) -> Result<()> {
    let study = held_study(dir)?;
    let mut records = Vec::new();
    for (k, (arm, seed, _)) in study.runs.iter().enumerate() {
        let rec_dir = dir.join("records").join(study.run_name(k));
        let Some(eval) = read_eval(&rec_dir)? else {
            continue;
        };
        let Some(summary) = Summary::read(&rec_dir)? else {
            continue;
        };
        let (curve, q0) = read_csv_curve(&rec_dir.join(RunDir::CSV))?;
        records.push(Record {
            arm: *arm,
            seed: *seed,
            curve,
            q0,
            summary,
            eval,
        });
    }
    if records.is_empty() {
        bail!(
            "{} has no records yet (`{} study status {}` says where the runs are)",
            dir.display(),
            esrl_run::command(),
            dir.display()
        );
    }
    let rows: Vec<RunRow> = records.iter().map(|r| run_row(&study, r)).collect();
    let planned = study.file.seeds.list().len();
    let mut md = format!(
        "# Study: {}\n\n{} arm(s) × {planned} seed(s); {} of {} runs recorded. Each run's \
         handed-over policy ({}) evaluated on {} deterministic episodes (reset seeds {}…). The \
         walking bar: `walk` in more than half of the episodes and at least 80 % past the 50 m \
         line. Intervals are 95 %: Wilson for rates, percentile bootstrap over runs (2,000 \
         resamples) for the IQM and the probability of improvement (Agarwal et al. 2021).\n\n",
        if study.file.description.is_empty() {
            dir.display().to_string()
        } else {
            study.file.description.clone()
        },
        study.file.arms.len(),
        records.len(),
        study.runs.len(),
        match study.file.eval.policy {
            Handover::Kept => "its kept policy, RUN/best/",
            Handover::Last => "its last checkpoint",
        },
        study.file.eval.episodes,
        study.file.eval.seed,
    );
    md.push_str(
        "## Per arm\n\n| arm | runs | at the bar | rate [95 %] | IQM Best-Win-50 [95 %] | walked \
         in training | IQM steps to walk [95 %] |\n|---|---:|---:|---|---|---:|---|\n",
    );
    let mut arms_json = Vec::new();
    for (a, arm) in study.file.arms.iter().enumerate() {
        let mine: Vec<&RunRow> = rows.iter().filter(|r| r.arm == arm.name).collect();
        if mine.is_empty() {
            continue;
        }
        let n = mine.len();
        let k = mine.iter().filter(|r| r.at_bar).count();
        let rate = wilson(k, n, Z95)?;
        let bw: Vec<f64> = mine.iter().map(|r| r.best_win_50).collect();
        let bw_iqm = iqm_interval(&bw, 1 + a as u64)?;
        let walked: Vec<f64> = mine.iter().filter_map(|r| r.steps_to_walk).collect();
        let steps_iqm = if walked.is_empty() {
            None
        } else {
            Some(iqm_interval(&walked, 100 + a as u64)?)
        };
        let rate_text = format!(
            "{:.0} % [{:.0}–{:.0} %]",
            100.0 * rate.estimate,
            100.0 * rate.lo,
            100.0 * rate.hi
        );
        // Runs made without the walking check cannot say when they first walked.
        let checked = mine.iter().filter(|r| r.checked).count();
        let walked_text = if checked == 0 {
            "– (no check)".to_string()
        } else {
            format!("{} of {checked}", walked.len())
        };
        md.push_str(&format!(
            "| {} | {n} | {k} | {rate_text} | {} | {walked_text} | {} |\n",
            arm.name,
            interval_text(&bw_iqm, 0, 1.0),
            steps_iqm.map_or("–".into(), |i| interval_text(&i, 2, 1e-6) + " M"),
        ));
        arms_json.push(json!({
            "arm": arm.name,
            "runs": n,
            "at_bar": k,
            "rate": rate,
            "best_win_50_iqm": bw_iqm,
            "walked_in_training": walked.len(),
            "checked_in_training": checked,
            "steps_to_walk_iqm": steps_iqm,
        }));
    }
    // Probability of improvement between arms, on Best-Win-50 and on reaching the bar.
    let mut poi_json = Vec::new();
    if study.file.arms.len() > 1 {
        md.push_str(
            "\n## Probability of improvement\n\nP(a run of the row arm beats one of the column \
             arm), on Best-Win-50 / on meeting the bar, with 95 % intervals.\n\n",
        );
        let values = |name: &str, f: &dyn Fn(&RunRow) -> f64| -> Vec<f64> {
            rows.iter().filter(|r| r.arm == name).map(f).collect()
        };
        for (i, x) in study.file.arms.iter().enumerate() {
            for (j, y) in study.file.arms.iter().enumerate() {
                if i == j {
                    continue;
                }
                let (bx, by) = (
                    values(&x.name, &|r| r.best_win_50),
                    values(&y.name, &|r| r.best_win_50),
                );
                if bx.is_empty() || by.is_empty() {
                    continue;
                }
                let bar = |r: &RunRow| f64::from(u8::from(r.at_bar));
                let (sx, sy) = (values(&x.name, &bar), values(&y.name, &bar));
                let seed = 1000 + (i * 100 + j) as u64;
                let p_bw = probability_of_improvement_interval(&bx, &by, seed)?;
                let p_bar = probability_of_improvement_interval(&sx, &sy, seed + 7)?;
                md.push_str(&format!(
                    "- {} over {}: {} / {}\n",
                    x.name,
                    y.name,
                    interval_text(&p_bw, 2, 1.0),
                    interval_text(&p_bar, 2, 1.0)
                ));
                poi_json.push(json!({"arm": x.name, "over": y.name,
                    "best_win_50": p_bw, "at_bar": p_bar}));
            }
        }
    }
    md.push_str(
        "\n## Every run\n\n| run | at bar | gait classes | finished | falls | track time (s) | \
         speed (m/s) | sway (m) | knee asym. | knee flexion (°) | double support | steps to \
         walk | env steps | wall (s) |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:\
         |---:|---:|\n",
    );
    let mut csv = String::from(
        "arm,seed,at_bar,classes,finished,falls,episodes,track_time,speed,sway,knee_asymmetry,\
         knee_flexion_deg,double_support,steps_to_walk,time_to_walk_s,env_steps,wall_s,\
         best_win_50\n",
    );
    for r in &rows {
        md.push_str(&format!(
            "| {}-s{} | {} | {} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0} |\n",
            r.arm,
            r.seed,
            if r.at_bar { "yes" } else { "no" },
            r.classes,
            r.finished,
            r.episodes,
            r.falls,
            fmt(r.track_time, 1),
            fmt(Some(r.speed), 2),
            fmt(Some(r.sway), 3),
            fmt(Some(100.0 * r.knee_asymmetry), 1) + " %",
            fmt(r.knee_flexion_deg, 0),
            fmt(r.double_support.map(|d| 100.0 * d), 1) + " %",
            r.steps_to_walk
                .map_or("–".into(), |s| format!("{:.2} M", s / 1e6)),
            r.env_steps,
            r.wall_s
        ));
        csv.push_str(&format!(
            "{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.arm,
            r.seed,
            r.at_bar,
            r.classes,
            r.finished,
            r.falls,
            r.episodes,
            fmt(r.track_time, 3),
            fmt(Some(r.speed), 4),
            fmt(Some(r.sway), 4),
            fmt(Some(r.knee_asymmetry), 4),
            fmt(r.knee_flexion_deg, 2),
            fmt(r.double_support, 4),
            fmt(r.steps_to_walk, 0),
            fmt(r.time_to_walk_s, 1),
            r.env_steps,
            fmt(Some(r.wall_s), 1),
            fmt(Some(r.best_win_50), 2),
        ));
    }
    // Table 1 of the arms (mean ± SD, as the paper; the one Table 1 writer).
    let mut agents = Vec::new();
    for (a, arm) in study.file.arms.iter().enumerate() {
        let mine: Vec<&Record> = records.iter().filter(|r| r.arm == a).collect();
        if mine.is_empty() {
            continue;
        }
        let curves: Vec<Vec<f64>> = mine.iter().map(|r| r.curve.clone()).collect();
        let summaries = summarize_method(&curves)?;
        agents.push(AgentRuns {
            agent: arm.name.clone(),
            seeds: summaries
                .into_iter()
                .zip(&mine)
                .map(|(summary, r)| SeedResult {
                    summary,
                    gait: r.eval.mean.gait.clone(),
                    q0_mean: r.q0,
                })
                .collect(),
        });
    }
    let table = table1(&agents)?;
    md.push_str("\n## Table 1 (mean ± sample SD across seeds)\n\n");
    md.push_str(&table1_markdown(&table));
    if table.iter().any(|r| r.gait_runs > 0) {
        md.push_str("\n## Mean |torque| and |power| per actuator (paper Fig. 5d)\n\n");
        md.push_str(&actuator_markdown(&table));
    }
    if table.iter().any(|r| !r.joint_names.is_empty()) {
        md.push_str(
            "\n## Range of motion (5th–95th percentile) and time within 1° of a limit per \
             joint\n\n",
        );
        md.push_str(&joint_markdown(&table));
    }
    md.push_str(
        "\nKnee flexion: the larger of the two knees' 95th-percentile angle; knee asym.: \
         |T_L − T_R| / ((T_L + T_R)/2) of the mean |knee torque|; steps to walk: environment \
         steps to the first policy the walking check found at the bar during training \
         (`checks.jsonl`); wall: training time as measured on the machine that ran it.\n",
    );
    let figures = json!({"arms": arms_json, "improvement": poi_json, "runs": rows});
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    write_atomic(&dir.join("report.csv"), csv.as_bytes())?;
    write_json_atomic(&dir.join("report.json"), &figures)?;
    if json_out {
        println!("{}", serde_json::to_string_pretty(&figures)?);
    } else {
        print!("{md}");
    }
    eprintln!(
        "wrote {}, {} and {} (`python -m esrl_rs.report --study {}` draws them)",
        dir.join("report.md").display(),
        dir.join("report.csv").display(),
        dir.join("report.json").display(),
        dir.display()
    );
    Ok(())
}

/// The `curve` and mean `q0` columns of a record's `metrics.csv`.
fn read_csv_curve(path: &Path) -> Result<(Vec<f64>, Option<f64>)> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .with_context(|| format!("{} is empty", path.display()))?
        .split(',')
        .collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let c = col("curve").with_context(|| format!("{} has no curve column", path.display()))?;
    let q = col("q0");
    let (mut curve, mut q0) = (Vec::new(), Vec::new());
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let value = |i: usize| cells.get(i).and_then(|v| v.parse::<f64>().ok());
        curve.push(
            value(c).with_context(|| format!("{}: a row without a curve value", path.display()))?,
        );
        q0.extend(q.and_then(value));
    }
    Ok((curve, esrl_metrics::q0_mean(&q0)))
}
