//! Starting a run from a trained policy's weights (`init` in `config.toml`,
//! `esrl train --init DIR`): fine-tuning.
//!
//! A run with `init = "DIR"` builds its learner as usual and then replaces the agent's
//! weights with those of the policy in `DIR` before anything trains: the actor, and the
//! critics, their targets, the optimiser state and α when the folder holds them
//! (`agent.safetensors`: a checkpoint or `RUN/best/`; a study record's `policy/` keeps the
//! actor alone, and the critics are then fresh). The hybrid loop's ES distribution is
//! centred on the loaded actor. The replay buffer starts empty and fills as any run's does.
//! Everything else is the run's own configuration: its reward, its disturbances
//! (`[walk.perturb]`), its budget and its walking check, which judges the run's own task.
//!
//! The loaded policy must mean what the run's policy means: the same environment, networks,
//! action mapping, observation (gait clock period, scaling), actuated joints, feet, standing
//! pose and robot. [`meaning_differences`] names what differs, and such a start is refused.
//!
//! `DIR` is read once, when the run starts: the weights loaded are copied into `RUN/init/`
//! ([`snapshot`]) and `RUN/init.json` ([`InitRecord`]) records the folder and their SHA-256.
//! A run with `[restart]` starts every attempt from that copy, and so does a run killed
//! before its first checkpoint that starts over; a resumed run continues from its own
//! checkpoint.

use crate::bail;
use crate::checkpoint::{self, sha256_file};
use crate::config::{config_differences, TrainConfig};
use crate::error::{Context, Result};
use crate::run_dir::{write_json_atomic, RunDir};
use esrl_agents::Agent;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file in a run folder that says which weights the run started from.
pub const INIT_FILE: &str = "init.json";

/// What `RUN/init.json` says about the weights a run started from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InitRecord {
    /// The run's `init` as configured.
    pub from: PathBuf,
    /// The policy folder the weights were read from ([`policy_folder`]).
    pub folder: PathBuf,
    /// Whether the critics, targets, optimiser state and α were loaded too (else the actor
    /// alone).
    pub critics: bool,
    /// The weights file loaded (`agent.safetensors` or `actor.safetensors`).
    pub file: String,
    /// Its SHA-256.
    pub sha256: String,
}

/// The policy folder `path` names: `path` itself when it holds weights (a checkpoint,
/// `best/` or a study record's `policy/`), or, for a run folder, its kept policy
/// `RUN/best/`, else its last checkpoint.
pub fn policy_folder(path: &Path) -> Result<PathBuf> {
    if !path.is_dir() {
        bail!(
            "init = {}: no such folder (a run folder, its best/ or checkpoint/, or a study \
             record's policy/)",
            path.display()
        );
    }
    if path.join("agent.safetensors").is_file() || path.join("actor.safetensors").is_file() {
        return Ok(path.to_path_buf());
    }
    if path.join(RunDir::CONFIG).is_file() {
        let best = path.join(checkpoint::BEST);
        if best.join("agent.safetensors").is_file() {
            return Ok(best);
        }
        if let Some(dir) = checkpoint::find(path) {
            return Ok(dir);
        }
    }
    bail!(
        "init = {}: holds no policy (no agent.safetensors or actor.safetensors, and no run \
         folder with best/ or a checkpoint)",
        path.display()
    )
}

/// The configuration the policy in `folder` was trained with: its own copy, checked
/// against its run's `config.toml` when it sits in a run folder ([`checkpoint::policy_config`]).
fn source_config(folder: &Path) -> Result<TrainConfig> {
    if is_copy(folder) {
        return TrainConfig::load(&folder.join(RunDir::CONFIG));
    }
    let run = folder
        .parent()
        .filter(|p| p.join(RunDir::CONFIG).is_file())
        .unwrap_or(folder);
    checkpoint::policy_config(run, folder)
}

/// The keys that give a policy its meaning: its inputs, its outputs and the body they act on,
/// each with whether the keys under it count too. The gait clock counts by its presence and
/// its period (what its phase input means); its reward terms may change.
const MEANING_KEYS: [(&str, bool); 12] = [
    ("env", false),
    ("network", true),
    ("walk.urdf", true),
    ("walk.control_period", false),
    ("walk.action", true),
    ("walk.target", true),
    ("walk.gait_clock", false),
    ("walk.gait_clock.period", false),
    ("walk.normalize_obs", false),
    ("walk.actuated_joints", true),
    ("walk.foot_links", true),
    ("walk.standing_pose", true),
];

