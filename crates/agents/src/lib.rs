//! SAC, TD3 and DDPG with recurrent sequence replay.

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
pub use rollout::{mix_seed, rollout, Episode};
pub use train::{EpisodeReport, Trainer};
