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
//! undisturbed = false             # true: on the plain task, without [walk.perturb]
//! default_starts = false          # true: from the task's standard starts (walk.init_noise,
//!                                 # walk.reset at their defaults), for runs trained from others
//! robustness_episodes = 0         # n > 0: also the robustness card, n episodes per row
//!                                 # (reset seeds 1000…), and the robustness goal's rows met
//!
//! [[arm]]
//! name = "default"
//! agent = "es-sac"                # preset "walker-even" (the default) unless `preset` says otherwise
//!
//! [[arm]]
//! name = "mirror"
//! agent = "es-sac"
//! config = "overlays/mirror.toml" # a file laid over the preset (relative to this file)
//! set = { rl = { mirror = true } } # or keys inline
//! steps = 2000000                 # budget: steps, generations, episodes
//! seeds = [3, 4]                  # this arm's own seeds (default: the study's)
//!
//! [[arm]]
//! name = "fine-tuned"
//! agent = "es-sac"
//! set = { init = "walker/records/default-s4/policy" } # start from a policy (relative to this file)
//!
//! [[arm]]
//! name = "own-walk"
//! agent = "es-sac"
//! set = { init = "sources/s{seed}" } # each seed from its own policy: {seed} is the run's seed
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
//! record (runs found finished are recorded before any training starts); finished runs and
//! written records are reused, so the same command continues a stopped study and gives the
//! records an uninterrupted one would. `--shard i/n` takes the runs whose index (arms in
//! order, seeds within) is i modulo n: n machines each run one shard into their own `DIR`,
//! and the records folders merge by copying. The report reads records only.

mod report;
mod run;

pub(crate) use report::report;
pub(crate) use run::run_study;

use crate::args::{AgentKind, Preset, StudyArgs, StudyCommand};
use anyhow::{bail, Context, Result};
use esrl_eval::EvalReport;
use esrl_metrics::gait_classes_text;
use esrl_run::{Overrides, TrainConfig};
use serde::{Deserialize, Serialize};
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

    /// At least one seed, none twice (`what` names them in the error).
    fn check(&self, what: &str) -> Result<()> {
        let seeds = self.list();
        if seeds.is_empty() {
            bail!("{what}: no seed");
        }
        let mut sorted = seeds.clone();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != seeds.len() {
            bail!("{what}: a seed is listed twice");
        }
        Ok(())
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
    /// Evaluate on the plain task, without the runs' training-time disturbances
    /// (`[walk.perturb]`; as `esrl eval --undisturbed`). Default false: each run's own task.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub undisturbed: bool,
    /// Evaluate from the task's standard starts (`walk.init_noise` and `walk.reset` at their
    /// defaults; as `esrl eval --default-starts`), for runs trained from other starts.
    /// Default false: each run's own starts.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub default_starts: bool,
    /// Episodes per row of the robustness card (`esrl eval --robustness`, from the same reset
    /// seeds; walking runs), kept in the record's `eval.json` with the robustness goal's rows
    /// met; the report counts the runs that meet each goal row. Default 0: no card (a card of
    /// 26 rows × 10 episodes is about 260 walking episodes a run).
    #[serde(skip_serializing_if = "is_zero")]
    pub robustness_episodes: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl Default for StudyEval {
    fn default() -> Self {
        Self {
            episodes: 20,
            seed: 1000,
            policy: Handover::Kept,
            traces: 1,
            undisturbed: false,
            default_starts: false,
            robustness_episodes: 0,
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
    /// The preset underneath (default `walker-even`).
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
    /// This arm's seeds, when not the study's (a count or a list).
    #[serde(default)]
    pub seeds: Option<Seeds>,
}

impl Arm {
    /// The arm's seeds: its own, else the study's.
    fn seeds<'a>(&'a self, study: &'a Seeds) -> &'a Seeds {
        self.seeds.as_ref().unwrap_or(study)
    }
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
        file.seeds.check("seeds")?;
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
            if let Some(seeds) = &arm.seeds {
                seeds.check(&format!("arm `{}`: seeds", arm.name))?;
            }
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
        let mut runs = Vec::new();
        for (i, arm) in self.file.arms.iter().enumerate() {
            for seed in arm.seeds(&self.file.seeds).list() {
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
                // A policy to start from is named from the study file's folder, as its
                // config files are; `{seed}` in its name is the run's seed.
                if let Some(init) = cfg.init.as_mut() {
                    let named =
                        PathBuf::from(init.to_string_lossy().replace("{seed}", &seed.to_string()));
                    let path = base.join(named);
                    *init = std::path::absolute(&path).unwrap_or(path);
                }
                if self.file.eval.robustness_episodes > 0 && cfg.env != esrl_run::EnvKind::Walk {
                    bail!(
                        "arm `{}`: eval.robustness_episodes asks for the robustness card, which is \
                         for walking runs (this arm trains on {:?})",
                        arm.name,
                        cfg.env
                    );
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
        StudyCommand::Status { dir } => run::status(dir),
        StudyCommand::Report { dir, json } => report(dir, *json),
    }
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
    let falls = match r.mean.falls {
        1 => "1 fall".to_string(),
        n => format!("{n} falls"),
    };
    format!(
        "{classes}; {}/{} finished, {falls}",
        r.mean.finished, r.mean.episodes
    )
}
