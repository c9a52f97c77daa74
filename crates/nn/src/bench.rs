//! Speed of the networks, for `esrl bench nn` and for comparison with PyTorch
//! (`crates/nn/scripts/torch_nn_bench.py` times the same shapes). The full SAC update that
//! training runs is timed where it lives, in `esrl_agents::bench` (`esrl bench update`).
//!
//! Everything runs on the calling thread (faer `Par::Seq`). Each figure is the median over
//! `reps` repetitions after `warmup` untimed runs.

use crate::error::NnError;
use crate::graph::Graph;
use crate::nets::{Actor, ActorConfig, Critic, CriticConfig, Module};
use crate::tensor::Tensor;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BenchConfig {
    /// Observation width. Default 43 (the walking env).
    pub obs_dim: usize,
    /// Action width. Default 6.
    pub act_dim: usize,
    /// Sequences per batch (and transitions per MLP batch). Default 256 (SPEC §4).
    pub batch: usize,
    /// Steps per sequence. Default 8 (as `peers/torch_sac_step.py`).
    pub seq_len: usize,
    /// Timed repetitions; the median is reported. Default 7.
    pub reps: usize,
    /// Untimed warm-up runs. Default 2.
    pub warmup: usize,
}

impl Default for BenchConfig {
    fn default() -> Self {
        Self {
            obs_dim: 43,
            act_dim: 6,
            batch: 256,
            seq_len: 8,
            reps: 7,
            warmup: 2,
        }
    }
}

/// Results in milliseconds (medians) and parameter counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// The configuration measured.
    pub config: BenchConfig,
    /// Parameters of the paper-size recurrent actor.
    pub actor_params: usize,
    /// Parameters of one paper-size recurrent critic.
    pub critic_params: usize,
    /// Forward + backward of the recurrent actor on batch × seq_len (sample, log-prob, loss).
    pub actor_ms: f64,
    /// Forward + backward of one recurrent critic on batch × seq_len (MSE loss).
    pub critic_ms: f64,
    /// Parameters of the feed-forward (MLP 256×256) actor.
    pub mlp_actor_params: usize,
    /// Parameters of one feed-forward critic.
    pub mlp_critic_params: usize,
    /// Forward + backward of the MLP actor on `batch` transitions.
    pub mlp_actor_ms: f64,
    /// Forward + backward of one MLP critic on `batch` transitions.
    pub mlp_critic_ms: f64,
    /// Fastest repetition of each figure above (ms), keyed like the fields (`actor`,
    /// `critic`, `mlp_actor`, `mlp_critic`): the least
    /// disturbed by other load on the machine.
    pub min_ms: std::collections::BTreeMap<String, f64>,
    /// Mean time this thread actually ran on a CPU per repetition (ms, Linux
    /// `/proc/thread-self/schedstat`, total over the repetitions / reps since the kernel may
    /// count in scheduler ticks; empty elsewhere), same keys: unlike wall time it does not
    /// grow when other processes take turns on the core, so it compares runs taken on a busy
    /// machine.
    pub cpu_ms: std::collections::BTreeMap<String, f64>,
    /// Threads used (always 1).
    pub threads: usize,
}

fn randn(rows: usize, cols: usize, rng: &mut ChaCha8Rng) -> Tensor {
    Tensor::from_vec(
        rows,
        cols,
        (0..rows * cols)
            .map(|_| rng.sample::<f32, _>(rand_distr::StandardNormal))
            .collect(),
    )
}

/// Nanoseconds this thread has spent on a CPU (Linux), if readable.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// Timing of one figure: wall median and minimum, on-CPU median (ms).
struct Timing {
    median: f64,
    min: f64,
    cpu: Option<f64>,
}

