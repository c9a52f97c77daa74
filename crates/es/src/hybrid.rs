//! The hybrid ES-X loop of the paper's §4–5 (Fig. 3), X ∈ {SAC, TD3, DDPG}, as ask/tell.
//!
//! One generation, [`Hybrid::step`], reads top to bottom:
//!
//! - eq. 8, [`ask`](Hybrid::ask): the population, the RL agent's current actor (individual
//!   0) and N − 1 perturbations θ + σεᵢ of the ES mean, each a [`Genome`] with its seeds;
//! - eq. 9, the [`Evaluator`]: every genome rolled out
//!   ([`rollout_genome`](crate::rollout_genome)), K episodes each, anywhere; all individuals
//!   of a generation see the same K initial states (common random numbers, so fitness
//!   differences come from the policies); fitness is the mean return;
//! - [`tell`](Hybrid::tell): every transition into the shared replay buffer, in individual
//!   order; eqs. 10–11, the elites update θ and σ; elitist replacement, the RL actor taking
//!   the best individual's parameters (for ES-SAC, log α too) if it beat the RL actor; and
//!   the inner training cycles (one minibatch update each), refining the actor the
//!   replacement left, which is individual 0 of the next generation.
//!
//! Replacement before training is the paper's order (§5: the agent "runs for 50 inner
//! training cycles to consolidate these improvements ... yielding a refined policy for the
//! next generation"), CEM-RL's and ERL's: the gradient work is always evaluated before
//! anything can replace it. `es.order = "train-then-replace"` ([`LoopOrder`]) is an ablation
//! switch: it trains first, which discards the updates whenever another individual beat the
//! untrained actor, and exists to measure that difference.
//!
//! How individuals act while scored is `es.fitness` ([`Fitness`]): by default ES-SAC
//! individuals sample their Gaussian policy (its std head and α are part of the genome, and
//! the buffer needs exploratory data) and ES-TD3/ES-DDPG individuals act deterministically,
//! the parameter noise being their exploration, as in CEM-RL.
//!
//! The learning curve is the best fitness of each generation (the fitness of the policy
//! kept by the replacement); [`Hybrid::kept`] is that policy's genome, for `RUN/best/`.
//!
//! Results do not depend on the thread count or on the evaluator: every individual's
//! rollouts use the random streams its genome names, and results are taken in individual
//! order.
//!
//! **Pipelining** wraps the evaluator and changes no number. The N − 1 perturbations of
//! generation g + 1 depend only on the ES mean and σ after generation g's eqs. 10–11, not on
//! the learner, so the inner training of g runs beside their rollouts (both on the rayon
//! pool the loop runs in), and eq. 9 of g + 1 then rolls out individual 0 alone, the trained
//! actor. Their transitions still enter the buffer at generation g + 1's tell, in individual
//! order, so the loop computes exactly what the sequential one does
//! ([`Hybrid::set_pipelined`] turns it off; `es/tests/pipeline.rs` compares the two). The
//! rollouts in flight are not part of a checkpoint: a run restored at a generation boundary
//! rolls them out again, with the same result.

use crate::evaluate::{Evaluation, Evaluator, Generation, Genome, RolloutSpec};
use crate::strategy::{rank, EsConfig, Fitness, LoopOrder, Strategy};
use esrl_agents::learner::{Learner, LearnerState, Resumable, Row};
use esrl_agents::{ActMode, Agent, AgentError, LossMeans, ReplayBuffer, Trainer};
use esrl_sim::MakeEnv;
use esrl_streams::Stream;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::Arc;

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

impl Row for GenerationReport {
    fn curve(&self) -> f64 {
        self.curve
    }

    fn q0(&self) -> f64 {
        self.q0
    }

    fn env_steps(&self) -> u64 {
        self.env_steps
    }

