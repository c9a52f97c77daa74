//! Evolution-strategy population and the hybrid ES-SAC / ES-TD3 / ES-DDPG loop.
//!
//! [`Strategy`] is the ES of the paper's §3.2 on flat parameter vectors; [`Hybrid`] runs the
//! paper's §4 loop around an [`esrl_agents::Agent`], evaluating the population in parallel
//! with bit-identical results at any thread count.

pub mod hybrid;
pub mod strategy;

pub use hybrid::{GenerationReport, Hybrid, LoopStats};
pub use strategy::{elite_weights, rank, ConfigError, EsConfig, Fitness, LoopOrder, Strategy};