/// Times `reps` runs of `f` after `warmup` untimed ones.
fn time_ms(reps: usize, warmup: usize, mut f: impl FnMut()) -> Timing {
    for _ in 0..warmup {
        f();
    }
    let reps = reps.max(1);
    let mut wall = Vec::with_capacity(reps);
    let c0 = thread_cpu_ns();
    for _ in 0..reps {
        let t0 = Instant::now();
        f();
        wall.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let cpu = match (c0, thread_cpu_ns()) {
        (Some(a), Some(b)) => Some(b.saturating_sub(a) as f64 / 1e6 / reps as f64),
        _ => None,
    };
    wall.sort_by(|a, b| a.total_cmp(b));
    Timing {
        median: wall[wall.len() / 2],
        min: wall[0],
        cpu,
    }
}

/// Forward + backward of an actor on (rows, obs) with a SAC-like loss mean(log π − Σa).
fn actor_fwd_bwd(actor: &Actor, obs: &Tensor, batch: usize, rng: &mut ChaCha8Rng) -> f32 {
    let mut g = Graph::new();
    let o = g.constant(obs.clone());
    let out = actor.forward(&mut g, o, batch, None);
    let s = actor.sample(&mut g, &out, rng);
    let asum = g.sum_cols(s.action);
    let d = g.sub(s.log_prob, asum);
    let loss = g.mean(d);
    let grads = g.backward(loss);
    grads.of(actor.params()).map_or(0.0, |v| v[0])
}

/// Forward + backward of a critic with an MSE loss.
fn critic_fwd_bwd(critic: &Critic, obs: &Tensor, act: &Tensor, y: &Tensor, batch: usize) -> f32 {
    let mut g = Graph::new();
    let (o, a, yv) = (
        g.constant(obs.clone()),
        g.constant(act.clone()),
        g.constant(y.clone()),
    );
    let q = critic.forward(&mut g, o, a, batch, None).q;
    let loss = g.mse(q, yv);
    let grads = g.backward(loss);
    grads.of(critic.params()).map_or(0.0, |v| v[0])
}

/// Random inputs of one timing: observations, actions and regression targets.
struct Batch {
    obs: Tensor,
    act: Tensor,
    rew: Tensor,
}

fn batch(rows: usize, obs_dim: usize, act_dim: usize, rng: &mut ChaCha8Rng) -> Batch {
    Batch {
        obs: randn(rows, obs_dim, rng),
        act: Tensor::from_vec(
            rows,
            act_dim,
            (0..rows * act_dim)
                .map(|_| rng.random_range(-1.0f32..1.0))
                .collect(),
        ),
        rew: randn(rows, 1, rng),
    }
}

/// Runs the benchmark on the calling thread.
pub fn run(config: &BenchConfig) -> Result<BenchReport, NnError> {
    if config.batch == 0 || config.seq_len == 0 {
        return Err(NnError::Config {
            field: "bench.batch/seq_len".into(),
            value: format!("{}/{}", config.batch, config.seq_len),
            reason: "must be ≥ 1".into(),
        });
    }
    let (od, ad, b, t) = (config.obs_dim, config.act_dim, config.batch, config.seq_len);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let actor = Actor::new(od, ad, &ActorConfig::paper(), 1)?;
    let critic = Critic::new(od, ad, &CriticConfig::paper(), 2)?;
    let mlp_actor = Actor::new(od, ad, &ActorConfig::feed_forward(), 3)?;
    let mlp_critic = Critic::new(od, ad, &CriticConfig::feed_forward(), 4)?;
    let seq = batch(b * t, od, ad, &mut rng);
    let flat = batch(b, od, ad, &mut rng);
    let mut sink = 0.0f32;
    let (reps, warm) = (config.reps, config.warmup);
    let mut min_ms = std::collections::BTreeMap::new();
    let mut cpu_ms = std::collections::BTreeMap::new();
    let mut record = |name: &str, t: Timing| {
        min_ms.insert(name.to_string(), t.min);
        if let Some(c) = t.cpu {
            cpu_ms.insert(name.to_string(), c);
        }
        t.median
    };
    let actor_ms = record(
        "actor",
        time_ms(reps, warm, || {
            sink += actor_fwd_bwd(&actor, &seq.obs, b, &mut rng)
        }),
    );
    let critic_ms = record(
        "critic",
        time_ms(reps, warm, || {
            sink += critic_fwd_bwd(&critic, &seq.obs, &seq.act, &seq.rew, b)
        }),
    );
    let mlp_actor_ms = record(
        "mlp_actor",
        time_ms(reps * 5, warm * 5, || {
            sink += actor_fwd_bwd(&mlp_actor, &flat.obs, b, &mut rng)
        }),
    );
    let mlp_critic_ms = record(
        "mlp_critic",
        time_ms(reps * 5, warm * 5, || {
            sink += critic_fwd_bwd(&mlp_critic, &flat.obs, &flat.act, &flat.rew, b)
        }),
    );
    std::hint::black_box(sink);
    Ok(BenchReport {
        config: config.clone(),
        actor_params: actor.num_params(),
        critic_params: critic.num_params(),
        actor_ms,
        critic_ms,
        mlp_actor_params: mlp_actor.num_params(),
        mlp_critic_params: mlp_critic.num_params(),
        mlp_actor_ms,
        mlp_critic_ms,
        min_ms,
        cpu_ms,
        threads: 1,
    })
}
