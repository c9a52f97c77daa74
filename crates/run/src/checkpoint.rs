//! Checkpoints: everything needed to continue a run exactly, written atomically.
//!
//! ```text
//! RUN/checkpoint/
//!   agent.safetensors   actor, critics, targets, Adam moments, log α (and the ES mean)
//!   actor.safetensors   the actor alone, tensor names of esrl-nn (loads in PyTorch/NumPy)
//!   state.json          counters, random streams, σ, the learning curve so far, and the
//!                       replay chunks (with their SHA-256) that make up the buffer
//!   config.toml         the configuration this checkpoint was trained with
//!   manifest.json       SHA-256 of the four files above, written last
//! RUN/replay/
//!   chunk-<first>.safetensors   the transitions pushed since the previous checkpoint,
//!                               oldest first (`first` = index of the first push)
//! ```
//!
//! The replay buffer is written incrementally: each checkpoint adds one chunk of the
//! transitions pushed since the last one, and chunks whose transitions have all left the
//! ring are deleted once a newer checkpoint is in place. A checkpoint rewrites the networks
//! (a few MB) and appends the new experience, instead of rewriting the whole buffer (≈ 118 MB
//! on `quick`). Checkpoints written before this layout keep `replay.safetensors` inside the
//! folder and still load.
//!
//! On resume every file is checked against the manifest and every chunk against its hash,
//! `state.json` against the configuration's rules and the metric logs, and the configuration
//! against the one the checkpoint was trained with: an edited or corrupted checkpoint is
//! refused with a message naming the file or field, never trusted.
//!
//! Runs whose learner keeps its scored policy apart from its agent (the hybrid loop) also
//! keep `RUN/best/` ([`save_best`]): the policy with the highest learning-curve value so
//! far, for `esrl eval RUN/best`.
//!
//! Everything a checkpoint holds comes through the learner's [`esrl_agents::Resumable`] interface: its counters and
//! streams ([`Resumable::state`](esrl_agents::Resumable::state), the learner's keys of `state.json` beside the run's own
//! [`RunState`]), its tensors ([`Resumable::tensors`](esrl_agents::Resumable::tensors)) and its replay buffer; resuming checks
//! them ([`Resumable::check`](esrl_agents::Resumable::check)) and hands them back ([`Resumable::restore`](esrl_agents::Resumable::restore)) to a learner built
//! fresh from the run's config.
//!
//! A checkpoint is written to `checkpoint.tmp/`, then swapped in with two renames; a kill at
//! any moment leaves `checkpoint/` or `checkpoint.old/` complete, and loading falls back to the
//! latter.

use crate::bail;
use crate::check::{CheckResult, CheckState};
use crate::compat;
use crate::config::{config_differences, TrainConfig};
use crate::error::{Context, Result};
use crate::run_dir::{write_atomic, write_json_atomic, RunDir};
use esrl_agents::{Agent, Learner, LearnerState, ReplayBuffer};
use esrl_nn::{load_tensors, save_params, save_tensors, Module, NamedTensor};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::{BTreeMap, HashMap};
use std::fs;
use std::path::{Path, PathBuf};

/// Version of `state.json` written now. What earlier versions meant is in `compat.rs`.
pub const STATE_VERSION: u32 = 2;

/// The run's own part of `state.json`: how far it is, and the replay chunks its buffer is
/// made of. The learner's counters and streams ([`esrl_agents::LearnerState`]) are the file's other keys.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    /// Format version ([`STATE_VERSION`]).
    pub version: u32,
    /// Metric rows covered (rows past this are dropped on resume).
    pub rows: usize,
    /// Wall-clock seconds of training so far.
    pub wall_s: f64,
    /// The learning curve so far.
    pub curve: Vec<f64>,
    /// Q₀ per row so far.
    pub q0: Vec<f64>,
    /// The replay chunks the buffer is made of (absent in checkpoints that keep
    /// `replay.safetensors` inside the folder).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayLog>,
    /// The walking checks so far (runs with a `[check]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check: Option<CheckState>,
}

impl RunState {
    /// A run that has not started.
    pub fn fresh() -> Self {
        Self {
            version: STATE_VERSION,
            rows: 0,
            wall_s: 0.0,
            curve: Vec::new(),
            q0: Vec::new(),
            replay: None,
            check: None,
        }
    }
}

