//! The resolved training configuration: preset, then a TOML file, then command-line flags
//! ([`Overrides`]).
//!
//! The run folder's `config.toml` is this struct serialised, so a run can be repeated with
//! `esrl train <agent> --config RUN/config.toml`. Unknown keys are refused with their name.

use crate::bail;
use crate::check::CheckConfig;
use crate::error::{Context, Result};
use crate::restart::RestartConfig;
use esrl_agents::{Algo, NetConfig, RlConfig};
use esrl_es::EsConfig;
use esrl_sim::WalkConfig;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The six agents.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum AgentKind {
    /// Hybrid evolution strategy + SAC (the paper's method).
    EsSac,
    /// Hybrid evolution strategy + TD3.
    EsTd3,
    /// Hybrid evolution strategy + DDPG.
    EsDdpg,
    /// Soft actor-critic.
    Sac,
    /// Twin delayed DDPG.
    Td3,
    /// Deep deterministic policy gradient.
    Ddpg,
}

impl AgentKind {
    /// All six, in the paper's Table 1 order.
    pub const ALL: [AgentKind; 6] = [
        AgentKind::EsSac,
        AgentKind::EsTd3,
        AgentKind::EsDdpg,
        AgentKind::Sac,
        AgentKind::Td3,
        AgentKind::Ddpg,
    ];

    /// The name used on the command line and in files (`es-sac`, …).
    pub fn name(self) -> &'static str {
        match self {
            AgentKind::EsSac => "es-sac",
            AgentKind::EsTd3 => "es-td3",
            AgentKind::EsDdpg => "es-ddpg",
            AgentKind::Sac => "sac",
            AgentKind::Td3 => "td3",
            AgentKind::Ddpg => "ddpg",
        }
    }

    /// Whether the agent runs ES generations (true) or plain episodes (false).
    pub fn is_hybrid(self) -> bool {
        matches!(
            self,
            AgentKind::EsSac | AgentKind::EsTd3 | AgentKind::EsDdpg
        )
    }

    /// Parses a name as written on the command line.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|a| a.name() == name.trim())
    }
}

/// Which environment to train on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum EnvKind {
    /// The humanoid on the 50 m track (the paper's task).
    Walk,
    /// Gymnasium's Pendulum-v1: a fast sanity task.
    Pendulum,
}

/// Named sets of settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The paper's literal §5 protocol: N = 25, σ = 0.25, 50 inner cycles, 1500
    /// generations/episodes, eq. 12's reward on torque actions. On this task it falls
    /// (σ = 0.25 destroys the population: `results/walking/README.md`).
    Paper,
    /// Visible learning on a 2-core machine, about a minute for ES-SAC (150 generations);
    /// it does not walk.
    Quick,
    /// `quick` with 5× the gradient updates per generation and 895 generations (the run of
    /// `results/README.md`'s `inner1000-s0`, made on the physics before `fade` limits).
    Long,
    /// The walking recipe of `results/walking`: `quick`'s networks on joint-angle targets
    /// around the standing pose, alive bonus 0.25, a gait clock that also prices foot
    /// chatter, a track that goes on past the 50 m line with speed paid up to 1.1 m/s,
    /// clipped TD targets, 0.25 gradient updates per environment step, 4 million environment
    /// steps, the kept policy chosen by a deterministic walking check from 10 starts.
    Walking,
    /// `walking` on the paper's torque actions (τ = a · effort) instead of
    /// joint-angle targets, stopping at the first policy at the walking bar (`--until walk`;
    /// at most the 4 M env steps, which end the run before any generation cap):
    /// `results/torque`.
    WalkingTorque,
    /// `walking-torque` stopping at a policy that finishes all 10 check starts and 19 of 20
    /// with 10 more (each check stopped at its first start that misses the line), and
    /// starting over as seed + 1000 when no check went 15 m by 1 M env steps (`[restart]`):
    /// `results/restart`. The default until 2026-12-07.
    Walker,
    /// `walker` asking for a walk within 40 s: a 0.8 s gait clock, speed paid up to
    /// 1.4 m/s, a stop at the first walk that reaches the line within 40 s from all 10
    /// check starts and 19 of 20, and 5 M env steps (`results/clock-fast`).
    WalkerFast,
    /// `walker-fast` with left↔right mirrored transitions in every update (`rl.mirror`) and
    /// the ES mean checked as a candidate of its own (`check.mean`):
    /// `results/unseen-starts/mirror-mean`. The default until 2026-12-07.
    WalkerMirror,
    /// The default: `walker-mirror` with a margin of symmetry in the walking check (the
    /// check episodes' mean knee-torque asymmetry at most 10 %, `check.max_knee_asymmetry`)
    /// and a whole budget of 4 M env steps, a restart's included (`restart.whole_budget`):
    /// `results/unseen-starts/mirror-mean-even`.
    #[default]
    WalkerEven,
    /// A second stage for a walk (`--init RUN/best` of a walking run, required on the
    /// walking task): `walker-even` trained on for 1.5 M env steps under issue 35's
    /// disturbances (pushes of 0.5 m/s every 5 s, friction 0.4–1.2, ±20 % mass and strength,
    /// slopes from −8° to +5°), speed paid only up to 1.1 m/s, the ES from σ = 0.01:
    /// `results/robustness` ("Eight of the default's walks, the stage as a preset").
    WalkerRobust,
    /// Seconds: tiny budget and networks, for tests.
    Smoke,
}

