//! The interface every training loop drives ([`Learner`]): a learner runs one row — an
//! episode of a plain agent ([`crate::Trainer`]), a generation of the hybrid ES loop
//! (`esrl_es::Hybrid`) — reports it, and saves and restores its full state. Whoever drives
//! it (the `esrl` binary, a test, a notebook) only loops, writes rows and checkpoints.

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
/// every learner has, and the learner's own (`own`: nothing for a plain trainer, the loop's
/// counters for the hybrid one), whose fields stand beside these in the file. Weights and the
/// replay buffer are saved apart.
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
    /// The learner's own counters. (Serde reads a flattened part through a buffer that
    /// cannot hold the streams' 128-bit counters, so the streams stay out here.)
    #[serde(flatten)]
    pub own: S,
}

/// The RL side's state alone: a plain trainer's.
pub type TrainerState = LearnerState<()>;

impl<S> LearnerState<S> {
    /// This state with `own` as the learner's own part, and the part it had.
    pub fn replace_own<T>(self, own: T) -> (LearnerState<T>, S) {
        let Self {
            episodes,
            env_steps,
            trainer_rng,
            agent_updates,
            agent_rng,
            episode_open,
            own: old,
        } = self;
        let state = LearnerState {
            episodes,
            env_steps,
            trainer_rng,
            agent_updates,
            agent_rng,
            episode_open,
            own,
        };
        (state, old)
    }
}

/// A learner trained row by row.
///
/// Its full state is three parts: [`Learner::state`] (counters and random streams, small,
/// serialisable), [`Learner::tensors`] (weights and optimiser moments) and
/// [`Learner::buffer`] (the replay buffer). Restoring the three into a learner built fresh
/// from the same configuration continues the run exactly. Learners are `Send`: a training
/// session steps them inside its thread pool.
pub trait Learner: Send {
    /// One row of the metrics.
    type Row: Row;
    /// The learner's own counters, beside the RL side's in [`LearnerState`].
    type Own: Serialize + DeserializeOwned + Clone;
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

    /// The replay buffer.
    fn buffer(&self) -> &ReplayBuffer;

    /// The agent whose policy scored the last row's learning-curve value, when that is not
    /// [`Learner::agent`] itself (the hybrid loop's best individual); `None` otherwise.
    fn scored_agent(&self) -> Result<Option<Agent>, AgentError> {
        Ok(None)
    }

    /// Run-level figures for `summary.json` beyond the curve's, by name.
    fn summary_figures(&self) -> Vec<(&'static str, Option<f64>)> {
        Vec::new()
    }

    /// Counters and random streams.
    fn state(&self) -> LearnerState<Self::Own>;

    /// Every tensor: the agent's (networks, targets, optimiser moments, log α) and the
    /// learner's own (the ES mean).
    fn tensors(&self) -> Vec<(String, Vec<f32>)>;

    /// Checks a saved state against this learner's configuration and the `rows` the
    /// checkpoint covers, before anything is restored; the error names the field.
    fn check(&self, state: &LearnerState<Self::Own>, rows: usize) -> Result<(), AgentError>;

    /// Restores a saved state, its tensors and its replay buffer.
    fn restore(
        &mut self,
        state: LearnerState<Self::Own>,
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
