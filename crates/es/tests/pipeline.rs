//! Contract: the pipelined loop (the next generation's perturbations rolled out while the
//! inner cycles train) computes exactly what the sequential loop does: the same rows and the
//! same weights, for ES-SAC and ES-TD3, at 1 and 2 threads, on an evaluator with its own pool
//! and on the pool the loop is stepped in. And it does pipeline: after the first generation
//! the evaluator is asked for individual 0 alone, the others having been rolled out during
//! the training.

mod common;

use common::{envs, hybrid_with};
use esrl_agents::{Algo, Resumable};
use esrl_es::{EsConfig, Evaluation, Evaluator, Generation, LocalEvaluator};
use std::sync::{Arc, Mutex};

/// A local evaluator that records how many genomes each call evaluated.
#[derive(Debug)]
struct Counting {
    inner: LocalEvaluator,
    calls: Mutex<Vec<usize>>,
}

impl Evaluator for Counting {
    fn evaluate(
        &self,
        generation: &Generation,
    ) -> Result<Vec<Evaluation>, esrl_agents::AgentError> {
        self.calls.lock().unwrap().push(generation.genomes.len());
        self.inner.evaluate(generation)
    }
}

fn counting(inner: LocalEvaluator) -> Arc<Counting> {
    Arc::new(Counting {
        inner,
        calls: Mutex::new(Vec::new()),
    })
}

#[test]
fn pipelined_and_sequential_loops_agree_bit_for_bit() {
    for algo in [Algo::Sac, Algo::Td3] {
        for threads in [1, 2] {
            for own_pool in [true, false] {
                let make = || {
                    if own_pool {
                        LocalEvaluator::new(envs(), threads).unwrap()
                    } else {
                        LocalEvaluator::on_calling_pool(envs())
                    }
                };
                let (ev_p, ev_s) = (counting(make()), counting(make()));
                let mut pipelined = hybrid_with(algo, EsConfig::default(), 6, ev_p.clone());
                let mut sequential = hybrid_with(algo, EsConfig::default(), 6, ev_s.clone());
                sequential.set_pipelined(false);
                assert!(pipelined.pipelined());
                let pool = esrl_nn::subnormal::thread_pool(threads).unwrap();
                for g in 0..5 {
                    let (a, b) = pool.install(|| (pipelined.step(), sequential.step()));
                    let (a, b) = (a.unwrap(), b.unwrap());
                    assert_eq!(a, b, "{algo:?}, {threads} threads, gen {g}: rows differ");
                }
                assert_eq!(
                    pipelined.tensors(),
                    sequential.tensors(),
                    "{algo:?}, {threads} threads: weights, moments or ES mean differ"
                );
                assert!(
                    pipelined.buffer() == sequential.buffer(),
                    "{algo:?}: the buffers hold the same transitions in the same order"
                );
                // Sequential: 6 genomes a generation. Pipelined: 6, then 5 ahead during each
                // training and individual 0 alone at the start of every later generation.
                assert_eq!(*ev_s.calls.lock().unwrap(), vec![6; 5]);
                assert_eq!(
                    *ev_p.calls.lock().unwrap(),
                    vec![6, 5, 1, 5, 1, 5, 1, 5, 1, 5],
                    "{algo:?}, {threads} threads, own pool {own_pool}"
                );
            }
        }
    }
}
