//! SAC, TD3 and DDPG with recurrent sequence replay, and the learner interface training
//! loops drive.
//!
//! One [`Agent`] type covers the three algorithms; [`Agent::update`] dispatches on the
//! algorithm to its update, each written top to bottom under its equation numbers in its own
//! file (`sac.rs`, `td3.rs`; DDPG is TD3 with one critic and its tricks off,
//! [`RlConfig::for_algo`]), with the steps they share in `steps.rs` and the deterministic
//! parallel execution over parts of the batch in `chunks.rs`.
//! Networks come from `esrl-nn` (the paper's LSTM actor and critics, or MLPs); experience
//! lives in an episode-aware [`ReplayBuffer`] that samples windows of consecutive steps for
//! recurrent training (burn-in, then trained steps, never crossing an episode) or single
//! transitions for feed-forward networks.
//!
//! A [`Learner`] runs one row at a time, reports it and saves and restores its full state;
//! [`Trainer`] is the plain one (an episode per row), the hybrid ES loop (`esrl-es`) the
//! other. Episodes run through `esrl_sim::run_episode`; every random stream is named in
//! `esrl-streams`.
//!
//! ```
//! use esrl_agents::{Agent, Algo, NetConfig, RlConfig, Trainer};
//! use esrl_sim::{Env, Pendulum};
//!
//! let mut env = Pendulum::new();
//! let cfg = RlConfig { batch_size: 16, warm_start: 100, ..RlConfig::for_algo(Algo::Sac) };
//! let agent = Agent::new(Algo::Sac, env.obs_dim(), env.act_dim(), &NetConfig::tiny(false), &cfg, 0)?;
//! let mut trainer = Trainer::new(agent, 0);
//! let report = trainer.episode(&mut env)?;
//! assert_eq!(report.length, 200);
//! # Ok::<(), esrl_agents::AgentError>(())
//! ```
//!
//! Threads: an update runs on the rayon pool it is called in; the critics (and the target
//! critics) train side by side, the actor's pass at s runs beside the TD targets and the
//! target critics' Polyak step beside the actor loss, and large products split by output
//! rows, so the result is the same at any pool size.
//!
//! Limitations: the burn-in runs
//! one step at a time without gradients; recurrent state is not stored in the buffer (burn-in
//! rebuilds it from the preceding steps of the same episode).

pub mod agent;
pub mod bench;
mod chunks;
pub mod config;
pub mod learner;
pub mod nets;
pub mod policy;
pub mod replay;
pub mod rollout;
mod sac;
mod steps;
mod td3;
pub mod train;
mod update;

pub use agent::{Agent, AgentError, UpdateStats};
pub use config::{Algo, ConfigError, LearnEvery, RlConfig};
pub use learner::{Learner, LearnerState, Resumable, Row, TrainerState};
pub use nets::NetConfig;
pub use policy::{ActMode, Exploration, Policy};
pub use replay::{ReplayBuffer, SequenceBatch, Transition};
pub use rollout::{rollout, Episode};
pub use train::{EpisodeReport, LossMeans, Trainer};