impl EnvKind {
    /// Every environment.
    pub const ALL: [EnvKind; 2] = [EnvKind::Walk, EnvKind::Pendulum];

    /// The name used on the command line and in files (`walk`, `pendulum`).
    pub fn name(self) -> &'static str {
        match self {
            EnvKind::Walk => "walk",
            EnvKind::Pendulum => "pendulum",
        }
    }

    /// Parses a name as written on the command line.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == name.trim())
    }
}

impl Preset {
    /// Every preset.
    pub const ALL: [Preset; 11] = [
        Preset::Paper,
        Preset::Quick,
        Preset::Long,
        Preset::Walking,
        Preset::WalkingTorque,
        Preset::Walker,
        Preset::WalkerFast,
        Preset::WalkerMirror,
        Preset::WalkerEven,
        Preset::WalkerRobust,
        Preset::Smoke,
    ];

    /// Parses a name as written on the command line.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name.trim())
    }

    /// The name used on the command line and in `config.toml` (`paper`, `quick`, …).
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper => "paper",
            Preset::Quick => "quick",
            Preset::Long => "long",
            Preset::Walking => "walking",
            Preset::WalkingTorque => "walking-torque",
            Preset::Walker => "walker",
            Preset::WalkerFast => "walker-fast",
            Preset::WalkerMirror => "walker-mirror",
            Preset::WalkerEven => "walker-even",
            Preset::WalkerRobust => "walker-robust",
            Preset::Smoke => "smoke",
        }
    }

    /// The preset's TOML file (`crates/run/presets/<name>.toml`, embedded in the binary):
    /// layers of `config.toml` keys, each for some agents and environments, laid over
    /// [`TrainConfig::defaults`] in order.
    pub fn file(self) -> &'static str {
        match self {
            Preset::Paper => include_str!("../presets/paper.toml"),
            Preset::Quick => include_str!("../presets/quick.toml"),
            Preset::Long => include_str!("../presets/long.toml"),
            Preset::Walking => include_str!("../presets/walking.toml"),
            Preset::WalkingTorque => include_str!("../presets/walking-torque.toml"),
            Preset::Walker => include_str!("../presets/walker.toml"),
            Preset::WalkerFast => include_str!("../presets/walker-fast.toml"),
            Preset::WalkerMirror => include_str!("../presets/walker-mirror.toml"),
            Preset::WalkerEven => include_str!("../presets/walker-even.toml"),
            Preset::WalkerRobust => include_str!("../presets/walker-robust.toml"),
            Preset::Smoke => include_str!("../presets/smoke.toml"),
        }
    }
}

/// A preset file: its layers, in order.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PresetFile {
    layer: Vec<toml::Table>,
}

impl AgentKind {
    /// The RL algorithm behind the agent.
    pub fn algo(self) -> Algo {
        match self {
            AgentKind::EsSac | AgentKind::Sac => Algo::Sac,
            AgentKind::EsTd3 | AgentKind::Td3 => Algo::Td3,
            AgentKind::EsDdpg | AgentKind::Ddpg => Algo::Ddpg,
        }
    }
}

/// What a user sets on top of a preset: a TOML file, then single settings (the flags of
/// `esrl train`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// The preset underneath. Default `walker-even`.
    pub preset: Preset,
    /// TOML file laid over the preset (any subset of `config.toml`'s keys). A file that
    /// names another `preset` (a run's `config.toml` does) is laid over that one.
    pub config: Option<PathBuf>,
    /// Environment (default: walk, or the file's).
    pub env: Option<EnvKind>,
    /// A URDF instead of the embedded humanoid.
    pub urdf: Option<PathBuf>,
    /// Rollout threads.
    pub threads: Option<usize>,
    /// ES generations.
    pub generations: Option<usize>,
    /// Plain training episodes.
    pub episodes: Option<usize>,
    /// Environment-step budget.
    pub steps: Option<u64>,
    /// Stop at the first policy at the walking bar (`Some(true)`, `--until walk`) or run the
    /// whole budget (`Some(false)`, `--until budget`); `None` keeps the config's.
    pub stop_at_walk: Option<bool>,
    /// Start from a trained policy's weights (`init`, `--init DIR`).
    pub init: Option<PathBuf>,
}