    fn summary(&self) -> String {
        format!(
            "gen {}: best {:.1}, RL actor {:.1}{}, σ {:.3}",
            self.generation,
            self.best_fitness,
            self.rl_fitness,
            if self.rl_replaced { " (replaced)" } else { "" },
            self.sigma
        )
    }
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

/// The hybrid loop's own counters, beside the RL side's in `state.json`
/// ([`LearnerState<EsState>`](LearnerState)). Checkpoints of earlier versions load through
/// `compat.rs`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "crate::compat::EsStateFile")]
pub struct EsState {
    /// Generations completed.
    pub generations: usize,
    /// ES σ.
    pub sigma: f64,
    /// The ES distribution's generation counter.
    pub es_generation: u64,
    /// Whether the RL actor carries inner updates not yet evaluated.
    pub rl_trained: bool,
    /// The loop's counts so far.
    pub loop_stats: LoopStats,
}

/// The loop's settings: the ES (its population, σ schedule, how individuals act while
/// scored, the order of replacement and training) and the inner training.
#[derive(Debug, Clone, PartialEq)]
pub struct HybridConfig {
    /// The evolution strategy and the loop order ([`EsConfig::fitness`], [`EsConfig::order`]).
    pub es: EsConfig,
    /// Inner training cycles (minibatch updates) per generation.
    pub inner_cycles: usize,
    /// When set, the inner cycles of a generation are this many per environment step it
    /// collected (rounded) instead of `inner_cycles`: the update-to-data ratio stays fixed as
    /// episodes lengthen.
    pub updates_per_step: Option<f64>,
    /// Whether [`Hybrid::step`] rolls the next generation's perturbations out while the inner
    /// cycles train (module docs). Results are the same either way.
    pub pipelined: bool,
}

impl HybridConfig {
    /// `es` with a fixed `inner_cycles` per generation, pipelined.
    pub fn new(es: EsConfig, inner_cycles: usize) -> Self {
        Self {
            es,
            inner_cycles,
            updates_per_step: None,
            pipelined: true,
        }
    }

    /// The inner training cycles of a generation that collected `steps` environment steps.
    pub fn inner_cycles_for(&self, steps: usize) -> usize {
        match self.updates_per_step {
            Some(ratio) => (ratio * steps as f64).round() as usize,
            None => self.inner_cycles,
        }
    }
}

/// The hybrid learner: an RL trainer (agent + buffer), the ES distribution, and the
/// evaluator that rolls its populations out.
#[derive(Debug, Clone)]
pub struct Hybrid {
    trainer: Trainer,
    strategy: Strategy,
    cfg: HybridConfig,
    generation: usize,
    /// The genome of the last generation's best individual (empty before the first).
    kept: Vec<f32>,
    /// Whether the RL actor carries inner-training updates not yet evaluated.
    rl_trained: bool,
    stats: LoopStats,
    evaluator: Arc<dyn Evaluator>,
    /// The next generation's perturbations and their evaluations, rolled out during the
    /// last training.
    prefetched: Option<Prefetched>,
}

/// Individuals 1.. of a generation, evaluated ahead of it.
#[derive(Debug, Clone)]
struct Prefetched {
    generation: usize,
    genomes: Vec<Genome>,
    evaluations: Vec<Evaluation>,
}

/// The tensor of a checkpoint that holds the ES mean θ.
const ES_MEAN: &str = "es.mean";

impl Hybrid {
    /// Starts the ES distribution at the agent's own genome, in the run with seed `seed`;
    /// `evaluator` rolls the populations out.
    pub fn new(agent: Agent, cfg: HybridConfig, seed: u64, evaluator: Arc<dyn Evaluator>) -> Self {
        let strategy = Strategy::new(agent.genome(), cfg.es.sigma, seed);
        Self {
            trainer: Trainer::new(agent, seed),
            strategy,
            cfg,
            generation: 0,
            kept: Vec::new(),
            rl_trained: false,
            stats: LoopStats::default(),
            evaluator,
            prefetched: None,
        }
    }

    /// Whether [`Hybrid::step`] pipelines (default true): rolls the next generation's
    /// perturbations out while the inner cycles train. Results are the same either way.
    pub fn set_pipelined(&mut self, on: bool) {
        self.cfg.pipelined = on;
        if !on {
            self.prefetched = None;
        }
    }

    /// Whether [`Hybrid::step`] pipelines.
    pub fn pipelined(&self) -> bool {
        self.cfg.pipelined
    }

    /// The RL side: agent, replay buffer, random stream, step counter.
    pub fn trainer(&self) -> &Trainer {
        &self.trainer
    }

    /// The RL side, mutable.
    pub fn trainer_mut(&mut self) -> &mut Trainer {
        &mut self.trainer
    }

