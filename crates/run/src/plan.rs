//! What a `train` command asks for, turned into a configuration and a folder: a new run from
//! a preset, a file and flags, or a run folder continued with the budget and thread flags
//! applied. One implementation for every front end (`esrl train`, `python -m esrl_rs.ray
//! train`), so a run started by one resumes in the other.

use crate::bail;
use crate::checkpoint;
use crate::config::{AgentKind, EnvKind, Overrides, Preset, TrainConfig};
use crate::error::Result;
use crate::restart;
use crate::run_dir::{write_atomic, RunDir};
use std::path::PathBuf;

/// A `train` command's arguments.
#[derive(Debug, Clone)]
pub struct TrainRequest {
    /// The agent.
    pub agent: AgentKind,
    /// Seed of every random stream (new runs).
    pub seed: Option<u64>,
    /// Run folder of a new run (default [`default_out`]).
    pub out: Option<PathBuf>,
    /// A run folder to continue from its last checkpoint.
    pub resume: Option<PathBuf>,
    /// Preset, config file and flags (on a resume only the budget and threads count).
    pub overrides: Overrides,
}

/// A run ready to open with [`crate::Training::open`].
#[derive(Debug, Clone, PartialEq)]
pub struct TrainPlan {
    /// Its configuration (on a resume, the folder's with the new budget and threads; the
    /// folder's `config.toml` already says so).
    pub cfg: TrainConfig,
    /// Its folder.
    pub root: PathBuf,
    /// Whether it continues an existing run.
    pub resume: bool,
    /// What the user should be told before it starts.
    pub notes: Vec<String>,
}

/// Where a run goes by default: `runs/<agent>-s<seed>` for the default preset on the walking
/// env, `runs/<agent>-<preset>-s<seed>` for another preset (`runs/es-sac-quick-s0`), with
/// `-<env>` before the seed on another env (`runs/sac-paper-pendulum-s0`) and `-init` for a
/// run that starts from a trained policy (`runs/es-sac-init-s4`), so the quick start's
/// commands never share a folder.
pub fn default_out(cfg: &TrainConfig) -> PathBuf {
    let mut name = cfg.agent.name().to_owned();
    if cfg.preset != Preset::default() {
        name = format!("{name}-{}", cfg.preset.name());
    }
    if cfg.env != EnvKind::Walk {
        name = format!("{name}-{}", cfg.env.name());
    }
    if cfg.init.is_some() {
        // A fine-tuning run is not the run of its seed.
        name = format!("{name}-init");
    }
    PathBuf::from("runs").join(format!("{name}-s{}", cfg.seed))
}

/// Resolves `req`. A resume reads the folder's `config.toml` (the agent must match), applies
/// `--generations`, `--episodes`, `--steps` and `--threads`, and writes the result back so
/// that `--config RUN/config.toml` keeps repeating the run as it now is.
pub fn plan(req: &TrainRequest) -> Result<TrainPlan> {
    let Some(dir) = &req.resume else {
        let cfg = TrainConfig::resolve(req.agent, &req.overrides, req.seed)?;
        let root = req.out.clone().unwrap_or_else(|| default_out(&cfg));
        if root.join(RunDir::JSONL).exists() || root.join(restart::RESTARTS_FILE).exists() {
            let how = if checkpoint::find(&root).is_some()
                || root.join(restart::RESTARTS_FILE).exists()
            {
                "continues it from its last checkpoint"
            } else {
                "starts it over (it stopped before its first checkpoint)"
            };
            bail!(
                "{dir} already holds a run; `{esrl} train {agent} --resume {dir}` {how}, or \
                 give this one a new folder with --out DIR",
                esrl = crate::command(),
                dir = root.display(),
                agent = req.agent.name(),
            );
        }
        return Ok(TrainPlan {
            cfg,
            root,
            resume: false,
            notes: Vec::new(),
        });
    };
    if let Some(init) = &req.overrides.init {
        bail!(
            "--init {}: a resumed run continues from its own checkpoint (its config.toml says \
             where it started); fine-tune into a new folder with --out instead",
            init.display()
        );
    }
    let path = dir.join(RunDir::CONFIG);
    if !path.exists() {
        bail!(
            "{} is not a run folder (it has no {}); start a new run with --out",
            dir.display(),
            RunDir::CONFIG
        );
    }
    // A policy folder (a run's best/ or checkpoint/ given directly, a study record's
    // policy/) has a config.toml too, but no run to continue: training there would write a
    // new run's files into it.
    let ran = dir.join(RunDir::JSONL).exists()
        || checkpoint::find(dir).is_some()
        || dir.join(restart::RESTARTS_FILE).exists();
    let weights = ["agent.safetensors", "actor.safetensors"]
        .iter()
        .any(|f| dir.join(f).is_file());
    if weights && !ran {
        bail!(
            "{dir} holds a policy, not a run (no {} and no checkpoint): nothing to resume. \
             Resume the run folder it came from, or fine-tune from it into a new folder: \
             `{esrl} train {agent} --init {dir} --out DIR`",
            RunDir::JSONL,
            dir = dir.display(),
            esrl = crate::command(),
            agent = req.agent.name(),
        );
    }
    let (mut cfg, legacy) = checkpoint::run_config(dir)?;
    if cfg.agent != req.agent {
        bail!(
            "{} is a {} run, not {}",
            dir.display(),
            cfg.agent.name(),
            req.agent.name()
        );
    }
    let mut notes = Vec::new();
    if legacy {
        notes.push(format!(
            "{}: a DDPG checkpoint from before DDPG honoured rl.policy_delay and \
             rl.target_noise; it trained with 1 and 0, and continues so (config.toml is \
             updated)",
            dir.display()
        ));
    }
    if checkpoint::find(dir).is_none() {
        notes.push(format!(
            "{} has no checkpoint yet (stopped before its first one): starting it over from \
             the beginning with its config.toml",
            dir.display()
        ));
    }
    let stored = TrainConfig::load(&path)?;
    cfg.apply_budget(&req.overrides);
    cfg.validate()?;
    if let Some(state) = checkpoint::find(dir).and_then(|c| checkpoint::rows_done(&c)) {
        let (budget, unit) = if cfg.agent.is_hybrid() {
            (cfg.generations, "generations")
        } else {
            (cfg.episodes, "episodes")
        };
        if budget < state {
            bail!(
                "--{unit} {budget}: {} has done {state} {unit} already; a budget below that \
                 cannot continue it (config.toml is left as it was)",
                dir.display()
            );
        }
    }
    if cfg != stored {
        write_atomic(&path, cfg.to_toml()?.as_bytes())?;
    }
    Ok(TrainPlan {
        cfg,
        root: dir.clone(),
        resume: true,
        notes,
    })
}
