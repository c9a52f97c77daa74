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
//! Hybrid runs also keep `RUN/best/` ([`save_best`]): the policy with the highest
//! learning-curve value so far, for `esrl eval RUN/best`.
//!
//! A checkpoint is written to `checkpoint.tmp/`, then swapped in with two renames; a kill at
//! any moment leaves `checkpoint/` or `checkpoint.old/` complete, and loading falls back to the
//! latter.

use crate::config::TrainConfig;
use crate::run_dir::RunDir;
use anyhow::{bail, Context, Result};
use esrl_agents::{Agent, ReplayBuffer, Trainer};
use esrl_es::Hybrid;
use esrl_nn::{load_tensors, save_params, save_tensors, Module, NamedTensor};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::{BTreeMap, HashMap};
use std::fs;
use std::path::{Path, PathBuf};

/// Counters and random streams of a checkpoint (`state.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CheckpointState {
    /// Format version.
    pub version: u32,
    /// Metric rows covered (rows past this are dropped on resume).
    pub rows: usize,
    /// Episodes (plain) completed.
    pub episodes: usize,
    /// Generations (hybrid) completed.
    pub generations: usize,
    /// Environment steps taken.
    pub env_steps: u64,
    /// The trainer's random stream.
    pub trainer_rng: ChaCha8Rng,
    /// Gradient updates done.
    pub agent_updates: u64,
    /// The agent's random stream.
    pub agent_rng: ChaCha8Rng,
    /// Whether the replay buffer's last episode is still open.
    pub episode_open: bool,
    /// ES σ (hybrid).
    pub sigma: Option<f64>,
    /// ES generation counter (hybrid).
    pub es_generation: Option<u64>,
    /// Whether the RL actor carries inner updates not yet evaluated (hybrid). Absent in
    /// checkpoints written before this field existed: then true after generation 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rl_trained: Option<bool>,
    /// The hybrid loop's counts so far (hybrid; absent in older checkpoints).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loop_stats: Option<esrl_es::LoopStats>,
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
}

