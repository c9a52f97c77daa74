//! The evolution strategy of the paper (§3.2) and the hybrid ES-SAC / ES-TD3 / ES-DDPG loop
//! (§4–5) around an [`esrl_agents::Agent`].
//!
//! - [`Strategy`] (`strategy.rs`): the ES on flat parameter vectors, eqs. 8–11 — perturb,
//!   recombine the elites with log-rank weights, decay σ.
//! - [`Hybrid`] (`hybrid.rs`): one generation as ask/tell. [`Hybrid::ask`] hands out a
//!   [`Generation`] of [`Genome`]s, each with its seeds; an [`Evaluator`] turns them into
//!   episodes with the stateless [`rollout_genome`] (`evaluate.rs`), on local threads
//!   ([`LocalEvaluator`]) or anywhere else; [`Hybrid::tell`] stores the transitions, updates
//!   the ES, replaces the RL actor when it was beaten and runs the inner training cycles.
//!   [`Hybrid::step`] does all three. `Hybrid` is an [`esrl_agents::Learner`], so the same
//!   loop that trains a plain agent drives it.
//!
//! - [`wire`]: genomes and evaluations as compact bytes, for evaluators in other processes;
//!   [`remote`]: both ends of such an evaluator ([`WireEvaluator`] over a [`Transport`] on
//!   the driver, [`Worker`] on the other side).
//!
//! Reading ES-SAC top to bottom: `hybrid.rs` ([`Hybrid::step`]: eq. 8 → 9 → 10–11 →
//! replacement → training), `evaluate.rs` (eq. 9), `strategy.rs` (eqs. 8, 10, 11), then
//! `esrl_agents`' `train.rs` (the inner cycles) and `sac.rs` (the SAC update, each line under
//! its equation).
//!
//! ```
//! use esrl_agents::{Agent, Algo, NetConfig, RlConfig};
//! use esrl_es::{EsConfig, Hybrid, HybridConfig, LocalEvaluator};
//! use esrl_sim::{Env, MakeEnv, Pendulum};
//! use std::sync::Arc;
//!
//! let cfg = RlConfig { batch_size: 8, warm_start: 100, ..RlConfig::for_algo(Algo::Sac) };
//! let agent = Agent::new(Algo::Sac, 3, 1, &NetConfig::tiny(false), &cfg, 0)?;
//! let envs: Arc<MakeEnv> = Arc::new(|| Box::new(Pendulum::new()) as Box<dyn Env>);
//! let evaluator = Arc::new(LocalEvaluator::new(envs, 2).expect("a thread pool"));
//! let es = EsConfig { population: 4, ..EsConfig::default() };
//! let mut hybrid = Hybrid::new(agent, HybridConfig::new(es, 5), 0, evaluator);
//! hybrid.warm_start(&mut Pendulum::new());
//! let row = hybrid.step()?;
//! assert_eq!(row.generation, 0);
//! assert_eq!(hybrid.trainer().agent().updates(), 5);
//! # Ok::<(), esrl_agents::AgentError>(())
//! ```
//!
//! # Limitations
//!
//! - Results are bit-identical for a seed at any thread count and with any evaluator that
//!   runs [`rollout_genome`] on the genomes it is given; they are not across CPUs whose SIMD
//!   widths differ (`esrl-nn`'s products) or across versions of the simulator.
//! - A generation waits for its slowest individual: every genome of a generation is rolled
//!   out before anything is learned. Only the next generation's perturbations overlap the
//!   inner cycles (pipelining, `hybrid.rs`); individual 0 waits for them.
//! - The strategy is isotropic (one σ for every parameter, no covariance), as the paper's;
//!   σ follows eq. 11's fixed decay rather than adapting to progress.
//! - Fitness is the mean return of K rollouts (K = 1 by default): noisy for stochastic
//!   policies, which `es.fitness` lets one trade against the buffer's exploratory data.

mod compat;
pub mod evaluate;
pub mod hybrid;
pub mod remote;
pub mod strategy;
pub mod wire;

pub use evaluate::{
    rollout_genome, Evaluation, Evaluator, Generation, Genome, LocalEvaluator, RolloutSpec,
};
pub use hybrid::{EsState, GenerationReport, Hybrid, HybridConfig, LoopStats};
pub use remote::{Traffic, Transport, WireEvaluator, Worker};
pub use strategy::{elite_weights, rank, ConfigError, EsConfig, Fitness, LoopOrder, Strategy};
pub use wire::{decode_evaluation, decode_genome, encode_evaluation, encode_genome, WireError};
