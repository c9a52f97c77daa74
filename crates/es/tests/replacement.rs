//! Contract: individual 0 of every population is the RL actor, and elitist replacement
//! happens exactly when another individual beat it: then the kept genome is that
//! individual's; otherwise the RL actor was the best and is kept. The learning curve is the
//! best fitness of the generation.

mod common;

use common::hybrid;
use esrl_agents::Algo;
use esrl_es::EsConfig;

#[test]
fn rl_actor_is_in_every_population_and_replaced_only_when_beaten() {
    for algo in [Algo::Sac, Algo::Td3, Algo::Ddpg] {
        let mut h = hybrid(algo, EsConfig::default(), 3);
        let (mut replaced, mut kept) = (0, 0);
        for _ in 0..8 {
            let population = h.population();
            assert_eq!(population.len(), 6);
            assert_eq!(
                population[0],
                h.trainer().agent().genome(),
                "individual 0 is the RL actor"
            );
            let r = h.step().unwrap();
            assert_eq!(
                r.rl_replaced,
                r.best_fitness > r.rl_fitness,
                "{algo:?}: {r:?}"
            );
            if r.rl_replaced {
                replaced += 1;
                let best = population
                    .iter()
                    .position(|g| g == h.kept())
                    .expect("the kept genome is a population member's");
                assert_ne!(best, 0);
            } else {
                kept += 1;
                assert_eq!(r.rl_rank, 0, "not replaced means the RL actor was best");
                assert_eq!(h.kept(), population[0]);
            }
            assert_eq!(r.curve, r.best_fitness);
        }
        assert!(
            replaced > 0 && kept + replaced == 8,
            "{algo:?}: replaced {replaced} of 8"
        );
    }
}

/// Contract: the hybrid loop's mean agent (`Learner::mean_agent`, checked with `check.mean`)
/// is the RL agent with the ES mean θ as its genome: the actor (and ES-SAC's log α) of θ,
/// which moves with each generation's eqs. 10–11.
#[test]
fn the_mean_agent_carries_the_es_mean() {
    use esrl_agents::Learner;
    for algo in [Algo::Sac, Algo::Td3] {
        let mut h = hybrid(algo, EsConfig::default(), 3);
        let mut means = Vec::new();
        for _ in 0..3 {
            h.step().unwrap();
            let agent = h.mean_agent().unwrap().expect("a hybrid has an ES mean");
            assert_eq!(agent.genome(), h.strategy().mean, "{algo:?}");
            assert_eq!(agent.genome_len(), h.trainer().agent().genome_len());
            means.push(agent.genome());
        }
        assert!(means[0] != means[2], "{algo:?}: the mean moved");
    }
}
