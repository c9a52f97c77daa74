//! The RL side of every learner ([`Trainer`]: an agent, its replay buffer, its random
//! stream), and plain (non-ES) training: one episode per row, learning as
//! [`RlConfig::learn_every`] says.

use crate::agent::{Agent, AgentError, UpdateStats};
use crate::config::{LearnEvery, RlConfig};
use crate::learner::{state_error, Learner, Resumable, Row, TrainerState};
use crate::policy::{ActMode, Policy};
use crate::replay::{ReplayBuffer, SequenceBatch, Transition};
use crate::rollout::{rollout, Actor, Episode};
use esrl_sim::{run_episode, Env, EpisodeHook, MakeEnv, Mirror, Step};
use esrl_streams::Stream;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};

/// One training episode's row of `metrics.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeReport {
    /// Episode index, from 0.
    pub episode: usize,
    /// Environment steps taken so far, this episode included.
    pub env_steps: u64,
    /// The learning-curve value: the training episode's return.
    pub curve: f64,
    /// The training episode's return.
    #[serde(rename = "return")]
    pub ret: f64,
    /// Steps in the episode.
    pub length: usize,
    /// Whether it ended in a terminal state (fall or success) rather than the time limit.
    pub terminated: bool,
    /// Q₀ at the episode's first state (SPEC §6).
    pub q0: f64,
    /// Mean critic loss over the episode's updates.
    pub critic_loss: Option<f64>,
    /// Mean actor loss over the episode's actor updates.
    pub actor_loss: Option<f64>,
    /// Entropy coefficient after the episode (SAC).
    pub alpha: Option<f64>,
    /// Gradient updates so far.
    pub updates: u64,
}

impl Row for EpisodeReport {
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
            "episode {}: return {:.1}, {} steps",
            self.episode, self.ret, self.length
        )
    }
}

/// Running means of update statistics.
#[derive(Debug, Default, Clone, Copy)]
pub struct LossMeans {
    critic: f64,
    actor: f64,
    n_critic: usize,
    n_actor: usize,
}

impl LossMeans {
    /// Adds one update's losses.
    pub fn add(&mut self, s: &UpdateStats) {
        self.critic += s.critic_loss;
        self.n_critic += 1;
        if let Some(a) = s.actor_loss {
            self.actor += a;
            self.n_actor += 1;
        }
    }

    /// Mean critic loss, if any update happened.
    pub fn critic(&self) -> Option<f64> {
        (self.n_critic > 0).then(|| self.critic / self.n_critic as f64)
    }

    /// Mean actor loss, if any actor update happened.
    pub fn actor(&self) -> Option<f64> {
        (self.n_actor > 0).then(|| self.actor / self.n_actor as f64)
    }
}

/// Draws the batch the agent's networks expect: sequences for recurrent networks, single
/// transitions otherwise.
pub fn sample_batch(
    buffer: &ReplayBuffer,
    cfg: &RlConfig,
    recurrent: bool,
    rng: &mut ChaCha8Rng,
) -> SequenceBatch {
    if recurrent {
        buffer.sample_sequences(rng, cfg.batch_size, cfg.seq_len, cfg.burn_in)
    } else {
        buffer.sample_transitions(rng, cfg.batch_size)
    }
}

/// Replaces every odd-numbered window of `batch` (1, 3, …) by its mirror image: each step's
/// observation, next observation and action through `mirror` (`rl.mirror`). Rewards, ends
/// and masks stay: the mirrored transition is a transition of the task with the same reward.
pub fn mirror_batch(batch: &mut SequenceBatch, mirror: &Mirror) {
    let o = mirror.obs_map().len();
    let a = mirror.action_map().len();
    let mut scratch = Vec::with_capacity(o.max(a));
    for t in 0..batch.window {
        for b in (1..batch.batch).step_by(2) {
            let row = batch.row(t, b);
            mirror.obs_in_place(&mut batch.obs[row * o..(row + 1) * o], &mut scratch);
            mirror.obs_in_place(&mut batch.next_obs[row * o..(row + 1) * o], &mut scratch);
            mirror.action_in_place(&mut batch.action[row * a..(row + 1) * a], &mut scratch);
        }
    }
}

