//! Command-line arguments of `esrl` (clap derive). `esrl --help` is generated from these docs.

use clap::{Args, Parser, Subcommand, ValueEnum};
use esrl_run::Overrides;
pub use esrl_run::{AgentKind, EnvKind, Preset};
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
    /// Record a rollout of a trained policy: MCAP for Foxglove, or an SVG animation.
    Record(RecordArgs),
    /// Run an experiment described by a study file (arms × seeds), resumably, and report it
    /// with interval estimates.
    Study(StudyArgs),
    /// Measure speed: environment steps, network passes, SAC updates, ES generations.
    Bench(BenchArgs),
}

/// Options shared by commands that train.
#[derive(Debug, Clone, Args)]
pub struct TrainOptions {
    /// Named settings; a --config file and the flags below override them. `walker-even`
    /// (the default) is the recipe that walks within 40 s on torque actions, learning from
    /// left↔right mirrored transitions, keeping the ES mean when it walks best and stopping
    /// only at a walk whose knees work alike (knee-torque asymmetry ≤ 10 %); `walker-mirror`
    /// the same without that margin of symmetry; `walker-fast` also without the mirror and
    /// the mean's check; `walker` the recipe with a 1 s gait clock (walks of 47–59 s; 4 M env
    /// steps), stopping at the first walk that finishes every check start and starting over
    /// from another seed when a run has not got going; `walking-torque` `walker` without the
    /// stricter stop and the restart; `walking` the recipe on joint-angle targets; `paper` the
    /// paper's literal §5 protocol; `walker-robust` a second stage that trains a walk on
    /// (`--init RUN/best`) under pushes, ground, body and slope disturbances.
    #[arg(long, value_enum, default_value_t = Preset::WalkerEven)]
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
    /// Worker threads for population rollouts and updates (results do not depend on it; 0: one
    /// per core, as `threads = 0` in config.toml) [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Generations for ES agents.
    #[arg(long)]
    pub generations: Option<usize>,
    /// Episodes for plain agents.
    #[arg(long)]
    pub episodes: Option<usize>,
    /// Environment-step budget: training stops once this many steps were taken (any agent;
    /// with `[restart]`, by each attempt, or by the whole run with `restart.whole_budget` as
    /// in the default preset).
    #[arg(long)]
    pub steps: Option<u64>,
    /// `walk`: stop as soon as a walking check meets the bar (the policy is kept in
    /// RUN/best/); `budget`: run the whole budget. [default: the preset's: `walk` for
    /// `walker`, `walker-fast` and `walking-torque`, else `budget`]
    #[arg(long, value_enum)]
    pub until: Option<Until>,
    /// Hide the progress bar (it is also hidden when stderr is not a terminal).
    #[arg(long)]
    pub no_progress: bool,
}

/// When a training stops (`--until`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Until {
    /// At the first policy at the walking bar (`stop_at_walk = true`).
    Walk,
    /// When the budget is spent.
    Budget,
}

impl TrainOptions {
    /// What these options set on top of the preset.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            preset: self.preset,
            config: self.config.clone(),
            env: self.env,
            urdf: self.urdf.clone(),
            threads: self.threads,
            generations: self.generations,
            episodes: self.episodes,
            steps: self.steps,
            stop_at_walk: self.until.map(|u| u == Until::Walk),
            init: None,
        }
    }
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
    /// the pendulum, `runs/<agent>-init-s<seed>` with --init].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Continue the run in DIR from its last checkpoint (its config.toml is used; --seed,
    /// --env, --urdf, --config and --preset cannot change it, --generations, --episodes,
    /// --steps and --threads can). A run stopped before its first checkpoint starts over.
    #[arg(
        long,
        value_name = "DIR",
        conflicts_with_all = ["out", "config", "preset", "seed", "env", "urdf", "init"]
    )]
    pub resume: Option<PathBuf>,
    /// Start from the weights of a trained policy (fine-tuning): a run folder (its kept
    /// policy), a checkpoint or best/ folder, or a study record's policy/. The critics come
    /// too when the folder has them; the policy must be for the same task and networks
    /// (`init` in config.toml; RUN/init.json records what was loaded).
    #[arg(long, value_name = "DIR")]
    pub init: Option<PathBuf>,
    /// Shared training options.
    #[command(flatten)]
    pub opts: TrainOptions,
}

