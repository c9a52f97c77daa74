//! Contract: a run is a function of its seed. ES-SAC smoke runs on 1 and 2 threads write the
//! same `metrics.jsonl` (wall-clock fields aside), and every plain agent repeats itself
//! exactly for the same seed and differs for another.

mod common;

use common::{ok as esrl, rows, tensors};

#[test]
fn es_sac_is_identical_on_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("t1"), tmp.path().join("t2"));
    for (dir, threads) in [(&a, "1"), (&b, "2")] {
        esrl(&[
            "train",
            "es-sac",
            "--preset",
            "smoke",
            "--generations",
            "3",
            "--seed",
            "5",
            "--threads",
            threads,
            "--out",
            dir.to_str().unwrap(),
        ]);
    }
    let (ra, rb) = (rows(&a), rows(&b));
    assert_eq!(ra.len(), 3);
    assert_eq!(ra, rb);
    let wa = tensors(&a.join("checkpoint/agent.safetensors"));
    let wb = tensors(&b.join("checkpoint/agent.safetensors"));
    assert_eq!(wa, wb, "final actor weights differ between thread counts");
}

#[test]
fn plain_agents_repeat_for_a_seed_and_differ_across_seeds() {
    let tmp = tempfile::tempdir().unwrap();
    for agent in ["sac", "td3", "ddpg"] {
        let run = |name: &str, seed: &str| {
            let dir = tmp.path().join(format!("{agent}-{name}"));
            esrl(&[
                "train",
                agent,
                "--env",
                "pendulum",
                "--preset",
                "smoke",
                "--seed",
                seed,
                "--out",
                dir.to_str().unwrap(),
            ]);
            rows(&dir)
        };
        let (a, b, c) = (run("a", "3"), run("b", "3"), run("c", "4"));
        assert_eq!(a, b, "{agent}: same seed, different metrics");
        assert_ne!(a, c, "{agent}: different seeds, same metrics");
    }
}
