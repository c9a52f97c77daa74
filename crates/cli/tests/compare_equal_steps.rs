//! Contract: `esrl compare --equal-steps` gives every run the environment-step budget that one
//! ES run of the preset actually spent (the first hybrid agent, seed 0): the other runs'
//! configs carry `max_env_steps` = that run's `env_steps`, and each spends at least the budget
//! and stops at the first episode/generation boundary past it; a run folder trained with a
//! different configuration is refused rather than mixed into the table.

mod common;

use common::{esrl, read_json, rows};
use serde_json::Value;
use std::path::Path;

fn summary(run: &Path) -> Value {
    read_json(&run.join("summary.json"))
}

#[test]
fn equal_steps_uses_the_measured_es_budget() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let d = dir.to_str().unwrap();
    let out = esrl(&[
        "compare",
        "--agents",
        "sac,es-td3",
        "--seeds",
        "2",
        "--preset",
        "smoke",
        "--out",
        d,
        "--equal-steps",
        "--no-progress",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");

    let reference = dir.join("es-td3-s0");
    let budget = summary(&reference)["env_steps"].as_u64().unwrap();
    assert!(budget > 0);
    assert!(
        err.contains(&format!("{budget} environment steps")),
        "{err}"
    );
    let md = std::fs::read_to_string(dir.join("table.md")).unwrap();
    assert!(md.contains(&format!("{budget} steps per run")), "{md}");

    for run in ["sac-s0", "sac-s1", "es-td3-s1"] {
        let p = dir.join(run);
        let config = std::fs::read_to_string(p.join("config.toml")).unwrap();
        assert!(
            config.contains(&format!("max_env_steps = {budget}")),
            "{run}: {config}"
        );
        let s = summary(&p);
        assert_eq!(s["finished"], true);
        let spent = s["env_steps"].as_u64().unwrap();
        assert!(spent >= budget, "{run} spent {spent} < {budget}");
        // Every row but the last ended below the budget.
        let r = rows(&p);
        let before_last = r
            .len()
            .checked_sub(2)
            .map_or(0, |i| r[i]["env_steps"].as_u64().unwrap());
        assert!(before_last < budget, "{run} went on past the budget");
    }
    // The reference run is the preset's own ES run, unchanged.
    let config = std::fs::read_to_string(reference.join("config.toml")).unwrap();
    assert!(!config.contains("max_env_steps"), "{config}");

    // Asking for another budget in the same folder is refused.
    let out = esrl(&[
        "compare",
        "--agents",
        "sac",
        "--seeds",
        "1",
        "--preset",
        "smoke",
        "--out",
        d,
        "--episodes",
        "3",
        "--no-progress",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("different configuration"), "{err}");
    assert!(err.contains("episodes"), "{err}");
}
