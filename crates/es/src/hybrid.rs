//! The hybrid ES-X loop of the paper's §4 (Fig. 3), X ∈ {SAC, TD3, DDPG}.
//!
//! One generation:
//! 1. the population: the RL agent's current actor (individual 0) and N − 1 perturbations
//!    θ + σεᵢ of the ES mean (eq. 8);
//! 2. every individual runs K episodes, in parallel on a rayon pool; all individuals of a
//!    generation see the same K initial states (common random numbers, so fitness differences
//!    come from the policies); fitness is the mean return (eq. 9);
//! 3. every transition goes into the shared replay buffer, in individual order;
//! 4. the elites update θ and σ (eqs. 10, 11);
//! 5. the RL agent runs its inner training cycles (one minibatch update each) on the buffer;
//! 6. elitist replacement: if the best individual's fitness beats the RL actor's, the RL actor
//!    takes its parameters (for ES-SAC, log α too).
//!
//! ES-SAC individuals act by sampling their Gaussian policy (its std head and α are part of the
//! genome, and the buffer needs exploratory data); ES-TD3/ES-DDPG individuals act
//! deterministically, the parameter noise being their exploration, as in CEM-RL.
//!
//! Results do not depend on the thread count: every individual's rollouts use random streams
//! keyed by (seed, generation, individual), and results are gathered in individual order.

use crate::strategy::{rank, EsConfig, Strategy};
use esrl_agents::rollout::{rollout, Actor as Acting};
use esrl_agents::{mix_seed, ActMode, Agent, AgentError, Algo, Episode, Trainer};
use esrl_sim::Env;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One generation's row of `metrics.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GenerationReport {
    /// Generation index, from 0.
    pub generation: usize,
    /// Environment steps so far (warm start and this generation included).
    pub env_steps: u64,
    /// The learning-curve value: the fitness of the policy kept after elitist replacement
    /// (the best fitness of the generation).
    pub curve: f64,
    /// Best fitness in the population.
    pub best_fitness: f64,
    /// Mean fitness of the population.
    pub mean_fitness: f64,
    /// Worst fitness of the population.
    pub worst_fitness: f64,
    /// The RL actor's fitness (individual 0).
    pub rl_fitness: f64,
    /// The RL actor's rank in the population (0 = best).
    pub rl_rank: usize,
    /// Whether the RL actor was among the elites.
    pub rl_elite: bool,
    /// Whether the RL actor was replaced by the best individual.
    pub rl_replaced: bool,
    /// σ after the update.
    pub sigma: f64,
    /// Entropy coefficient after the generation (ES-SAC).
    pub alpha: Option<f64>,
    /// Mean critic loss over the inner cycles.
    pub critic_loss: Option<f64>,
    /// Mean actor loss over the inner cycles.
    pub actor_loss: Option<f64>,
    /// Q₀ of the kept policy at the generation's first initial state.
    pub q0: f64,
    /// Mean episode length in the population.
    pub mean_length: f64,
}

/// The hybrid trainer: an RL trainer (agent + buffer) and the ES distribution.
#[derive(Debug, Clone)]
pub struct Hybrid {
    /// The RL side: agent, replay buffer, random stream, step counter.
    pub trainer: Trainer,
    /// The ES distribution.
    pub strategy: Strategy,
    /// ES settings.
    pub es: EsConfig,
    /// Gradient updates per generation.
    pub inner_cycles: usize,
    /// Generations completed.
    pub generation: usize,
    /// The genome of the last generation's best individual: the policy whose fitness is that
    /// generation's learning-curve value (empty before the first generation). The RL actor
    /// differs from it when the RL actor itself was best, by the inner updates that followed
    /// its evaluation.
    pub kept: Vec<f32>,
}

/// What one individual's evaluation produced.
struct Evaluated {
    fitness: f64,
    episodes: Vec<Episode>,
}

impl Hybrid {
    /// Starts the ES distribution at the agent's own genome.
    pub fn new(agent: Agent, es: EsConfig, inner_cycles: usize, seed: u64) -> Self {
        let strategy = Strategy::new(agent.genome(), es.sigma, mix_seed(seed, 0xE5, 0));
        Self {
            trainer: Trainer::new(agent, seed),
            strategy,
            es,
            inner_cycles,
            generation: 0,
            kept: Vec::new(),
        }
    }

    /// Fills the buffer with random-action episodes until the warm-start budget is spent
    /// (no-op once done). Returns the steps taken.
    pub fn warm_start(&mut self, env: &mut dyn Env) -> u64 {
        let target = self.trainer.agent.config().warm_start as u64;
        let mut taken = 0;
        while self.trainer.env_steps < target {
            let seed = mix_seed(self.trainer.seed, 3, self.trainer.env_steps);
            let left = (target - self.trainer.env_steps) as usize;
            let ep = rollout(
                env,
                Acting::Random,
                seed,
                Some(left),
                &mut self.trainer.rng,
                |_| {},
            );
            ep.push_into(&mut self.trainer.buffer);
            self.trainer.env_steps += ep.len() as u64;
            taken += ep.len() as u64;
        }
        taken
    }

    /// This generation's individuals: the RL actor's genome first, then N − 1 perturbations of
    /// the ES mean.
    pub fn population(&self) -> Vec<Vec<f32>> {
        let n = self.es.population;
        let mut genomes = Vec::with_capacity(n);
        genomes.push(self.trainer.agent.genome());
        genomes.extend((1..n).map(|i| self.strategy.perturbation(i)));
        genomes
    }