/// An agent, its replay buffer and its random stream ([`Stream::Trainer`]): the RL side of
/// both learners. Trained alone it runs episodes ([`Trainer::episode`]); the hybrid loop
/// stores its population's episodes here and runs the inner cycles ([`Trainer::train`]).
#[derive(Debug, Clone)]
pub struct Trainer {
    agent: Agent,
    buffer: ReplayBuffer,
    /// Warm-start actions, plain agents' exploration, batch sampling.
    rng: ChaCha8Rng,
    /// The run seed (episode seeds derive from it).
    seed: u64,
    env_steps: u64,
    episodes: usize,
    /// The task's mirror, for `rl.mirror` ([`mirror_batch`]).
    mirror: Option<Mirror>,
}

impl Trainer {
    /// A trainer around `agent` with an empty buffer sized by the agent's config, in the run
    /// with seed `seed`.
    pub fn new(agent: Agent, seed: u64) -> Self {
        let cfg = agent.config();
        let buffer = ReplayBuffer::new(agent.obs_dim(), agent.act_dim(), cfg.buffer_size);
        Self {
            agent,
            buffer,
            rng: Stream::Trainer.rng(seed),
            seed,
            env_steps: 0,
            episodes: 0,
            mirror: None,
        }
    }

    /// Sets the task's mirror that `rl.mirror` applies to every batch (none: batches are
    /// used as drawn).
    pub fn set_mirror(&mut self, mirror: Option<Mirror>) {
        self.mirror = mirror;
    }

    /// The agent.
    pub fn agent(&self) -> &Agent {
        &self.agent
    }

    /// The agent, mutable (elitist replacement).
    pub fn agent_mut(&mut self) -> &mut Agent {
        &mut self.agent
    }

    /// The replay buffer.
    pub fn buffer(&self) -> &ReplayBuffer {
        &self.buffer
    }

    /// The run seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Environment steps taken (warm start included).
    pub fn env_steps(&self) -> u64 {
        self.env_steps
    }

    /// Training episodes completed (plain training).
    pub fn episodes(&self) -> usize {
        self.episodes
    }

    /// Whether the warm-start steps are all taken, so learning may begin.
    pub fn warmed_up(&self) -> bool {
        self.env_steps >= self.agent.config().warm_start as u64
    }

    /// One gradient update on a fresh batch (mirrored by `rl.mirror`).
    pub fn update(&mut self) -> Result<UpdateStats, AgentError> {
        let mut batch = sample_batch(
            &self.buffer,
            self.agent.config(),
            self.agent.recurrent(),
            &mut self.rng,
        );
        if self.agent.config().mirror {
            match &self.mirror {
                Some(m) => mirror_batch(&mut batch, m),
                None => {
                    return Err(AgentError::State {
                        field: "rl.mirror".into(),
                        reason: "is on but the trainer was given no mirror of the task".into(),
                    })
                }
            }
        }
        self.agent.update(&batch)
    }

    /// `cycles` gradient updates once the warm start is done (none before), with a helper
    /// thread for their parallel steps ([`with_helper`]).
    pub fn train(&mut self, cycles: usize) -> Result<LossMeans, AgentError> {
        let mut losses = LossMeans::default();
        if self.warmed_up() && cycles > 0 {
            with_helper(|| {
                for _ in 0..cycles {
                    losses.add(&self.update()?);
                }
                Ok::<_, AgentError>(())
            })?;
        }
        Ok(losses)
    }

    /// Puts a finished episode's transitions into the buffer and counts its steps.
    pub fn store(&mut self, episode: &Episode) {
        episode.push_into(&mut self.buffer);
        self.env_steps += episode.len() as u64;
    }

