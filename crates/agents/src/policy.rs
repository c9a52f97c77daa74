//! A policy acting one step at a time: an actor, its recurrent state, and how it explores.

use esrl_nn::{Actor, ActorStepState, Module};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// How a policy chooses actions during a rollout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ActMode {
    /// tanh(μ): evaluation, and ES individuals of TD3/DDPG.
    Deterministic,
    /// The algorithm's exploration ([`Exploration`]).
    Explore,
}

/// How an algorithm explores ([`ActMode::Explore`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Exploration {
    /// SAC: a sample of the tanh-squashed Gaussian policy.
    Sample,
    /// TD3/DDPG: tanh(μ) plus Gaussian noise of this standard deviation, clipped to [−1, 1].
    Noise(f32),
}

/// An actor ready to act one step at a time (no graph, no allocation per step).
#[derive(Debug, Clone)]
pub struct Policy {
    actor: Actor,
    state: ActorStepState,
    exploration: Exploration,
}

impl Policy {
    /// Wraps `actor`, exploring as `exploration` says.
    pub fn new(actor: Actor, exploration: Exploration) -> Self {
        let state = actor.step_state();
        Self {
            actor,
            state,
            exploration,
        }
    }

    /// Zeroes the recurrent state for a new episode.
    pub fn reset(&mut self) {
        self.state.reset();
    }

    /// The wrapped actor.
    pub fn actor(&self) -> &Actor {
        &self.actor
    }

    /// How it explores.
    pub fn exploration(&self) -> Exploration {
        self.exploration
    }

    /// Takes `actor`'s current weights, keeping the recurrent state (a learner's policy
    /// mid-episode).
    pub fn sync_from(&mut self, actor: &Actor) -> Result<(), esrl_nn::NnError> {
        self.actor.params_mut().copy_from(actor.params())
    }

    /// Sets the actor's weights from a flat vector (an ES genome's actor part).
    pub fn set_weights(&mut self, flat: &[f32]) -> Result<(), esrl_nn::NnError> {
        self.actor.params_mut().set_flat(flat)
    }

    /// Chooses the action for `obs` into `action` (each entry in [−1, 1]).
    pub fn act<R: Rng + ?Sized>(
        &mut self,
        obs: &[f32],
        mode: ActMode,
        rng: &mut R,
        action: &mut [f32],
    ) {
        self.actor.step(obs, &mut self.state);
        match (mode, self.exploration) {
            (ActMode::Deterministic, _) => self.state.deterministic_action(action),
            (ActMode::Explore, Exploration::Sample) => self.state.sample_action(rng, action),
            (ActMode::Explore, Exploration::Noise(sd)) => {
                self.state.deterministic_action(action);
                for a in action.iter_mut() {
                    let e: f32 = rng.sample(StandardNormal);
                    *a = (*a + sd * e).clamp(-1.0, 1.0);
                }
            }
        }
    }
}
