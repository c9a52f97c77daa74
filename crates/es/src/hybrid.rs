//! The hybrid ES-X loop of the paper's §4–5 (Fig. 3), X ∈ {SAC, TD3, DDPG}.
//!
//! One generation ([`Hybrid::step`]):
//! 1. the population: the RL agent's current actor (individual 0) and N − 1 perturbations
//!    θ + σεᵢ of the ES mean (eq. 8);
//! 2. every individual runs K episodes, in parallel on a rayon pool; all individuals of a
//!    generation see the same K initial states (common random numbers, so fitness differences
//!    come from the policies); fitness is the mean return (eq. 9); every transition goes into
//!    the shared replay buffer, in individual order;
//! 3. the elites update θ and σ (eqs. 10, 11);
//! 4. elitist replacement: if the best individual's fitness beats the RL actor's, the RL actor
//!    takes its parameters (for ES-SAC, log α too);
//! 5. the RL agent runs its inner training cycles (one minibatch update each) on the buffer,
//!    refining the actor step 4 left, which is individual 0 of the next generation.
//!
//! Steps 4 and 5 in this order are the paper's (§5: the agent "runs for 50 inner training
//! cycles to consolidate these improvements ... yielding a refined policy for the next
//! generation"), CEM-RL's and ERL's: the gradient work is always evaluated before anything can
//! replace it. `es.order = "train-then-replace"` ([`LoopOrder`]) runs 5 before 4, which
//! discards the updates whenever another individual beat the untrained actor; it is kept to
//! measure that difference.
//!
//! How individuals act while scored is `es.fitness` ([`Fitness`]): by default ES-SAC
//! individuals sample their Gaussian policy (its std head and α are part of the genome, and
//! the buffer needs exploratory data) and ES-TD3/ES-DDPG individuals act deterministically,
//! the parameter noise being their exploration, as in CEM-RL.
//!
//! The learning curve is the best fitness of each generation (the fitness of the policy kept
//! at step 4); [`Hybrid::kept`] is that policy's genome, for `RUN/best/`.
//!
//! Results do not depend on the thread count: every individual's rollouts use random streams
//! keyed by (seed, generation, individual), and results are gathered in individual order.

use crate::strategy::{rank, EsConfig, Fitness, LoopOrder, Strategy};
use esrl_agents::rollout::{rollout, Actor as Acting};
use esrl_agents::train::LossMeans;
use esrl_agents::{mix_seed, ActMode, Agent, AgentError, Algo, Episode, Policy, Trainer};
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
    /// The learning-curve value: the fitness of the policy kept at elitist replacement (the
    /// best fitness of the generation).
    pub curve: f64,
    /// Best fitness in the population.
    pub best_fitness: f64,
    /// Mean fitness of the population.
    pub mean_fitness: f64,
    /// Worst fitness of the population.
    pub worst_fitness: f64,
    /// The RL actor's fitness (individual 0).
    pub rl_fitness: f64,
    /// Whether individual 0 carried inner-training updates made since its genome was last
    /// evaluated (false in generation 0, with `inner_cycles = 0`, and, under
    /// `train-then-replace`, after a generation that replaced the RL actor).
    pub rl_trained: bool,
    /// The RL actor's rank in the population (0 = best; ties go to the lower index).
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
    /// Q₀ of the RL actor after the generation (individual 0 of the next one) at this
    /// generation's first initial state.
    pub q0: f64,
    /// Mean episode length over the generation's rollouts.
    pub mean_length: f64,
}

/// Counts over a run's generations that show whether the gradient work pays: how often the
/// trained actor, once evaluated, was the best individual or an elite.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LoopStats {
    /// Generations run.
    pub generations: usize,
    /// Generations whose individual 0 was a trained actor ([`GenerationReport::rl_trained`]).
    pub trained: usize,
    /// Of those, the generations where it was the best individual.
    pub trained_best: usize,
    /// Of those, the generations where it was an elite.
    pub trained_elite: usize,
    /// Generations where the RL actor was replaced.
    pub replaced: usize,
}

