//! Contract: training resumes exactly. Four generations straight equal two generations, a
//! stop, `--resume` and two more — the same metrics rows and the same final weights; a run
//! folder is never overwritten by a new run.

mod common;

use common::{esrl, ok, rows, smoke, tensors};

fn check_resume(agent: &str, extra: &[&str], budget_flag: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let (straight, split) = (tmp.path().join("straight"), tmp.path().join("split"));
    let p = split.to_str().unwrap();
    for (dir, budget) in [(&straight, "4"), (&split, "2")] {
        let mut flags = vec!["--seed", "2", budget_flag, budget];
        flags.extend_from_slice(extra);
        smoke(agent, dir, &flags);
    }
    ok(&["train", agent, "--resume", p, budget_flag, "4"]);
    assert_eq!(rows(&straight).len(), 4);
    assert_eq!(
        rows(&straight),
        rows(&split),
        "{agent}: resumed metrics differ"
    );
    for file in ["actor.safetensors", "agent.safetensors"] {
        let x = tensors(&straight.join("checkpoint").join(file));
        let y = tensors(&split.join("checkpoint").join(file));
        assert_eq!(x, y, "{agent}: resumed {file} differs");
    }
}

#[test]
fn es_sac_resumes_exactly() {
    check_resume("es-sac", &[], "--generations");
}

#[test]
fn td3_resumes_exactly_on_pendulum() {
    check_resume("td3", &["--env", "pendulum"], "--episodes");
}

#[test]
fn an_existing_run_is_not_overwritten() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let d = dir.to_str().unwrap();
    ok(&[
        "train", "sac", "--env", "pendulum", "--preset", "smoke", "--out", d,
    ]);
    let before = std::fs::read(dir.join("metrics.jsonl")).unwrap();
    let out = esrl(&[
        "train", "sac", "--env", "pendulum", "--preset", "smoke", "--out", d,
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--resume"));
    assert_eq!(std::fs::read(dir.join("metrics.jsonl")).unwrap(), before);
}

/// The checks (`check.mean`: the ES mean's too) without their timings, in file order.
fn checks(dir: &std::path::Path) -> Vec<serde_json::Value> {
    common::jsonl_without(&dir.join("checks.jsonl"), &["wall_s", "seconds"])
}

/// With walking checks of the ES mean (`check.mean`), a run stopped and resumed checks and
/// keeps the same policies as one run straight, and so does one at another thread count: the
/// same check log and `best/`.
#[test]
fn es_sac_with_checks_of_the_es_mean_resumes_exactly() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("mean.toml");
    std::fs::write(
        &cfg,
        "[check]\nstarts = 2\nevery_steps = 200\nmean = true\n",
    )
    .unwrap();
    let (straight, split) = (tmp.path().join("straight"), tmp.path().join("split"));
    let c = cfg.to_str().unwrap();
    let two = tmp.path().join("two-threads");
    for (dir, budget, threads) in [(&straight, "6", "1"), (&split, "3", "1"), (&two, "6", "2")] {
        let flags = ["--seed", "2", "--generations", budget, "--config", c];
        smoke(
            "es-sac",
            dir,
            &[&flags[..], &["--threads", threads]].concat(),
        );
    }
    ok(&[
        "train",
        "es-sac",
        "--resume",
        split.to_str().unwrap(),
        "--generations",
        "6",
    ]);
    assert_eq!(rows(&straight), rows(&split));
    let log = checks(&straight);
    assert_eq!(log, checks(&split), "resumed checks differ");
    assert_eq!(log, checks(&two), "checks differ at 2 threads");
    assert!(
        log.iter().any(|c| c["mean"] == true) && log.iter().any(|c| c.get("mean").is_none()),
        "both kinds of check ran: {log:?}"
    );
    let best = |d: &std::path::Path| common::read_json(&d.join("best/best.json"));
    assert_eq!(best(&straight), best(&split));
    assert_eq!(
        tensors(&straight.join("best/actor.safetensors")),
        tensors(&split.join("best/actor.safetensors"))
    );
}
