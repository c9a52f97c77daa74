//! SAC, TD3 and DDPG with recurrent sequence replay.
//!
//! One [`Agent`] type covers the three algorithms (DDPG is TD3 with one critic, no target
//! smoothing and no delay); an [`Algo`] picks which. Networks come from `esrl-nn` (the paper's
//! LSTM actor and critics, or MLPs); experience lives in an episode-aware [`ReplayBuffer`] that
//! samples windows of consecutive steps for recurrent training (burn-in, then trained steps,
//! never crossing an episode) or single transitions for feed-forward networks. [`Trainer`] runs
//! plain training episode by episode; the hybrid ES loop (`esrl-es`) drives the same agent.
//!
//! ```
//! use esrl_agents::{Agent, Algo, NetConfig, RlConfig, Trainer};
//! use esrl_sim::{Env, Pendulum};
//!
//! let mut env = Pendulum::new();
//! let cfg = RlConfig { batch_size: 16, warm_start: 100, ..RlConfig::default() };
//! let agent = Agent::new(Algo::Sac, env.obs_dim(), env.act_dim(), &NetConfig::tiny(false), &cfg, 0)?;
//! let mut trainer = Trainer::new(agent, 0);
//! let report = trainer.episode(&mut env)?;
//! assert_eq!(report.length, 200);
//! # Ok::<(), esrl_agents::AgentError>(())
//! ```
//!
//! Limitations: single-threaded updates (parallelism belongs to rollouts); the burn-in runs
//! one step at a time without gradients; recurrent state is not stored in the buffer (burn-in
//! rebuilds it from the preceding steps of the same episode).

pub mod agent;
pub mod config;
pub mod nets;
pub mod replay;
pub mod rollout;
pub mod train;

pub use agent::{ActMode, Agent, AgentError, Policy, UpdateStats};
pub use config::{Algo, ConfigError, LearnEvery, RlConfig};
pub use nets::NetConfig;
pub use replay::{ReplayBuffer, SequenceBatch, Transition};
pub use rollout::{rollout, Episode};
pub use train::{EpisodeReport, Trainer};
