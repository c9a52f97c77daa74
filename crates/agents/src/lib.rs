//! SAC, TD3 and DDPG with recurrent sequence replay.

pub mod replay;

pub use replay::{ReplayBuffer, SequenceBatch, Transition};
