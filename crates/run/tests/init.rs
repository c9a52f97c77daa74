//! `init`: a run that starts from a trained policy's weights. Its agent holds the policy's
//! tensors (actor, critics, targets, optimiser state, α) and the ES distribution is centred
//! on its actor; a policy folder with the actor alone loads the actor alone; a policy for
//! another network or action mapping is refused; `RUN/init.json` names what was loaded; a
//! resumed run takes its weights from its own checkpoint, not from `init`.

use esrl_agents::Learner;
use esrl_run::checkpoint::{self, read_tensors};
use esrl_run::init::{InitRecord, INIT_FILE};
use esrl_run::TrainRequest;
use esrl_run::{build, plan, AgentKind, AnyLearner, Overrides, Preset, Session, TrainConfig};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn smoke(seed: u64, init: Option<PathBuf>) -> TrainConfig {
    let overrides = Overrides {
        preset: Preset::Smoke,
        threads: Some(1),
        init,
        ..Overrides::default()
    };
    TrainConfig::resolve(AgentKind::EsSac, &overrides, Some(seed)).unwrap()
}

/// Trains `cfg` to the end of its budget in `root`.
fn train(cfg: &TrainConfig, root: &Path, resume: bool) {
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let (mut session, _) =
        Session::open(cfg, root, &envs, build::local_evaluator(&envs), resume).unwrap();
    while !session.done() {
        session.step().unwrap();
    }
    session.finish(true).unwrap();
}

fn hybrid(cfg: &TrainConfig) -> esrl_es::Hybrid {
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    match build::learner(cfg, &envs).unwrap() {
        AnyLearner::Hybrid(h) => *h,
        AnyLearner::Plain(_) => panic!("ES-SAC is a hybrid agent"),
    }
}

fn tensors(h: &esrl_es::Hybrid) -> HashMap<String, Vec<f32>> {
    h.agent().state_tensors().into_iter().collect()
}

#[test]
fn a_run_starts_from_the_policy_it_names() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("source");
    train(&smoke(1, None), &source, false);
    let kept = source.join(checkpoint::BEST);
    let want = read_tensors(&kept).unwrap();

    // The run folder names its kept policy; so does the best/ folder itself.
    for from in [source.clone(), kept.clone()] {
        let h = hybrid(&smoke(2, Some(from)));
        let got = tensors(&h);
        assert_eq!(got.len(), want.len());
        for (name, data) in &want {
            assert_eq!(&got[name], data, "{name}");
        }
        assert_eq!(h.strategy().mean, h.agent().genome());
    }
    // Without `init` the seed-2 agent is another one: the comparison above can fail.
    let fresh = tensors(&hybrid(&smoke(2, None)));
    assert_ne!(fresh["actor"], want["actor"]);

    // A trained fine-tuning run records what it loaded, and resumes from its own checkpoint
    // when the policy it started from is gone.
    let tuned = dir.path().join("tuned");
    let cfg = smoke(2, Some(source.clone()));
    train(&cfg, &tuned, false);
    let record: InitRecord =
        serde_json::from_str(&std::fs::read_to_string(tuned.join(INIT_FILE)).unwrap()).unwrap();
    assert_eq!(record.folder, kept);
    assert!(record.critics);
    assert_eq!(record.file, "agent.safetensors");
    assert_eq!(record.sha256.len(), 64, "a hex SHA-256: {}", record.sha256);
    assert!(TrainConfig::load(&tuned.join("config.toml"))
        .unwrap()
        .init
        .is_some_and(|p| p == source));
    // The run keeps a copy of the weights it loaded, with the source's configuration.
    let copy = tuned.join("init");
    let bytes = std::fs::read(copy.join("agent.safetensors")).unwrap();
    assert_eq!(
        bytes,
        std::fs::read(kept.join("agent.safetensors")).unwrap()
    );
    std::fs::remove_dir_all(&source).unwrap();
    // What a restart loads once the source is gone: the copy, the same tensors.
    let from_copy = tensors(&hybrid(&TrainConfig {
        init: Some(copy),
        ..cfg.clone()
    }));
    for (name, data) in &want {
        assert_eq!(&from_copy[name], data, "{name}");
    }
    let more = TrainConfig {
        generations: cfg.generations + 1,
        ..cfg.clone()
    };
    train(&more, &tuned, true);
    let rows = std::fs::read_to_string(tuned.join("metrics.csv")).unwrap();
    assert_eq!(rows.lines().count(), 1 + more.generations);
    // A fresh run that names the vanished policy is refused, naming it.
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let err = build::learner(&cfg, &envs).err().unwrap().to_string();
    assert!(err.contains("no such folder"), "{err}");
}

#[test]
fn an_actor_alone_loads_the_actor_alone() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("source");
    train(&smoke(1, None), &source, false);
    // A study record's policy/: actor.safetensors, config.toml, best.json, no manifest.
    let policy = dir.path().join("policy");
    std::fs::create_dir(&policy).unwrap();
    for f in ["actor.safetensors", "config.toml", "best.json"] {
        std::fs::copy(source.join("best").join(f), policy.join(f)).unwrap();
    }
    let want = read_tensors(&source.join("best")).unwrap();
    let h = hybrid(&smoke(2, Some(policy)));
    let got = tensors(&h);
    let fresh = tensors(&hybrid(&smoke(2, None)));
    assert_eq!(got["actor"], want["actor"]);
    assert_eq!(got["critic1"], fresh["critic1"]);
    assert_ne!(got["critic1"], want["critic1"]);
}

#[test]
fn a_policy_for_another_network_or_action_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("source");
    train(&smoke(1, None), &source, false);
    let envs_of = |c: &TrainConfig| build::envs(c.env, &c.walk).unwrap();
    let refusal = |c: &TrainConfig| build::learner(c, &envs_of(c)).err().unwrap().to_string();

    let mut wider = smoke(2, Some(source.clone()));
    wider.network.actor.fc = vec![24];
    let err = refusal(&wider);
    assert!(err.contains("network.actor.fc"), "{err}");

    let mut targets = smoke(2, Some(source.clone()));
    targets.walk.action = esrl_sim::ActionMode::Target;
    let err = refusal(&targets);
    assert!(err.contains("walk.action"), "{err}");

    let mut spans = smoke(2, Some(source.clone()));
    spans
        .walk
        .target
        .joint_range
        .insert("left_knee".into(), 0.6);
    let err = refusal(&spans);
    assert!(err.contains("walk.target.joint_range"), "{err}");

    let td3 = TrainConfig::resolve(
        AgentKind::EsTd3,
        &Overrides {
            preset: Preset::Smoke,
            init: Some(source.clone()),
            ..Overrides::default()
        },
        Some(2),
    )
    .unwrap();
    let err = refusal(&td3);
    assert!(err.contains("agent: es-sac vs es-td3"), "{err}");

    // Another reward or budget is what fine-tuning is for.
    let mut reward = smoke(2, Some(source.clone()));
    reward.walk.reward.alive = 0.5;
    reward.generations = 3;
    assert!(build::learner(&reward, &envs_of(&reward)).is_ok());
}

#[test]
fn a_resume_cannot_change_where_a_run_started() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    train(&smoke(1, None), &run, false);
    let err = plan(&TrainRequest {
        agent: AgentKind::EsSac,
        seed: None,
        out: None,
        resume: Some(run.clone()),
        overrides: Overrides {
            init: Some(run.clone()),
            ..Overrides::default()
        },
    })
    .err()
    .unwrap()
    .to_string();
    assert!(err.contains("--init"), "{err}");
}
