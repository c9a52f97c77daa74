//! Checkpoints: everything needed to continue a run exactly, written atomically.
//!
//! ```text
//! RUN/checkpoint/
//!   agent.safetensors   actor, critics, targets, Adam moments, log α (and the ES mean)
//!   actor.safetensors   the actor alone, tensor names of esrl-nn (loads in PyTorch/NumPy)
//!   replay.safetensors  the replay buffer, oldest transition first
//!   state.json          counters, random streams, σ, the learning curve so far
//! ```
//!
//! Hybrid runs also keep `RUN/best/` ([`save_best`]): the policy with the highest
//! learning-curve value so far, for `esrl eval RUN/best`.
//!
//! A checkpoint is written to `checkpoint.tmp/`, then swapped in with two renames; a kill at
//! any moment leaves `checkpoint/` or `checkpoint.old/` complete, and loading falls back to the
//! latter.

use anyhow::{bail, Context, Result};
use esrl_agents::{Agent, ReplayBuffer, Trainer};
use esrl_es::Hybrid;
use esrl_nn::{load_tensors, save_params, save_tensors, Module, NamedTensor};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
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
}

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

/// Writes a checkpoint of `learner` into `run/checkpoint/` atomically.
pub fn save(run: &Path, learner: &Learner, state: &CheckpointState) -> Result<()> {
    let tmp = fresh_dir(&run.join("checkpoint.tmp"))?;
    let trainer = learner.trainer();
    let es_mean = match learner {
        Learner::Hybrid(h) => Some(NamedTensor {
            name: "es.mean".into(),
            shape: vec![h.strategy.mean.len()],
            data: h.strategy.mean.clone(),
        }),
        Learner::Plain(_) => None,
    };
    write_agent(&tmp, &trainer.agent, es_mean)?;
    trainer.buffer.save(&tmp.join("replay.safetensors"))?;
    crate::run_dir::write_json_atomic(&tmp.join("state.json"), state)?;
    swap_in(&tmp, &run.join("checkpoint"), &run.join("checkpoint.old"))
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

/// Reads `state.json` of a checkpoint folder.
pub fn load_state(dir: &Path) -> Result<CheckpointState> {
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
    trainer.buffer = ReplayBuffer::load(
        &dir.join("replay.safetensors"),
        trainer.agent.obs_dim(),
        trainer.agent.act_dim(),
        cfg.buffer_size,
        state.episode_open,
    )
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
