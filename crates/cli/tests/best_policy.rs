//! Contract: a hybrid run keeps `RUN/best/`, the policy that scored the highest learning-curve
//! value, and `esrl eval RUN/best` evaluates that very policy. Checked independently with
//! ES-TD3, whose individuals act deterministically: replaying the best generation's episode
//! (same reset seed) with the saved policy must give back the fitness it was kept for.

mod common;

use common::{curve, read_json, stdout as esrl};
use esrl_streams::Stream;
use serde_json::Value;

#[test]
fn best_folder_holds_the_policy_that_scored_the_best_curve_value() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let run_s = run.to_str().unwrap();
    common::smoke(
        "es-td3",
        &run,
        &["--seed", "3", "--generations", "6", "--threads", "1"],
    );

    let curve = curve(&run);
    assert_eq!(curve.len(), 6);
    let (argmax, max) =
        curve
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |a, (i, c)| if c > a.1 { (i, c) } else { a },
            );

    let info = read_json(&run.join("best/best.json"));
    assert_eq!(info["generation"].as_u64().unwrap() as usize, argmax);
    assert_eq!(info["fitness"].as_f64().unwrap(), max);
    assert!(!run.join("best.tmp").exists() && !run.join("best.old").exists());

    // Generation g's individuals all started from the same reset (K = 1).
    let reset = Stream::EvaluationReset {
        generation: argmax as u64,
        evaluation: 0,
        evaluations: 1,
    }
    .seed(3)
    .to_string();
    let best = run.join("best");
    let report: Value = serde_json::from_str(&esrl(&[
        "eval",
        best.to_str().unwrap(),
        "--seed",
        &reset,
        "--json",
    ]))
    .unwrap();
    let ret = report["episodes"][0]["return"].as_f64().unwrap();
    assert!(
        best.join("eval.json").is_file(),
        "the best policy's report stays in best/"
    );
    assert!(!run.join("eval.json").exists());
    assert!(
        (ret - max).abs() <= 1e-9 * max.abs().max(1.0),
        "replayed return {ret} vs kept fitness {max}"
    );

    // The last checkpoint's actor is a different policy unless the best came last.
    let last: Value =
        serde_json::from_str(&esrl(&["eval", run_s, "--seed", &reset, "--json"])).unwrap();
    if argmax + 1 < curve.len() {
        assert_ne!(last["episodes"][0]["return"].as_f64().unwrap(), ret);
    }
}

#[test]
fn best_snapshots_hold_the_best_policy_as_it_stood_at_each_step_mark() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let every = 100u64;
    let config = tmp.path().join("snapshots.toml");
    std::fs::write(&config, format!("best_every_steps = {every}\n")).unwrap();
    common::smoke(
        "es-td3",
        &run,
        &[
            "--seed",
            "3",
            "--generations",
            "6",
            "--threads",
            "1",
            "--config",
            config.to_str().unwrap(),
        ],
    );
    // From the metric rows alone: after each row, the best generation so far; a mark k·every
    // reached by row i holds the best of rows 0..=i.
    let rows = common::rows(&run);
    let mut expected = Vec::new();
    let (mut best_gen, mut best, mut before) = (0, f64::NEG_INFINITY, 0u64);
    for (i, r) in rows.iter().enumerate() {
        let (c, steps) = (
            r["curve"].as_f64().unwrap(),
            r["env_steps"].as_u64().unwrap(),
        );
        if c > best {
            (best_gen, best) = (i, c);
        }
        for k in before / every + 1..=steps / every {
            expected.push((format!("best-{}", k * every), best_gen, best));
        }
        before = steps;
    }
    assert!(
        expected.len() >= 3,
        "{} marks in {before} steps",
        expected.len()
    );
    let mut found: Vec<String> = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.starts_with("best-"))
        .collect();
    found.sort();
    let mut names: Vec<String> = expected.iter().map(|e| e.0.clone()).collect();
    names.sort();
    assert_eq!(found, names, "no temporary or extra folders either");
    for (name, generation, fitness) in &expected {
        let info = read_json(&run.join(name).join("best.json"));
        assert_eq!(
            info["generation"].as_u64().unwrap() as usize,
            *generation,
            "{name}"
        );
        assert_eq!(info["fitness"].as_f64().unwrap(), *fitness, "{name}");
    }
    // A snapshot is a policy folder `esrl eval` takes like `best/`.
    let (name, ..) = &expected[0];
    let report: Value = serde_json::from_str(&esrl(&[
        "eval",
        run.join(name).to_str().unwrap(),
        "--episodes",
        "1",
        "--json",
    ]))
    .unwrap();
    assert_eq!(report["episodes"].as_array().unwrap().len(), 1);
}
