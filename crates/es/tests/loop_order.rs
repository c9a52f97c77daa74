//! Contract: the gradient work is never discarded unevaluated. After generation g, the genome
//! evaluated as individual 0 of generation g + 1 is the actor of generation g's replacement
//! (the best individual's genome when it beat the RL actor) refined by that generation's
//! inner training cycles — under the default `es.order = "replace-then-train"`.
//!
//! The expected genome is built independently: the same evaluations told to a copy with no
//! inner cycles (replacement only), then the inner updates applied by hand.

mod common;

use common::{hybrid, local};
use esrl_agents::Algo;
use esrl_es::EsConfig;

#[test]
fn individual_zero_of_the_next_generation_is_the_replaced_then_trained_actor() {
    let evaluator = local(2);
    let inner = 4;
    for algo in [Algo::Sac, Algo::Td3, Algo::Ddpg] {
        let mut h = hybrid(algo, EsConfig::default(), inner);
        let (mut replaced, mut kept) = (0, 0);
        for g in 0..10 {
            let generation = h.ask();
            let evaluated = evaluator.evaluate(&generation).unwrap();
            let mut expected = h.clone();
            let r = h.tell(&generation, evaluated.clone()).unwrap();

            expected.set_inner_cycles(0);
            let r0 = expected.tell(&generation, evaluated).unwrap();
            assert_eq!(
                (r0.rl_replaced, r0.best_fitness, r0.rl_fitness),
                (r.rl_replaced, r.best_fitness, r.rl_fitness),
                "{algo:?} gen {g}: the inner cycles come after the evaluation"
            );
            if r.rl_replaced {
                assert_eq!(
                    expected.trainer().agent().genome(),
                    h.kept(),
                    "replacement gives the RL actor the best genome"
                );
                replaced += 1;
            } else {
                kept += 1;
            }
            for _ in 0..inner {
                expected.trainer_mut().update().unwrap();
            }
            assert_eq!(
                h.population()[0],
                expected.trainer().agent().genome(),
                "{algo:?} gen {g}: individual 0 of the next generation is the refined actor"
            );
            assert!(
                h.rl_trained(),
                "{algo:?} gen {g}: the next individual 0 is trained"
            );
            assert_eq!(r.rl_trained, g > 0, "{algo:?} gen {g}: {r:?}");
            if r.rl_replaced {
                assert_ne!(
                    h.population()[0],
                    h.kept(),
                    "{algo:?} gen {g}: the replaced actor was trained further"
                );
            }
        }
        assert!(
            replaced > 0 && kept > 0,
            "{algo:?}: both branches exercised (replaced {replaced}, kept {kept})"
        );
        assert_eq!(h.stats().generations, 10);
        assert_eq!(h.stats().trained, 9);
        assert_eq!(h.stats().replaced, replaced);
    }
}