/// Where the policy trained under `source` would mean something else under `cfg`, as
/// `key: source vs run`: the keys of [`MEANING_KEYS`], and the algorithm (an ES-SAC policy
/// may start a SAC run, not a TD3 one).
pub fn meaning_differences(source: &TrainConfig, cfg: &TrainConfig) -> Result<Vec<String>> {
    let mut out: Vec<String> = config_differences(source, cfg)?
        .into_iter()
        .filter(|d| {
            let key = d.split_once(": ").map_or(d.as_str(), |(k, _)| k);
            MEANING_KEYS.iter().any(|&(k, under)| {
                key == k || (under && key.strip_prefix(k).is_some_and(|r| r.starts_with('.')))
            })
        })
        .collect();
    if source.agent.algo() != cfg.agent.algo() {
        out.push(format!(
            "agent: {} vs {}",
            source.agent.name(),
            cfg.agent.name()
        ));
    }
    Ok(out)
}

/// Loads the weights `cfg.init` names into `agent`, when it names some. Refuses a policy
/// whose meaning differs from the run's ([`meaning_differences`]). What was loaded is
/// [`record`]'s to say (the session hashes it once, before loading).
pub fn load(cfg: &TrainConfig, agent: &mut Agent) -> Result<()> {
    let Some(from) = &cfg.init else {
        return Ok(());
    };
    let folder = policy_folder(from)?;
    let source = source_config(&folder)
        .with_context(|| format!("init = {}: its configuration", from.display()))?;
    let diff = meaning_differences(&source, cfg)?;
    if !diff.is_empty() {
        bail!(
            "init = {}: the policy was trained for another task or network than this run's \
             ({}; the policy's vs the run's), so its weights would mean something else here",
            from.display(),
            diff.join(", ")
        );
    }
    checkpoint::load_agent(&folder, agent)
        .with_context(|| format!("init = {}: loading its weights", from.display()))
}

/// What a run with `init = from` loads: the folder, which file, and its SHA-256.
pub fn record(from: &Path) -> Result<InitRecord> {
    let folder = policy_folder(from)?;
    let critics = checkpoint::has_critics(&folder);
    let file = if critics {
        "agent.safetensors"
    } else {
        "actor.safetensors"
    };
    Ok(InitRecord {
        from: from.to_path_buf(),
        sha256: sha256_file(&folder.join(file))?,
        folder,
        critics,
        file: file.into(),
    })
}

/// The folder in a run that keeps a copy of the policy it started from.
pub const INIT_DIR: &str = "init";

/// Whether `folder` is a run's own copy of its starting policy (`RUN/init/`).
fn is_copy(folder: &Path) -> bool {
    folder.file_name().is_some_and(|n| n == INIT_DIR)
        && folder.parent().is_some_and(|r| r.join(INIT_FILE).is_file())
}

/// The run's own copy of the policy it started from, once written ([`snapshot`]): what a
/// restart, or a start over before the first checkpoint, loads instead of `init`'s folder,
/// which may have changed or gone since.
pub fn local(root: &Path) -> Option<PathBuf> {
    let dir = root.join(INIT_DIR);
    (root.join(INIT_FILE).is_file() && dir.join(RunDir::CONFIG).is_file()).then_some(dir)
}

/// Copies the policy `record` names into `RUN/init/` (its weights file and its training
/// configuration) and writes `RUN/init.json`. Refused when the copy is not the file that
/// was hashed when the run loaded it (the folder changed meanwhile).
pub fn snapshot(root: &Path, record: &InitRecord) -> Result<()> {
    let tmp = root.join("init.tmp");
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
    }
    std::fs::create_dir_all(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
    let from = record.folder.join(&record.file);
    std::fs::copy(&from, tmp.join(&record.file))
        .with_context(|| format!("copying {}", from.display()))?;
    if sha256_file(&tmp.join(&record.file))? != record.sha256 {
        bail!(
            "init = {}: {} changed while the run started; start it again",
            record.from.display(),
            from.display()
        );
    }
    let source = source_config(&record.folder)?;
    crate::run_dir::write_atomic(&tmp.join(RunDir::CONFIG), source.to_toml()?.as_bytes())?;
    let dir = root.join(INIT_DIR);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
    }
    std::fs::rename(&tmp, &dir).with_context(|| format!("moving {}", tmp.display()))?;
    write_json_atomic(&root.join(INIT_FILE), record)
}
