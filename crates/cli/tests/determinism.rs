//! Contract: a run is a function of its seed. ES-SAC smoke runs on 1 and 2 threads write the
//! same `metrics.jsonl` (wall-clock fields aside), and every plain agent repeats itself
//! exactly for the same seed and differs for another.

use std::collections::BTreeMap;
use std::path::Path;

/// Every tensor of a safetensors file, by name (file bytes may differ in header order).
fn tensors(path: &Path) -> BTreeMap<String, Vec<u32>> {
    esrl_nn::load_tensors(path)
        .unwrap()
        .into_iter()
        .map(|(k, t)| (k, t.data.iter().map(|x| x.to_bits()).collect()))
        .collect()
}
use std::process::Command;

fn esrl(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_esrl"))
        .args(args)
        .output()
        .expect("run esrl");
    assert!(
        out.status.success(),
        "esrl {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The metric rows without their wall-clock field.
fn rows(dir: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    text.lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("wall_s");
            v
        })
        .collect()
}

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