    /// Fills the buffer with random-action episodes until the warm-start budget is spent
    /// (the hybrid loop's warm start; plain training warms up inside its episodes). Episode
    /// seeds are [`Stream::WarmStartReset`] of the step each starts at. No-op once done;
    /// returns the steps taken.
    pub fn warm_start(&mut self, env: &mut dyn Env) -> u64 {
        let target = self.agent.config().warm_start as u64;
        let mut taken = 0;
        while self.env_steps < target {
            let seed = Stream::WarmStartReset(self.env_steps).seed(self.seed);
            let left = (target - self.env_steps) as usize;
            let ep = rollout(env, Actor::Random, seed, Some(left), &mut self.rng);
            self.store(&ep);
            taken += ep.len() as u64;
        }
        taken
    }

    /// Runs one training episode on `env` ([`Stream::EpisodeReset`] of its index), learning
    /// along the way.
    pub fn episode(&mut self, env: &mut dyn Env) -> Result<EpisodeReport, AgentError> {
        let cfg = self.agent.config().clone();
        let env_seed = Stream::EpisodeReset(self.episodes as u64).seed(self.seed);
        let mut policy = self.agent.policy();
        policy.reset();
        let mut learning = Learning {
            trainer: self,
            policy,
            losses: LossMeans::default(),
            q0: f64::NAN,
        };
        // The updates come every few steps inside the episode: the helper stays for all of it.
        let end = with_helper(|| run_episode(env, env_seed, None, &mut learning))?;
        let (losses, q0) = (learning.losses, learning.q0);
        self.buffer.end_episode();
        let mut losses = losses;
        if cfg.learn_every == LearnEvery::Episode && self.warmed_up() {
            for _ in 0..cfg.updates_per_learn {
                losses.add(&self.update()?);
            }
        }
        let report = EpisodeReport {
            episode: self.episodes,
            env_steps: self.env_steps,
            curve: end.ret,
            ret: end.ret,
            length: end.steps,
            terminated: end.terminated,
            q0,
            critic_loss: losses.critic(),
            actor_loss: losses.actor(),
            alpha: self.agent.has_entropy().then(|| self.agent.alpha()),
            updates: self.agent.updates(),
        };
        self.episodes += 1;
        Ok(report)
    }

    /// The counters and random streams.
    pub fn state(&self) -> TrainerState {
        let (agent_updates, agent_rng) = self.agent.counters();
        TrainerState {
            episodes: self.episodes,
            env_steps: self.env_steps,
            trainer_rng: self.rng.clone(),
            agent_updates,
            agent_rng,
            episode_open: self.buffer.episode_open(),
            loop_state: (),
        }
    }

    /// Restores a saved state, the agent's tensors and the replay buffer.
    pub fn restore(
        &mut self,
        state: TrainerState,
        tensors: &HashMap<String, Vec<f32>>,
        buffer: ReplayBuffer,
    ) -> Result<(), AgentError> {
        self.agent.load_state_tensors(tensors)?;
        self.agent
            .set_counters(state.agent_updates, state.agent_rng);
        self.rng = state.trainer_rng;
        self.env_steps = state.env_steps;
        self.episodes = state.episodes;
        self.buffer = buffer;
        Ok(())
    }
}

/// The hook of a training episode: acts (randomly during the warm start, else exploring),
/// stores every transition, and learns every `learn_every` steps.
struct Learning<'t> {
    trainer: &'t mut Trainer,
    policy: Policy,
    losses: LossMeans,
    q0: f64,
}

impl<E: Env + ?Sized> EpisodeHook<E> for Learning<'_> {
    type Error = AgentError;

    fn start(&mut self, obs: &[f32]) -> Result<(), AgentError> {
        self.q0 = self.trainer.agent.q0(obs);
        Ok(())
    }

    fn act(&mut self, obs: &[f32], action: &mut [f32]) {
        let t = &mut *self.trainer;
        if t.warmed_up() {
            self.policy.act(obs, ActMode::Explore, &mut t.rng, action);
        } else {
            action
                .iter_mut()
                .for_each(|x| *x = t.rng.random_range(-1.0..=1.0));
        }
    }

    fn step(&mut self, _: &E, obs: &[f32], action: &[f32], step: &Step) -> Result<(), AgentError> {
        let t = &mut *self.trainer;
        t.buffer.push(Transition {
            obs,
            action,
            reward: step.reward,
            next_obs: &step.obs,
            terminated: step.terminated,
        });
        t.env_steps += 1;
        let cfg = t.agent.config();
        if let LearnEvery::Steps(n) = cfg.learn_every {
            if t.warmed_up() && t.env_steps.is_multiple_of(n as u64) {
                for _ in 0..cfg.updates_per_learn {
                    self.losses.add(&t.update()?);
                }
                self.policy.sync_from(t.agent.actor())?;
            }
        }
        Ok(())
    }
}