impl LoopStats {
    /// Counts one generation's row in.
    pub fn add(&mut self, r: &GenerationReport) {
        self.generations += 1;
        self.replaced += usize::from(r.rl_replaced);
        if r.rl_trained {
            self.trained += 1;
            self.trained_best += usize::from(r.rl_rank == 0);
            self.trained_elite += usize::from(r.rl_elite);
        }
    }

    /// Share of trained generations in which the trained actor was best (None before any).
    pub fn trained_best_share(&self) -> Option<f64> {
        (self.trained > 0).then(|| self.trained_best as f64 / self.trained as f64)
    }

    /// Share of trained generations in which the trained actor was an elite.
    pub fn trained_elite_share(&self) -> Option<f64> {
        (self.trained > 0).then(|| self.trained_elite as f64 / self.trained as f64)
    }

    /// Share of generations in which the RL actor was replaced.
    pub fn replaced_share(&self) -> Option<f64> {
        (self.generations > 0).then(|| self.replaced as f64 / self.generations as f64)
    }
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
    /// When set, the inner cycles of a generation are this many per environment step the
    /// generation collected (rounded), instead of [`Hybrid::inner_cycles`]: the update-to-data
    /// ratio stays fixed as episodes lengthen.
    pub updates_per_step: Option<f64>,
    /// Generations completed.
    pub generation: usize,
    /// The genome of the last generation's best individual: the policy whose fitness is that
    /// generation's learning-curve value (empty before the first generation). The RL actor
    /// differs from it by the inner updates that followed replacement.
    pub kept: Vec<f32>,
    /// Whether the RL actor carries inner-training updates not yet evaluated (it will be
    /// individual 0 of the next generation).
    pub rl_trained: bool,
    /// Counts over the generations run so far.
    pub stats: LoopStats,
}

/// What one individual's evaluation produced.
struct Evaluated {
    /// Mean return of the scored rollouts (eq. 9).
    fitness: f64,
    /// Every rollout, in the order they go into the buffer.
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
            updates_per_step: None,
            generation: 0,
            kept: Vec::new(),
            rl_trained: false,
            stats: LoopStats::default(),
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

