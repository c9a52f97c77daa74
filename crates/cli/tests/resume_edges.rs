//! Contract: `--resume` cannot silently change a run (its seed, env or URDF), keeps
//! `config.toml` true when the budget is raised (so `--config RUN/config.toml` still repeats
//! the run), and a run stopped before its first checkpoint is not a dead end: `--resume`
//! starts it over, and `--out` on it says how; a folder that holds a policy but no run is
//! refused.

mod common;

use common::{esrl, fails, ok, rows, smoke};

#[test]
fn resume_refuses_seed_env_and_urdf() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let r = run.to_str().unwrap();
    smoke("sac", &run, &["--episodes", "1"]);
    for flag in [["--seed", "5"], ["--env", "pendulum"], ["--urdf", "x.urdf"]] {
        let out = esrl(&["train", "sac", "--resume", r, flag[0], flag[1]]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(stderr.contains(flag[0]), "{stderr}");
    }
}

#[test]
fn raising_the_budget_on_resume_updates_config_toml() {
    let tmp = tempfile::tempdir().unwrap();
    let (run, again) = (tmp.path().join("run"), tmp.path().join("again"));
    let r = run.to_str().unwrap();
    smoke("es-td3", &run, &["--seed", "3", "--generations", "2"]);
    ok(&["train", "es-td3", "--resume", r, "--generations", "3"]);
    let text = std::fs::read_to_string(run.join("config.toml")).unwrap();
    assert!(text.contains("generations = 3"), "{text}");
    let cfg = run.join("config.toml");
    ok(&[
        "train",
        "es-td3",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
    ]);
    assert_eq!(rows(&run), rows(&again));
}

#[test]
fn a_run_without_checkpoint_restarts_on_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let (run, fresh) = (tmp.path().join("run"), tmp.path().join("fresh"));
    let r = run.to_str().unwrap();
    let args = |dir: &str| {
        vec![
            "train".to_string(),
            "es-sac".into(),
            "--preset".into(),
            "smoke".into(),
            "--generations".into(),
            "3".into(),
            "--out".into(),
            dir.into(),
        ]
    };
    let a = args(r);
    ok(&a.iter().map(String::as_str).collect::<Vec<_>>());
    // As if killed before its first checkpoint: rows written, no checkpoint.
    std::fs::remove_dir_all(run.join("checkpoint")).unwrap();
    std::fs::remove_dir_all(run.join("replay")).unwrap();
    let stderr = fails(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(stderr.contains(&format!("--resume {r}")), "{stderr}");
    let stderr = ok(&["train", "es-sac", "--resume", r]);
    assert!(stderr.contains("starting it over"), "{stderr}");
    let f = args(fresh.to_str().unwrap());
    ok(&f.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(rows(&run), rows(&fresh));
}

/// A folder that holds a policy but no run (a run's `best/` or `checkpoint/` given directly,
/// a study record's `policy/`) is refused by `--resume`, which would have started a new run
/// in it, and is left as it was.
#[test]
fn a_policy_folder_is_not_resumed() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "2"]);
    let record = tmp.path().join("policy");
    std::fs::create_dir(&record).unwrap();
    for f in ["actor.safetensors", "config.toml"] {
        std::fs::copy(run.join("best").join(f), record.join(f)).unwrap();
    }
    let listing = |dir: &std::path::Path| {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        names
    };
    for dir in [run.join("best"), run.join("checkpoint"), record] {
        let before = listing(&dir);
        let err = fails(&["train", "es-sac", "--resume", dir.to_str().unwrap()]);
        assert!(
            err.contains("holds a policy, not a run") && err.contains("--init"),
            "{err}"
        );
        assert_eq!(listing(&dir), before, "{} changed", dir.display());
    }
}
