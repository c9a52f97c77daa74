//! Speed of the one update ([`Agent::update`], critics, actor, α and targets) that training
//! runs, for `esrl bench update`, `esrl bench nn` and `esrl bench es`, on random data of the
//! PyTorch baseline's shapes (`peers/torch_sac_step.py`): 256 sequences × 8 steps without
//! burn-in for recurrent networks, 256 transitions for feed-forward ones. Single thread;
//! batch sampling is not timed.

use crate::agent::{Agent, AgentError, UpdateStats};
use crate::config::{Algo, RlConfig};
use crate::nets::NetConfig;
use crate::replay::{ReplayBuffer, SequenceBatch, Transition};
use esrl_nn::Module;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Transitions of random data the batches are drawn from.
const BUFFER: usize = 20_000;
/// Length of the random episodes in that buffer.
const EPISODE: usize = 500;

/// What [`time_update`] measured (milliseconds).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UpdateTiming {
    /// Median wall time of one update.
    pub ms_per_update: f64,
    /// Fastest update: the least disturbed by other load on the machine.
    pub min_ms: f64,
    /// Timed updates.
    pub reps: usize,
    /// Parameters of the actor.
    pub actor_params: usize,
    /// Parameters of one critic.
    pub critic_params: usize,
}

/// Untimed updates run for at least this long before the timed ones. A pool of two threads
/// on a machine that was idle needs it: on the 2-core Xeon the first 2-thread updates took
/// 1.7 ms and the later ones 1.05 ms (`esrl bench update --threads 2`: 1.74 ms median over
/// 21 reps after 2 warm-up updates, 1.05–1.07 ms over 100–1,000), while one thread is at its
/// pace from the first update. In training the pool is never idle for long.
const WARMUP_S: f64 = 0.5;

/// Times `reps` updates of an `algo` agent with networks `nets` for observations of
/// `obs_dim` and actions of `act_dim` on batches of `batch` sequences (recurrent) or
/// transitions, after `warmup` untimed ones and at least [`WARMUP_S`] of them, its batch
/// split into `batch_chunks` chunks (`rl.batch_chunks`).
#[allow(clippy::too_many_arguments)]
pub fn time_update(
    algo: Algo,
    nets: &NetConfig,
    obs_dim: usize,
    act_dim: usize,
    batch: usize,
    reps: usize,
    warmup: usize,
    batch_chunks: usize,
) -> Result<UpdateTiming, AgentError> {
    let mut run = RandomData::new(algo, nets, obs_dim, act_dim, batch, 0, batch_chunks)?;
    // Back to back, as `Trainer::train` runs them: with its helper thread.
    let mut times = Vec::with_capacity(reps.max(1));
    crate::train::with_helper(|| {
        let start = Instant::now();
        let mut done = 0;
        while done < warmup || start.elapsed().as_secs_f64() < WARMUP_S {
            run.update()?;
            done += 1;
        }
        for _ in 0..reps.max(1) {
            times.push(run.update()? * 1e3);
        }
        Ok::<_, AgentError>(())
    })?;
    let agent = run.agent;
    times.sort_by(f64::total_cmp);
    Ok(UpdateTiming {
        ms_per_update: times[times.len() / 2],
        min_ms: times[0],
        reps: times.len(),
        actor_params: agent.actor().num_params(),
        critic_params: agent.critics()[0].num_params(),
    })
}

/// `updates` updates of a fresh `algo` agent (seed 0) with networks `nets`, on batches of
/// `batch` sequences × 8 steps after 4 steps of burn-in (recurrent) or `batch` transitions
/// drawn from random data, split into `batch_chunks` chunks: the agent afterwards and each
/// update's statistics. The
/// same arguments give the same agent, bit for bit, on a rayon pool of any size
/// (`tests/threaded_update.rs`).
pub fn train_on_random_data(
    algo: Algo,
    nets: &NetConfig,
    obs_dim: usize,
    act_dim: usize,
    batch: usize,
    batch_chunks: usize,
    updates: usize,
) -> Result<(Agent, Vec<UpdateStats>), AgentError> {
    let mut run = RandomData::new(algo, nets, obs_dim, act_dim, batch, 4, batch_chunks)?;
    let mut stats = Vec::with_capacity(updates);
    for _ in 0..updates {
        let b = run.batch();
        stats.push(run.agent.update(&b)?);
    }
    Ok((run.agent, stats))
}

/// An agent updating on batches drawn from a buffer of random data.
struct RandomData {
    agent: Agent,
    buffer: ReplayBuffer,
    rng: ChaCha8Rng,
    batch: usize,
    seq_len: usize,
    burn_in: usize,
    recurrent: bool,
}

impl RandomData {
    fn new(
        algo: Algo,
        nets: &NetConfig,
        obs_dim: usize,
        act_dim: usize,
        batch: usize,
        burn_in: usize,
        batch_chunks: usize,
    ) -> Result<Self, AgentError> {
        let cfg = RlConfig {
            burn_in,
            seq_len: 8,
            batch_size: batch,
            batch_chunks,
            ..RlConfig::for_algo(algo)
        };
        Ok(Self {
            agent: Agent::new(algo, obs_dim, act_dim, nets, &cfg, 0)?,
            buffer: random_buffer(obs_dim, act_dim),
            rng: ChaCha8Rng::seed_from_u64(0),
            batch,
            seq_len: cfg.seq_len,
            burn_in,
            recurrent: nets.recurrent(),
        })
    }

    /// The next batch.
    fn batch(&mut self) -> SequenceBatch {
        if self.recurrent {
            self.buffer
                .sample_sequences(&mut self.rng, self.batch, self.seq_len, self.burn_in)
        } else {
            self.buffer.sample_transitions(&mut self.rng, self.batch)
        }
    }

    /// One update on a fresh batch; returns its seconds (batch sampling not timed).
    fn update(&mut self) -> Result<f64, AgentError> {
        let b = self.batch();
        let t = Instant::now();
        self.agent.update(&b)?;
        Ok(t.elapsed().as_secs_f64())
    }
}

/// A buffer of random transitions in episodes of [`EPISODE`] steps.
fn random_buffer(obs_dim: usize, act_dim: usize) -> ReplayBuffer {
    let mut buf = ReplayBuffer::new(obs_dim, act_dim, BUFFER);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut o = vec![0.0f32; obs_dim];
    let mut a = vec![0.0f32; act_dim];
    for i in 0..BUFFER {
        o.iter_mut().for_each(|x| *x = rng.random_range(-1.0..1.0));
        a.iter_mut().for_each(|x| *x = rng.random_range(-1.0..1.0));
        let next: Vec<f32> = o.iter().map(|x| x * 0.9).collect();
        let end = i % EPISODE == EPISODE - 1;
        buf.push(Transition {
            obs: &o,
            action: &a,
            reward: rng.random_range(-1.0..1.0),
            next_obs: &next,
            terminated: end,
        });
        if end {
            buf.end_episode();
        }
    }
    buf
}
