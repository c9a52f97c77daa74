//! Contract: a run whose check asks for a margin of speed (`check.max_track_time`), or of
//! symmetry (`check.max_knee_asymmetry`), keeps the first policy at the walking bar without
//! the margins in `RUN/first-walk/`, and its summary
//! says when it came (`steps_to_any_walk`, `time_to_any_walk_s`), while its own bar, kept
//! policy and stop stay those of the margin. A run without a margin writes neither. The run
//! starts from the committed flagship walk (about 46 s over the 50 m) with the ES at a tiny
//! σ, so its first generation's best individual walks.

use esrl_run::check::{CheckConfig, CheckRecord};
use esrl_run::checkpoint::{self, FIRST_WALK};
use esrl_run::{build, Session, TrainConfig};
use std::path::{Path, PathBuf};

fn flagship() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../results/walking/flagship")
}

/// One generation of two individuals from the flagship, checked from 2 starts.
fn config(max_track_time: Option<f64>) -> TrainConfig {
    let dir = flagship();
    let mut cfg = TrainConfig::load(&dir.join("config.toml")).unwrap();
    cfg.init = Some(dir);
    cfg.generations = 1;
    cfg.max_env_steps = None;
    cfg.updates_per_step = Some(0.01);
    cfg.es.population = 2;
    cfg.es.sigma = 0.001;
    cfg.es.sigma_min = 0.001;
    cfg.threads = 2;
    cfg.check = Some(CheckConfig {
        starts: 2,
        finish_share: 1.0,
        max_track_time,
        stop_early: true,
        ..CheckConfig::default()
    });
    cfg.validate().unwrap();
    cfg
}

fn train(cfg: &TrainConfig, root: &Path) -> (Option<CheckRecord>, Option<CheckRecord>) {
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let (mut session, _) =
        Session::open(cfg, root, &envs, build::local_evaluator(&envs), false).unwrap();
    while !session.done() {
        session.step().unwrap();
    }
    session.finish(true).unwrap();
    (
        session.first_walk().cloned(),
        session.first_any_walk().cloned(),
    )
}

fn summary(root: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(root.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn the_first_walk_below_the_speed_margin_is_kept_and_timed() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("run");
    let (first, any) = train(&config(Some(40.0)), &root);
    assert!(
        first.is_none(),
        "a 46 s walk is not at a 40 s bar: {first:?}"
    );
    let any = any.expect("the flagship walks to the line within the episode");
    assert_eq!(any.result.walking, Some(true));
    assert!(!any.result.at_bar);
    // The policy is a policy folder `esrl eval` takes, and it is the one checked.
    let folder = root.join(FIRST_WALK);
    let info: checkpoint::BestInfo =
        serde_json::from_str(&std::fs::read_to_string(folder.join("best.json")).unwrap()).unwrap();
    assert_eq!(info.generation, any.row);
    assert_eq!(info.env_steps, any.env_steps);
    let check = info.check.expect("the check is recorded");
    assert_eq!(
        (check.walking, check.at_bar, check.finished, check.starts),
        (Some(true), false, 2, 2)
    );
    assert!(checkpoint::read_tensors(&folder).is_ok());
    let s = summary(&root);
    assert_eq!(s["steps_to_any_walk"].as_f64(), Some(any.env_steps as f64));
    // Training seconds, through JSON's decimal text: equal to the last digit or so.
    let time = s["time_to_any_walk_s"].as_f64().unwrap();
    assert!((time - any.wall_s).abs() < 1e-9, "{time} vs {}", any.wall_s);
    assert!(s.get("steps_to_walk").is_none(), "{s}");

    // A margin of symmetry the flagship misses (its knees differ by about 10 %) is a
    // margin too: its first walk without the margins is kept, its bar's is not met.
    let even = tmp.path().join("even");
    let mut cfg = config(None);
    if let Some(check) = &mut cfg.check {
        check.max_knee_asymmetry = Some(0.001);
    }
    let (first, any) = train(&cfg, &even);
    assert!(
        first.is_none(),
        "an uneven walk is not at the bar: {first:?}"
    );
    let any = any.expect("the flagship walks to the line");
    assert_eq!((any.result.walking, any.result.at_bar), (Some(true), false));
    assert!(any.result.knee_asymmetry.is_some_and(|a| a > 0.001));
    assert!(even.join(FIRST_WALK).join("best.json").exists());

    // Without a margin the run's first walk is its bar's: no second folder or figure.
    let plain = tmp.path().join("plain");
    let (first, any) = train(&config(None), &plain);
    assert!(first.is_some() && any.is_none());
    assert!(!plain.join(FIRST_WALK).exists());
    let s = summary(&plain);
    assert!(s.get("steps_to_any_walk").is_none());
    assert!(s["steps_to_walk"].as_f64().is_some());
}