/// `state.json` as written: the run's keys, then the learner's.
#[derive(Serialize)]
struct StateFile<'a, S: Serialize> {
    #[serde(flatten)]
    run: &'a RunState,
    #[serde(flatten)]
    learner: &'a S,
}

/// The replay buffer of a checkpoint as chunks in `RUN/replay/`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ReplayLog {
    /// The buffer's push count at the checkpoint (the chunks end there).
    pub pushed: u64,
    /// The chunks, oldest first; together they hold at least the buffer's contents.
    pub chunks: Vec<ReplayChunk>,
}

/// One file of `RUN/replay/`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplayChunk {
    /// File name inside `RUN/replay/`.
    pub file: String,
    /// Push index of its first transition.
    pub start: u64,
    /// Transitions in it.
    pub len: u64,
    /// SHA-256 of the file, hex.
    pub sha256: String,
}

/// Where a run's replay chunks live.
pub const REPLAY: &str = "replay";

/// `manifest.json` of a checkpoint folder: the SHA-256 of each file, written last.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Manifest {
    sha256: BTreeMap<String, String>,
}

/// Hex SHA-256 of a file.
pub(crate) fn sha256_file(path: &Path) -> Result<String> {
    let bytes = fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(format!("{:x}", Sha256::digest(&bytes)))
}

/// The files a manifest covers.
const MANIFEST_FILES: [&str; 4] = [
    "agent.safetensors",
    "actor.safetensors",
    "state.json",
    "config.toml",
];

/// The files the manifest of `RUN/best/` covers.
const BEST_MANIFEST_FILES: [&str; 4] = [
    "agent.safetensors",
    "actor.safetensors",
    BEST_INFO,
    "config.toml",
];

/// Writes `dir/manifest.json` with the SHA-256 of `files` (written last).
fn write_manifest(dir: &Path, files: &[&str]) -> Result<()> {
    let mut sha256 = BTreeMap::new();
    for name in files {
        sha256.insert(name.to_string(), sha256_file(&dir.join(name))?);
    }
    write_json_atomic(&dir.join("manifest.json"), &Manifest { sha256 })
}

/// Where the newest complete checkpoint of a run folder is, if any.
pub fn find(run: &Path) -> Option<PathBuf> {
    ["checkpoint", "checkpoint.old"]
        .iter()
        .map(|d| run.join(d))
        .find(|d| d.join("state.json").exists() && d.join("agent.safetensors").exists())
}

/// The rows (generations or episodes) the checkpoint folder `dir` covers, read from its
/// `state.json` without checking it (`None` when it cannot be read).
pub fn rows_done(dir: &Path) -> Option<usize> {
    let text = fs::read_to_string(dir.join("state.json")).ok()?;
    let value: serde_json::Value = serde_json::from_str(&text).ok()?;
    value.get("rows")?.as_u64().map(|r| r as usize)
}

/// Writes a checkpoint of `learner` into `run/checkpoint/` atomically: the new replay chunk
/// first, then the checkpoint folder (manifest last), swapped in with renames; chunks no
/// longer needed are deleted only once the new checkpoint is in place.
pub fn save<L: Learner>(
    run: &Path,
    cfg: &TrainConfig,
    learner: &L,
    state: &mut RunState,
) -> Result<()> {
    state.version = STATE_VERSION;
    state.replay = Some(append_replay(run, learner.buffer(), state.replay.take())?);
    let tmp = fresh_dir(&run.join("checkpoint.tmp"))?;
    write_agent(&tmp, learner.tensors(), learner.agent())?;
    let file = StateFile {
        run: state,
        learner: &learner.state(),
    };
    write_json_atomic(&tmp.join("state.json"), &file)?;
    write_atomic(&tmp.join("config.toml"), cfg.to_toml()?.as_bytes())?;
    write_manifest(&tmp, &MANIFEST_FILES)?;
    swap_in(&tmp, &run.join("checkpoint"), &run.join("checkpoint.old"))?;
    prune_replay(run, state.replay.as_ref())
}