/// `esrl eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A run folder (its kept policy, RUN/best/, when it has one; else its last checkpoint),
    /// or a checkpoint or best/ folder.
    pub path: PathBuf,
    /// Evaluate a run folder's last checkpoint instead of its kept policy (RUN/best/).
    #[arg(long)]
    pub last: bool,
    /// Where to write the report [default: eval.json beside the policy: RUN/best/eval.json,
    /// RUN/eval.json for the last checkpoint].
    #[arg(long, value_name = "FILE.json")]
    pub out: Option<PathBuf>,
    /// Replace the report file if it exists (it is never replaced otherwise when --out is
    /// given).
    #[arg(long)]
    pub force: bool,
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
    /// Episodes (the first ones) whose per-step trace (path, contacts, joint angles, side
    /// view; ≈ 0.4 MB per 60 s walking episode) the report keeps for figures; the others
    /// keep their metrics.
    #[arg(long, default_value_t = 10)]
    pub traces: usize,
    /// Evaluate under a disturbance, KIND=VALUE (repeatable): push_sagittal, push_lateral
    /// (m/s, every 5 s), friction (coefficient; 1 is the task's), mass, strength (scales),
    /// slope (degrees, positive uphill), obs_noise (SD of the scaled observation), delay
    /// (control steps).
    #[arg(long, value_name = "KIND=VALUE")]
    pub perturb: Vec<String>,
    /// Evaluate on the run's task without its training-time disturbances (`[walk.perturb]`):
    /// how a policy trained under randomization walks on the plain track (--perturb then
    /// disturbs the plain task, as the robustness card does).
    #[arg(long)]
    pub undisturbed: bool,
    /// Evaluate from the task's default starts (the standing pose with its default joint
    /// noise: `walk.init_noise` and `walk.reset` at their defaults) instead of the run's own:
    /// how a policy trained from wider or other starts walks from the standard ones.
    #[arg(long)]
    pub default_starts: bool,
    /// What the observed torso orientation is measured against on a slope (`--perturb
    /// slope=…`, the card's slopes): `ground` (the frame of the flat ground under tilted
    /// gravity: the slope's tilt does not show) or `gravity` (as an IMU on a real slope
    /// reports it). Default: the run's own (`walk.orientation_frame`, `ground` unless set).
    #[arg(long, value_name = "FRAME", value_parser = ["ground", "gravity"])]
    pub orientation_frame: Option<String>,
    /// Also run the robustness card: the policy under pushes, friction, mass, strength,
    /// slopes, noise and delay at several magnitudes, --episodes each (into the report's
    /// `robustness`).
    #[arg(long)]
    pub robustness: bool,
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
    /// The study folder: `DIR/study.toml`, runs in `DIR/runs/<agent>-s<seed>`, records in
    /// `DIR/records/`, the report in `DIR/report.{md,csv,json}`.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Runs trained at the same time [default: cores / threads].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Deterministic evaluation episodes per trained policy.
    #[arg(long, default_value_t = 20)]
    pub eval_episodes: usize,
    /// Reset seed of the first evaluation episode (then +1 each); the default, 1000, is a
    /// start no training, walking check or `esrl eval` default uses.
    #[arg(long, default_value_t = 1000)]
    pub eval_seed: u64,
    /// Evaluate each run's last checkpoint (for ES runs the last RL actor) instead of its
    /// kept policy, `RUN/best/`.
    #[arg(long)]
    pub eval_last: bool,
    /// Shared training options. An equal environment-step budget for every agent: `--steps
    /// N` (the `walking` preset's budget is 4 M steps for every agent already).
    #[command(flatten)]
    pub opts: TrainOptions,
}