    /// The ES distribution.
    pub fn strategy(&self) -> &Strategy {
        &self.strategy
    }

    /// The ES settings.
    pub fn es(&self) -> &EsConfig {
        &self.cfg.es
    }

    /// Gradient updates per generation.
    pub fn inner_cycles(&self) -> usize {
        self.cfg.inner_cycles
    }

    /// Sets the gradient updates of the following generations (0 isolates the evaluation
    /// and replacement, as the loop's tests do).
    pub fn set_inner_cycles(&mut self, cycles: usize) {
        self.cfg.inner_cycles = cycles;
    }

    /// Gradient updates per environment step collected, when set (see
    /// [`Hybrid::set_updates_per_step`]).
    pub fn updates_per_step(&self) -> Option<f64> {
        self.cfg.updates_per_step
    }

    /// When `Some(ratio)`, the inner cycles of each following generation are `ratio` per
    /// environment step that generation collected (rounded), replacing the fixed
    /// [`Hybrid::inner_cycles`]: the update-to-data ratio stays fixed as episodes lengthen.
    pub fn set_updates_per_step(&mut self, ratio: Option<f64>) {
        self.cfg.updates_per_step = ratio;
    }

    /// Generations completed.
    pub fn generation(&self) -> usize {
        self.generation
    }

    /// The genome of the last generation's best individual: the policy whose fitness is that
    /// generation's learning-curve value (empty before the first generation). The RL actor
    /// differs from it by the inner updates that followed replacement.
    pub fn kept(&self) -> &[f32] {
        &self.kept
    }

    /// Whether the RL actor carries inner-training updates not yet evaluated (it will be
    /// individual 0 of the next generation).
    pub fn rl_trained(&self) -> bool {
        self.rl_trained
    }

    /// Counts over the generations run so far.
    pub fn stats(&self) -> &LoopStats {
        &self.stats
    }

    /// Fills the buffer with random-action episodes until the warm-start budget is spent
    /// (no-op once done). Returns the steps taken.
    pub fn warm_start(&mut self, env: &mut dyn esrl_sim::Env) -> u64 {
        self.trainer.warm_start(env)
    }

    /// This generation's individuals: the RL actor's genome first, then N − 1 perturbations of
    /// the ES mean.
    pub fn population(&self) -> Vec<Vec<f32>> {
        let n = self.cfg.es.population;
        let mut genomes = Vec::with_capacity(n);
        genomes.push(self.trainer.agent().genome());
        genomes.extend((1..n).map(|i| self.strategy.perturbation(i)));
        genomes
    }

    /// The rollouts of one evaluation, run in this order from the same initial state.
    fn rollout_plan(&self) -> Vec<RolloutSpec> {
        let spec = |mode, scored| RolloutSpec { mode, scored };
        let explore = vec![spec(ActMode::Explore, true)];
        let deterministic = vec![spec(ActMode::Deterministic, true)];
        match self.cfg.es.fitness {
            Fitness::Auto if self.trainer.agent().has_entropy() => explore,
            Fitness::Auto | Fitness::Deterministic => deterministic,
            Fitness::Sampled => explore,
            Fitness::Both => vec![
                spec(ActMode::Explore, false),
                spec(ActMode::Deterministic, true),
            ],
        }
    }

    /// Eq. 8: the generation to evaluate, each genome with its action stream, the
    /// generation's K initial states and the rollouts of `es.fitness`.
    pub fn ask(&self) -> Generation {
        Generation {
            index: self.generation,
            policy: self.trainer.agent().policy(),
            genomes: self.genomes(self.generation, 0, self.population()),
        }
    }

    /// Generation `gen`'s individuals 1.. (the perturbations of the current ES mean), ready
    /// to roll out: valid once the ES update of generation `gen − 1` is done.
    fn perturbations(&self, gen: usize) -> Vec<Genome> {
        let params = (1..self.cfg.es.population).map(|i| self.strategy.perturbation(i));
        self.genomes(gen, 1, params)
    }

