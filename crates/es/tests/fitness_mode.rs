//! Contract: `es.fitness` decides how individuals act while scored. Under `deterministic`
//! and `both`, the kept individual's fitness is exactly the return of a tanh μ rollout of its
//! genome from the generation's initial state; `both` also runs an exploratory rollout per
//! evaluation (twice the steps); `auto` samples for ES-SAC (its fitness is not the tanh μ
//! return) and acts by tanh μ for ES-TD3.

mod common;

use common::hybrid;
use esrl_agents::rollout::{rollout, Actor};
use esrl_agents::{ActMode, Algo};
use esrl_es::{EsConfig, Fitness, Hybrid};
use esrl_sim::Pendulum;
use esrl_streams::Stream;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Return of the kept genome acting by tanh μ from generation `gen`'s first initial state.
fn deterministic_return(h: &Hybrid, gen: u64) -> f64 {
    let mut policy = h.trainer().agent().policy_from_genome(h.kept()).unwrap();
    let mut env = Pendulum::new();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let seed = Stream::EvaluationReset {
        generation: gen,
        evaluation: 0,
        evaluations: 1,
    }
    .seed(h.trainer().seed());
    rollout(
        &mut env,
        Actor::Policy(&mut policy, ActMode::Deterministic),
        seed,
        None,
        &mut rng,
    )
    .ret
}

fn with(fitness: Fitness, algo: Algo) -> Hybrid {
    hybrid(
        algo,
        EsConfig {
            fitness,
            ..EsConfig::default()
        },
        2,
    )
}

#[test]
fn deterministic_and_both_score_the_tanh_mu_rollout() {
    for fitness in [Fitness::Deterministic, Fitness::Both] {
        let mut h = with(fitness, Algo::Sac);
        for g in 0..3 {
            let steps = h.trainer().env_steps();
            let r = h.step().unwrap();
            assert_eq!(r.curve, deterministic_return(&h, g), "{fitness:?} gen {g}");
            let per_individual = if fitness == Fitness::Both { 400 } else { 200 };
            assert_eq!(r.env_steps - steps, 6 * per_individual, "{fitness:?}");
        }
    }
}

#[test]
fn auto_samples_for_sac_and_is_deterministic_for_td3() {
    let mut sac = with(Fitness::Auto, Algo::Sac);
    let r = sac.step().unwrap();
    assert_ne!(r.curve, deterministic_return(&sac, 0), "ES-SAC samples");
    let mut td3 = with(Fitness::Auto, Algo::Td3);
    let r = td3.step().unwrap();
    assert_eq!(
        r.curve,
        deterministic_return(&td3, 0),
        "ES-TD3 acts by tanh μ"
    );
}