/// `esrl record`.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// A run folder (its kept policy, RUN/best/, when it has one; else its last checkpoint),
    /// or a checkpoint or best/ folder.
    pub path: PathBuf,
    /// Record a run folder's last checkpoint instead of its kept policy (RUN/best/).
    #[arg(long)]
    pub last: bool,
    /// The file to write: FILE.mcap (for Foxglove) or FILE.svg (an animated side view that
    /// any browser plays).
    #[arg(long, value_name = "FILE.mcap|FILE.svg")]
    pub out: PathBuf,
    /// Replace FILE if it exists (a regular file only; devices, pipes and links are never
    /// replaced).
    #[arg(long)]
    pub force: bool,
    /// Seed of the rollout's initial state.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// `esrl study`.
#[derive(Debug, Args)]
pub struct StudyArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: StudyCommand,
}

/// The study subcommands.
#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Train every run of the study that is not finished (resuming stopped ones), evaluate
    /// its handed-over policy and write its record; run it again to continue.
    Run {
        /// The study file (TOML; the format is in `esrl_cli::study`'s docs and the README).
        study: PathBuf,
        /// The study folder [default: studies/<file stem>].
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Trainings side by side [default: cores / threads].
        #[arg(long)]
        jobs: Option<usize>,
        /// Only runs i, i + n, i + 2n, … (arms in order, seeds within): one of n machines.
        #[arg(long, value_name = "i/n")]
        shard: Option<String>,
        /// Threads per training [default: cores / jobs]; results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Hide the progress bar of a single training.
        #[arg(long)]
        no_progress: bool,
    },
    /// Where every run of a study folder stands.
    Status {
        /// The study folder.
        dir: PathBuf,
    },
    /// Per arm, the success rate at the walking bar (Wilson 95 %), IQMs with bootstrap
    /// intervals, the probability of improvement between arms, every run's gait and Table 1:
    /// DIR/report.md and DIR/report.csv from the records.
    Report {
        /// The study folder.
        dir: PathBuf,
        /// Print the figures as one JSON object instead of the Markdown.
        #[arg(long)]
        json: bool,
    },
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
        /// Control steps to run (at least 1).
        #[arg(long, default_value_t = 20_000, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
        steps: u64,
        /// Preset whose walking task is stepped (action mode, servo, gait clock); default
        /// the paper's task (torque actions), the one `mujoco_urdf.py` compares with.
        #[arg(long, value_enum)]
        preset: Option<Preset>,
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
    /// Time of one full SAC update (critics, actor, α, targets) on N threads (its large
    /// matrix products split by output rows; the result is the same at any N).
    Update {
        /// Network family.
        #[arg(long, value_enum, default_value_t = Arch::Lstm)]
        arch: Arch,
        /// Sequences (LSTM) or transitions (MLP) per batch: 256 is the peer's size, 64 the
        /// walking recipe's (`rl.batch_size`).
        #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u64).range(1..=65536))]
        batch: u64,
        /// Threads the update's products may use.
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Chunks the batch is split into (`rl.batch_chunks`: each chunk's forward and
        /// backward on its own thread, gradients summed in chunk order).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=256))]
        batch_chunks: u64,
        /// Updates timed (after untimed ones for at least 0.5 s); the median and the fastest
        /// are reported.
        #[arg(long, default_value_t = 21, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
        reps: u64,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Wall time of an ES generation at 1 and N threads: its rollouts alone, one update, and
    /// whole generations (rollouts + training, pipelined) as `esrl train` runs them.
    Es {
        /// Threads to compare with one (2 to 1024).
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(2..=1024))]
        threads: u64,
        /// Preset whose population and networks are timed.
        #[arg(long, value_enum, default_value_t = Preset::Paper)]
        preset: Preset,
        /// Time the generations of a walking phase: start from this trained policy (as `esrl
        /// train --init`; it must be the preset's task and networks) with the ES at its
        /// `sigma_min`, where a long run's σ has decayed to. Without it, the generations are
        /// a run's first ones, from random weights.
        #[arg(long, value_name = "DIR")]
        init: Option<PathBuf>,
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
