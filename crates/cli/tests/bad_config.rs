//! Contract: impossible or malformed settings stop `esrl train` before anything is written,
//! with a message naming the field and a non-zero exit — never a panic.

mod common;

use common::esrl;

fn train_with(toml: &str, agent: &str) -> (bool, String, bool) {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("c.toml");
    std::fs::write(&cfg, toml).unwrap();
    let out_dir = tmp.path().join("run");
    let out = esrl(&[
        "train",
        agent,
        "--preset",
        "smoke",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "panic on {toml:?}: {stderr}");
    (
        out.status.success(),
        stderr,
        out_dir.join("metrics.jsonl").exists(),
    )
}

#[test]
fn bad_values_name_their_field() {
    let cases = [
        ("[es]\nsigma = -0.5\n", "es-sac", "sigma"),
        ("[es]\npopulation = 1\n", "es-sac", "population"),
        ("[rl]\nbatch_size = 0\n", "sac", "batch_size"),
        ("[rl]\ngamma = nan\n", "sac", "gamma"),
        ("[rl]\nactor_lr = -1.0\n", "td3", "actor_lr"),
        ("[es]\nsigmaa = 0.1\n", "es-sac", "sigmaa"),
        ("bogus_key = 3\n", "sac", "bogus_key"),
        ("[rl]\nbatch_size = \"many\"\n", "sac", "batch_size"),
        ("this is not toml", "sac", "TOML"),
        ("[check]\nmean = true\n", "sac", "check.mean"),
    ];
    for (toml, agent, field) in cases {
        let (ok, stderr, wrote) = train_with(toml, agent);
        assert!(!ok, "{toml:?} was accepted");
        assert!(
            stderr.contains(field),
            "{toml:?}: message does not name {field}: {stderr}"
        );
        assert!(!wrote, "{toml:?}: a run folder was written");
    }
}

#[test]
fn unknown_agent_is_refused_with_the_valid_names() {
    let out = esrl(&["train", "es-ppo"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("es-sac") && stderr.contains("ddpg"),
        "{stderr}"
    );
}
