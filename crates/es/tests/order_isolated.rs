//! Contract: the loop order changes nothing but the fate of the inner updates. With no inner
//! cycles, `replace-then-train` and `train-then-replace` give identical rows and weights for
//! the same seed; with inner cycles they part ways.

mod common;

use common::hybrid;
use esrl_agents::Algo;
use esrl_es::{EsConfig, GenerationReport, LoopOrder};

fn run(algo: Algo, order: LoopOrder, inner: usize) -> (Vec<GenerationReport>, Vec<f32>) {
    let es = EsConfig {
        order,
        ..EsConfig::default()
    };
    let mut h = hybrid(algo, es, inner);
    let rows = (0..8).map(|_| h.step().unwrap()).collect();
    (rows, h.trainer().agent().genome())
}

#[test]
fn without_inner_cycles_both_orders_are_identical() {
    for algo in [Algo::Sac, Algo::Td3] {
        let new = run(algo, LoopOrder::ReplaceThenTrain, 0);
        let old = run(algo, LoopOrder::TrainThenReplace, 0);
        assert_eq!(new, old, "{algo:?}");
        assert!(new
            .0
            .iter()
            .all(|r| !r.rl_trained && r.critic_loss.is_none()));
    }
}

#[test]
fn with_inner_cycles_the_orders_differ_and_flag_trained_actors() {
    for algo in [Algo::Sac, Algo::Td3] {
        let (new, _) = run(algo, LoopOrder::ReplaceThenTrain, 3);
        let (old, _) = run(algo, LoopOrder::TrainThenReplace, 3);
        assert_ne!(new, old, "{algo:?}");
        assert!(new[1..].iter().all(|r| r.rl_trained), "{algo:?}");
        // The old order evaluates a trained actor only after a generation that kept it.
        for w in old.windows(2) {
            assert_eq!(w[1].rl_trained, !w[0].rl_replaced, "{algo:?}: {w:?}");
        }
    }
}
