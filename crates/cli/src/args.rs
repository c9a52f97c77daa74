//! Command-line arguments of `esrl` (clap derive). `esrl --help` is generated from these docs.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Train, evaluate, compare and record humanoid walking controllers (ES-SAC, ES-TD3, ES-DDPG,
/// SAC, TD3, DDPG).
#[derive(Debug, Parser)]
#[command(name = "esrl", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Train an agent; writes a run folder (config, metrics, checkpoints, summary).
    Train(TrainArgs),
    /// Evaluate a trained policy deterministically on the 50 m track; writes eval.json.
    Eval(EvalArgs),
    /// Train or collect several agents × seeds and write Table 1 (Markdown and CSV).
    Compare(CompareArgs),
    /// Record a rollout of a trained policy to an MCAP file for Foxglove.
    Record(RecordArgs),
    /// Measure speed: environment steps, network passes, SAC updates, ES generations.
    Bench(BenchArgs),
}

/// The six agents.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, serde::Serialize, serde::Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EnvKind {
    /// The humanoid on the 50 m track (the paper's task).
    Walk,
    /// Gymnasium's Pendulum-v1: a fast sanity task.
    Pendulum,
}

/// Named sets of settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The paper's numbers: N = 25, σ = 0.25, 50 inner cycles, 1500 generations/episodes.
    Paper,
    /// Visible learning on a 2-core machine: about 3 minutes for ES-SAC (150 generations).
    Quick,
    /// `quick` with 5× the gradient updates per generation and 895 generations: the ES-SAC
    /// run (seed 0) that stayed up 60 s on the former hard-limit physics (about 75 minutes
    /// on one core); on today's physics it is not that run.
    Long,
    /// The walking recipe of `results/walking`: `quick`'s networks on joint-angle targets
    /// around the standing pose, alive bonus 0.25, a gait clock, 0.25 gradient updates per
    /// environment step, 4 million environment steps (about 1.5 hours for ES-SAC on one
    /// core: 89–91 min measured).
    Walking,
    /// Seconds: tiny budget and networks, for tests.
    Smoke,
}

/// The name of a preset as written on the command line and in `config.toml`.
pub fn preset_name(preset: Preset) -> String {
    preset
        .to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_owned())
}

/// Options shared by commands that train.
#[derive(Debug, Clone, Args)]
pub struct TrainOptions {
    /// Named settings; a --config file and the flags below override them.
    #[arg(long, value_enum, default_value_t = Preset::Paper)]
    pub preset: Preset,
    /// TOML file overriding the preset (same keys as a run folder's config.toml).
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
    /// Environment [default: walk, or the config file's].
    #[arg(long, value_enum)]
    pub env: Option<EnvKind>,
    /// A URDF to use instead of the embedded humanoid.
    #[arg(long, value_name = "PATH")]
    pub urdf: Option<PathBuf>,
    /// Worker threads for population rollouts (results do not depend on it) [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Generations for ES agents.
    #[arg(long)]
    pub generations: Option<usize>,
    /// Episodes for plain agents.
    #[arg(long)]
    pub episodes: Option<usize>,
    /// Environment-step budget: training stops once this many steps were taken (any agent).
    #[arg(long)]
    pub steps: Option<u64>,
    /// Hide the progress bar (it is also hidden when stderr is not a terminal).
    #[arg(long)]
    pub no_progress: bool,
}

/// `esrl train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// The agent.
    #[arg(value_enum)]
    pub agent: AgentKind,
    /// Seed of every random stream in the run.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Run folder [default: `runs/<agent>-s<seed>`; `runs/<agent>-pendulum-s<seed>` on
    /// the pendulum].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Continue the run in DIR from its last checkpoint (its config.toml is used; --seed,
    /// --env, --urdf, --config and --preset cannot change it, --generations, --episodes,
    /// --steps and --threads can). A run stopped before its first checkpoint starts over.
    #[arg(
        long,
        value_name = "DIR",
        conflicts_with_all = ["out", "config", "preset", "seed", "env", "urdf"]
    )]
    pub resume: Option<PathBuf>,
    /// Shared training options.
    #[command(flatten)]
    pub opts: TrainOptions,
}

/// `esrl eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A run folder or a checkpoint folder.
    pub path: PathBuf,
    /// Deterministic rollouts to run (each with its own seeded initial perturbation).
    #[arg(long, default_value_t = 1)]
    pub episodes: usize,
    /// Seed of the first rollout's initial state.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also write one MCAP recording per episode into this folder.
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
}

/// `esrl compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Comma-separated agents.
    #[arg(long, default_value = "es-sac,es-td3,es-ddpg,sac,td3,ddpg")]
    pub agents: String,
    /// Seeds per agent (0, 1, …).
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// Output folder: runs go to `DIR/<agent>-s<seed>`, the table to `DIR/table.{md,csv}`.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Give every agent the same environment-step budget (that of one ES run of the preset)
    /// instead of the same number of generations/episodes.
    #[arg(long)]
    pub equal_steps: bool,
    /// Runs trained at the same time [default: cores / threads].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Evaluation rollouts per trained policy.
    #[arg(long, default_value_t = 1)]
    pub eval_episodes: usize,
    /// Shared training options.
    #[command(flatten)]
    pub opts: TrainOptions,
}

/// `esrl record`.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// A run folder or a checkpoint folder.
    pub path: PathBuf,
    /// The MCAP file to write.
    #[arg(long, value_name = "FILE.mcap")]
    pub out: PathBuf,
    /// Seed of the rollout's initial state.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// `esrl bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// What to measure.
    #[command(subcommand)]
    pub what: BenchWhat,
}

/// Benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchWhat {
    /// Control steps per second of the walking env on one core, random actions, resets included.
    Env {
        /// Control steps to run.
        #[arg(long, default_value_t = 20_000)]
        steps: usize,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Forward + backward time of the paper-size actor and critic on 256 × 8, one thread.
    Nn {
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Time of one full SAC update (critics, actor, α, targets), one thread.
    Update {
        /// Network family.
        #[arg(long, value_enum, default_value_t = Arch::Lstm)]
        arch: Arch,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Wall time of one ES generation's evaluation at 1 and N threads.
    Es {
        /// Threads to compare with one.
        #[arg(long, default_value_t = 2)]
        threads: usize,
        /// Preset whose population and networks are timed.
        #[arg(long, value_enum, default_value_t = Preset::Paper)]
        preset: Preset,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
}

/// Network family for `bench update`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Arch {
    /// Paper-size LSTM actor and critics on 256 sequences × 8 steps.
    Lstm,
    /// MLP 256×256 actor and critics on 256 transitions.
    Mlp,
}
