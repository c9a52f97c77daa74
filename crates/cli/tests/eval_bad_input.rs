//! Contract: `esrl eval` and `esrl record` answer bad input — a missing folder, a folder that
//! is no run, a corrupt config, a run without checkpoint, a checkpoint of another architecture,
//! zero episodes, a file where `--record` wants a folder — with a non-zero exit and a message
//! naming the file, never a panic, and leave the run's files as they were.

mod common;

use common::{esrl, smoke as train};
use std::path::Path;

/// Runs `args`, expects failure (status 1) with every `needle` in stderr and no panic.
fn fails(args: &[&str], needles: &[&str]) {
    let err = common::fails(args);
    assert_eq!(esrl(args).status.code(), Some(1), "esrl {args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "esrl {args:?}: `{n}` not in: {err}");
    }
}

#[test]
fn bad_inputs_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let t = |name: &str| tmp.path().join(name);
    let s = |p: &Path| p.to_str().unwrap().to_string();

    fails(&["eval", &s(&t("missing"))], &["missing", "no such"]);
    std::fs::create_dir(t("empty")).unwrap();
    fails(
        &["eval", &s(&t("empty"))],
        &["empty", "neither a run folder"],
    );
    fails(
        &["record", &s(&t("empty")), "--out", &s(&t("x.mcap"))],
        &["neither a run folder"],
    );

    // A real run whose config is then corrupted.
    let run = t("run");
    train("es-sac", &run, &[]);
    fails(&["eval", &s(&run), "--episodes", "0"], &["--episodes 0"]);
    std::fs::write(t("afile"), "keep").unwrap();
    fails(
        &["eval", &s(&run), "--record", &s(&t("afile"))],
        &["--record", "afile", "not a folder"],
    );
    assert_eq!(std::fs::read_to_string(t("afile")).unwrap(), "keep");
    let config = std::fs::read_to_string(run.join("config.toml")).unwrap();
    std::fs::write(run.join("config.toml"), "agent = \"es-sac\"\nnonsense = [").unwrap();
    fails(&["eval", &s(&run)], &["config.toml"]);
    std::fs::write(run.join("config.toml"), &config).unwrap();

    // A checkpoint of another architecture: the pendulum run's SAC checkpoint
    // (feed-forward networks, 3-dim observations) in place of the walking run's.
    let pend = t("pend");
    train("sac", &pend, &["--env", "pendulum"]);
    let ckpt = run.join("checkpoint");
    let before = std::fs::read(ckpt.join("agent.safetensors")).unwrap();
    std::fs::copy(
        pend.join("checkpoint/agent.safetensors"),
        ckpt.join("agent.safetensors"),
    )
    .unwrap();
    fails(&["eval", &s(&run), "--last"], &["agent.safetensors"]);
    fails(
        &["record", &s(&ckpt), "--out", &s(&t("y.mcap"))],
        &["agent.safetensors"],
    );
    assert!(!t("y.mcap").exists(), "no recording of a failed load");
    std::fs::write(ckpt.join("agent.safetensors"), &before).unwrap();

    // A run that never reached a checkpoint.
    std::fs::remove_dir_all(&ckpt).unwrap();
    fails(&["eval", &s(&run), "--last"], &["no complete checkpoint"]);
    assert_eq!(
        std::fs::read_to_string(run.join("config.toml")).unwrap(),
        config,
        "nothing written is lost"
    );
    assert!(!run.join("eval.json").exists());
}
