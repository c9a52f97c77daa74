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

#[test]
fn undisturbed_evaluates_a_randomized_policy_on_the_plain_task() {
    let tmp = tempfile::tempdir().unwrap();
    let overlay = tmp.path().join("noisy.toml");
    std::fs::write(
        &overlay,
        "[walk.perturb]\nobs_noise = 0.3\nfriction_range = [0.5, 1.0]\n",
    )
    .unwrap();
    let run = tmp.path().join("run");
    smoke(
        "es-sac",
        &run,
        &["--generations", "1", "--config", overlay.to_str().unwrap()],
    );
    // The same weights in two policy folders (a study record's layout): one with the run's
    // config, one with its [walk.perturb] table removed by hand.
    let (noisy, plain) = (tmp.path().join("noisy"), tmp.path().join("plain"));
    for dir in [&noisy, &plain] {
        std::fs::create_dir(dir).unwrap();
        for f in ["actor.safetensors", "config.toml"] {
            std::fs::copy(run.join("best").join(f), dir.join(f)).unwrap();
        }
    }
    let text = std::fs::read_to_string(plain.join("config.toml")).unwrap();
    let mut table: toml::Table = toml::from_str(&text).unwrap();
    let walk = table["walk"].as_table_mut().unwrap();
    assert!(
        walk.remove("perturb").is_some(),
        "the run trained disturbed"
    );
    std::fs::write(plain.join("config.toml"), toml::to_string(&table).unwrap()).unwrap();

    let eval = |dir: &std::path::Path, extra: &[&str], name: &str| {
        let out = tmp.path().join(name);
        let mut args = vec![
            "eval",
            dir.to_str().unwrap(),
            "--episodes",
            "2",
            "--traces",
            "0",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        ok(&args);
        read_json(&out)
    };
    let undisturbed = eval(&noisy, &["--undisturbed"], "u.json");
    let reference = eval(&plain, &[], "p.json");
    let disturbed = eval(&noisy, &[], "d.json");
    assert_eq!(undisturbed["undisturbed"], true);
    assert_eq!(undisturbed["episodes"], reference["episodes"]);
    assert_ne!(disturbed["episodes"], reference["episodes"]);
}
