//! Contract: `esrl eval --perturb KIND=VALUE` evaluates a policy under the disturbances it
//! names (the report says which) and refuses unknown ones by name; `--robustness` adds the
//! card: the undisturbed task and each disturbance of the standard set, in order.

mod common;

use common::{fails, ok, read_json, smoke};

#[test]
fn perturbed_evaluations_and_the_card() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "1"]);
    let r = run.to_str().unwrap();
    let out = tmp.path().join("p.json");
    let o = out.to_str().unwrap();
    ok(&[
        "eval",
        r,
        "--perturb",
        "friction=0.4",
        "--perturb",
        "delay=1",
        "--perturb",
        "contact=30",
        "--out",
        o,
    ]);
    let report = read_json(&out);
    assert_eq!(
        report["perturb"],
        serde_json::json!([
            {"kind": "friction", "value": 0.4},
            {"kind": "delay", "value": 1},
            {"kind": "contact", "value": 30.0}
        ])
    );
    let plain = tmp.path().join("plain.json");
    ok(&["eval", r, "--out", plain.to_str().unwrap()]);
    assert!(read_json(&plain).get("perturb").is_none());
    for (bad, want) in [
        ("wind=3", "unknown disturbance `wind`"),
        ("delay=0.5", "whole control steps"),
        ("friction", "KIND=VALUE"),
        ("friction=-1", "friction"),
        ("contact=0.5", "contact_frequency"),
    ] {
        let err = fails(&["eval", r, "--perturb", bad]);
        assert!(err.contains(want), "{bad}: {err}");
    }
    let card = tmp.path().join("card.json");
    let stdout = common::stdout(&["eval", r, "--robustness", "--out", card.to_str().unwrap()]);
    assert!(stdout.contains("| push_sagittal 0.5 m/s |"), "{stdout}");
    let rows = read_json(&card)["robustness"].as_array().unwrap().clone();
    assert_eq!(
        rows.len(),
        1 + 25,
        "the undisturbed task and 25 disturbances"
    );
    assert!(rows[0]["disturbance"].is_null());
    assert_eq!(rows[1]["disturbance"]["kind"], "push_sagittal");
    assert_eq!(
        rows[25]["disturbance"],
        serde_json::json!({"kind": "delay", "value": 2})
    );
}