/// Writes the transitions pushed since `log` as a new chunk and returns the updated log,
/// without the chunks whose transitions have all left the buffer.
fn append_replay(run: &Path, buffer: &ReplayBuffer, log: Option<ReplayLog>) -> Result<ReplayLog> {
    let mut log = log.unwrap_or_default();
    let dir = run.join(REPLAY);
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let pushed = buffer.pushed();
    if pushed > log.pushed || log.chunks.is_empty() {
        let new = pushed.saturating_sub(log.pushed).min(buffer.len() as u64);
        let start = pushed - new;
        let file = format!("chunk-{start:012}.safetensors");
        let path = dir.join(&file);
        buffer
            .save_since(&path, start)
            .with_context(|| format!("writing {}", path.display()))?;
        if start > log.pushed {
            // More was pushed than the buffer holds: older chunks are all overwritten.
            log.chunks.clear();
        }
        log.chunks.push(ReplayChunk {
            file,
            start,
            len: new,
            sha256: sha256_file(&path)?,
        });
        log.pushed = pushed;
    }
    let oldest_kept = pushed - buffer.len() as u64;
    log.chunks
        .retain(|c| c.start + c.len > oldest_kept || c.len == 0);
    Ok(log)
}

/// Deletes the chunk files of `RUN/replay/` that `log` does not list.
fn prune_replay(run: &Path, log: Option<&ReplayLog>) -> Result<()> {
    let dir = run.join(REPLAY);
    let Ok(entries) = fs::read_dir(&dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !log.is_some_and(|l| l.chunks.iter().any(|c| c.file == name)) {
            fs::remove_file(entry.path()).ok();
        }
    }
    Ok(())
}

/// Creates `dir` empty, removing what a killed write left there.
fn fresh_dir(dir: &Path) -> Result<PathBuf> {
    if dir.exists() {
        fs::remove_dir_all(dir).with_context(|| format!("removing {}", dir.display()))?;
    }
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    Ok(dir.to_path_buf())
}

/// Writes `agent.safetensors` (`tensors`) and `actor.safetensors` (`agent`'s actor alone,
/// under the tensor names of esrl-nn) into `dir`.
fn write_agent(dir: &Path, tensors: Vec<(String, Vec<f32>)>, agent: &Agent) -> Result<()> {
    let tensors: Vec<NamedTensor> = tensors
        .into_iter()
        .map(|(name, data)| NamedTensor {
            shape: vec![data.len()],
            name,
            data,
        })
        .collect();
    save_tensors(&dir.join("agent.safetensors"), &tensors, None)?;
    save_params(
        &dir.join("actor.safetensors"),
        &[("", agent.actor().params())],
    )?;
    Ok(())
}

/// Replaces `current` by the complete folder `tmp` with two renames, so that a kill at any
/// moment leaves `current` or `old` complete.
fn swap_in(tmp: &Path, current: &Path, old: &Path) -> Result<()> {
    if old.exists() {
        fs::remove_dir_all(old).with_context(|| format!("removing {}", old.display()))?;
    }
    if current.exists() {
        fs::rename(current, old).with_context(|| format!("moving {}", current.display()))?;
    }
    fs::rename(tmp, current).with_context(|| format!("moving {}", tmp.display()))?;
    if old.exists() {
        fs::remove_dir_all(old).ok();
    }
    Ok(())
}

/// Where a run's best policy so far is kept (see [`save_best`]).
pub const BEST: &str = "best";
/// The file in `RUN/best/` that says which policy it holds ([`BestInfo`]).
pub const BEST_INFO: &str = "best.json";

/// What `RUN/best/best.json` says about the policy in `RUN/best/`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BestInfo {
    /// The generation (0-based) whose best individual this is.
    pub generation: usize,
    /// Its fitness: that generation's learning-curve value, the highest so far.
    pub fitness: f64,
    /// Environment steps taken by the end of that generation.
    pub env_steps: u64,
    /// Whether the policy is the ES mean θ after that generation (`check.mean`), not its best
    /// individual. Absent when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mean: bool,
    /// Whether the policy is the one the run started from (`init`), kept because no policy
    /// the run trained ranked above it on the walking check (then `generation`, `fitness`
    /// and `env_steps` are 0). Absent when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub start: bool,
    /// What the walking check found for it, when the run chooses `best/` by the check
    /// (`[check]`; then `fitness` is its row's curve value, not necessarily the highest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check: Option<CheckResult>,
}