    /// Runs one generation. `make_env` builds an environment per individual (called from pool
    /// threads); `pool` runs the rollouts.
    pub fn step(
        &mut self,
        make_env: &(dyn Fn() -> Box<dyn Env> + Sync),
        pool: &rayon::ThreadPool,
    ) -> Result<GenerationReport, AgentError> {
        let n = self.es.population;
        let genomes = self.population();
        let agent = &self.trainer.agent;

        let gen = self.generation as u64;
        let seed = self.trainer.seed;
        let k = self.es.evaluations;
        let mode = if agent.algo() == Algo::Sac {
            ActMode::Explore
        } else {
            ActMode::Deterministic
        };
        let evaluated: Vec<Result<Evaluated, AgentError>> = pool.install(|| {
            genomes
                .par_iter()
                .enumerate()
                .map(|(i, genome)| {
                    let mut env = make_env();
                    let mut policy = agent.policy_from_genome(genome)?;
                    let mut rng = ChaCha8Rng::seed_from_u64(mix_seed(seed, 4 + gen, i as u64));
                    let episodes: Vec<Episode> = (0..k)
                        .map(|e| {
                            let env_seed = mix_seed(seed, 2, gen * k as u64 + e as u64);
                            rollout(
                                env.as_mut(),
                                Acting::Policy(&mut policy, mode),
                                env_seed,
                                None,
                                &mut rng,
                                |_| {},
                            )
                        })
                        .collect();
                    let fitness = episodes.iter().map(|e| e.ret).sum::<f64>() / k as f64;
                    Ok(Evaluated { fitness, episodes })
                })
                .collect()
        });
        let evaluated = evaluated.into_iter().collect::<Result<Vec<_>, _>>()?;

        let mut lengths = 0usize;
        for ev in &evaluated {
            for ep in &ev.episodes {
                ep.push_into(&mut self.trainer.buffer);
                self.trainer.env_steps += ep.len() as u64;
                lengths += ep.len();
            }
        }
        let fitness: Vec<f64> = evaluated.iter().map(|e| e.fitness).collect();
        let refs: Vec<&[f32]> = genomes.iter().map(Vec::as_slice).collect();
        let order = self.strategy.update(&refs, &fitness, &self.es);

        let mut losses = esrl_agents::train::LossMeans::default();
        if self.trainer.env_steps >= self.trainer.agent.config().warm_start as u64 {
            for _ in 0..self.inner_cycles {
                losses.add(&self.trainer.update()?);
            }
        }

        let best = order[0];
        let rl_rank = order.iter().position(|&i| i == 0).unwrap_or(n);
        let replaced = best != 0 && fitness[best] > fitness[0];
        if replaced {
            self.trainer.agent.set_genome(&genomes[best])?;
        }
        self.kept.clone_from(&genomes[best]);
        let finite: Vec<f64> = fitness.iter().copied().filter(|f| f.is_finite()).collect();
        let mut env0 = make_env();
        let obs0 = env0.reset(mix_seed(seed, 2, gen * k as u64));
        let report = GenerationReport {
            generation: self.generation,
            env_steps: self.trainer.env_steps,
            curve: fitness[best],
            best_fitness: fitness[best],
            mean_fitness: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
            worst_fitness: finite.iter().copied().fold(f64::INFINITY, f64::min),
            rl_fitness: fitness[0],
            rl_rank,
            rl_elite: rl_rank < self.es.elites(),
            rl_replaced: replaced,
            sigma: self.strategy.sigma,
            alpha: (self.trainer.agent.algo() == Algo::Sac).then(|| self.trainer.agent.alpha()),
            critic_loss: losses.critic(),
            actor_loss: losses.actor(),
            q0: self.trainer.agent.q0(&obs0),
            mean_length: lengths as f64 / (n * k) as f64,
        };
        self.generation += 1;
        Ok(report)
    }
}

/// Position of the best of `fitness` (NaN worst, ties to the lowest index).
pub fn best_index(fitness: &[f64]) -> Option<usize> {
    rank(fitness).first().copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use esrl_agents::{NetConfig, RlConfig};
    use esrl_sim::Pendulum;

    fn hybrid(algo: Algo) -> Hybrid {
        let cfg = RlConfig {
            batch_size: 8,
            warm_start: 100,
            ..RlConfig::default()
        };
        let agent = Agent::new(algo, 3, 1, &NetConfig::tiny(false), &cfg, 7).unwrap();
        let es = EsConfig {
            population: 6,
            sigma: 0.5,
            ..EsConfig::default()
        };
        Hybrid::new(agent, es, 3, 7)
    }

    #[test]
    fn rl_actor_is_in_every_population_and_replaced_only_when_beaten() {
        let make_env = || Box::new(Pendulum::new()) as Box<dyn Env>;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        for algo in [Algo::Sac, Algo::Td3, Algo::Ddpg] {
            let mut h = hybrid(algo);
            h.warm_start(make_env().as_mut());
            let (mut replaced, mut kept) = (0, 0);
            for _ in 0..8 {
                let population = h.population();
                assert_eq!(population.len(), 6);
                assert_eq!(
                    population[0],
                    h.trainer.agent.genome(),
                    "individual 0 is the RL actor"
                );
                let r = h.step(&make_env, &pool).unwrap();
                assert_eq!(
                    r.rl_replaced,
                    r.best_fitness > r.rl_fitness,
                    "{algo:?}: {r:?}"
                );
                if r.rl_replaced {
                    replaced += 1;
                    let best = population
                        .iter()
                        .position(|g| *g == h.trainer.agent.genome())
                        .expect("the replaced actor carries a population member's genome");
                    assert_ne!(best, 0);
                } else {
                    kept += 1;
                    assert_eq!(r.rl_rank, 0, "not replaced means the RL actor was best");
                }
                assert_eq!(r.curve, r.best_fitness);
            }
            assert!(
                replaced > 0 && kept + replaced == 8,
                "{algo:?}: replaced {replaced} of 8"
            );
        }
    }
}