/// Everything a training run depends on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// The agent (`es-sac`, `es-td3`, `es-ddpg`, `sac`, `td3`, `ddpg`).
    pub agent: AgentKind,
    /// The environment (`walk` or `pendulum`).
    pub env: EnvKind,
    /// The preset the run started from (for the record; the values below are what counts).
    pub preset: Preset,
    /// Seed of every random stream.
    pub seed: u64,
    /// Rollout threads; 0 means one per core. Results do not depend on it.
    pub threads: usize,
    /// ES generations (hybrid agents). Paper: 1500.
    pub generations: usize,
    /// Training episodes (plain agents). Paper: 1500.
    pub episodes: usize,
    /// Optional environment-step budget that ends training early (any agent): each attempt's
    /// under `[restart]`, the whole run's with `restart.whole_budget`.
    pub max_env_steps: Option<u64>,
    /// Gradient updates per ES generation (the inner training cycles). Paper: 50.
    pub inner_cycles: usize,
    /// ES-X: when set, the inner cycles of each generation are this many per environment
    /// step it collected (the update-to-data ratio), replacing `inner_cycles`. Default none
    /// (the paper's fixed count).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub updates_per_step: Option<f64>,
    /// Write a checkpoint every this many generations/episodes (and at the end).
    pub checkpoint_every: usize,
    /// The walking check (`[check]`, module [`crate::check`]): a deterministic evaluation
    /// from several starts against the walking bar that chooses `RUN/best/` and times the
    /// first policy at the bar. Default none (`RUN/best/` keeps the highest learning-curve
    /// value, the paper's choice); the `walking` preset sets it on the walking task.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check: Option<CheckConfig>,
    /// Stop the run as soon as a walking check meets the bar (`esrl train --until walk`).
    /// Needs `[check]`. Default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stop_at_walk: bool,
    /// Start the run over from another seed when it has not got going (`[restart]`, module
    /// [`crate::restart`]): no walk and no check past a distance by a number of env steps.
    /// Needs `[check]`. Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart: Option<RestartConfig>,
    /// Every this many environment steps, keep a copy of `RUN/best/` as it stands then in
    /// `RUN/best-<steps>/` (e.g. `best-2M`), so the policy a run kept at each point of its
    /// budget can be evaluated after `best/` has moved on. Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best_every_steps: Option<u64>,
    /// Start from the weights of a trained policy instead of drawing them from the seed
    /// (fine-tuning, e.g. a walking policy under `[walk.perturb]`): a run folder (its kept
    /// policy `RUN/best/`, else its last checkpoint), a `checkpoint/` or `best/` folder, or a
    /// study record's `policy/`. The actor is loaded, and with it the critics, targets,
    /// optimiser state and α when the folder holds them (a `policy/` keeps the actor alone);
    /// the ES distribution is centred on the loaded actor; the replay buffer starts empty.
    /// The policy's meaning must be the run's: the same environment, networks, action
    /// mapping, observation (gait clock, scaling), joints and robot. A relative path is taken
    /// from the working directory. Read once, when the run starts (a resumed run continues
    /// from its own checkpoint); `RUN/init.json` records which weights were loaded.
    /// `esrl train --init DIR`. Default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init: Option<PathBuf>,
    /// The walking environment.
    pub walk: WalkConfig,
    /// Actor and critic networks.
    pub network: NetConfig,
    /// SAC/TD3/DDPG hyperparameters.
    pub rl: RlConfig,
    /// Evolution strategy (hybrid agents).
    pub es: EsConfig,
}

impl TrainConfig {
    /// The settings of `preset` for `agent` on `env`: the preset's embedded TOML file
    /// (`crates/run/presets/`, [`Preset::file`]) laid over [`TrainConfig::defaults`].
    pub fn preset(agent: AgentKind, env: EnvKind, preset: Preset) -> Self {
        let mut c = Self::defaults(agent, env);
        c.apply_preset_file(preset, 0);
        c.preset = preset;
        c
    }

    /// The paper's values for `agent` on `env`, before any preset: each key's default is
    /// documented where it is declared.
    pub fn defaults(agent: AgentKind, env: EnvKind) -> Self {
        Self {
            agent,
            env,
            preset: Preset::Paper,
            seed: 0,
            threads: 0,
            generations: 1500,
            episodes: 1500,
            max_env_steps: None,
            inner_cycles: 50,
            updates_per_step: None,
            checkpoint_every: 10,
            check: None,
            stop_at_walk: false,
            restart: None,
            best_every_steps: None,
            init: None,
            walk: WalkConfig::default(),
            network: NetConfig::default(),
            rl: RlConfig::for_algo(agent.algo()),
            es: EsConfig::default(),
        }
    }

    /// Applies the layers of `preset`'s file that hold for this agent and environment, in
    /// order (`depth` bounds the chain of `use`). The files are part of the binary and every
    /// preset is resolved by `tests/presets.rs`, so a file that does not parse is a bug of
    /// the build, not of the user's input.
    fn apply_preset_file(&mut self, preset: Preset, depth: usize) {
        assert!(
            depth < Preset::ALL.len(),
            "presets `use` each other in a circle"
        );
        let file: PresetFile = toml::from_str(preset.file())
            .unwrap_or_else(|e| panic!("the embedded preset {}: {e}", preset.name()));
        for mut layer in file.layer {
            let when = layer.remove("when");
            if !when.is_none_or(|w| self.matches(&w)) {
                continue;
            }
            if let Some(base) = layer.remove("use") {
                let base = base.as_str().and_then(Preset::parse).unwrap_or_else(|| {
                    panic!("the embedded preset {}: `use = {base}`", preset.name())
                });
                *self = Self::defaults(self.agent, self.env);
                self.apply_preset_file(base, depth + 1);
            }
            *self = self
                .merged_with_table(layer)
                .unwrap_or_else(|e| panic!("the embedded preset {}: {e:#}", preset.name()));
        }
    }