impl CheckpointState {
    /// The state of a run that has not started: counters at zero, the learner's streams.
    pub fn fresh(learner: &Learner) -> Self {
        Self {
            version: 1,
            rows: 0,
            episodes: 0,
            generations: 0,
            env_steps: 0,
            trainer_rng: learner.trainer().rng.clone(),
            agent_updates: 0,
            agent_rng: learner.trainer().agent.counters().1,
            episode_open: false,
            sigma: None,
            es_generation: None,
            rl_trained: None,
            loop_stats: None,
            wall_s: 0.0,
            curve: Vec::new(),
            q0: Vec::new(),
            replay: None,
        }
    }
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
fn sha256_file(path: &Path) -> Result<String> {
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

/// The training state a checkpoint holds: a plain trainer or a hybrid one.
pub enum Learner {
    /// SAC / TD3 / DDPG.
    Plain(Box<Trainer>),
    /// ES-SAC / ES-TD3 / ES-DDPG.
    Hybrid(Box<Hybrid>),
}

impl Learner {
    /// The RL trainer inside.
    pub fn trainer(&self) -> &Trainer {
        match self {
            Learner::Plain(t) => t,
            Learner::Hybrid(h) => &h.trainer,
        }
    }

    /// The RL trainer inside, mutable.
    pub fn trainer_mut(&mut self) -> &mut Trainer {
        match self {
            Learner::Plain(t) => t,
            Learner::Hybrid(h) => &mut h.trainer,
        }
    }
}

/// Where the newest complete checkpoint of a run folder is, if any.
pub fn find(run: &Path) -> Option<PathBuf> {
    ["checkpoint", "checkpoint.old"]
        .iter()
        .map(|d| run.join(d))
        .find(|d| d.join("state.json").exists() && d.join("agent.safetensors").exists())
}

/// Writes a checkpoint of `learner` into `run/checkpoint/` atomically: the new replay chunk
/// first, then the checkpoint folder (manifest last), swapped in with renames; chunks no
/// longer needed are deleted only once the new checkpoint is in place.
pub fn save(
    run: &Path,
    cfg: &TrainConfig,
    learner: &Learner,
    state: &mut CheckpointState,
) -> Result<()> {
    let trainer = learner.trainer();
    state.replay = Some(append_replay(run, &trainer.buffer, state.replay.take())?);
    let tmp = fresh_dir(&run.join("checkpoint.tmp"))?;
    let es_mean = match learner {
        Learner::Hybrid(h) => Some(NamedTensor {
            name: "es.mean".into(),
            shape: vec![h.strategy.mean.len()],
            data: h.strategy.mean.clone(),
        }),
        Learner::Plain(_) => None,
    };
    write_agent(&tmp, &trainer.agent, es_mean)?;
    crate::run_dir::write_json_atomic(&tmp.join("state.json"), state)?;
    crate::run_dir::write_atomic(&tmp.join("config.toml"), cfg.to_toml()?.as_bytes())?;
    let mut sha256 = BTreeMap::new();
    for name in MANIFEST_FILES {
        sha256.insert(name.to_string(), sha256_file(&tmp.join(name))?);
    }
    crate::run_dir::write_json_atomic(&tmp.join("manifest.json"), &Manifest { sha256 })?;
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

/// Writes `agent.safetensors` (the agent's state tensors, plus `extra`) and
/// `actor.safetensors` (the actor alone) into `dir`.
fn write_agent(dir: &Path, agent: &Agent, extra: Option<NamedTensor>) -> Result<()> {
    let tensors: Vec<NamedTensor> = agent
        .state_tensors()
        .into_iter()
        .map(|(name, data)| NamedTensor {
            shape: vec![data.len()],
            name,
            data,
        })
        .chain(extra)
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

/// Where a hybrid run's best policy so far is kept (see [`save_best`]).
pub const BEST: &str = "best";

/// What `RUN/best/best.json` says about the policy in `RUN/best/`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BestInfo {
    /// The generation (0-based) whose best individual this is.
    pub generation: usize,
    /// Its fitness: that generation's learning-curve value, the highest so far.
    pub fitness: f64,
    /// Environment steps taken by the end of that generation.
    pub env_steps: u64,
}

/// Writes `RUN/best/`: the hybrid run's agent with the actor (and, for ES-SAC, log α) of the
/// generation's best individual ([`Hybrid::kept`]), i.e. the policy that scored the highest
/// learning-curve value so far. `esrl eval RUN/best` evaluates it.
///
/// Same layout as a checkpoint less the replay buffer and `state.json`, written to
/// `best.tmp/` and swapped in like one. It is not a point to resume from.
pub fn save_best(run: &Path, hybrid: &Hybrid, info: &BestInfo) -> Result<()> {
    let tmp = fresh_dir(&run.join("best.tmp"))?;
    let mut agent = hybrid.trainer.agent.clone();
    agent
        .set_genome(&hybrid.kept)
        .context("taking the best individual's genome")?;
    write_agent(&tmp, &agent, None)?;
    crate::run_dir::write_json_atomic(&tmp.join("best.json"), info)?;
    swap_in(&tmp, &run.join(BEST), &run.join("best.old"))
}

/// Removes `RUN/best/` (a run started over must not keep a policy of its previous start).
pub fn remove_best(run: &Path) -> Result<()> {
    let dir = run.join(BEST);
    if dir.exists() {
        fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
    }
    Ok(())
}

/// Checks every file of a checkpoint folder against its `manifest.json` (checkpoints written
/// before manifests existed have none and pass).
fn verify_manifest(dir: &Path) -> Result<()> {
    let p = dir.join("manifest.json");
    if !p.exists() {
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
                "{} does not match its SHA-256 in {}: it was modified or corrupted after the                  checkpoint was written. Restore it, or start a new run",
                file.display(),
                p.display()
            );
        }
    }
    Ok(())
}

/// Refuses to resume when the run's configuration changed since the checkpoint was written,
/// naming what changed. Budget keys (`generations`, `episodes`, `max_env_steps`), `threads`
/// and `checkpoint_every` may change.
pub fn check_config(dir: &Path, cfg: &TrainConfig) -> Result<()> {
    let p = dir.join("config.toml");
    if !p.exists() {
        return Ok(());
    }
    let stored = TrainConfig::load(&p)?;
    let free = [
        "generations",
        "episodes",
        "max_env_steps",
        "threads",
        "checkpoint_every",
    ];
    let diff: Vec<String> = crate::compare::config_differences(&stored, cfg)?
        .into_iter()
        .filter(|d| !free.iter().any(|k| d.starts_with(&format!("{k}:"))))
        .collect();
    if !diff.is_empty() {
        bail!(
            "the run's config.toml differs from the configuration its checkpoint was trained              with ({}; checkpoint vs config.toml). A resumed run keeps its settings (only the              budget and threads may change): restore the settings from {}, or start a new run              with --config and another --out",
            diff.join(", "),
            p.display()
        );
    }
    Ok(())
}

/// Checks `state.json` against the configuration's rules and the run's metric log, before
/// anything is truncated: an inconsistent state is refused, naming the field.
pub fn check_state(
    run: &Path,
    dir: &Path,
    state: &CheckpointState,
    cfg: &TrainConfig,
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
    let counted = if cfg.agent.is_hybrid() {
        state.generations
    } else {
        state.episodes
    };
    if counted != state.rows {
        let field = if cfg.agent.is_hybrid() {
            "generations"
        } else {
            "episodes"
        };
        return bad(field, format!("= {counted} but rows = {}", state.rows));
    }
    if cfg.agent.is_hybrid() {
        let Some(sigma) = state.sigma else {
            return bad("sigma", "is missing for an ES run".into());
        };
        let (lo, hi) = (
            cfg.es.sigma.min(cfg.es.sigma_min),
            cfg.es.sigma.max(cfg.es.sigma_min),
        );
        if !(sigma.is_finite() && sigma >= lo * (1.0 - 1e-9) && sigma <= hi * (1.0 + 1e-9)) {
            return bad(
                "sigma",
                format!("= {sigma}, outside [{lo}, {hi}] where eq. 11 keeps it"),
            );
        }
        if state.es_generation != Some(state.generations as u64) {
            return bad(
                "es_generation",
                format!(
                    "= {:?} but generations = {}",
                    state.es_generation, state.generations
                ),
            );
        }
    }
    if let Some(log) = &state.replay {
        if log.pushed != state.env_steps {
            return bad(
                "env_steps",
                format!(
                    "= {} but the replay log holds {} pushes",
                    state.env_steps, log.pushed
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
                "{} has {} rows but the checkpoint says {}: the metrics were cut or the state                  was edited",
                metrics.display(),
                text.lines().count(),
                state.rows
            );
        };
        let row: serde_json::Value = serde_json::from_str(line)
            .with_context(|| format!("parsing row {} of {}", state.rows, metrics.display()))?;
        if row["env_steps"].as_u64() != Some(state.env_steps) {
            return bad(
                "env_steps",
                format!(
                    "= {} but row {} of {} says {}",
                    state.env_steps,
                    state.rows,
                    metrics.display(),
                    row["env_steps"]
                ),
            );
        }
    }
    Ok(())
}

/// Reads `state.json` of a checkpoint folder, after checking the folder against its manifest.
pub fn load_state(dir: &Path) -> Result<CheckpointState> {
    verify_manifest(dir)?;
    let p = dir.join("state.json");
    let text = fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    let state: CheckpointState =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    if state.version != 1 {
        bail!(
            "{}: unsupported checkpoint version {}",
            p.display(),
            state.version
        );
    }
    Ok(state)
}

/// Loads the agent tensors of a checkpoint folder into `agent` (same architecture).
pub fn load_agent(dir: &Path, agent: &mut Agent) -> Result<HashMap<String, Vec<f32>>> {
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
                "{}: tensor `{name}` holds non-finite values (NaN or ±inf); these weights cannot be evaluated or trained (the run diverged before this checkpoint?)",
                p.display()
            );
        }
    }
    agent.load_state_tensors(&tensors).with_context(|| {
        format!(
            "loading {} (does config.toml match the checkpoint?)",
            p.display()
        )
    })?;
    Ok(tensors)
}

