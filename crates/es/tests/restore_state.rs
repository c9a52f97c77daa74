//! Contract: a hybrid's full state is what the learner interface saves. A hybrid built fresh
//! from the same settings and restored from another's state (through JSON, as `state.json`),
//! tensors and replay buffer continues exactly as the original: the same rows, weights and
//! ES mean for the generations that follow.

mod common;

use common::hybrid;
use esrl_agents::{Algo, Learner, LearnerState, Resumable};
use esrl_es::{EsConfig, EsState};
use std::collections::HashMap;

#[test]
fn restored_hybrid_continues_bit_for_bit() {
    for algo in [Algo::Sac, Algo::Ddpg] {
        let mut original = hybrid(algo, EsConfig::default(), 3);
        for _ in 0..3 {
            original.step().unwrap();
        }
        let state = serde_json::to_string(&original.state()).unwrap();
        let tensors: HashMap<String, Vec<f32>> = original.tensors().into_iter().collect();
        let buffer = original.buffer().clone();

        let mut restored = hybrid(algo, EsConfig::default(), 3);
        let state: LearnerState<EsState> = serde_json::from_str(&state).unwrap();
        restored.restore(state, &tensors, buffer).unwrap();
        assert_eq!(restored.rows(), 3);
        for g in 3..6 {
            let (a, b) = (original.step().unwrap(), restored.step().unwrap());
            assert_eq!(a, b, "{algo:?} generation {g}");
        }
        assert_eq!(
            original.trainer().agent().state_tensors(),
            restored.trainer().agent().state_tensors(),
            "{algo:?}"
        );
        assert_eq!(original.strategy(), restored.strategy(), "{algo:?}");
    }
}
