//! A small hybrid on the pendulum, shared by the loop tests.

use esrl_agents::{Agent, Algo, NetConfig, RlConfig};
use esrl_es::{EsConfig, Hybrid};
use esrl_sim::{Env, Pendulum};

/// A pendulum environment for the population.
pub fn make_env() -> Box<dyn Env> {
    Box::new(Pendulum::new())
}

/// A rollout pool of `threads` threads.
pub fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// A warm-started hybrid of `algo` with tiny networks, 6 individuals, σ 0.5 and
/// `inner_cycles` updates per generation.
pub fn hybrid(algo: Algo, es: EsConfig, inner_cycles: usize) -> Hybrid {
    let cfg = RlConfig {
        batch_size: 8,
        warm_start: 100,
        ..RlConfig::default()
    };
    let agent = Agent::new(algo, 3, 1, &NetConfig::tiny(false), &cfg, 7).unwrap();
    let es = EsConfig {
        population: 6,
        sigma: 0.5,
        ..es
    };
    let mut h = Hybrid::new(agent, es, inner_cycles, 7);
    h.warm_start(make_env().as_mut());
    h
}