/// Writes `RUN/best/`: `agent`, the agent whose policy scored the highest learning-curve
/// value so far ([`Learner::scored_agent`]: for the hybrid loop, the RL agent with the actor
/// and log α of that generation's best individual). `esrl eval RUN/best` evaluates it.
///
/// Same layout as a checkpoint less the replay buffer and `state.json` (weights, `best.json`,
/// the run's `config.toml`, a `manifest.json` of their SHA-256), written to `best.tmp/` and
/// swapped in like one. It is not a point to resume from.
pub fn save_best(run: &Path, cfg: &TrainConfig, agent: &Agent, info: &BestInfo) -> Result<()> {
    save_policy(run, BEST, cfg, agent, info)
}

/// The folder of the first walk of a run that asks for speed or symmetry
/// (`check.max_track_time`, `check.max_knee_asymmetry`): the first policy at the walking bar
/// without those margins, in [`save_best`]'s layout.
pub const FIRST_WALK: &str = "first-walk";

/// Writes `agent` as a policy folder `RUN/<name>/` in [`save_best`]'s layout.
pub fn save_policy(
    run: &Path,
    name: &str,
    cfg: &TrainConfig,
    agent: &Agent,
    info: &BestInfo,
) -> Result<()> {
    let tmp = fresh_dir(&run.join(format!("{name}.tmp")))?;
    write_agent(&tmp, agent.state_tensors(), agent)?;
    write_json_atomic(&tmp.join(BEST_INFO), info)?;
    write_atomic(&tmp.join("config.toml"), cfg.to_toml()?.as_bytes())?;
    write_manifest(&tmp, &BEST_MANIFEST_FILES)?;
    swap_in(&tmp, &run.join(name), &run.join(format!("{name}.old")))
}

/// The folder of [`snapshot_best`] at `steps` environment steps: `best-2M`, `best-500k`,
/// `best-1234`.
pub fn best_snapshot_name(steps: u64) -> String {
    if steps.is_multiple_of(1_000_000) {
        format!("{BEST}-{}M", steps / 1_000_000)
    } else if steps.is_multiple_of(1000) {
        format!("{BEST}-{}k", steps / 1000)
    } else {
        format!("{BEST}-{steps}")
    }
}

/// Copies `RUN/best/` as it stands to `RUN/best-<steps>/` ([`best_snapshot_name`]), through
/// a temporary folder swapped in like a checkpoint: the policy a run kept at that point of
/// its budget, for `esrl eval RUN/best-2M` (`best/` itself moves on to whatever scores
/// higher later). Nothing is written while there is no `best/`.
pub fn snapshot_best(run: &Path, steps: u64) -> Result<()> {
    let best = run.join(BEST);
    if !best.is_dir() {
        return Ok(());
    }
    let name = best_snapshot_name(steps);
    let tmp = fresh_dir(&run.join(format!("{name}.tmp")))?;
    for entry in fs::read_dir(&best).with_context(|| format!("reading {}", best.display()))? {
        let path = entry?.path();
        if path.is_file() {
            let to = tmp.join(path.file_name().expect("a file has a name"));
            fs::copy(&path, &to).with_context(|| format!("copying {}", path.display()))?;
        }
    }
    swap_in(&tmp, &run.join(&name), &run.join(format!("{name}.old")))
}

/// Removes `RUN/best/` and its snapshots `RUN/best-*/` (a run started over must not keep a
/// policy of its previous start).
pub fn remove_best(run: &Path) -> Result<()> {
    let dir = run.join(BEST);
    if dir.exists() {
        fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
    }
    let prefix = format!("{BEST}-");
    for entry in fs::read_dir(run).with_context(|| format!("reading {}", run.display()))? {
        let path = entry?.path();
        let snapshot = path
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with(&prefix));
        if snapshot && path.is_dir() {
            fs::remove_dir_all(&path).with_context(|| format!("removing {}", path.display()))?;
        }
    }
    Ok(())
}