    /// Genomes of generation `gen` with parameters `params`, individuals `first`, `first` + 1,
    /// …, each with its action stream, the generation's K initial states and the rollouts of
    /// `es.fitness`.
    fn genomes(
        &self,
        gen: usize,
        first: usize,
        params: impl IntoIterator<Item = Vec<f32>>,
    ) -> Vec<Genome> {
        let seed = self.trainer.seed();
        let gen = gen as u64;
        let k = self.cfg.es.evaluations as u64;
        let env_seeds: Vec<u64> = (0..k)
            .map(|evaluation| {
                Stream::EvaluationReset {
                    generation: gen,
                    evaluation,
                    evaluations: k,
                }
                .seed(seed)
            })
            .collect();
        let rollouts = self.rollout_plan();
        params
            .into_iter()
            .enumerate()
            .map(|(i, params)| Genome {
                index: first + i,
                params,
                action_seed: Stream::Individual {
                    generation: gen,
                    index: (first + i) as u64,
                }
                .seed(seed),
                env_seeds: env_seeds.clone(),
                rollouts: rollouts.clone(),
            })
            .collect()
    }

    /// The rest of a generation on the evaluations of [`Hybrid::ask`]'s generation, in
    /// individual order: the transitions into the buffer, the ES update (eqs. 10–11), elitist
    /// replacement and the inner training cycles, in the configured order. Returns the
    /// generation's row.
    pub fn tell(
        &mut self,
        generation: &Generation,
        evaluated: Vec<Evaluation>,
    ) -> Result<GenerationReport, AgentError> {
        self.tell_and_prefetch(generation, evaluated, false)
    }

    /// [`Hybrid::tell`]; with `prefetch`, the next generation's perturbations roll out on
    /// the evaluator while the inner cycles train.
    fn tell_and_prefetch(
        &mut self,
        generation: &Generation,
        evaluated: Vec<Evaluation>,
        prefetch: bool,
    ) -> Result<GenerationReport, AgentError> {
        let genomes = &generation.genomes;
        let n = genomes.len();
        if generation.index != self.generation || evaluated.len() != n {
            return Err(AgentError::State {
                field: "evaluations".into(),
                reason: format!(
                    "{} evaluations of generation {} told to generation {} of {n} individuals",
                    evaluated.len(),
                    generation.index,
                    self.generation
                ),
            });
        }
        let rl_trained = self.rl_trained;

        // Every transition into the buffer, in individual order.
        let mut steps = 0usize;
        let mut rollouts = 0usize;
        for ev in &evaluated {
            for ep in &ev.episodes {
                self.trainer.store(ep);
                steps += ep.len();
                rollouts += 1;
            }
        }
        // Every individual's first rollout starts from the generation's first initial state.
        let obs0 = evaluated
            .first()
            .and_then(|e| e.episodes.first())
            .map(|ep| ep.first_obs().to_vec())
            .unwrap_or_default();

        // Eqs. 10–11: the elites' weighted mean becomes θ, and σ decays toward σ_min.
        let fitness: Vec<f64> = evaluated.iter().map(|e| e.fitness).collect();
        let refs: Vec<&[f32]> = genomes.iter().map(|g| g.params.as_slice()).collect();
        let order = self.strategy.update(&refs, &fitness, &self.cfg.es);
        let best = order[0];
        let replaced = best != 0 && fitness[best] > fitness[0];

        // Elitist replacement and the inner training cycles, in the configured order.
        let losses = match self.cfg.es.order {
            LoopOrder::ReplaceThenTrain => {
                if replaced {
                    self.trainer.agent_mut().set_genome(&genomes[best].params)?;
                }
                self.train(self.cfg.inner_cycles_for(steps), prefetch)?
            }
            LoopOrder::TrainThenReplace => {
                let losses = self.train(self.cfg.inner_cycles_for(steps), prefetch)?;
                if replaced {
                    self.trainer.agent_mut().set_genome(&genomes[best].params)?;
                }
                losses
            }
        };
        let trained_now = losses.critic().is_some();
        self.rl_trained = match self.cfg.es.order {
            LoopOrder::ReplaceThenTrain => trained_now,
            LoopOrder::TrainThenReplace => trained_now && !replaced,
        };
        self.kept.clone_from(&genomes[best].params);

        let rl_rank = order.iter().position(|&i| i == 0).unwrap_or(n);
        let finite: Vec<f64> = fitness.iter().copied().filter(|f| f.is_finite()).collect();
        let agent = self.trainer.agent();
        let report = GenerationReport {
            generation: self.generation,
            env_steps: self.trainer.env_steps(),
            curve: fitness[best],
            best_fitness: fitness[best],
            mean_fitness: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
            worst_fitness: finite.iter().copied().fold(f64::INFINITY, f64::min),
            rl_fitness: fitness[0],
            rl_trained,
            rl_rank,
            rl_elite: rl_rank < self.cfg.es.elites(),
            rl_replaced: replaced,
            sigma: self.strategy.sigma,
            alpha: agent.has_entropy().then(|| agent.alpha()),
            critic_loss: losses.critic(),
            actor_loss: losses.actor(),
            q0: agent.q0(&obs0),
            mean_length: steps as f64 / rollouts.max(1) as f64,
        };
        self.stats.add(&report);
        self.generation += 1;
        Ok(report)
    }