    /// The rollouts of one evaluation: `(mode, scored)` pairs, run in this order from the same
    /// initial state.
    fn rollout_plan(&self) -> &'static [(ActMode, bool)] {
        const EXPLORE: &[(ActMode, bool)] = &[(ActMode::Explore, true)];
        const DETERMINISTIC: &[(ActMode, bool)] = &[(ActMode::Deterministic, true)];
        const BOTH: &[(ActMode, bool)] =
            &[(ActMode::Explore, false), (ActMode::Deterministic, true)];
        match self.es.fitness {
            Fitness::Auto if self.trainer.agent.algo() == Algo::Sac => EXPLORE,
            Fitness::Auto | Fitness::Deterministic => DETERMINISTIC,
            Fitness::Sampled => EXPLORE,
            Fitness::Both => BOTH,
        }
    }

    /// Evaluates `genomes` on the pool (step 2), each on the generation's K initial states.
    fn evaluate(
        &self,
        genomes: &[Vec<f32>],
        make_env: &(dyn Fn() -> Box<dyn Env> + Sync),
        pool: &rayon::ThreadPool,
    ) -> Result<Vec<Evaluated>, AgentError> {
        let agent = &self.trainer.agent;
        let gen = self.generation as u64;
        let seed = self.trainer.seed;
        let k = self.es.evaluations;
        let plan = self.rollout_plan();
        let scored_per_eval = plan.iter().filter(|(_, scored)| *scored).count();
        let evaluate_one = |i: usize, genome: &Vec<f32>| -> Result<Evaluated, AgentError> {
            let mut env = make_env();
            let mut policy: Policy = agent.policy_from_genome(genome)?;
            let mut rng = ChaCha8Rng::seed_from_u64(mix_seed(seed, 4 + gen, i as u64));
            let mut episodes = Vec::with_capacity(k * plan.len());
            let mut score = 0.0;
            for e in 0..k {
                let env_seed = mix_seed(seed, 2, gen * k as u64 + e as u64);
                for &(mode, scored) in plan {
                    let ep = rollout(
                        env.as_mut(),
                        Acting::Policy(&mut policy, mode),
                        env_seed,
                        None,
                        &mut rng,
                        |_| {},
                    );
                    if scored {
                        score += ep.ret;
                    }
                    episodes.push(ep);
                }
            }
            Ok(Evaluated {
                fitness: score / (k * scored_per_eval) as f64,
                episodes,
            })
        };
        let evaluated: Vec<Result<Evaluated, AgentError>> = pool.install(|| {
            genomes
                .par_iter()
                .enumerate()
                .map(|(i, g)| evaluate_one(i, g))
                .collect()
        });
        evaluated.into_iter().collect()
    }

    /// The inner training cycles (step 5), once the warm start is in the buffer: `steps` is
    /// what the generation collected.
    fn train(&mut self, steps: usize) -> Result<LossMeans, AgentError> {
        let mut losses = LossMeans::default();
        let cycles = match self.updates_per_step {
            Some(ratio) => (ratio * steps as f64).round() as usize,
            None => self.inner_cycles,
        };
        if self.trainer.env_steps >= self.trainer.agent.config().warm_start as u64 {
            for _ in 0..cycles {
                losses.add(&self.trainer.update()?);
            }
        }
        Ok(losses)
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
        let rl_trained = self.rl_trained;

        // 2. Evaluate; every transition into the buffer, in individual order.
        let evaluated = self.evaluate(&genomes, make_env, pool)?;
        let mut steps = 0usize;
        let mut rollouts = 0usize;
        for ev in &evaluated {
            for ep in &ev.episodes {
                ep.push_into(&mut self.trainer.buffer);
                steps += ep.len();
                rollouts += 1;
            }
        }
        self.trainer.env_steps += steps as u64;

        // 3. The ES update.
        let fitness: Vec<f64> = evaluated.iter().map(|e| e.fitness).collect();
        let refs: Vec<&[f32]> = genomes.iter().map(Vec::as_slice).collect();
        let order = self.strategy.update(&refs, &fitness, &self.es);
        let best = order[0];
        let replaced = best != 0 && fitness[best] > fitness[0];

        // 4 and 5: replacement and the inner cycles, in the configured order.
        let losses = match self.es.order {
            LoopOrder::ReplaceThenTrain => {
                if replaced {
                    self.trainer.agent.set_genome(&genomes[best])?;
                }
                self.train(steps)?
            }
            LoopOrder::TrainThenReplace => {
                let losses = self.train(steps)?;
                if replaced {
                    self.trainer.agent.set_genome(&genomes[best])?;
                }
                losses
            }
        };
        let trained_now = losses.critic().is_some();
        self.rl_trained = match self.es.order {
            LoopOrder::ReplaceThenTrain => trained_now,
            LoopOrder::TrainThenReplace => trained_now && !replaced,
        };
        self.kept.clone_from(&genomes[best]);

        let rl_rank = order.iter().position(|&i| i == 0).unwrap_or(n);
        let finite: Vec<f64> = fitness.iter().copied().filter(|f| f.is_finite()).collect();
        let mut env0 = make_env();
        let k = self.es.evaluations as u64;
        let obs0 = env0.reset(mix_seed(self.trainer.seed, 2, self.generation as u64 * k));
        let report = GenerationReport {
            generation: self.generation,
            env_steps: self.trainer.env_steps,
            curve: fitness[best],
            best_fitness: fitness[best],
            mean_fitness: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
            worst_fitness: finite.iter().copied().fold(f64::INFINITY, f64::min),
            rl_fitness: fitness[0],
            rl_trained,
            rl_rank,
            rl_elite: rl_rank < self.es.elites(),
            rl_replaced: replaced,
            sigma: self.strategy.sigma,
            alpha: (self.trainer.agent.algo() == Algo::Sac).then(|| self.trainer.agent.alpha()),
            critic_loss: losses.critic(),
            actor_loss: losses.actor(),
            q0: self.trainer.agent.q0(&obs0),
            mean_length: steps as f64 / rollouts.max(1) as f64,
        };
        self.stats.add(&report);
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
                        .position(|g| *g == h.kept)
                        .expect("the kept genome is a population member's");
                    assert_ne!(best, 0);
                } else {
                    kept += 1;
                    assert_eq!(r.rl_rank, 0, "not replaced means the RL actor was best");
                    assert_eq!(h.kept, population[0]);
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
