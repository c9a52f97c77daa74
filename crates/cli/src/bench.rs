//! `esrl bench`: speed of the environment, the networks, one SAC update and one ES generation.

use crate::args::{Arch, BenchWhat, EnvKind, Preset};
use crate::checkpoint::Learner;
use crate::config::TrainConfig;
use crate::train::{build_learner, env_factory};
use anyhow::Result;
use esrl_agents::{Agent, Algo, NetConfig, ReplayBuffer, RlConfig, Transition};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use serde_json::json;
use std::time::Instant;

fn emit<T: Serialize>(json_out: bool, value: &T, text: String) -> Result<()> {
    if json_out {
        println!("{}", serde_json::to_string(value)?);
    } else {
        println!("{text}");
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Times one full SAC update of `Agent::update` (critics, actor, α, targets) on random data of
/// the PyTorch baseline's shapes: obs 31, act 6, 256 sequences × 8 steps (LSTM, no burn-in) or
/// 256 transitions (MLP 256×256).
pub fn update_ms(arch: Arch, reps: usize) -> Result<serde_json::Value> {
    let (obs_dim, act_dim) = (31, 6);
    let nets = match arch {
        Arch::Lstm => NetConfig::default(),
        Arch::Mlp => NetConfig::feed_forward(),
    };
    let cfg = RlConfig {
        burn_in: 0,
        seq_len: 8,
        batch_size: 256,
        ..RlConfig::default()
    };
    let mut agent = Agent::new(Algo::Sac, obs_dim, act_dim, &nets, &cfg, 0)?;
    let mut buf = ReplayBuffer::new(obs_dim, act_dim, 20_000);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut o = vec![0.0f32; obs_dim];
    let mut a = vec![0.0f32; act_dim];
    for i in 0..20_000 {
        o.iter_mut().for_each(|x| *x = rng.random_range(-1.0..1.0));
        a.iter_mut().for_each(|x| *x = rng.random_range(-1.0..1.0));
        let next: Vec<f32> = o.iter().map(|x| x * 0.9).collect();
        buf.push(Transition {
            obs: &o,
            action: &a,
            reward: rng.random_range(-1.0..1.0),
            next_obs: &next,
            terminated: i % 500 == 499,
        });
        if i % 500 == 499 {
            buf.end_episode();
        }
    }
    let sample = |rng: &mut ChaCha8Rng| match arch {
        Arch::Lstm => buf.sample_sequences(rng, 256, 8, 0),
        Arch::Mlp => buf.sample_transitions(rng, 256),
    };
    for _ in 0..2 {
        let b = sample(&mut rng);
        agent.update(&b)?;
    }
    let mut times = Vec::new();
    for _ in 0..reps {
        let b = sample(&mut rng);
        let t = Instant::now();
        agent.update(&b)?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (na, nc) = (
        esrl_nn::Module::num_params(agent.actor()),
        esrl_nn::Module::num_params(&agent.critics()[0]),
    );
    Ok(json!({
        "arch": format!("{arch:?}").to_lowercase(),
        "ms_per_update": median(times.clone()),
        "min_ms": times.iter().copied().fold(f64::INFINITY, f64::min),
        "reps": reps,
        "actor_params": na,
        "critic_params": nc,
        "threads": 1,
    }))
}

/// Generations timed by `bench es` (without gradient updates, so the policies stay random).
const ES_BENCH_GENERATIONS: usize = 5;

/// Times one ES generation's evaluation (no gradient updates) at `threads` threads.
fn es_generation_s(preset: Preset, threads: usize) -> Result<(f64, u64)> {
    let mut cfg = TrainConfig::preset(crate::args::AgentKind::EsSac, EnvKind::Walk, preset);
    cfg.inner_cycles = 0;
    cfg.rl.warm_start = 0;
    let make_env = env_factory(&cfg)?;
    let Learner::Hybrid(mut h) = build_learner(&cfg, &make_env)? else {
        anyhow::bail!("an ES agent builds a hybrid learner");
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let t = Instant::now();
    h.step(make_env.as_ref(), &pool)?;
    Ok((t.elapsed().as_secs_f64(), h.trainer.env_steps))
}

/// Runs `esrl bench`.
pub fn run(what: &BenchWhat) -> Result<()> {
    match what {
        BenchWhat::Env { steps, json } => {
            let r = esrl_sim::bench::bench_walk(&esrl_sim::WalkConfig::default(), *steps, 0)?;
            let text = format!(
                "walking env, one core: {:.0} control steps/s ({} steps in {:.2} s, {} episodes, \
                 {:.0}× real time); physics dt {} s × {} substeps, {} solver iterations",
                r.steps_per_s,
                r.steps,
                r.wall_s,
                r.episodes,
                r.realtime_factor,
                r.dt,
                r.substeps,
                r.solver_iterations
            );
            emit(*json, &r, text)
        }
        BenchWhat::Nn { json } => {
            let r = esrl_nn::bench::run(&esrl_nn::bench::BenchConfig::default())?;
            let c = &r.config;
            let ms = |x: Option<f64>| x.map_or_else(|| "–".to_string(), |v| format!("{v:.1} ms"));
            let text = format!(
                "forward + backward on {} × {} steps, one thread:\n  \
                 LSTM actor ({} params) {:.2} ms, critic ({} params) {:.2} ms, SAC update {}\n  \
                 MLP actor ({} params) {:.2} ms, critic ({} params) {:.2} ms, SAC update {}",
                c.batch,
                c.seq_len,
                r.actor_params,
                r.actor_ms,
                r.critic_params,
                r.critic_ms,
                ms(r.sac_update_ms),
                r.mlp_actor_params,
                r.mlp_actor_ms,
                r.mlp_critic_params,
                r.mlp_critic_ms,
                ms(r.mlp_sac_update_ms)
            );
            emit(*json, &r, text)
        }
        BenchWhat::Update { arch, json } => {
            let r = update_ms(*arch, 7)?;
            let text = format!(
                "one SAC update ({}): {:.2} ms median over {} reps (actor {} params, critic {} params)",
                r["arch"], r["ms_per_update"].as_f64().unwrap_or(f64::NAN), r["reps"], r["actor_params"], r["critic_params"]
            );
            emit(*json, &r, text)
        }
        BenchWhat::Es {
            threads,
            preset,
            json,
        } => {
            let (t1, steps) = es_generation_s(*preset, 1)?;
            let (tn, _) = es_generation_s(*preset, *threads)?;
            let eff = t1 / (tn * *threads as f64);
            let cfg = TrainConfig::preset(crate::args::AgentKind::EsSac, EnvKind::Walk, *preset);
            let arch = if cfg.network.recurrent() {
                Arch::Lstm
            } else {
                Arch::Mlp
            };
            let upd = update_ms(arch, 3)?["ms_per_update"]
                .as_f64()
                .unwrap_or(f64::NAN);
            let train_s = upd * cfg.inner_cycles as f64 / 1e3;
            let r = json!({
                "preset": format!("{preset:?}").to_lowercase(),
                "population": cfg.es.population,
                "env_steps_per_generation": steps,
                "env_steps_per_s_1_thread": steps as f64 / t1,
                "eval_s_1_thread": t1,
                "eval_s_n_threads": tn,
                "threads": threads,
                "parallel_efficiency": eff,
                "inner_cycles": cfg.inner_cycles,
                "update_ms": upd,
                "train_s_per_generation": train_s,
            });
            let text = format!(
                "one generation ({} individuals, {steps} env steps, mean of {ES_BENCH_GENERATIONS}): {t1:.3} s on 1 thread, {tn:.3} s on {threads} (efficiency {:.0}%); \
                 {} inner updates ≈ {train_s:.2} s",
                cfg.es.population, eff * 100.0, cfg.inner_cycles
            );
            emit(*json, &r, text)
        }
    }
}