    /// Runs one generation (module docs): eq. 8, eq. 9, then eqs. 10–11, replacement and
    /// the inner training ([`Hybrid::tell`]), pipelined unless turned off.
    pub fn step(&mut self) -> Result<GenerationReport, AgentError> {
        // Pipelined, individuals 1.. were drawn and rolled out during the last generation's
        // training (nothing they depend on changes between a tell and the next step; a
        // restore drops them).
        let ahead = self
            .prefetched
            .take()
            .filter(|p| p.generation == self.generation);
        let (generation, evaluated) = match ahead {
            None => {
                let generation = self.ask(); // eq. 8
                let evaluated = self.evaluator.evaluate(&generation)?; // eq. 9
                (generation, evaluated)
            }
            Some(ahead) => {
                // Eq. 8 and eq. 9 for individual 0 (the RL actor), the rest as prefetched.
                let first = Generation {
                    index: self.generation,
                    policy: self.trainer.agent().policy(),
                    genomes: self.genomes(self.generation, 0, [self.trainer.agent().genome()]),
                };
                let mut evaluated = self.evaluator.evaluate(&first)?;
                evaluated.extend(ahead.evaluations);
                let mut generation = first;
                generation.genomes.extend(ahead.genomes);
                (generation, evaluated)
            }
        };
        self.tell_and_prefetch(&generation, evaluated, self.cfg.pipelined)
    }

    /// The inner training cycles; with `prefetch`, beside them on the rayon pool, the
    /// rollouts of the next generation's perturbations (kept for the next [`Hybrid::step`]; an
    /// evaluation error there surfaces when that generation is evaluated again).
    fn train(&mut self, cycles: usize, prefetch: bool) -> Result<LossMeans, AgentError> {
        if !prefetch || self.cfg.es.population < 2 {
            return self.trainer.train(cycles);
        }
        let next = Generation {
            index: self.generation + 1,
            policy: self.trainer.agent().policy(),
            genomes: self.perturbations(self.generation + 1),
        };
        let evaluator = Arc::clone(&self.evaluator);
        let trainer = &mut self.trainer;
        let (losses, evaluated) =
            rayon::join(|| trainer.train(cycles), || evaluator.evaluate(&next));
        self.prefetched = evaluated.ok().map(|evaluations| Prefetched {
            generation: next.index,
            genomes: next.genomes,
            evaluations,
        });
        losses
    }
}

impl Learner for Hybrid {
    type Row = GenerationReport;
    const UNIT: &'static str = "generation";

    /// The warm start, from one environment of `envs`.
    fn prepare(&mut self, envs: &MakeEnv) -> Result<(), AgentError> {
        let mut env = envs();
        self.warm_start(env.as_mut());
        Ok(())
    }

    /// One generation on the hybrid's own evaluator (which has its own environments).
    fn run_row(&mut self, _envs: &MakeEnv) -> Result<GenerationReport, AgentError> {
        self.step()
    }

    fn rows(&self) -> usize {
        self.generation
    }

    fn env_steps(&self) -> u64 {
        self.trainer.env_steps()
    }

    fn agent(&self) -> &Agent {
        self.trainer.agent()
    }

    /// The agent with the actor (and, for ES-SAC, log α) of the last generation's best
    /// individual ([`Hybrid::kept`]).
    fn scored_agent(&self) -> Result<Option<Agent>, AgentError> {
        if self.kept.is_empty() {
            return Ok(None);
        }
        let mut agent = self.trainer.agent().clone();
        agent.set_genome(&self.kept)?;
        Ok(Some(agent))
    }

