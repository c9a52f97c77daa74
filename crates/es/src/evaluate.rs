//! Eq. 9 of a generation: turning genomes into episodes and fitness.
//!
//! [`Hybrid::ask`](crate::Hybrid::ask) hands out a [`Generation`]: every [`Genome`] carries
//! what a worker needs to roll it out deterministically (its parameters, the seed of its
//! action stream, the initial-state seeds of its K evaluations, and how it acts in each
//! rollout). [`rollout_genome`] is the stateless function that does it; an [`Evaluator`]
//! runs it over a generation, anywhere, and returns the results in individual order.
//! [`LocalEvaluator`] is the rayon one; any evaluator that calls [`rollout_genome`] on the
//! same genomes gives the same results, bit for bit.

use esrl_agents::{rollout, ActMode, AgentError, Episode, Policy};
use esrl_sim::MakeEnv;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::sync::Arc;

/// One rollout of an evaluation: how the policy acts, and whether its return scores.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct RolloutSpec {
    /// Deterministic (tanh μ) or exploring.
    pub mode: ActMode,
    /// Whether the rollout's return counts toward the fitness (its data is kept either way).
    pub scored: bool,
}

/// One individual of a generation, ready to be rolled out anywhere.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Genome {
    /// Its place in the population: 0 is the RL actor, 1.. the perturbations.
    pub index: usize,
    /// The actor's weights and biases (both heads), then log α for ES-SAC (which rollouts
    /// do not use).
    pub params: Vec<f32>,
    /// Seed of its action stream ([`esrl_streams::Stream::Individual`]).
    pub action_seed: u64,
    /// Initial-state seed of each of its K evaluations, the same for every individual of
    /// the generation ([`esrl_streams::Stream::EvaluationReset`]).
    pub env_seeds: Vec<u64>,
    /// The rollouts of each evaluation, in order, all from that evaluation's initial state.
    pub rollouts: Vec<RolloutSpec>,
}

/// A generation to evaluate: its genomes and the policy they plug into.
#[derive(Debug, Clone)]
pub struct Generation {
    /// Generation index, from 0.
    pub index: usize,
    /// A policy of the agent's architecture and exploration; each genome's parameters
    /// replace its weights.
    pub policy: Policy,
    /// The individuals, RL actor first.
    pub genomes: Vec<Genome>,
}

/// What rolling one genome out produced.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// Mean return of the scored rollouts (eq. 9).
    pub fitness: f64,
    /// Every rollout, in the order they go into the replay buffer.
    pub episodes: Vec<Episode>,
}

/// Rolls `genome` out on `env`: for each of its K evaluations, the rollouts of
/// `genome.rollouts` from that evaluation's initial state, acting with `policy`'s
/// architecture and exploration and `genome`'s weights, drawing from the genome's own action
/// stream. Fitness is the mean return of the scored rollouts (eq. 9). Stateless: the same
/// genome gives the same evaluation on any thread or machine.
pub fn rollout_genome(
    policy: &Policy,
    genome: &Genome,
    env: &mut dyn esrl_sim::Env,
) -> Result<Evaluation, AgentError> {
    let n = esrl_nn::Module::num_params(policy.actor());
    if genome.params.len() < n {
        return Err(AgentError::GenomeLength {
            expected: n,
            found: genome.params.len(),
        });
    }
    let mut policy = policy.clone();
    policy.set_weights(&genome.params[..n])?;
    let mut rng = ChaCha8Rng::seed_from_u64(genome.action_seed);
    let mut episodes = Vec::with_capacity(genome.env_seeds.len() * genome.rollouts.len());
    let (mut score, mut scored) = (0.0, 0usize);
    for &env_seed in &genome.env_seeds {
        for spec in &genome.rollouts {
            let acting = rollout::Actor::Policy(&mut policy, spec.mode);
            let ep = rollout::rollout(env, acting, env_seed, None, &mut rng);
            if spec.scored {
                score += ep.ret;
                scored += 1;
            }
            episodes.push(ep);
        }
    }
    Ok(Evaluation {
        fitness: score / scored as f64, // eq. 9
        episodes,
    })
}

/// Runs [`rollout_genome`] over a generation's genomes and returns one evaluation per genome,
/// in the order of `generation.genomes`. That list may be part of the population: the
/// pipelined loop asks for individuals 1.. ahead, then individual 0 alone (each genome names
/// its place in [`Genome::index`]). Implementations may run anywhere (threads, processes,
/// machines); results must not depend on where or in which order the genomes ran.
pub trait Evaluator: Send + Sync + fmt::Debug {
    /// Evaluates every genome of `generation`.
    fn evaluate(&self, generation: &Generation) -> Result<Vec<Evaluation>, AgentError>;
}

/// Evaluates on a rayon pool of this process, one fresh environment per individual: a pool
/// of its own, or the pool it is called from (where the learner's updates run too, so the
/// rollouts and the updates share its threads).
pub struct LocalEvaluator {
    make_env: Arc<MakeEnv>,
    pool: Option<rayon::ThreadPool>,
}

impl LocalEvaluator {
    /// An evaluator on a pool of its own of `threads` threads (at least one) taking
    /// environments from `make_env`.
    pub fn new(
        make_env: Arc<MakeEnv>,
        threads: usize,
    ) -> Result<Self, rayon::ThreadPoolBuildError> {
        let pool = esrl_nn::subnormal::thread_pool(threads.max(1))?;
        Ok(Self {
            make_env,
            pool: Some(pool),
        })
    }

    /// An evaluator on the rayon pool it is called from (rayon's global pool outside any).
    pub fn on_calling_pool(make_env: Arc<MakeEnv>) -> Self {
        Self {
            make_env,
            pool: None,
        }
    }
}

impl fmt::Debug for LocalEvaluator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let threads = self.pool.as_ref().map(|p| p.current_num_threads());
        f.debug_struct("LocalEvaluator")
            .field("threads", &threads)
            .finish()
    }
}

impl Evaluator for LocalEvaluator {
    fn evaluate(&self, generation: &Generation) -> Result<Vec<Evaluation>, AgentError> {
        let run = || -> Vec<Result<Evaluation, AgentError>> {
            generation
                .genomes
                .par_iter()
                .map(|genome| {
                    let mut env = (self.make_env)();
                    rollout_genome(&generation.policy, genome, env.as_mut())
                })
                .collect()
        };
        let evaluated = match &self.pool {
            Some(pool) => pool.install(run),
            None => run(),
        };
        evaluated.into_iter().collect()
    }
}
