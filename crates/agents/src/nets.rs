//! Which actor and critic networks an agent builds.

use esrl_nn::{ActorConfig, CriticConfig, NnError};
use serde::{Deserialize, Serialize};

/// Actor and critic sizes. The default is the paper's recurrent pair (Fig. 1), sized to its
/// parameter counts (actor ≈153.7k, critic ≈169.6k for the walking env).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct NetConfig {
    /// The actor (Fig. 1a).
    pub actor: ActorConfig,
    /// Each critic (Fig. 1b).
    pub critic: CriticConfig,
}

impl NetConfig {
    /// Feed-forward MLP 256×256 actor and critics (the usual SAC/TD3 networks).
    pub fn feed_forward() -> Self {
        Self {
            actor: ActorConfig::feed_forward(),
            critic: CriticConfig::feed_forward(),
        }
    }

    /// Very small networks of the same family, for smoke tests.
    pub fn tiny(recurrent: bool) -> Self {
        Self {
            actor: ActorConfig {
                fc: vec![16],
                recurrent,
                lstm_hidden: 8,
                ..ActorConfig::default()
            },
            critic: CriticConfig {
                obs_fc: vec![16],
                act_fc: vec![8],
                joint_fc: if recurrent { vec![] } else { vec![16] },
                recurrent,
                lstm_hidden: 8,
            },
        }
    }

    /// Whether the networks carry LSTM state (sequence replay) or not (single transitions).
    pub fn recurrent(&self) -> bool {
        self.actor.recurrent || self.critic.recurrent
    }

    /// Checks both networks' fields.
    pub fn validate(&self) -> Result<(), NnError> {
        self.actor.validate()?;
        self.critic.validate()
    }
}