    /// Whether a preset layer's `when = { env = …, agent = … }` holds for this config.
    fn matches(&self, when: &toml::Value) -> bool {
        let field = |key: &str| when.get(key).and_then(toml::Value::as_str);
        let env = field("env").is_none_or(|e| e == self.env.name());
        let agent = field("agent").is_none_or(|a| match a {
            "hybrid" => self.agent.is_hybrid(),
            "plain" => !self.agent.is_hybrid(),
            name => name == self.agent.name(),
        });
        env && agent
    }

    /// What a run of this configuration takes on a 2-core machine, as measured
    /// (`results/speed/README.md`): the one place the banner and the README take their time
    /// statements from (`crates/cli/tests/readme_times.rs` keeps the README in step). `None`
    /// where nothing was measured.
    pub fn typical_time(&self) -> Option<&'static str> {
        match (self.preset, self.env, self.agent) {
            (Preset::Walker, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKER),
            (Preset::WalkerFast, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKER_FAST),
            (Preset::WalkerMirror, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKER_MIRROR),
            (Preset::WalkerEven, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKER_EVEN),
            (Preset::WalkerRobust, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKER_ROBUST),
            (Preset::WalkingTorque, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKING_TORQUE),
            (Preset::Walking, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_WALKING),
            (Preset::Quick, EnvKind::Walk, AgentKind::EsSac) => Some(TIME_QUICK),
            (Preset::Paper, EnvKind::Walk, a) if a.is_hybrid() => Some(TIME_PAPER),
            (
                Preset::Walker
                | Preset::WalkerFast
                | Preset::WalkerMirror
                | Preset::WalkerEven
                | Preset::WalkerRobust
                | Preset::WalkingTorque
                | Preset::Walking
                | Preset::Paper,
                EnvKind::Pendulum,
                AgentKind::Sac,
            ) => Some(TIME_PENDULUM),
            _ => None,
        }
    }

    /// The settings this config changes from its preset as it comes, as dotted keys (the
    /// seed, the thread count and `--until` aside, which the preset's measured times cover,
    /// and for `walker-robust`, which always starts from a walk, the walk given by `--init`):
    /// empty for the runs [`TrainConfig::typical_time`] was measured on; `max_env_steps`,
    /// `init`, `walk.perturb.slope_range`, … after `--steps`, `--init` or a `--config` file.
    pub fn changed_from_preset(&self) -> Vec<String> {
        let mut preset = Self::preset(self.agent, self.env, self.preset);
        preset.seed = self.seed;
        preset.stop_at_walk = self.stop_at_walk;
        if self.preset == Preset::WalkerRobust {
            preset.init = self.init.clone();
        }
        config_differences(&preset, self)
            .map(|d| {
                d.into_iter()
                    .map(|line| line.split(':').next().unwrap_or_default().to_string())
                    .collect()
            })
            .unwrap_or_else(|_| vec!["(the settings could not be compared)".into()])
    }

    /// Applies the flags a resumed run may change too: `--generations`, `--episodes`,
    /// `--steps`, `--threads` and `--until`.
    pub fn apply_budget(&mut self, opts: &Overrides) {
        if let Some(t) = opts.threads {
            self.threads = t;
        }
        if let Some(g) = opts.generations {
            self.generations = g;
        }
        if let Some(e) = opts.episodes {
            self.episodes = e;
        }
        if let Some(s) = opts.steps {
            self.max_env_steps = Some(s);
        }
        if let Some(stop) = opts.stop_at_walk {
            self.stop_at_walk = stop;
        }
    }

    /// Resolves preset, file and flags, in that order, and validates the result.
    pub fn resolve(agent: AgentKind, opts: &Overrides, seed: Option<u64>) -> Result<Self> {
        let env = opts.env.unwrap_or(EnvKind::Walk);
        let mut cfg = Self::preset(agent, env, opts.preset);
        if let Some(path) = &opts.config {
            cfg = cfg.merged_with_file(path)?;
            if cfg.preset != opts.preset {
                // A whole `config.toml` of another preset: lay it over that preset instead,
                // so the settings a preset sets and the file leaves out (optional keys left
                // unset) are that preset's, and the file repeats its run exactly.
                let base = Self::preset(agent, opts.env.unwrap_or(cfg.env), cfg.preset);
                cfg = base.merged_with_file(path)?;
            }
            if cfg.agent != agent {
                bail!(
                    "{} sets agent = \"{}\" but the command trains {}: the agent comes from the \
                     command line; remove the key or train {}",
                    path.display(),
                    cfg.agent.name(),
                    agent.name(),
                    cfg.agent.name()
                );
            }
            if let Some(env) = opts.env {
                cfg.env = env;
            }
        }
        if let Some(s) = seed {
            cfg.seed = s;
        }
        cfg.apply_budget(opts);
        if let Some(init) = &opts.init {
            // Absolute, so that the run can be continued from any working directory.
            cfg.init = Some(std::path::absolute(init).unwrap_or_else(|_| init.clone()));
        }
        if let Some(u) = &opts.urdf {
            if cfg.env != EnvKind::Walk {
                bail!(
                    "--urdf {}: the {} environment has no robot to replace (--urdf is for the \
                     walking task)",
                    u.display(),
                    cfg.env.name()
                );
            }
            cfg.walk.urdf = Some(u.clone());
        }
        cfg.validate()?;
        if cfg.preset == Preset::WalkerRobust && cfg.env == EnvKind::Walk && cfg.init.is_none() {
            bail!(
                "--preset walker-robust trains a walk on under disturbances: give the walk to \
                 start from with --init RUN/best (RUN of `esrl train es-sac`, the default; its \
                 actor and critics); from the first step under these disturbances no seed \
                 found a walk (results/torque-randomized)"
            );
        }
        Ok(cfg)
    }

    /// This config with the keys of a TOML file laid over it. Unknown keys are errors.
    pub fn merged_with_file(&self, path: &Path) -> Result<Self> {
        let text = esrl_sim::read_text_file(path, MAX_CONFIG_BYTES)
            .with_context(|| format!("reading config file {}", path.display()))?;
        self.merged_with_str(&text)
            .with_context(|| format!("in config file {}", path.display()))
    }

    /// This config with the keys of a TOML text laid over it.
    pub fn merged_with_str(&self, text: &str) -> Result<Self> {
        self.merged_with_table(toml::from_str(text)?)
    }

    /// This config with the keys of a TOML table laid over it.
    fn merged_with_table(&self, overlay: toml::Table) -> Result<Self> {
        let mut base = toml::Table::try_from(self)?;
        merge(&mut base, overlay);
        let merged: Self = toml::Value::Table(base).try_into()?;
        Ok(merged)
    }

    /// Reads a run folder's `config.toml` as it was written (no preset underneath).
    pub fn load(path: &Path) -> Result<Self> {
        let text = esrl_sim::read_text_file(path, MAX_CONFIG_BYTES)
            .with_context(|| format!("reading {}", path.display()))?;
        Self::from_toml(&text).with_context(|| format!("parsing {}", path.display()))
    }

    /// A whole configuration from `config.toml` text ([`TrainConfig::to_toml`]'s), checked.
    pub fn from_toml(text: &str) -> Result<Self> {
        let cfg: Self = toml::from_str(text)?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// The TOML text written to `config.toml`.
    pub fn to_toml(&self) -> Result<String> {
        Ok(toml::to_string_pretty(self)?)
    }

    /// The same configuration with another seed (an attempt of `[restart]`).
    pub fn with_seed(&self, seed: u64) -> Self {
        Self {
            seed,
            ..self.clone()
        }
    }

    /// Checks every field, naming the first that cannot work.
    pub fn validate(&self) -> Result<()> {
        if self.agent.is_hybrid() && self.generations == 0 {
            bail!("generations = 0: needs at least one generation");
        }
        if !self.agent.is_hybrid() && self.episodes == 0 {
            bail!("episodes = 0: needs at least one episode");
        }
        if self.generations > MAX_ROWS {
            bail!(
                "generations = {}: at most {MAX_ROWS} (the paper runs 1500)",
                self.generations
            );
        }
        if self.episodes > MAX_ROWS {
            bail!(
                "episodes = {}: at most {MAX_ROWS} (the paper runs 1500)",
                self.episodes
            );
        }
        if self.inner_cycles > MAX_INNER_CYCLES {
            bail!(
                "inner_cycles = {}: at most {MAX_INNER_CYCLES} gradient updates per generation \
                 (the paper runs 50; a generation must end within minutes so a stop signal is \
                 answered)",
                self.inner_cycles
            );
        }
        if self.threads > MAX_THREADS {
            bail!(
                "threads = {}: at most {MAX_THREADS} (results do not depend on the thread count; \
                 0 uses every core)",
                self.threads
            );
        }
        if let Some(r) = self.updates_per_step {
            if !(r.is_finite() && r > 0.0 && r <= 64.0) {
                bail!("updates_per_step = {r}: must be in (0, 64]");
            }
        }
        match self.max_env_steps {
            Some(0) => {
                bail!("max_env_steps = 0 (--steps 0): the budget must allow at least one step")
            }
            // The hybrid loop takes its warm start before the first generation, whatever the
            // budget: a budget it fills would end the run with no generation at all.
            Some(s) if self.agent.is_hybrid() && s <= self.rl.warm_start as u64 => bail!(
                "max_env_steps = {s} (--steps {s}): the hybrid loop takes rl.warm_start = {} \
                 random env steps before its first generation, so the budget must be larger \
                 (or rl.warm_start smaller)",
                self.rl.warm_start
            ),
            _ => {}
        }
        if let Some(check) = &self.check {
            check.validate()?;
            if check.mean && !self.agent.is_hybrid() {
                bail!(
                    "check.mean = true needs a hybrid agent (es-sac, es-td3, es-ddpg): {} has \
                     no ES mean to check",
                    self.agent.name()
                );
            }
        }
        if self.rl.mirror && self.env != EnvKind::Walk {
            bail!(
                "rl.mirror = true needs the walking task: the {} environment has no left↔right \
                 mirror",
                self.env.name()
            );
        }
        if self.stop_at_walk && (self.check.is_none() || self.env != EnvKind::Walk) {
            bail!(
                "stop_at_walk (--until walk) needs the walking check: a `[check]` table on the \
                 walking task (the default `walker-even` and the walking presets have one)"
            );
        }
        if let Some(restart) = &self.restart {
            restart.validate()?;
            crate::restart::attempt_seed(self.seed, restart.max)?;
            if self.check.is_none() || self.env != EnvKind::Walk {
                bail!(
                    "[restart] needs the walking check: a `[check]` table on the walking task \
                     (the rule is judged on its checks)"
                );
            }
        }
        if self.best_every_steps == Some(0) {
            bail!("best_every_steps = 0: must be ≥ 1 (or left out)");
        }
        if self.checkpoint_every == 0 {
            bail!("checkpoint_every = 0: must be ≥ 1");
        }
        self.rl.validate()?;
        self.es.validate()?;
        self.network
            .validate()
            .context("in the [network] settings")?;
        self.walk.validate()?;
        Ok(())
    }
}