    /// The agent with the actor (and, for ES-SAC, log α) of the ES mean θ after the last
    /// generation's eqs. 10–11.
    fn mean_agent(&self) -> Result<Option<Agent>, AgentError> {
        let mut agent = self.trainer.agent().clone();
        agent.set_genome(&self.strategy.mean)?;
        Ok(Some(agent))
    }

    fn summary_figures(&self) -> Vec<(&'static str, Option<f64>)> {
        vec![
            ("rl_trained_best_share", self.stats.trained_best_share()),
            ("rl_trained_elite_share", self.stats.trained_elite_share()),
            ("rl_replaced_share", self.stats.replaced_share()),
        ]
    }
}

impl Resumable for Hybrid {
    type LoopState = EsState;

    fn buffer(&self) -> &ReplayBuffer {
        self.trainer.buffer()
    }

    fn state(&self) -> LearnerState<EsState> {
        let es = EsState {
            generations: self.generation,
            sigma: self.strategy.sigma,
            es_generation: self.strategy.generation,
            rl_trained: self.rl_trained,
            loop_stats: self.stats.clone(),
        };
        self.trainer.state().with_loop_state(es).0
    }

    fn tensors(&self) -> Vec<(String, Vec<f32>)> {
        let mut tensors = self.trainer.agent().state_tensors();
        tensors.push((ES_MEAN.into(), self.strategy.mean.clone()));
        tensors
    }

    /// Refuses a state whose generation count is not `rows`, whose σ lies outside the range
    /// eq. 11 keeps it in, or whose ES generation counter disagrees.
    fn check(&self, state: &LearnerState<EsState>, rows: usize) -> Result<(), AgentError> {
        let state = &state.loop_state;
        let bad = |field: &str, reason: String| {
            Err(AgentError::State {
                field: field.into(),
                reason,
            })
        };
        if state.generations != rows {
            return bad(
                "generations",
                format!("= {} but rows = {rows}", state.generations),
            );
        }
        let sigma = state.sigma;
        let (lo, hi) = (
            self.cfg.es.sigma.min(self.cfg.es.sigma_min),
            self.cfg.es.sigma.max(self.cfg.es.sigma_min),
        );
        if !(sigma.is_finite() && sigma >= lo * (1.0 - 1e-9) && sigma <= hi * (1.0 + 1e-9)) {
            return bad(
                "sigma",
                format!("= {sigma}, outside [{lo}, {hi}] where eq. 11 keeps it"),
            );
        }
        if state.es_generation != state.generations as u64 {
            return bad(
                "es_generation",
                format!(
                    "= {} but generations = {}",
                    state.es_generation, state.generations
                ),
            );
        }
        Ok(())
    }

    fn restore(
        &mut self,
        state: LearnerState<EsState>,
        tensors: &HashMap<String, Vec<f32>>,
        buffer: ReplayBuffer,
    ) -> Result<(), AgentError> {
        self.prefetched = None;
        let mean = tensors.get(ES_MEAN).ok_or_else(|| AgentError::State {
            field: ES_MEAN.into(),
            reason: "the checkpoint lacks this tensor".into(),
        })?;
        if mean.len() != self.strategy.mean.len() {
            return Err(AgentError::State {
                field: ES_MEAN.into(),
                reason: format!(
                    "has {} values, expected {}",
                    mean.len(),
                    self.strategy.mean.len()
                ),
            });
        }
        let (rl, state) = state.with_loop_state(());
        self.trainer.restore(rl, tensors, buffer)?;
        self.strategy.mean.clone_from(mean);
        self.strategy.sigma = state.sigma;
        self.strategy.generation = state.es_generation;
        self.generation = state.generations;
        // A loop without inner training never carries a trained actor.
        self.rl_trained =
            state.rl_trained && (self.cfg.inner_cycles > 0 || self.cfg.updates_per_step.is_some());
        self.stats = state.loop_stats;
        Ok(())
    }
}

/// Position of the best of `fitness` (NaN worst, ties to the lowest index).
pub fn best_index(fitness: &[f64]) -> Option<usize> {
    rank(fitness).first().copied()
}
