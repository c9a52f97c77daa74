//! Contract: genomes and evaluations cross the wire unchanged, bit for bit (the genomes of a
//! real generation, the evaluations a local evaluator made of them on the pendulum and on the
//! walking env); an evaluation sends each observation row once (the next observation is the
//! following step's observation), which on the walker is under 0.6 of the four arrays sent
//! whole; and bytes that do not decode
//! (any truncation, a wrong tag, a bad flag, trailing bytes) are errors, never panics.

mod common;

use common::{envs, hybrid};
use esrl_agents::Algo;
use esrl_es::{
    decode_evaluation, decode_genome, encode_evaluation, encode_genome, rollout_genome, EsConfig,
    Evaluator, LocalEvaluator, WireError,
};
use esrl_sim::{WalkConfig, WalkEnv};

#[test]
fn a_generation_crosses_the_wire_unchanged() {
    let h = hybrid(Algo::Sac, EsConfig::default(), 0);
    let generation = h.ask();
    let evaluations = LocalEvaluator::new(envs(), 1)
        .unwrap()
        .evaluate(&generation)
        .unwrap();
    for (genome, evaluation) in generation.genomes.iter().zip(&evaluations) {
        let bytes = encode_genome(genome);
        assert_eq!(&decode_genome(&bytes).unwrap(), genome);
        assert_eq!(
            bytes.len(),
            4 + 4 + 8 + 4 + 8 + 4 + 2 + 4 + 4 * genome.params.len()
        );

        let bytes = encode_evaluation(evaluation);
        assert_eq!(&decode_evaluation(&bytes).unwrap(), evaluation);
        // Each episode: 21 bytes of header, T flags, a layout byte, and T + 1 observation
        // rows, T action rows and T rewards.
        let expected: usize = 16
            + evaluation
                .episodes
                .iter()
                .map(|e| {
                    let t = e.len();
                    21 + t + 1 + 4 * ((t + 1) * e.obs_dim + t * e.act_dim + t)
                })
                .sum::<usize>();
        assert_eq!(bytes.len(), expected);
    }
}

#[test]
fn walking_episodes_cross_the_wire_unchanged() {
    let h = hybrid(Algo::Td3, EsConfig::default(), 0);
    let generation = h.ask();
    // The pendulum hybrid's genomes do not fit the walker's actor: roll a walker's own out.
    let mut env = WalkEnv::new(WalkConfig::default()).unwrap();
    let agent = esrl_agents::Agent::new(
        Algo::Td3,
        esrl_sim::Env::obs_dim(&env),
        esrl_sim::Env::act_dim(&env),
        &esrl_agents::NetConfig::tiny(false),
        &esrl_agents::RlConfig::for_algo(Algo::Td3),
        3,
    )
    .unwrap();
    let genome = esrl_es::Genome {
        params: agent.genome(),
        ..generation.genomes[1].clone()
    };
    let evaluation = rollout_genome(&agent.policy(), &genome, &mut env).unwrap();
    assert!(evaluation.episodes.iter().all(|e| e.len() > 1));
    let bytes = encode_evaluation(&evaluation);
    assert_eq!(decode_evaluation(&bytes).unwrap(), evaluation);
    // With the walker's wide observation the shared rows halve the traffic, nearly.
    let whole: usize = evaluation
        .episodes
        .iter()
        .map(|e| 4 * (e.obs.len() + e.next_obs.len() + e.action.len() + e.reward.len()))
        .sum();
    assert!(
        (bytes.len() as f64) < 0.6 * whole as f64,
        "{} bytes against {whole} for the arrays sent whole",
        bytes.len()
    );
}

#[test]
fn bad_bytes_are_errors() {
    let h = hybrid(Algo::Sac, EsConfig::default(), 0);
    let generation = h.ask();
    let genome = encode_genome(&generation.genomes[0]);
    let evaluation = encode_evaluation(
        &LocalEvaluator::new(envs(), 1)
            .unwrap()
            .evaluate(&generation)
            .unwrap()[0],
    );
    for cut in [0, 3, 4, 10, 30, genome.len() - 1] {
        assert!(matches!(
            decode_genome(&genome[..cut]),
            Err(WireError::Truncated { .. })
        ));
    }
    for cut in (0..evaluation.len()).step_by(97) {
        assert!(
            decode_evaluation(&evaluation[..cut]).is_err(),
            "cut at {cut}"
        );
    }
    assert!(matches!(
        decode_genome(&evaluation),
        Err(WireError::Magic { .. })
    ));
    let mut trailing = genome.clone();
    trailing.push(0);
    assert_eq!(decode_genome(&trailing), Err(WireError::Trailing(1)));
    let mut bad_mode = genome.clone();
    // The first rollout's mode byte: tag, index, action seed, K, K seeds, R.
    let k = generation.genomes[0].env_seeds.len();
    bad_mode[4 + 4 + 8 + 4 + 8 * k + 4] = 7;
    assert_eq!(
        decode_genome(&bad_mode),
        Err(WireError::Value {
            what: "rollout mode",
            value: 7
        })
    );
}
