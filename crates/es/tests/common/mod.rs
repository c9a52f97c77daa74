//! A small hybrid on the pendulum, shared by the loop tests.
#![allow(dead_code)]

use esrl_agents::{Agent, Algo, NetConfig, RlConfig};
use esrl_es::{EsConfig, Evaluator, Hybrid, HybridConfig, LocalEvaluator};
use esrl_sim::{Env, MakeEnv, Pendulum};
use std::sync::Arc;

/// Pendulum environments for the population.
pub fn envs() -> Arc<MakeEnv> {
    Arc::new(|| Box::new(Pendulum::new()) as Box<dyn Env>)
}

/// The local evaluator on `threads` threads.
pub fn local(threads: usize) -> Arc<dyn Evaluator> {
    Arc::new(LocalEvaluator::new(envs(), threads).unwrap())
}

/// A warm-started hybrid of `algo` with tiny networks, 6 individuals, σ 0.5 and
/// `inner_cycles` updates per generation, evaluated by `evaluator`.
pub fn hybrid_with(
    algo: Algo,
    es: EsConfig,
    inner_cycles: usize,
    evaluator: Arc<dyn Evaluator>,
) -> Hybrid {
    let cfg = RlConfig {
        batch_size: 8,
        warm_start: 100,
        ..RlConfig::for_algo(algo)
    };
    let agent = Agent::new(algo, 3, 1, &NetConfig::tiny(false), &cfg, 7).unwrap();
    let es = EsConfig {
        population: 6,
        sigma: 0.5,
        ..es
    };
    let mut h = Hybrid::new(agent, HybridConfig::new(es, inner_cycles), 7, evaluator);
    h.warm_start(&mut Pendulum::new());
    h
}

/// [`hybrid_with`] on the local evaluator with 2 threads.
pub fn hybrid(algo: Algo, es: EsConfig, inner_cycles: usize) -> Hybrid {
    hybrid_with(algo, es, inner_cycles, local(2))
}