/// `--preset walker`'s time (`esrl train es-sac` until 2026-12-07: until the first policy
/// that finishes every check start) at `--threads 2` on an idle 2-core Intel Xeon
/// (`results/speed`). Over the twenty seeds of `results/strict`, `results/restart` and
/// `results/holdout`, the env steps to the first walk are 0.75–3.40 M (19 of 20 walk) and the
/// median lies between seeds 14 and 13 (2.47 and 2.49 M), both measured with checks that stop
/// early (`check.stop_early`): 876 and 873 s. The range follows from the steps at the
/// 2,490–2,930 env steps/s measured; the whole 4 M budget was measured on seed 1 (1,551 s,
/// `--until budget`, before checks stopped early, which makes it shorter); a seed that never
/// walks spends 1 M + 4 M after a restart (seed 8, measured with checks that stop early:
/// 1,778 s; 1,882 s before).
pub const TIME_WALKER: &str = "until the first walk: 5-23 min at --threads 2 on an idle 2-core machine (median over twenty seeds about 14.6 min, measured on the two median seeds: 14.6 min each; 19 of 20 walk); the whole 4 M env steps at most 26 min (measured on seed 1), 30 min when a run starts over and still finds no walk (5 M env steps; measured on seed 8)";
/// `--preset walker-fast`'s time (until the first walk that reaches the line within 40 s from
/// every check start) at `--threads 2` on an idle 2-core Intel Xeon (`results/clock-fast`,
/// "Wall time at two threads" and "More budget"; `results/clock-fast/holdout`): seeds 8, 13,
/// 14, 0 and 12, which met the stop at 1.92, 2.02, 2.90, 3.23 and 3.35 M env steps, measured
/// (770, 813, 1,125, 1,258 and 1,322 s); the range follows from the steps of the twelve of
/// seventeen seeds that met it within the 5 M (1.92–4.52 M) at the rate measured (2,490–2,590
/// env steps/s); the whole budget measured on held-out seed 15, which never met it (1,976 s);
/// the first walk at any speed (`RUN/first-walk/`, `check.max_track_time`'s module docs)
/// measured on seeds 11–15 on the faster Xeon of 2026-12-06 (580, 360, 320, 462 and 513 s).
pub const TIME_WALKER_FAST: &str = "until a walk within 40 s: 13-30 min at --threads 2 on an idle 2-core machine (13-22 min measured on five seeds, median 19 min; 12 of 17 seeds get there), otherwise the whole 5 M env steps: 33 min (measured on seed 15); the first walk at any speed, kept in RUN/first-walk/, after 5-10 min (measured on seeds 11-15, median 7.7 min)";
/// The default command's time (`esrl train es-sac`, preset `walker-even`: until the first
/// even walk that reaches the line within 40 s from every check start) at `--threads 2` on an
/// idle 2-core Intel Xeon with AMX (`results/unseen-starts/README.md`, "The default
/// (`walker-even`)"; `results/speed/README.md`): seed 2, the median of the nine of ten seeds
/// that met the stop (1.40–3.21 M env steps), measured: the stop at 2.46 M env steps after
/// 1,058 s, the first walk at any speed at 1.01 M after 435 s, 2,340 env steps/s. The same run
/// step for step (`walker-mirror`'s: the same checks, stop and kept actor) took 876 s
/// ([`TIME_WALKER_MIRROR`]) on the same machine earlier that day, so the machine's pace, not
/// the preset, makes the difference; the figures give both. The range follows from the nine
/// stops at the two rates; the median over all ten (between seeds 2 and 9, 2.46 and 2.60 M)
/// at them, 14.9–18.0 min. Seed 8, which started over at 1 M and spends the whole 4 M env
/// steps (`restart.whole_budget`), measured: 1,762 s (2,271 env steps/s; `results/speed`,
/// "The whole budget in 30 minutes"), its first walk at any speed after 1,072 s; 23.6 min at
/// the faster rate. The first walks at any speed of the other nine seeds (0.41–1.40 M env
/// steps) at the two rates give 2–10 min.
pub const TIME_WALKER_EVEN: &str = "until an even walk within 40 s: 8-23 min at --threads 2 on an idle 2-core machine (median over ten seeds 15-18 min; 17.6 min measured on seed 2, the median of the nine that get there, and 14.6 min for the same run earlier that day), otherwise the whole 4 M env steps, a restart's included: 24-30 min (29.4 min measured on seed 8); the first walk at any speed, kept in RUN/first-walk/, after 2-10 min on nine seeds of ten (7.2 and 6.2 min measured on seed 2; 17.9 min on seed 8, after its restart)";
/// `--preset walker-robust`'s time (`esrl train es-sac --preset walker-robust --init
/// RUN/best`, the whole 1.5 M env steps) at `--threads 2` on an idle 2-core Intel Xeon with AMX
/// (`results/robustness/README.md`, "Eight of the default's walks, the stage as a preset"):
/// seed 3 from the default's walk, measured: 1,500,089 env steps in 529 s (2,834 env
/// steps/s), its kept actor byte-identical to the same run's at one thread.
pub const TIME_WALKER_ROBUST: &str = "the whole 1.5 M env steps: about 9 min at --threads 2 on an idle 2-core machine (8.8 min measured on seed 3)";
/// `--preset walker-mirror`'s time (`esrl train es-sac --preset walker-mirror`: until the first
/// walk that reaches the line within 40 s from every check start) at `--threads 2` on an idle
/// 2-core Intel Xeon with AMX (`results/unseen-starts/README.md`, "The default
/// (`walker-mirror`)"): seed 2, the median of the nine of ten seeds that met the stop
/// (1.34–3.04 M env steps), measured: the
/// stop at 2.46 M env steps after 876 s, the first walk at any speed at 1.01 M after 373 s,
/// 2,830 env steps/s. The range follows from the steps at that rate; seed 8, which started
/// over at 1 M and spent the 5 M (6.02 M in all), from its steps at that rate, not measured;
/// the median over all ten (between seeds 2 and 9, 2.46 and 2.60 M) at that rate, 14.9 min.
pub const TIME_WALKER_MIRROR: &str = "until a walk within 40 s: 8-18 min at --threads 2 on an idle 2-core machine (median over ten seeds about 15 min; 14.6 min measured on seed 2, the median of the nine that get there), otherwise about 35 min for a restart and the whole 5 M env steps (6 M in all, at the measured rate); the first walk at any speed, kept in RUN/first-walk/, after 2-8 min (6.2 min measured on seed 2)";
/// `--preset walking-torque`'s time (until the first policy at the walking bar) at
/// `--threads 2` on an idle 2-core Intel Xeon, measured on
/// seeds 4, 1 and 5 of `results/torque`'s seed study (`results/speed`, "Time to walk of the
/// default command"); the median over its ten seeds follows from their steps to the first
/// walk, and the whole budget from the measured step rate (2,620–2,750 env steps/s).
pub const TIME_WALKING_TORQUE: &str =
    "until the first walk: 5-20 min at --threads 2 on an idle 2-core machine (5, 8 and 15 min measured on three seeds; median over ten seeds about 11 min, 8 of 10 walk), about 25 min for the whole 4 M env steps when no walk comes";