/// Checks every file of a checkpoint or `best/` folder against its `manifest.json`.
/// Checkpoints of format version 2 and later always have one, so one without is refused;
/// checkpoints written before manifests existed, and `best/` folders and policy copies
/// written before `best/` had one (the committed `results/` policies), have none and pass.
pub fn verify_manifest(dir: &Path) -> Result<()> {
    let p = dir.join("manifest.json");
    if !p.exists() {
        let version = read_run_state(dir).map(|s| s.version).unwrap_or(1);
        if dir.join("state.json").exists() && compat::has_manifest(version) {
            bail!(
                "{} is missing: a checkpoint of this format always has one, so it was removed \
                 and nothing in {} can be verified. Restore it, or start a new run",
                p.display(),
                dir.display()
            );
        }
        return Ok(());
    }
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    let manifest: Manifest =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    for (name, want) in &manifest.sha256 {
        let file = dir.join(name);
        if !file.exists() {
            bail!(
                "{} is missing (listed in {}): the checkpoint is incomplete",
                file.display(),
                p.display()
            );
        }
        if sha256_file(&file)? != *want {
            bail!(
                "{} does not match its SHA-256 in {}: it was modified or corrupted after the \
                 checkpoint was written. Restore it, or start a new run",
                file.display(),
                p.display()
            );
        }
    }
    Ok(())
}

/// A run folder's configuration as it trains: its `config.toml`, with the settings its
/// newest checkpoint was trained with where the meaning of a key changed since
/// (`compat.rs`). Returns the config and whether it differs from the file.
pub fn run_config(run: &Path) -> Result<(TrainConfig, bool)> {
    let mut cfg = TrainConfig::load(&run.join(RunDir::CONFIG))?;
    let changed = match find(run) {
        Some(dir) => compat::as_trained(&mut cfg, read_run_state(&dir)?.version),
        None => false,
    };
    Ok((cfg, changed))
}

/// Keys a run may change after a checkpoint: its budget, threads and checkpoint period, and
/// the path of the policy it started from (read once; the run keeps a copy, `RUN/init/`).
const FREE_KEYS: [&str; 7] = [
    "generations",
    "episodes",
    "max_env_steps",
    "threads",
    "checkpoint_every",
    "stop_at_walk",
    "init",
];

/// Differences between two configurations outside [`FREE_KEYS`].
fn fixed_differences(stored: &TrainConfig, cfg: &TrainConfig) -> Result<Vec<String>> {
    Ok(config_differences(stored, cfg)?
        .into_iter()
        .filter(|d| !FREE_KEYS.iter().any(|k| d.starts_with(&format!("{k}:"))))
        .collect())
}

/// The configuration the policy in `dir` (a checkpoint or `best/` folder of `run`) was
/// trained with: the copy in `dir` when it has one, else the copy in the run's last
/// checkpoint, else the run's `config.toml`. Refused when the run's `config.toml` was
/// changed since in anything but its budget and threads: evaluation and recordings use the
/// settings a policy was trained with, never edited ones.
pub fn policy_config(run: &Path, dir: &Path) -> Result<TrainConfig> {
    let (run_cfg, _) = run_config(run)?;
    let copy = [Some(dir.to_path_buf()), find(run)]
        .into_iter()
        .flatten()
        .map(|d| d.join(RunDir::CONFIG))
        .find(|p| p.is_file());
    let Some(p) = copy.filter(|p| *p != run.join(RunDir::CONFIG)) else {
        return Ok(run_cfg);
    };
    let mut stored = TrainConfig::load(&p)?;
    let version = p
        .parent()
        .and_then(|d| read_run_state(d).ok())
        .map_or(STATE_VERSION, |s| s.version);
    compat::as_trained(&mut stored, version);
    let diff = fixed_differences(&stored, &run_cfg)?;
    if !diff.is_empty() {
        bail!(
            "{} differs from the configuration the policy was trained with ({}; trained vs \
             config.toml, from {}): evaluations and recordings use a policy's own settings. \
             Restore config.toml",
            run.join(RunDir::CONFIG).display(),
            diff.join(", "),
            p.display()
        );
    }
    Ok(stored)
}

