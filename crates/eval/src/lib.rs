//! Evaluating a trained policy, one implementation for `esrl eval`, `esrl record`,
//! `esrl compare` and Python (`esrl_rs`).
//!
//! - [`load`]: a run folder, a checkpoint folder or `RUN/best` → [`LoadedRun`] (the run's
//!   config, its environment, the agent with the checkpoint's weights).
//! - [`episode`]: one deterministic episode through `esrl_sim`'s episode loop, keeping the
//!   first observation and, on the walking task, the gait samples ([`walk_episode`]).
//! - [`report`]: K episodes in parallel → [`EvalReport`] with the gait metrics of SPEC §6,
//!   written to `RUN/eval.json`.
//! - [`stick`]: the robot's side view along an episode; [`recording`]: MCAP for Foxglove.
//! - [`robustness`]: the policy under pushes, friction, mass, strength, slopes, noise and
//!   delay (`esrl eval --perturb`, `--robustness`).
//!
//! ```no_run
//! let loaded = esrl_eval::load_run(std::path::Path::new("runs/es-sac-s0"))?;
//! let report = esrl_eval::evaluate(&loaded, 0, 10, None)?;
//! println!("mean return {:.1}, {} of 10 fell", report.mean.ret, report.mean.falls);
//! # Ok::<(), esrl_run::Error>(())
//! ```
//!
//! # Limitations
//!
//! - Evaluation is deterministic (tanh μ) and on the run's own environment settings unless a
//!   disturbance is asked for ([`robustness`]).
//! - A 60 s walking episode adds about 0.4 MB of trace to `eval.json`; `esrl eval` keeps the
//!   traces of the first 10 episodes unless asked (`--traces`).

pub mod disturbance;
pub mod episode;
pub mod load;
pub mod recording;
pub mod report;
pub mod robustness;
pub mod stick;

pub use disturbance::{CardRow, Disturbance};
pub use episode::{rollout, walk_episode, Rollout, WalkEpisode};
pub use load::{load_run, load_run_pick, locate, locate_pick, LoadedRun, Pick};
pub use recording::{metadata, Recorder};
pub use report::{
    eval_path, evaluate, evaluate_and_write, evaluate_with, mean_gait, EpisodeEval, EvalMean,
    EvalOptions, EvalReport, Trace, EVAL_FILE,
};
pub use robustness::{
    card, card_markdown, goal_markdown, goal_rows, goal_set, standard_set, GoalMiss, GoalRows,
    GOAL_SHARE,
};
pub use stick::{animated_svg, render_rgb, StickFigure, StickRecorder, DEFAULT_INTERVAL};