/// `--preset walking`'s time (its whole 4 M env steps), from the step rates
/// measured on the two 2-core machines of `results/speed/`: an AMD EPYC (80,000 steps in
/// 39.5 s at 2 threads, so 4 M steps in about 33 min; two full runs side by side at one
/// thread each took 72–73 min) and an Intel Xeon (1,400–1,630 steps/s at 2 threads, early
/// and late in a run: 42–48 min).
pub const TIME_WALKING: &str =
    "about 33-48 min at --threads 2 on an idle 2-core machine; 72 min of one core each when two run side by side";
/// `--preset quick` for ES-SAC (52 s measured at 2 threads, `results/speed/`).
pub const TIME_QUICK: &str = "about 1 min at --threads 2 (52 s measured)";
/// `--preset paper` for an ES agent: the paper's 1500 generations.
pub const TIME_PAPER: &str =
    "hours: 1500 generations of 25 individuals (5–8 h for ES-SAC on 2 cores, by its own ETA)";
/// `train sac --env pendulum` (12 s measured at 2 threads, `results/speed/`).
pub const TIME_PENDULUM: &str = "about 12 s";

/// Most gradient updates per generation a run may ask for (`inner_cycles`).
pub const MAX_INNER_CYCLES: usize = 100_000;

/// Most threads a run may ask for (`--threads`); a run on a machine with fewer cores is
/// refused more than 4 per core when it starts ([`crate::build::pool`]).
pub const MAX_THREADS: usize = 1024;