/// Refuses to resume when the run's configuration changed since the checkpoint was written,
/// naming what changed. Budget keys (`generations`, `episodes`, `max_env_steps`,
/// `stop_at_walk`), `threads` and `checkpoint_every` may change.
pub fn check_config(dir: &Path, state: &RunState, cfg: &TrainConfig) -> Result<()> {
    let p = dir.join("config.toml");
    if !p.exists() {
        return Ok(());
    }
    let mut stored = TrainConfig::load(&p)?;
    compat::as_trained(&mut stored, state.version);
    let diff = fixed_differences(&stored, cfg)?;
    if !diff.is_empty() {
        bail!(
            "the run's config.toml differs from the configuration its checkpoint was trained \
             with ({}; checkpoint vs config.toml). A resumed run keeps its settings (only the \
             budget and threads may change): restore the settings from {}, or start a new run \
             with --config and another --out",
            diff.join(", "),
            p.display()
        );
    }
    Ok(())
}

/// Checks `state.json` against the learner built from the run's configuration and the
/// run's metric log, before anything is truncated: an inconsistent state is refused, naming
/// the field.
pub fn check_state<L: Learner>(
    run: &Path,
    dir: &Path,
    learner: &L,
    state: &RunState,
    learner_state: &LearnerState<L::LoopState>,
) -> Result<()> {
    let p = dir.join("state.json");
    let bad = |field: &str, why: String| -> Result<()> {
        bail!(
            "{}: `{field}` {why}; the checkpoint cannot be trusted",
            p.display()
        )
    };
    if state.curve.len() != state.rows {
        return bad(
            "rows",
            format!(
                "= {} but the curve has {} values",
                state.rows,
                state.curve.len()
            ),
        );
    }
    if state.q0.len() != state.rows {
        return bad(
            "q0",
            format!("has {} values for {} rows", state.q0.len(), state.rows),
        );
    }
    if let Err(esrl_agents::AgentError::State { field, reason }) =
        learner.check(learner_state, state.rows)
    {
        return bad(&field, reason);
    }
    let env_steps = learner_state.env_steps;
    if let Some(log) = &state.replay {
        if log.pushed != env_steps {
            return bad(
                "env_steps",
                format!(
                    "= {env_steps} but the replay log holds {} pushes",
                    log.pushed
                ),
            );
        }
    }
    if state.rows > 0 {
        let metrics = run.join(RunDir::JSONL);
        let text = fs::read_to_string(&metrics)
            .with_context(|| format!("reading {}", metrics.display()))?;
        let Some(line) = text.lines().nth(state.rows - 1) else {
            bail!(
                "{} has {} rows but the checkpoint says {}: the metrics were cut or the state \
                 was edited",
                metrics.display(),
                text.lines().count(),
                state.rows
            );
        };
        let row: serde_json::Value = serde_json::from_str(line)
            .with_context(|| format!("parsing row {} of {}", state.rows, metrics.display()))?;
        if row["env_steps"].as_u64() != Some(env_steps) {
            return bad(
                "env_steps",
                format!(
                    "= {env_steps} but row {} of {} says {}",
                    state.rows,
                    metrics.display(),
                    row["env_steps"]
                ),
            );
        }
    }
    Ok(())
}

/// Reads the run's part of a checkpoint's `state.json` (no manifest check).
fn read_run_state(dir: &Path) -> Result<RunState> {
    let p = dir.join("state.json");
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
}

/// Reads `state.json` of a checkpoint folder, after checking the folder against its
/// manifest: the run's part and the learner's.
pub fn load_state<S: DeserializeOwned>(dir: &Path) -> Result<(RunState, LearnerState<S>)> {
    verify_manifest(dir)?;
    let p = dir.join("state.json");
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    let state: RunState =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    if !(1..=STATE_VERSION).contains(&state.version) {
        bail!(
            "{}: unsupported checkpoint version {}",
            p.display(),
            state.version
        );
    }
    let learner: LearnerState<S> =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    Ok((state, learner))
}

