//! Contract: `esrl eval --perturb KIND=VALUE` evaluates a policy under the disturbances it
//! names (the report says which) and refuses unknown ones by name; `--robustness` adds the
//! card: the undisturbed task and each disturbance of the standard set, in order;
//! `--undisturbed` (and a study's `[eval] undisturbed = true`) evaluates a policy trained under
//! disturbances on the plain task; `--orientation-frame gravity` observes a slope as an IMU on a
//! real slope would, and changes nothing on flat ground.

mod common;

use std::path::Path;

use common::{fails, ok, read_json, smoke};

/// `esrl eval POLICY --episodes 2 --traces 0 --out OUT EXTRA…`, and the report it wrote.
fn eval_json(policy: &Path, extra: &[&str], out: &Path) -> serde_json::Value {
    let mut args = vec![
        "eval",
        policy.to_str().unwrap(),
        "--episodes",
        "2",
        "--traces",
        "0",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    ok(&args);
    read_json(out)
}

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
        ("slope=100", "in degrees, within ±45°"),
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
    // Each row counts the episodes that finished or stayed up: at least either count, at most
    // their sum.
    for row in &rows {
        let n = |k: &str| row[k].as_u64().unwrap_or_else(|| panic!("{k} in {row}"));
        let either = n("finished_or_up");
        assert!(either >= n("survived").max(n("finished")), "{row}");
        assert!(
            either <= (n("survived") + n("finished")).min(n("episodes")),
            "{row}"
        );
    }
    assert!(stdout.contains("| finished or stayed up |"), "{stdout}");
    // Under the table, the robustness goal's rows met and missed, kept in the report.
    let goal = &read_json(&card)["robustness_goal"];
    let (met, rows) = (
        goal["met"].as_u64().unwrap(),
        goal["rows"].as_u64().unwrap(),
    );
    assert_eq!(rows, 12, "{goal}");
    assert!(
        stdout.contains(&format!("{met} of 12 rows met")),
        "{stdout}"
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

    let eval =
        |dir: &Path, extra: &[&str], name: &str| eval_json(dir, extra, &tmp.path().join(name));
    let undisturbed = eval(&noisy, &["--undisturbed"], "u.json");
    let reference = eval(&plain, &[], "p.json");
    let disturbed = eval(&noisy, &[], "d.json");
    assert_eq!(undisturbed["undisturbed"], true);
    assert_eq!(undisturbed["episodes"], reference["episodes"]);
    assert_ne!(disturbed["episodes"], reference["episodes"]);
}

#[test]
fn a_study_evaluates_on_the_plain_task_when_asked() {
    let tmp = tempfile::tempdir().unwrap();
    let study = tmp.path().join("plain.toml");
    std::fs::write(
        &study,
        r#"
seeds = [0]
[eval]
episodes = 2
traces = 0
undisturbed = true
[[arm]]
name = "noisy"
agent = "es-sac"
preset = "smoke"
generations = 1
set = { walk = { perturb = { obs_noise = 0.3, friction_range = [0.5, 1.0] } } }
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    ok(&[
        "study",
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-progress",
    ]);
    let record = out.join("records/noisy-s0");
    let recorded = read_json(&record.join("eval.json"));
    assert_eq!(recorded["undisturbed"], true);
    let policy = record.join("policy");
    let eval = |extra: &[&str], name: &str| {
        let mut args = vec!["--seed", "1000"];
        args.extend(extra);
        eval_json(&policy, &args, &tmp.path().join(name))
    };
    let episodes = |report: serde_json::Value| common::episodes_without_q0(&report);
    let plain = episodes(eval(&["--undisturbed"], "u.json"));
    assert!(
        episodes(recorded) == plain,
        "the record differs from `esrl eval --undisturbed`"
    );
    assert!(
        episodes(eval(&[], "d.json")) != plain,
        "the disturbances changed nothing"
    );
    ok(&["study", "report", out.to_str().unwrap()]);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("on the plain task, without the runs' training-time disturbances"),
        "{report}"
    );
}

#[test]
fn the_orientation_frame_matters_on_a_slope_only() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "1"]);
    let eval = |extra: &[&str], name: &str| eval_json(&run, extra, &tmp.path().join(name));
    let flat = eval(&[], "flat.json");
    let flat_gravity = eval(&["--orientation-frame", "gravity"], "flat-g.json");
    assert!(
        flat.get("orientation_frame").is_none(),
        "ground is the default"
    );
    assert_eq!(flat_gravity["orientation_frame"], "gravity");
    assert_eq!(flat["episodes"], flat_gravity["episodes"]);
    let slope = eval(&["--perturb", "slope=-5"], "slope.json");
    let slope_gravity = eval(
        &["--perturb", "slope=-5", "--orientation-frame", "gravity"],
        "slope-g.json",
    );
    assert_ne!(slope["episodes"], slope_gravity["episodes"]);
    let err = fails(&["eval", run.to_str().unwrap(), "--orientation-frame", "up"]);
    assert!(err.contains("ground") && err.contains("gravity"), "{err}");
}
