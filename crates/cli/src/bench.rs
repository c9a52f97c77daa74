//! `esrl bench`: speed of the environment, the networks, one SAC update and one ES generation.

use crate::args::{AgentKind, Arch, BenchWhat, EnvKind, Preset};
use anyhow::Result;
use esrl_agents::bench::{self, UpdateTiming};
use esrl_agents::{Algo, Learner, NetConfig};
use esrl_run::{build, AnyLearner, TrainConfig};
use serde::Serialize;
use serde_json::json;
use std::path::Path;
use std::time::Instant;

fn emit<T: Serialize>(json_out: bool, value: &T, text: String) -> Result<()> {
    if json_out {
        println!("{}", serde_json::to_string(value)?);
    } else {
        println!("{text}");
    }
    Ok(())
}

/// Times the one update of training, `Agent::update` (critics, actor, α, targets), for SAC
/// with the paper-size LSTM or the MLP 256×256 networks, on random data of the PyTorch
/// baseline's shapes (`esrl_agents::bench`; `batch` sequences or transitions), on a pool of
/// `threads` threads, the batch split into `batch_chunks` chunks (`rl.batch_chunks`).
pub fn update_ms(
    arch: Arch,
    obs_dim: usize,
    batch: usize,
    reps: usize,
    threads: usize,
    batch_chunks: usize,
) -> Result<UpdateTiming> {
    let nets = match arch {
        Arch::Lstm => NetConfig::default(),
        Arch::Mlp => NetConfig::feed_forward(),
    };
    let pool = esrl_nn::subnormal::thread_pool(threads.max(1))?;
    Ok(pool.install(|| {
        bench::time_update(Algo::Sac, &nets, obs_dim, 6, batch, reps, 2, batch_chunks)
    })?)
}

/// Generations timed by `bench es` (without gradient updates, so the policies stay random).
const ES_BENCH_GENERATIONS: usize = 5;

/// The configuration `bench es` times: ES-SAC on the walking task with `preset`; with
/// `init`, started from that policy with the ES at its `sigma_min` (a walking phase).
fn es_config(preset: Preset, init: Option<&Path>) -> TrainConfig {
    let mut cfg = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, preset);
    if let Some(dir) = init {
        cfg.init = Some(std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf()));
        cfg.es.sigma = cfg.es.sigma_min;
    }
    cfg
}

/// Times ES generations' evaluation (no gradient updates) of `cfg` at `threads` threads:
/// seconds per generation and environment steps per generation, over
/// [`ES_BENCH_GENERATIONS`].
fn es_generation_s(cfg: &TrainConfig, threads: usize) -> Result<(f64, u64)> {
    let mut cfg = cfg.clone();
    cfg.inner_cycles = 0;
    cfg.updates_per_step = None;
    cfg.rl.warm_start = 0;
    let envs = build::envs(cfg.env, &cfg.walk)?;
    let AnyLearner::Hybrid(mut h) = build::learner(&cfg, &envs)? else {
        anyhow::bail!("an ES agent builds a hybrid learner");
    };
    let pool = build::pool(threads)?;
    let t = Instant::now();
    for _ in 0..ES_BENCH_GENERATIONS {
        pool.install(|| h.step())?;
    }
    let n = ES_BENCH_GENERATIONS as f64;
    Ok((
        t.elapsed().as_secs_f64() / n,
        h.env_steps() / ES_BENCH_GENERATIONS as u64,
    ))
}

/// Whole generations are timed for at least this many seconds on one thread (and as many
/// generations on N threads).
const WHOLE_MIN_S: f64 = 4.0;

/// Seconds per whole ES-SAC generation of `cfg` at `threads` threads, as `esrl train` runs
/// it (rollouts, ES update and inner cycles, pipelined, on one pool): the warm start, one
/// generation untimed, then the mean of `generations` (when `None`, as many as fill
/// [`WHOLE_MIN_S`], at least 2). Returns the seconds, the generations timed and their env
/// steps per generation. The same seed gives the same generations at any thread count.
fn whole_generation_s(
    cfg: &TrainConfig,
    threads: usize,
    generations: Option<usize>,
) -> Result<(f64, usize, f64)> {
    let envs = build::envs(cfg.env, &cfg.walk)?;
    let AnyLearner::Hybrid(mut h) = build::learner(cfg, &envs)? else {
        anyhow::bail!("an ES agent builds a hybrid learner");
    };
    let pool = build::pool(threads)?;
    pool.install(|| {
        h.prepare(envs.make.as_ref())?;
        let t = Instant::now();
        h.step()?;
        let first = t.elapsed().as_secs_f64();
        let n = generations.unwrap_or_else(|| ((WHOLE_MIN_S / first).ceil() as usize).max(2));
        let steps = h.env_steps();
        let t = Instant::now();
        for _ in 0..n {
            h.step()?;
        }
        let per = (h.env_steps() - steps) as f64 / n as f64;
        Ok((t.elapsed().as_secs_f64() / n as f64, n, per))
    })
}