impl Learner for Trainer {
    type Row = EpisodeReport;
    const UNIT: &'static str = "episode";

    fn run_row(&mut self, envs: &MakeEnv) -> Result<EpisodeReport, AgentError> {
        let mut env = envs();
        self.episode(env.as_mut())
    }

    fn rows(&self) -> usize {
        self.episodes
    }

    fn env_steps(&self) -> u64 {
        self.env_steps
    }

    fn agent(&self) -> &Agent {
        &self.agent
    }
}

impl Resumable for Trainer {
    type LoopState = ();

    fn buffer(&self) -> &ReplayBuffer {
        &self.buffer
    }

    fn state(&self) -> TrainerState {
        Trainer::state(self)
    }

    fn tensors(&self) -> Vec<(String, Vec<f32>)> {
        self.agent.state_tensors()
    }

    fn check(&self, state: &TrainerState, rows: usize) -> Result<(), AgentError> {
        if state.episodes != rows {
            return Err(state_error(
                "episodes",
                format!("= {} but rows = {rows}", state.episodes),
            ));
        }
        Ok(())
    }

    fn restore(
        &mut self,
        state: TrainerState,
        tensors: &HashMap<String, Vec<f32>>,
        buffer: ReplayBuffer,
    ) -> Result<(), AgentError> {
        Trainer::restore(self, state, tensors, buffer)
    }
}

/// Runs `work` on this thread and offers the rayon pool one helper: a thread that, once it
/// has nothing of its own to do (in the hybrid loop: the next generation's rollouts are
/// done), runs the pool's pending jobs until `work` ends instead of going to sleep. The
/// parallel steps of an update (the two critics side by side, the TD targets beside the
/// actor's pass) last a fraction of a millisecond, and a sleeping thread wakes too late for
/// them: without the helper the recipe's updates ran slower at 2 threads than at one
/// (`results/speed/README.md`). Scheduling only: no number depends on which thread runs a
/// step. On a pool of one thread `work` simply runs.
pub fn with_helper<T: Send>(work: impl FnOnce() -> T + Send) -> T {
    if rayon::current_num_threads() < 2 {
        return work();
    }
    /// Ends the help when `work` returns or unwinds (a helper left spinning would keep
    /// `rayon::join` from returning the panic).
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(false, Ordering::Release);
        }
    }
    let busy = AtomicBool::new(true);
    let (out, ()) = rayon::join(
        || {
            let _done = Done(&busy);
            work()
        },
        || {
            while busy.load(Ordering::Acquire) {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    std::thread::yield_now();
                }
            }
        },
    );
    out
}

#[cfg(test)]
mod helper_tests {
    use super::with_helper;

    #[test]
    fn work_runs_once_and_its_value_comes_back_on_any_pool() {
        for threads in [1, 2, 3] {
            let pool = esrl_nn::subnormal::thread_pool(threads).unwrap();
            let mut runs = 0;
            let sum: u64 = pool.install(|| {
                with_helper(|| {
                    runs += 1;
                    // Parallel steps inside, as an update has.
                    (0..1000u64)
                        .map(|i| rayon::join(|| i, || 2 * i))
                        .map(|(a, b)| a + b)
                        .sum()
                })
            });
            assert_eq!((runs, sum), (1, 3 * 999 * 1000 / 2), "{threads} threads");
        }
    }

    #[test]
    fn a_panic_in_the_work_ends_the_help_and_propagates() {
        let pool = esrl_nn::subnormal::thread_pool(2).unwrap();
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| with_helper(|| panic!("update failed")))
        }));
        assert!(caught.is_err());
    }
}