/// The tensors of a checkpoint folder's `agent.safetensors`, refused when any is not finite.
pub fn read_tensors(dir: &Path) -> Result<HashMap<String, Vec<f32>>> {
    let p = dir.join("agent.safetensors");
    let tensors: HashMap<String, Vec<f32>> = load_tensors(&p)
        .with_context(|| format!("reading {}", p.display()))?
        .into_iter()
        .map(|(k, t)| (k, t.data))
        .collect();
    let mut names: Vec<&String> = tensors.keys().collect();
    names.sort();
    for name in names {
        if tensors[name].iter().any(|x| !x.is_finite()) {
            bail!(
                "{}: tensor `{name}` holds non-finite values (NaN or ±inf); these weights \
                 cannot be evaluated or trained (the run diverged before this checkpoint?)",
                p.display()
            );
        }
    }
    Ok(tensors)
}

/// Loads the agent tensors of a checkpoint folder into `agent` (same architecture).
///
/// A policy folder with `actor.safetensors` but no `agent.safetensors` (a study record's
/// `policy/`, kept small) loads the actor alone; [`has_critics`] says which.
pub fn load_agent(dir: &Path, agent: &mut Agent) -> Result<()> {
    verify_manifest(dir)?;
    if !has_critics(dir) && dir.join("actor.safetensors").is_file() {
        let p = dir.join("actor.safetensors");
        return agent
            .load_actor(&p)
            .with_context(|| format!("loading {} (does config.toml match it?)", p.display()));
    }
    let tensors = read_tensors(dir)?;
    agent.load_state_tensors(&tensors).with_context(|| {
        format!(
            "loading {} (does config.toml match the checkpoint?)",
            dir.join("agent.safetensors").display()
        )
    })
}

/// Whether a policy folder holds the whole agent (`agent.safetensors`: critics, targets,
/// optimiser state) and not only its actor.
pub fn has_critics(dir: &Path) -> bool {
    dir.join("agent.safetensors").is_file()
}

/// The replay buffer a checkpoint folder names, for looking inside a run
/// (`examples/critic_probe.rs`): read and checked as on resume, with the episode in progress
/// at the checkpoint counted as ended.
pub fn replay_buffer(dir: &Path, agent: &Agent) -> Result<ReplayBuffer> {
    let state = read_run_state(dir)?;
    read_buffer(dir, &state, agent, false)
}

/// The replay buffer of a checkpoint: its chunks in `RUN/replay/`, each checked against its
/// hash (or the `replay.safetensors` of checkpoints before chunks).
fn read_buffer(
    dir: &Path,
    state: &RunState,
    agent: &Agent,
    episode_open: bool,
) -> Result<ReplayBuffer> {
    let (obs_dim, act_dim) = (agent.obs_dim(), agent.act_dim());
    let capacity = agent.config().buffer_size;
    match &state.replay {
        Some(log) => {
            let run = dir.parent().unwrap_or(Path::new("."));
            let paths: Vec<PathBuf> = log
                .chunks
                .iter()
                .map(|c| run.join(REPLAY).join(&c.file))
                .collect();
            for (c, path) in log.chunks.iter().zip(&paths) {
                if !path.exists() {
                    bail!(
                        "{} is missing: the replay buffer cannot be restored",
                        path.display()
                    );
                }
                if sha256_file(path)? != c.sha256 {
                    bail!(
                        "{} does not match its SHA-256 in {}: modified or corrupted",
                        path.display(),
                        dir.join("state.json").display()
                    );
                }
            }
            let refs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
            ReplayBuffer::load_chunks(&refs, obs_dim, act_dim, capacity, episode_open, log.pushed)
        }
        None => ReplayBuffer::load(
            &dir.join("replay.safetensors"),
            obs_dim,
            act_dim,
            capacity,
            episode_open,
        ),
    }
    .with_context(|| format!("loading the replay buffer of {}", dir.display()))
}

/// Restores `learner` (built fresh from the run's config) from a checkpoint folder: its
/// tensors, its replay buffer and its counters.
pub fn restore<L: Learner>(
    dir: &Path,
    learner: &mut L,
    state: &RunState,
    learner_state: LearnerState<L::LoopState>,
) -> Result<()> {
    let tensors = read_tensors(dir)?;
    let buffer = read_buffer(dir, state, learner.agent(), learner_state.episode_open)?;
    let p = dir.join("agent.safetensors");
    learner
        .restore(learner_state, &tensors, buffer)
        .with_context(|| {
            format!(
                "loading {} (does config.toml match the checkpoint?)",
                p.display()
            )
        })
}
