//! Contract: no two purposes share a seed. For several run seeds, every stream a run can
//! reach — generations up to 2,000 with 64 individuals and 4 evaluations each, 20,000 plain
//! episodes, 20,000 warm-start steps, 1,000 check starts, both critics — gets its own seed, and the seeds of the
//! streams named before issue 18 keep their old values (except the two moved generations).

use esrl_streams::{mix, Stream};
use std::collections::HashMap;

const GENERATIONS: u64 = 2_000;
const INDIVIDUALS: u64 = 64;
const EVALUATIONS: u64 = 4;

/// Every stream of one run, with K evaluations per individual.
fn streams(evaluations: u64) -> Vec<Stream> {
    let mut all = vec![
        Stream::ActorWeights,
        Stream::CriticWeights(0),
        Stream::CriticWeights(1),
        Stream::Updates,
        Stream::Trainer,
    ];
    all.extend((0..20_000).map(Stream::EpisodeReset));
    all.extend((0..20_000).map(Stream::WarmStartReset));
    all.extend((0..1_000).map(Stream::CheckReset));
    for generation in 0..GENERATIONS {
        all.extend((0..evaluations).map(|evaluation| Stream::EvaluationReset {
            generation,
            evaluation,
            evaluations,
        }));
        all.extend((0..INDIVIDUALS).map(|index| Stream::Individual { generation, index }));
        all.extend((1..INDIVIDUALS).map(|index| Stream::Perturbation { generation, index }));
    }
    all
}

#[test]
fn every_stream_of_a_run_has_its_own_seed() {
    for run_seed in [0, 1, 3, 42, 0x7A, u64::MAX] {
        for evaluations in [1, EVALUATIONS] {
            let mut seen: HashMap<u64, Stream> = HashMap::new();
            for stream in streams(evaluations) {
                if let Some(other) = seen.insert(stream.seed(run_seed), stream) {
                    panic!("run seed {run_seed}: {stream:?} and {other:?} share a seed");
                }
            }
        }
    }
}

#[test]
fn streams_named_before_keep_their_seeds() {
    let s = 7;
    assert_eq!(Stream::Trainer.seed(s), mix(s, 0x7A, 0));
    assert_eq!(Stream::EpisodeReset(5).seed(s), mix(s, 1, 5));
    assert_eq!(Stream::WarmStartReset(900).seed(s), mix(s, 3, 900));
    let reset = Stream::EvaluationReset {
        generation: 4,
        evaluation: 1,
        evaluations: 3,
    };
    assert_eq!(reset.seed(s), mix(s, 2, 13));
    assert_eq!(Stream::ActorWeights.seed(s), 31 * 7 + 1);
    assert_eq!(Stream::CriticWeights(1).seed(s), 31 * 7 + 3);
    assert_eq!(Stream::Updates.seed(s), 7 ^ 0x5EED_A6E7);
    let base = mix(s, 0xE5, 0);
    let eps = Stream::Perturbation {
        generation: 9,
        index: 2,
    };
    assert_eq!(eps.seed(s), mix(base, 9, 2));
    for generation in (0..GENERATIONS).filter(|g| ![118, 225].contains(g)) {
        let ind = Stream::Individual {
            generation,
            index: 5,
        };
        assert_eq!(
            ind.seed(s),
            mix(s, 4 + generation, 5),
            "generation {generation}"
        );
    }
}

#[test]
fn the_old_key_collided_where_individuals_were_moved() {
    // The reason for the move: keyed (4 + g, i), individual 0 of generation 118 drew the
    // trainer's stream.
    let s = 11;
    assert_eq!(mix(s, 4 + 118, 0), Stream::Trainer.seed(s));
    let moved = Stream::Individual {
        generation: 118,
        index: 0,
    };
    assert_ne!(moved.seed(s), Stream::Trainer.seed(s));
}