/// Largest config file read, bytes (1 MiB; a whole `config.toml` is about 3 kB).
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// Most generations or episodes a run may ask for: 10⁷ (the paper runs 1500; a typo such as
/// `--generations 1e12` is refused instead of promising a run that cannot end).
pub const MAX_ROWS: usize = 10_000_000;

/// What a run will hold in memory, by the setting that drives each part (bytes).
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryEstimate {
    /// (setting, what, bytes), largest first.
    pub parts: Vec<(&'static str, &'static str, u64)>,
}

impl MemoryEstimate {
    /// Total bytes.
    pub fn total(&self) -> u64 {
        self.parts.iter().map(|p| p.2).sum()
    }
}

/// "1.5 GiB", "320 MiB".
pub fn human_bytes(b: u64) -> String {
    let gib = b as f64 / (1u64 << 30) as f64;
    if gib >= 1.0 {
        format!("{gib:.1} GiB")
    } else {
        format!("{:.0} MiB", b as f64 / (1u64 << 20) as f64)
    }
}

impl TrainConfig {
    /// Estimates the memory a run needs before anything is allocated, from the settings and
    /// the environment's sizes: the replay buffer, the networks with their optimiser state and
    /// one batch of activations, and the population (genomes and the episodes held until they
    /// enter the buffer). Within a small factor of the real use; meant to refuse what cannot
    /// fit, not to plan to the megabyte.
    pub fn memory_estimate(
        &self,
        obs_dim: usize,
        act_dim: usize,
        max_steps: usize,
    ) -> MemoryEstimate {
        let f = 4u64; // f32
        let (o, a) = (obs_dim as u64, act_dim as u64);
        let transition = f * (2 * o + a + 1) + 1 + 8 + 4;
        let replay = self.rl.buffer_size as u64 * transition;
        let actor = self.network.actor.param_count(obs_dim, act_dim) as u64;
        let critic = self.network.critic.param_count(obs_dim, act_dim) as u64;
        // Actor: weights, gradient, two Adam moments; critics: the same plus a target, ×2.
        let weights = f * (4 * actor + 2 * 5 * critic);
        let widths: u64 = self
            .network
            .actor
            .fc
            .iter()
            .chain(&self.network.critic.obs_fc)
            .chain(&self.network.critic.act_fc)
            .chain(&self.network.critic.joint_fc)
            .map(|&w| w as u64)
            .sum::<u64>()
            + 8 * (self.network.actor.lstm_hidden + self.network.critic.lstm_hidden) as u64;
        let window = if self.network.recurrent() {
            (self.rl.seq_len + self.rl.burn_in) as u64
        } else {
            1
        };
        // Forward values and their gradients, for the actor and three critic passes.
        let activations = f * self.rl.batch_size as u64 * window * widths * 2 * 4;
        let n = if self.agent.is_hybrid() {
            self.es.population as u64
        } else {
            1
        };
        let k = if self.agent.is_hybrid() {
            self.es.evaluations as u64 * 2
        } else {
            1
        };
        let population = n * (2 * f * actor + k * max_steps as u64 * transition);
        let mut parts = vec![
            ("rl.buffer_size", "replay buffer", replay),
            ("network", "networks and optimiser state", weights),
            ("rl.batch_size", "one batch of activations", activations),
            (
                "es.population × the actor's size",
                "population genomes and episodes",
                population,
            ),
        ];
        parts.sort_by_key(|p| std::cmp::Reverse(p.2));
        MemoryEstimate { parts }
    }

