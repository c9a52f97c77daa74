//! The gradient update of SAC, TD3 and DDPG ([`Agent::update`]): training and every
//! benchmark run this code. It dispatches on the algorithm to its own straight-line update,
//! each step under its equation number: `sac.rs` (paper eqs. 3–7) and `td3.rs` (DDPG is TD3
//! with one critic and its tricks off). The steps they share are in `steps.rs`, the
//! deterministic parallel execution over parts of the batch in `chunks.rs`.

use crate::agent::{Agent, AgentError, UpdateStats};
use crate::config::Algo;
use crate::replay::SequenceBatch;
use crate::{sac, td3};

impl Agent {
    /// One gradient update on `batch`: the algorithm's (`sac.rs`, or `td3.rs` for TD3 and DDPG),
    /// with subnormal floats flushed to zero ([`esrl_nn::subnormal`]).
    pub fn update(&mut self, batch: &SequenceBatch) -> Result<UpdateStats, AgentError> {
        esrl_nn::subnormal::flushing(|| match self.algo {
            Algo::Sac => sac::update(self, batch),
            Algo::Td3 | Algo::Ddpg => td3::update(self, batch),
        })
    }
}