/// Runs `esrl bench`.
pub fn run(what: &BenchWhat) -> Result<()> {
    match what {
        BenchWhat::Env {
            steps,
            preset,
            json,
        } => {
            let walk = match preset {
                Some(p) => TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, *p).walk,
                None => esrl_sim::WalkConfig::default(),
            };
            let r = esrl_sim::bench::bench_walk(&walk, *steps as usize, 0)?;
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
            // The full update is training's own (`Agent::update`), on the same shapes.
            let lstm = update_ms(Arch::Lstm, c.obs_dim, 256, c.reps, 1, 1)?;
            let mlp = update_ms(Arch::Mlp, c.obs_dim, 256, c.reps * 5, 1, 1)?;
            let ms = |t: &UpdateTiming| format!("{:.1} ms", t.ms_per_update);
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
                ms(&lstm),
                r.mlp_actor_params,
                r.mlp_actor_ms,
                r.mlp_critic_params,
                r.mlp_critic_ms,
                ms(&mlp)
            );
            let mut value = serde_json::to_value(&r)?;
            if let Some(m) = value.as_object_mut() {
                m.insert("sac_update_ms".into(), json!(lstm.ms_per_update));
                m.insert("mlp_sac_update_ms".into(), json!(mlp.ms_per_update));
            }
            emit(*json, &value, text)
        }
        BenchWhat::Update {
            arch,
            batch,
            threads,
            batch_chunks,
            reps,
            json,
        } => {
            let t = update_ms(
                *arch,
                31,
                *batch as usize,
                *reps as usize,
                *threads,
                *batch_chunks as usize,
            )?;
            let arch = format!("{arch:?}").to_lowercase();
            let text = format!(
                "one SAC update ({arch}, batch {batch}, {threads} thread(s), {batch_chunks} batch \
                 chunk(s)): {:.2} ms median, {:.2} ms fastest, over {} reps (actor {} params, \
                 critic {} params)",
                t.ms_per_update, t.min_ms, t.reps, t.actor_params, t.critic_params
            );
            let r = json!({
                "arch": arch,
                "batch": batch,
                "ms_per_update": t.ms_per_update,
                "min_ms": t.min_ms,
                "reps": t.reps,
                "actor_params": t.actor_params,
                "critic_params": t.critic_params,
                "threads": threads,
                "batch_chunks": batch_chunks,
            });
            emit(*json, &r, text)
        }
        BenchWhat::Es {
            threads,
            preset,
            init,
            json,
        } => {
            let threads = *threads as usize;
            let cfg = es_config(*preset, init.as_deref());
            let (t1, steps) = es_generation_s(&cfg, 1)?;
            let (tn, _) = es_generation_s(&cfg, threads)?;
            let eff = t1 / (tn * threads as f64);
            let arch = if cfg.network.recurrent() {
                Arch::Lstm
            } else {
                Arch::Mlp
            };
            let chunks = cfg.rl.batch_chunks;
            let batch = cfg.rl.batch_size;
            let upd = update_ms(arch, 31, batch, 3, 1, chunks)?.ms_per_update;
            let upd_n = update_ms(arch, 31, batch, 3, threads, chunks)?.ms_per_update;
            // The inner updates of a generation that collected `steps` env steps.
            let cycles = build::hybrid_config(&cfg).inner_cycles_for(steps as usize);
            let train_s = upd * cycles as f64 / 1e3;
            let (g1, whole, whole_steps) = whole_generation_s(&cfg, 1, None)?;
            let (gn, _, _) = whole_generation_s(&cfg, threads, Some(whole))?;
            let r = json!({
                "preset": format!("{preset:?}").to_lowercase(),
                "init": cfg.init,
                "sigma": cfg.es.sigma,
                "population": cfg.es.population,
                "env_steps_per_generation": steps,
                "env_steps_per_s_1_thread": steps as f64 / t1,
                "eval_s_1_thread": t1,
                "eval_s_n_threads": tn,
                "threads": threads,
                "parallel_efficiency": eff,
                "inner_cycles": cycles,
                "update_ms": upd,
                "update_ms_n_threads": upd_n,
                "train_s_per_generation": train_s,
                "generation_s_1_thread": g1,
                "generation_s_n_threads": gn,
                "generation_speedup": g1 / gn,
                "generations_timed": whole,
                "whole_env_steps_per_generation": whole_steps,
            });
            let text = format!(
                "rollouts of one generation ({} individuals, {steps} env steps, mean of \
                 {ES_BENCH_GENERATIONS}, no training): {t1:.3} s on 1 thread, {tn:.3} s on \
                 {threads} (efficiency {:.0}%)\n\
                 one SAC update: {upd:.2} ms on 1 thread, {upd_n:.2} ms on {threads}; {} inner \
                 updates ≈ {train_s:.2} s on 1 thread\n\
                 whole generation as `esrl train` runs it (rollouts + training, mean of \
                 {whole} after one, {whole_steps:.0} env steps each): {g1:.2} s on 1 thread, \
                 {gn:.2} s on {threads} ({:.2}×){}",
                cfg.es.population,
                eff * 100.0,
                cycles,
                g1 / gn,
                match &cfg.init {
                    Some(dir) => format!(
                        "\nfrom the policy in {} with the ES at σ = {}",
                        dir.display(),
                        cfg.es.sigma
                    ),
                    None => String::new(),
                }
            );
            emit(*json, &r, text)
        }
    }
}
