//! Contract: a DDPG run checkpointed before DDPG honoured `rl.policy_delay` and
//! `rl.target_noise` (state.json version 1, whose config.toml lists TD3's 2 and 0.2 that DDPG
//! then ignored) resumes as it was trained — with delay 1 and no smoothing: its rows and
//! weights equal those of a run trained straight through — and its config.toml is corrected to
//! say so. A version-2 checkpoint with the same settings trains DDPG with TD3's tricks.

mod common;

use common::{ok, rows, smoke, tensors};
use std::path::Path;

/// Makes `run` look as an older esrl left it: state version 1, TD3's values in both copies
/// of the config, no manifest (older checkpoints had none).
fn age(run: &Path) {
    let ckpt = run.join("checkpoint");
    std::fs::remove_file(ckpt.join("manifest.json")).unwrap();
    let state = ckpt.join("state.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&state).unwrap()).unwrap();
    v["version"] = 1.into();
    std::fs::write(&state, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    for config in [run.join("config.toml"), ckpt.join("config.toml")] {
        let text = std::fs::read_to_string(&config).unwrap();
        let text = text
            .replace("policy_delay = 1", "policy_delay = 2")
            .replace("target_noise = 0.0", "target_noise = 0.2");
        std::fs::write(&config, text).unwrap();
    }
}

#[test]
fn an_old_ddpg_checkpoint_resumes_as_it_was_trained() {
    let tmp = tempfile::tempdir().unwrap();
    let (straight, old) = (tmp.path().join("straight"), tmp.path().join("old"));
    smoke("ddpg", &straight, &["--episodes", "6"]);
    smoke("ddpg", &old, &["--episodes", "3"]);
    age(&old);
    let stderr = ok(&[
        "train",
        "ddpg",
        "--resume",
        old.to_str().unwrap(),
        "--episodes",
        "6",
    ]);
    assert!(stderr.contains("trained with 1 and 0"), "{stderr}");
    assert_eq!(rows(&straight), rows(&old));
    let agent = |run: &Path| tensors(&run.join("checkpoint/agent.safetensors"));
    assert_eq!(agent(&straight), agent(&old));
    let config = std::fs::read_to_string(old.join("config.toml")).unwrap();
    assert!(config.contains("policy_delay = 1"), "{config}");

    // The same settings in a current checkpoint are honoured: DDPG then trains otherwise.
    let honoured = tmp.path().join("honoured");
    let overlay = tmp.path().join("td3-tricks.toml");
    std::fs::write(&overlay, "[rl]\npolicy_delay = 2\ntarget_noise = 0.2\n").unwrap();
    smoke(
        "ddpg",
        &honoured,
        &["--episodes", "6", "--config", overlay.to_str().unwrap()],
    );
    assert_ne!(agent(&straight), agent(&honoured));
}
