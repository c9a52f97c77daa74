//! The interface every training loop drives, in two small traits: [`Learner`] runs one row —
//! an episode of a plain agent ([`crate::Trainer`]), a generation of the hybrid ES loop
//! (`esrl_es::Hybrid`) — and reports it; [`Resumable`] saves and restores its full state.
//! Whoever drives it (the `esrl` binary, a test, a notebook) only loops, writes rows and
//! checkpoints.

use crate::agent::{Agent, AgentError};
use crate::replay::ReplayBuffer;
use esrl_sim::MakeEnv;
use rand_chacha::ChaCha8Rng;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// One row of a run's metrics (`metrics.jsonl`): its columns are the row's serialised fields.
pub trait Row: Serialize + Send {
    /// The learning-curve value of the row (SPEC §6).
    fn curve(&self) -> f64;
    /// Q₀ of the row (SPEC §6).
    fn q0(&self) -> f64;
    /// Environment steps taken so far, this row included.
    fn env_steps(&self) -> u64;
    /// One line for progress bars and logs.
    fn summary(&self) -> String;
}

/// A learner's counters and random streams, as `state.json` keeps them: the RL side's, which
/// every learner has, and its loop's (`loop_state`: nothing for a plain trainer, the ES
/// loop's counters for the hybrid one), whose fields stand beside these in the file. Weights
/// and the replay buffer are saved apart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnerState<S = ()> {
    /// Training episodes completed (plain agents).
    pub episodes: usize,
    /// Environment steps taken.
    pub env_steps: u64,
    /// The trainer's random stream.
    pub trainer_rng: ChaCha8Rng,
    /// Gradient updates done.
    pub agent_updates: u64,
    /// The agent's random stream.
    pub agent_rng: ChaCha8Rng,
    /// Whether the replay buffer's last episode is still open.
    pub episode_open: bool,
    /// The loop's counters. (Serde reads a flattened part through a buffer that cannot hold
    /// the streams' 128-bit counters, so the streams stay out here.)
    #[serde(flatten)]
    pub loop_state: S,
}

/// The RL side's state alone: a plain trainer's.
pub type TrainerState = LearnerState<()>;

impl<S> LearnerState<S> {
    /// This state with `loop_state` as its loop's part, and the part it had.
    pub fn with_loop_state<T>(self, loop_state: T) -> (LearnerState<T>, S) {
        let Self {
            episodes,
            env_steps,
            trainer_rng,
            agent_updates,
            agent_rng,
            episode_open,
            loop_state: old,
        } = self;
        let state = LearnerState {
            episodes,
            env_steps,
            trainer_rng,
            agent_updates,
            agent_rng,
            episode_open,
            loop_state,
        };
        (state, old)
    }
}

/// A learner trained row by row. Learners are `Send`: a training session steps them inside
/// its thread pool; [`Resumable`] is how a session checkpoints them.
pub trait Learner: Resumable + Send {
    /// One row of the metrics.
    type Row: Row;
    /// What a row is: `"episode"` or `"generation"`.
    const UNIT: &'static str;

    /// Work before the first row that is no row itself (the hybrid loop's warm start);
    /// nothing once done, so it may run again after a restore.
    fn prepare(&mut self, _envs: &MakeEnv) -> Result<(), AgentError> {
        Ok(())
    }

    /// Runs one row, taking fresh environments from `envs`.
    fn run_row(&mut self, envs: &MakeEnv) -> Result<Self::Row, AgentError>;

    /// Rows completed.
    fn rows(&self) -> usize;

    /// Environment steps taken.
    fn env_steps(&self) -> u64;

    /// The RL agent.
    fn agent(&self) -> &Agent;

    /// The agent whose policy scored the last row's learning-curve value, when that is not
    /// [`Learner::agent`] itself (the hybrid loop's best individual); `None` otherwise.
    fn scored_agent(&self) -> Result<Option<Agent>, AgentError> {
        Ok(None)
    }

    /// The agent whose policy is the centre of the learner's search distribution (the hybrid
    /// loop's ES mean θ, with which its perturbations of the next generation are drawn);
    /// `None` for a learner without one.
    fn mean_agent(&self) -> Result<Option<Agent>, AgentError> {
        Ok(None)
    }

    /// Run-level figures for `summary.json` beyond the curve's, by name.
    fn summary_figures(&self) -> Vec<(&'static str, Option<f64>)> {
        Vec::new()
    }
}

/// A learner's full state, in three parts: [`Resumable::state`] (counters and random
/// streams, small, serialisable), [`Resumable::tensors`] (weights and optimiser moments) and
/// [`Resumable::buffer`] (the replay buffer). Restoring the three into a learner built fresh
/// from the same configuration continues the run exactly.
pub trait Resumable {
    /// The loop's counters, beside the RL side's in [`LearnerState`] (`()` for a plain
    /// trainer).
    type LoopState: Serialize + DeserializeOwned + Clone;

    /// Counters and random streams.
    fn state(&self) -> LearnerState<Self::LoopState>;

    /// Every tensor: the agent's (networks, targets, optimiser moments, log α) and the
    /// learner's own (the ES mean).
    fn tensors(&self) -> Vec<(String, Vec<f32>)>;

    /// The replay buffer.
    fn buffer(&self) -> &ReplayBuffer;

    /// Checks a saved state against this learner's configuration and the `rows` the
    /// checkpoint covers, before anything is restored; the error names the field.
    fn check(&self, state: &LearnerState<Self::LoopState>, rows: usize) -> Result<(), AgentError>;

    /// Restores a saved state, its tensors and its replay buffer.
    fn restore(
        &mut self,
        state: LearnerState<Self::LoopState>,
        tensors: &HashMap<String, Vec<f32>>,
        buffer: ReplayBuffer,
    ) -> Result<(), AgentError>;
}

/// A [`AgentError::State`] for `field`.
pub(crate) fn state_error(field: &str, reason: String) -> AgentError {
    AgentError::State {
        field: field.into(),
        reason,
    }
}
