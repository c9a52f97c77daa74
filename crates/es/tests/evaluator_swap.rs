//! Contract: the evaluator is replaceable. An evaluator that runs `rollout_genome`
//! elsewhere — here every genome sent through JSON, as to a remote worker, and rolled out on
//! its own thread, last genome first — gives the hybrid loop the same rows and weights, bit
//! for bit, as the local rayon evaluator on 1 or 3 threads.

mod common;

use common::{hybrid_with, local};
use esrl_agents::{AgentError, Algo};
use esrl_es::{rollout_genome, EsConfig, Evaluation, Evaluator, Generation, Genome};
use esrl_sim::Pendulum;
use std::sync::Arc;

/// A stand-in for a remote worker pool: genomes cross a serialisation boundary and come back
/// out of order.
#[derive(Debug)]
struct Remote;

impl Evaluator for Remote {
    fn evaluate(&self, generation: &Generation) -> Result<Vec<Evaluation>, AgentError> {
        let mut results: Vec<Option<Evaluation>> = vec![None; generation.genomes.len()];
        for (at, genome) in generation.genomes.iter().enumerate().rev() {
            let wire = serde_json::to_string(genome).unwrap();
            let policy = generation.policy.clone();
            let evaluation = std::thread::spawn(move || {
                let genome: Genome = serde_json::from_str(&wire).unwrap();
                rollout_genome(&policy, &genome, &mut Pendulum::new())
            })
            .join()
            .unwrap()?;
            results[at] = Some(evaluation);
        }
        Ok(results.into_iter().map(|r| r.unwrap()).collect())
    }
}

#[test]
fn a_remote_evaluator_gives_the_local_results() {
    for algo in [Algo::Sac, Algo::Td3] {
        let run = |evaluator: Arc<dyn Evaluator>| {
            let mut h = hybrid_with(algo, EsConfig::default(), 3, evaluator);
            let rows: Vec<_> = (0..4).map(|_| h.step().unwrap()).collect();
            (
                rows,
                h.trainer().agent().genome(),
                h.strategy().mean.clone(),
            )
        };
        let reference = run(local(1));
        assert_eq!(run(local(3)), reference, "{algo:?}: thread count");
        assert_eq!(
            run(Arc::new(Remote)),
            reference,
            "{algo:?}: remote evaluator"
        );
        assert!(
            reference.0.iter().any(|r| r.rl_replaced),
            "{algo:?}: replacement happened, so the genomes mattered"
        );
    }
}
