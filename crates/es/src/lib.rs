//! Evolution-strategy population and the hybrid ES-SAC / ES-TD3 / ES-DDPG loop.

pub mod strategy;

pub use strategy::{EsConfig, Strategy};