/// Restores `learner` (built fresh from the run's config) from a checkpoint folder.
pub fn restore(dir: &Path, learner: &mut Learner, state: &CheckpointState) -> Result<()> {
    let tensors = {
        let trainer = learner.trainer_mut();
        load_agent(dir, &mut trainer.agent)?
    };
    let trainer = learner.trainer_mut();
    trainer
        .agent
        .set_counters(state.agent_updates, state.agent_rng.clone());
    trainer.rng = state.trainer_rng.clone();
    trainer.env_steps = state.env_steps;
    trainer.episodes = state.episodes;
    let cfg = trainer.agent.config().clone();
    let (obs_dim, act_dim) = (trainer.agent.obs_dim(), trainer.agent.act_dim());
    trainer.buffer = match &state.replay {
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
            ReplayBuffer::load_chunks(
                &refs,
                obs_dim,
                act_dim,
                cfg.buffer_size,
                state.episode_open,
                log.pushed,
            )
        }
        None => ReplayBuffer::load(
            &dir.join("replay.safetensors"),
            obs_dim,
            act_dim,
            cfg.buffer_size,
            state.episode_open,
        ),
    }
    .with_context(|| format!("loading the replay buffer of {}", dir.display()))?;
    if let Learner::Hybrid(h) = learner {
        let mean = tensors
            .get("es.mean")
            .with_context(|| format!("{}: no es.mean tensor", dir.display()))?;
        if mean.len() != h.strategy.mean.len() {
            bail!(
                "{}: es.mean has {} values, expected {}",
                dir.display(),
                mean.len(),
                h.strategy.mean.len()
            );
        }
        h.strategy.mean = mean.clone();
        h.strategy.sigma = state.sigma.unwrap_or(h.strategy.sigma);
        h.strategy.generation = state.es_generation.unwrap_or(0);
        h.generation = state.generations;
        h.rl_trained = state
            .rl_trained
            .unwrap_or(h.generation > 0 && h.inner_cycles > 0);
        h.stats = state.loop_stats.clone().unwrap_or_default();
    }
    Ok(())
}
