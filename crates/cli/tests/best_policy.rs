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
