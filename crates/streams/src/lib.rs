//! Named random streams: every random number of a training run comes from a ChaCha8 stream
//! whose seed is derived, here and nowhere else, from the run seed (`--seed`) and the
//! stream's purpose, a [`Stream`].
//!
//! Keying streams by purpose and index, never by which thread runs them, is what makes a run
//! bit-identical at any thread count: individual 3 of generation 7 draws the same numbers
//! whichever worker evaluates it, and a remote worker given the same [`Stream`] does too.
//!
//! ```
//! use esrl_streams::Stream;
//!
//! let run_seed = 42;
//! let a = Stream::Individual { generation: 7, index: 3 }.seed(run_seed);
//! assert_eq!(a, Stream::Individual { generation: 7, index: 3 }.seed(run_seed));
//! assert_ne!(a, Stream::Individual { generation: 7, index: 4 }.seed(run_seed));
//! let _rng = Stream::Trainer.rng(run_seed); // a ChaCha8 generator
//! ```
//!
//! # Derivation
//!
//! Most purposes mix the run seed with a purpose tag `a` and an index `b` through [`mix`]
//! (a SplitMix64 finaliser):
//!
//! | purpose | key |
//! |---|---|
//! | [`Stream::EpisodeReset`] `n` | `mix(s, 1, n)` |
//! | [`Stream::EvaluationReset`] | `mix(s, 2, g·K + e)` |
//! | [`Stream::WarmStartReset`] `n` | `mix(s, 3, n)` |
//! | [`Stream::Individual`] | `mix(s, 4 + g, i)` (two generations moved, below) |
//! | [`Stream::Trainer`] | `mix(s, 0x7A, 0)` |
//! | [`Stream::Perturbation`] | `mix(mix(s, 0xE5, 0), g, i)` |
//! | [`Stream::CheckReset`] `k` | `mix(s, 2⁶² + 0xC4EC, k)` |
//! | [`Stream::ActorWeights`] | `31·s + 1` |
//! | [`Stream::CriticWeights`] `k` | `31·s + 2 + k` |
//! | [`Stream::Updates`] | `s ⊕ 0x5EED_A6E7` |
//!
//! The individual tag `4 + g` grows with the generation and would meet the fixed tags `0x7A`
//! at g = 118 and `0xE5` at g = 225; those two generations take the tag `2⁶³ + 4 + g`
//! instead, a range no other purpose uses (CHANGELOG.md says why the tags are these). The
//! crate's tests check that no two purposes share a seed.
//!
//! # Limitations
//!
//! Distinct keys give distinct seeds ([`mix`] is a bijection of its input), but the input
//! `s ⊕ a·K₁ ⊕ b·K₂` of two different `(a, b)` could in principle coincide; the tests check
//! the ranges a run can reach (generations, individuals, episodes, steps), not all 2¹²⁸.

use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Why a random stream exists. [`Stream::seed`] derives its seed from the run seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stream {
    /// The actor's initial weights.
    ActorWeights,
    /// Critic `k`'s initial weights (0-based).
    CriticWeights(u64),
    /// The agent's own draws during updates: SAC's action samples in the target, the actor
    /// loss and the burn-in; TD3's target smoothing noise.
    Updates,
    /// The trainer's draws: warm-start actions, plain agents' exploration, replay batches.
    Trainer,
    /// The initial state of plain training episode `n` (0-based).
    EpisodeReset(u64),
    /// The initial state of evaluation `evaluation` (of `evaluations` per individual) of
    /// generation `generation`, shared by every individual of the generation (common random
    /// numbers: fitness differences come from the policies).
    EvaluationReset {
        /// Generation, from 0.
        generation: u64,
        /// Which of the individual's K evaluations, from 0.
        evaluation: u64,
        /// K, evaluations per individual.
        evaluations: u64,
    },
    /// The initial state of the warm-start episode that starts at environment step `n`.
    WarmStartReset(u64),
    /// Individual `index`'s action draws (exploration) in generation `generation`.
    Individual {
        /// Generation, from 0.
        generation: u64,
        /// Individual, from 0 (0 is the RL actor).
        index: u64,
    },
    /// The initial state of start `k` of the walking check (`esrl-run`'s `check`): the same
    /// starts for every check of a run.
    CheckReset(u64),
    /// The ES noise εᵢ of individual `index` in generation `generation` (eq. 8).
    Perturbation {
        /// Generation, from 0.
        generation: u64,
        /// Individual, from 1 (individual 0 is the RL actor, not a perturbation).
        index: u64,
    },
}

/// Purpose tags of [`mix`] (see the crate docs' table).
const EPISODE: u64 = 1;
const EVALUATION: u64 = 2;
const WARM_START: u64 = 3;
const INDIVIDUAL: u64 = 4;
const TRAINER: u64 = 0x7A;
const PERTURBATION: u64 = 0xE5;
/// Above every individual tag a run can reach (4 + g, g < 2⁶²) and below [`MOVED`].
const CHECK: u64 = (1 << 62) | 0xC4EC;
/// Where the two generations whose individual tag meets a fixed tag go instead.
const MOVED: u64 = 1 << 63;

impl Stream {
    /// The seed of this stream in the run with seed `run_seed`.
    pub fn seed(self, run_seed: u64) -> u64 {
        let s = run_seed;
        match self {
            Stream::ActorWeights => s.wrapping_mul(31).wrapping_add(1),
            Stream::CriticWeights(k) => s.wrapping_mul(31).wrapping_add(2).wrapping_add(k),
            Stream::Updates => s ^ 0x5EED_A6E7,
            Stream::Trainer => mix(s, TRAINER, 0),
            Stream::EpisodeReset(n) => mix(s, EPISODE, n),
            Stream::EvaluationReset {
                generation,
                evaluation,
                evaluations,
            } => mix(
                s,
                EVALUATION,
                generation
                    .wrapping_mul(evaluations)
                    .wrapping_add(evaluation),
            ),
            Stream::WarmStartReset(n) => mix(s, WARM_START, n),
            Stream::Individual { generation, index } => {
                let tag = INDIVIDUAL.wrapping_add(generation);
                let tag = if tag == TRAINER || tag == PERTURBATION {
                    MOVED | tag
                } else {
                    tag
                };
                mix(s, tag, index)
            }
            Stream::Perturbation { generation, index } => {
                mix(mix(s, PERTURBATION, 0), generation, index)
            }
            Stream::CheckReset(k) => mix(s, CHECK, k),
        }
    }

    /// A ChaCha8 generator on this stream.
    pub fn rng(self, run_seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(self.seed(run_seed))
    }
}

/// Mixes a seed with two indices into an independent 64-bit seed: a SplitMix64 finaliser of
/// `seed ⊕ a·K₁ ⊕ b·K₂`. The finaliser is a bijection, so equal outputs mean equal inputs.
pub fn mix(seed: u64, a: u64, b: u64) -> u64 {
    let mut z =
        seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
