//! Loading a trained policy: a run folder (its newest checkpoint), a checkpoint folder, or
//! `RUN/best`, with the run's configuration and environment.

use esrl_agents::Agent;
use esrl_run::checkpoint;
use esrl_run::{bail, build, Context, Result, RunDir, TrainConfig};
use esrl_sim::{RobotModel, WalkEnv};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A trained agent loaded from a run or checkpoint folder.
pub struct LoadedRun {
    /// The run folder (holds `config.toml`).
    pub run: PathBuf,
    /// The checkpoint folder the weights came from.
    pub checkpoint: PathBuf,
    /// The run's configuration.
    pub config: TrainConfig,
    /// The agent with the checkpoint's weights.
    pub agent: Agent,
    /// The robot model (walking runs).
    pub model: Option<Arc<RobotModel>>,
}

impl LoadedRun {
    /// The same policy on the walking task `walk` (a disturbed copy of the run's own, for
    /// robustness tests), checked.
    pub fn with_walk(&self, walk: esrl_sim::WalkConfig) -> Result<LoadedRun> {
        walk.validate().context("the walking task to evaluate on")?;
        let mut config = self.config.clone();
        config.walk = walk;
        Ok(LoadedRun {
            run: self.run.clone(),
            checkpoint: self.checkpoint.clone(),
            config,
            agent: self.agent.clone(),
            model: self.model.clone(),
        })
    }

    /// The same policy on its task without the training-time disturbances (`[walk.perturb]`
    /// cleared): how a policy trained under disturbances walks on the plain task
    /// (`esrl eval --undisturbed`, a study's `[eval] undisturbed = true`).
    pub fn undisturbed(&self) -> Result<LoadedRun> {
        let mut walk = self.config.walk.clone();
        walk.perturb = esrl_sim::Perturb::default();
        self.with_walk(walk)
    }

    /// The same policy from the task's default starts: `walk.init_noise` and `walk.reset` at
    /// their defaults (the standing pose, ±0.01 rad and ±0.01 rad/s of joint noise), the rest
    /// of the run's task unchanged: how a policy trained from other starts walks from the
    /// standard ones (`esrl eval --default-starts`).
    pub fn default_starts(&self) -> Result<LoadedRun> {
        let mut walk = self.config.walk.clone();
        walk.init_noise = esrl_sim::InitNoise::default();
        walk.reset = esrl_sim::ResetConfig::default();
        self.with_walk(walk)
    }

    /// A fresh walking environment of this run (`None` for a pendulum run).
    pub fn walk_env(&self) -> Result<Option<WalkEnv>> {
        match &self.model {
            Some(model) => Ok(Some(
                WalkEnv::from_model(model.clone(), self.config.walk.clone())
                    .context("building the walking environment")?,
            )),
            None => Ok(None),
        }
    }
}

/// Which policy of a run folder to load.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pick {
    /// The policy the run hands over: `RUN/best/` when the run keeps one (ES runs, and any
    /// run with a walking check), else the last checkpoint.
    #[default]
    Kept,
    /// The last checkpoint's actor.
    Last,
}

/// Finds the run folder and the policy folder of `path`; a run folder means the policy it
/// hands over, as `esrl eval RUN` takes it ([`Pick::Kept`]; [`locate_pick`] chooses).
pub fn locate(path: &Path) -> Result<(PathBuf, PathBuf)> {
    locate_pick(path, Pick::Kept)
}

/// Finds the run folder and the policy folder of `path`: a checkpoint or `best/` folder as
/// given, or, for a run folder, `RUN/best/` or the last checkpoint as `pick` says.
pub fn locate_pick(path: &Path, pick: Pick) -> Result<(PathBuf, PathBuf)> {
    if !path.exists() {
        bail!("{}: no such run or checkpoint folder", path.display());
    }
    if !path.is_dir() {
        bail!(
            "{} is a file; expected a run folder (with config.toml) or a checkpoint folder \
             (with agent.safetensors)",
            path.display()
        );
    }
    // A policy folder that keeps the actor alone (a study record's `policy/`): it has its
    // own config.toml and no checkpoint inside.
    if path.join("actor.safetensors").is_file()
        && !path.join("agent.safetensors").exists()
        && path.join(RunDir::CONFIG).is_file()
        && checkpoint::find(path).is_none()
    {
        return Ok((path.to_path_buf(), path.to_path_buf()));
    }
    // A checkpoint folder (it holds the weights; checkpoints also keep a copy of the run's
    // config.toml, so test for the weights first).
    if path.join("agent.safetensors").is_file() {
        let abs = path
            .canonicalize()
            .with_context(|| format!("resolving {}", path.display()))?;
        if let Some(run) = abs.parent().filter(|r| r.join(RunDir::CONFIG).is_file()) {
            return Ok((run.to_path_buf(), path.to_path_buf()));
        }
        if path.join(RunDir::CONFIG).is_file() {
            return Ok((path.to_path_buf(), path.to_path_buf()));
        }
        bail!(
            "{} looks like a checkpoint folder, but neither it nor its parent folder has a \
             config.toml, so the architecture of the networks is unknown",
            path.display()
        );
    }
    if path.join(RunDir::CONFIG).is_file() {
        let best = path.join(checkpoint::BEST);
        if pick == Pick::Kept && best.join("agent.safetensors").is_file() {
            return Ok((path.to_path_buf(), best));
        }
        let ckpt = checkpoint::find(path).with_context(|| {
            format!(
                "{} has no complete checkpoint (checkpoint/ with state.json and \
                 agent.safetensors); a run killed before its first checkpoint has none",
                path.display()
            )
        })?;
        return Ok((path.to_path_buf(), ckpt));
    }
    bail!(
        "{} is neither a run folder (no config.toml) nor a checkpoint folder (no \
         agent.safetensors)",
        path.display()
    )
}

/// Loads the run's config and the policy's weights (a run, checkpoint, `best/` or record
/// `policy/` folder; a run folder means the policy it hands over, `RUN/best/` when it keeps
/// one, as `esrl eval RUN` takes it: [`Pick::Kept`]; [`load_run_pick`] chooses).
pub fn load_run(path: &Path) -> Result<LoadedRun> {
    load_run_pick(path, Pick::Kept)
}

/// Loads a policy ([`locate_pick`]) with the configuration it was trained with: the copy in
/// its folder when it has one (checkpoints and `best/` keep one), else the run's. Refuses a
/// run whose `config.toml` was changed since (other than its budget and thread keys), and
/// weights that do not match their folder's `manifest.json`.
pub fn load_run_pick(path: &Path, pick: Pick) -> Result<LoadedRun> {
    let (run, ckpt) = locate_pick(path, pick)?;
    let config = checkpoint::policy_config(&run, &ckpt)?;
    let envs = build::envs(config.env, &config.walk)
        .with_context(|| format!("the environment of {}", run.display()))?;
    let mut agent =
        build::agent(&config, &envs).with_context(|| format!("in {}", run.display()))?;
    checkpoint::load_agent(&ckpt, &mut agent)?;
    Ok(LoadedRun {
        run,
        checkpoint: ckpt,
        config,
        agent,
        model: envs.model,
    })
}
