//! `esrl study run` and `esrl study status`: training a study's runs (resumable,
//! shardable) and writing each finished run's record.

use super::{describe_eval, held_study, read_eval, Handover, Study, StudyEval, STUDY_FILE};
use crate::runs::{check_config, run_state, train_all, Plan, RunState};
use anyhow::{bail, Context, Result};
use esrl_eval::{card, evaluate_with, goal_rows, load_run_pick, standard_set, EvalOptions, Pick};
use esrl_run::checkpoint::{BEST, BEST_INFO};
use esrl_run::run_dir::{write_atomic, write_json_atomic};
use esrl_run::{RunDir, Summary};
use serde_json::json;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

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
    // Runs that had finished before this command are recorded first, so a study stopped
    // during the trainings keeps them (runs trained here are recorded as they finish).
    for p in plans
        .iter()
        .filter(|p| !pending.iter().any(|q| q.dir == p.dir))
    {
        if run_state(&p.dir)? != RunState::Finished {
            continue;
        }
        if crate::signals::requested().is_some() {
            break;
        }
        if let Err(e) = record_of(p) {
            failures.push(format!("{}: {e:#}", p.name()));
        }
    }
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
    let mut loaded = load_run_pick(run, pick)?;
    if eval.undisturbed {
        loaded = loaded.undisturbed()?;
    }
    if eval.default_starts {
        loaded = loaded.default_starts()?;
    }
    let mut report = evaluate_with(
        &loaded,
        eval.seed,
        eval.episodes,
        None,
        &EvalOptions {
            traces: eval.traces,
            stop: None,
        },
    )?;
    report.undisturbed = eval.undisturbed;
    report.default_starts = eval.default_starts;
    if eval.robustness_episodes > 0 {
        let rows = card(
            &loaded,
            eval.seed,
            eval.robustness_episodes,
            &standard_set(),
            None,
        )?;
        report.robustness_goal = Some(goal_rows(&rows));
        report.robustness = Some(rows);
    }
    let tmp = record.with_extension("tmp");
    if tmp.exists() {
        fs::remove_dir_all(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
    }
    let policy = tmp.join("policy");
    fs::create_dir_all(&policy).with_context(|| format!("creating {}", policy.display()))?;
    let logs = [
        RunDir::CSV,
        RunDir::SUMMARY,
        esrl_run::training::CHECKS_FILE,
    ];
    copy_present(
        run,
        &tmp,
        &[RunDir::CONFIG, esrl_run::restart::RESTARTS_FILE],
    )?;
    copy_present(run, &tmp, &logs)?;
    // A run that started over: its abandoned attempts' records beside its own.
    for abandoned in esrl_run::restart::read(run)? {
        let dest = tmp.join(&abandoned.folder);
        fs::create_dir_all(&dest).with_context(|| format!("creating {}", dest.display()))?;
        copy_present(&run.join(&abandoned.folder), &dest, &logs)?;
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

/// Copies each of the files `names` that `from` holds into `to`.
fn copy_present(from: &Path, to: &Path, names: &[&str]) -> Result<()> {
    for name in names {
        let file = from.join(name);
        if file.is_file() {
            fs::copy(&file, to.join(name))
                .with_context(|| format!("copying {}", file.display()))?;
        }
    }
    Ok(())
}

/// Prints each run's state: recorded, training now (another process holds its lock), trained,
/// stopped, not started.
pub(super) fn status(dir: &Path) -> Result<()> {
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
        } else if esrl_run::training::is_training(&run) {
            "training now"
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
