//! Speed of the one update ([`Agent::update`], critics, actor, α and targets) that training
//! runs, for `esrl bench update`, `esrl bench nn` and `esrl bench es`, on random data of the
//! PyTorch baseline's shapes (`peers/torch_sac_step.py`): 256 sequences × 8 steps without
//! burn-in for recurrent networks, 256 transitions for feed-forward ones. Single thread;
//! batch sampling is not timed.

use crate::agent::{Agent, AgentError};
use crate::config::{Algo, RlConfig};
use crate::nets::NetConfig;
use crate::replay::{ReplayBuffer, Transition};
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

/// Times `reps` updates of an `algo` agent with networks `nets` for observations of
/// `obs_dim` and actions of `act_dim`, after `warmup` untimed ones.
pub fn time_update(
    algo: Algo,
    nets: &NetConfig,
    obs_dim: usize,
    act_dim: usize,
    reps: usize,
    warmup: usize,
) -> Result<UpdateTiming, AgentError> {
    let cfg = RlConfig {
        burn_in: 0,
        seq_len: 8,
        batch_size: 256,
        ..RlConfig::for_algo(algo)
    };
    let mut agent = Agent::new(algo, obs_dim, act_dim, nets, &cfg, 0)?;
    let buffer = random_buffer(obs_dim, act_dim);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let sample = |rng: &mut ChaCha8Rng| {
        if nets.recurrent() {
            buffer.sample_sequences(rng, cfg.batch_size, cfg.seq_len, 0)
        } else {
            buffer.sample_transitions(rng, cfg.batch_size)
        }
    };
    for _ in 0..warmup {
        let b = sample(&mut rng);
        agent.update(&b)?;
    }
    let mut times = Vec::with_capacity(reps.max(1));
    for _ in 0..reps.max(1) {
        let b = sample(&mut rng);
        let t = Instant::now();
        agent.update(&b)?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    Ok(UpdateTiming {
        ms_per_update: times[times.len() / 2],
        min_ms: times[0],
        reps: times.len(),
        actor_params: agent.actor().num_params(),
        critic_params: agent.critics()[0].num_params(),
    })
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