    /// Refuses a run whose memory estimate exceeds what the machine has available, naming
    /// the setting that drives the largest part.
    pub fn check_memory(&self, obs_dim: usize, act_dim: usize, max_steps: usize) -> Result<()> {
        let est = self.memory_estimate(obs_dim, act_dim, max_steps);
        let total = est.total();
        let available = available_memory().unwrap_or(u64::MAX);
        // Without /proc/meminfo, still refuse what no machine this tool targets has.
        let limit = available.min(1 << 40);
        if total > limit {
            let (setting, what, bytes) = est.parts[0];
            let breakdown = est
                .parts
                .iter()
                .map(|(s, w, b)| format!("{w} ({s}): {}", human_bytes(*b)))
                .collect::<Vec<_>>()
                .join(", ");
            bail!(
                "this configuration needs about {} of memory but {} is available; the largest part is the {what}, {} from `{setting}`: lower it. ({breakdown})",
                human_bytes(total),
                human_bytes(limit),
                human_bytes(bytes)
            );
        }
        Ok(())
    }
}

/// Memory available to a new allocation (Linux `MemAvailable`), if known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Lays `over` onto `base`, recursing into tables so a file can set one nested key.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// Paths (dotted) where two configs differ, the thread count excepted, as
/// `key: stored vs wanted`.
pub fn config_differences(stored: &TrainConfig, wanted: &TrainConfig) -> Result<Vec<String>> {
    fn walk(a: &toml::Value, b: &toml::Value, path: &str, out: &mut Vec<String>) {
        match (a, b) {
            (toml::Value::Table(x), toml::Value::Table(y)) => {
                let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
                keys.sort();
                keys.dedup();
                for k in keys {
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    match (x.get(k), y.get(k)) {
                        (Some(va), Some(vb)) => walk(va, vb, &p, out),
                        (va, vb) => out.push(format!(
                            "{p}: {} vs {}",
                            va.map_or("none".into(), ToString::to_string),
                            vb.map_or("none".into(), ToString::to_string)
                        )),
                    }
                }
            }
            _ if a != b => out.push(format!("{path}: {a} vs {b}")),
            _ => {}
        }
    }
    let mut a = toml::Table::try_from(stored)?;
    let mut b = toml::Table::try_from(wanted)?;
    a.remove("threads");
    b.remove("threads");
    let mut out = Vec::new();
    walk(&toml::Value::Table(a), &toml::Value::Table(b), "", &mut out);
    Ok(out)
}
