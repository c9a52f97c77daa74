//! A run whose genomes go out as bytes to workers built from its `config.toml` text (what
//! `python -m esrl_rs.ray` does over Ray) equals the run on the local evaluator: rows,
//! weights, best policy and replay buffer, for ES-SAC (sampled fitness) and ES-TD3
//! (deterministic), with pipelining.

use esrl_es::{Evaluator, Transport, WireEvaluator, Worker};
use esrl_run::{build, AgentKind, AnyLearner, EnvKind, Overrides, Preset, TrainConfig, Training};
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// Workers in threads of this process, each genome on whichever thread takes it.
#[derive(Debug)]
struct Threads(Worker);

impl Transport for Threads {
    fn roll_out(&self, genomes: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, String> {
        genomes
            .par_iter()
            .map(|g| self.0.rollout(g).map_err(|e| e.to_string()))
            .collect()
    }
}

fn train(cfg: &TrainConfig, root: &Path, evaluator: Option<Arc<dyn Evaluator>>) {
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let learner = match evaluator {
        Some(e) => build::learner_with(cfg, &envs, e).unwrap(),
        None => build::learner(cfg, &envs).unwrap(),
    };
    let AnyLearner::Hybrid(hybrid) = learner else {
        panic!("a hybrid agent");
    };
    let (mut t, _) = Training::open(cfg, root, *hybrid, envs.make.clone(), false).unwrap();
    while !t.done() {
        t.step().unwrap();
    }
    t.finish(true).unwrap();
}

fn rows(root: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(root.join("metrics.csv")).unwrap();
    // Every column but the last (wall_s).
    text.lines()
        .map(|l| l.rsplit_once(',').unwrap().0.to_string())
        .collect()
}

fn same_files(a: &Path, b: &Path, names: &[&str]) {
    for name in names {
        let (x, y) = (std::fs::read(a.join(name)), std::fs::read(b.join(name)));
        assert_eq!(x.unwrap(), y.unwrap(), "{name} differs");
    }
}

fn check(agent: AgentKind, env: EnvKind) {
    let overrides = Overrides {
        preset: Preset::Smoke,
        env: Some(env),
        generations: Some(5),
        threads: Some(2),
        ..Overrides::default()
    };
    let cfg = TrainConfig::resolve(agent, &overrides, Some(7)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (local, remote) = (dir.path().join("local"), dir.path().join("remote"));
    train(&cfg, &local, None);

    // The worker knows the run only by its config.toml text, as a remote process would.
    let worker = build::worker(&TrainConfig::from_toml(&cfg.to_toml().unwrap()).unwrap()).unwrap();
    let wire = Arc::new(WireEvaluator::new(Threads(worker)));
    train(&cfg, &remote, Some(wire.clone()));

    assert_eq!(rows(&local), rows(&remote));
    assert_eq!(rows(&local).len(), 6, "a header and 5 generations");
    same_files(
        &local,
        &remote,
        &[
            "checkpoint/agent.safetensors",
            "checkpoint/actor.safetensors",
            "best/actor.safetensors",
        ],
    );
    let traffic = wire.traffic();
    let population = cfg.es.population as u64;
    // Pipelined: generation 0 whole in one call, then per generation the next one's
    // perturbations (during the training) and its own individual 0; the last generation also
    // rolls the next one's perturbations out ahead.
    assert_eq!(traffic.genomes, 5 * population + population - 1);
    assert_eq!(traffic.calls, 1 + 5 + 4);
    assert!(traffic.bytes_out > 0 && traffic.bytes_in > 0);
}

#[test]
fn es_sac_on_the_pendulum_equals_the_local_run() {
    check(AgentKind::EsSac, EnvKind::Pendulum);
}

#[test]
fn es_td3_walking_equals_the_local_run() {
    check(AgentKind::EsTd3, EnvKind::Walk);
}

#[test]
fn bad_genome_bytes_are_an_error() {
    let cfg = TrainConfig::resolve(
        AgentKind::EsTd3,
        &Overrides {
            preset: Preset::Smoke,
            env: Some(EnvKind::Pendulum),
            ..Overrides::default()
        },
        Some(0),
    )
    .unwrap();
    let worker = build::worker(&cfg).unwrap();
    let err = worker.rollout(b"ESG1\x00").unwrap_err().to_string();
    assert!(err.contains("genome bytes"), "{err}");
}
