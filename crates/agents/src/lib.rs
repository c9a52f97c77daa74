//! SAC, TD3 and DDPG with recurrent sequence replay.

pub mod config;
pub mod replay;

pub use config::{Algo, ConfigError, LearnEvery, RlConfig};
pub use replay::{ReplayBuffer, SequenceBatch, Transition};
