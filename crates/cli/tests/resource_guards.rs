//! Contract: settings that cannot fit or cannot end are refused before anything is
//! allocated or written, within seconds, with a non-zero exit and a message naming the
//! setting: a huge population or network, batch larger than the buffer, absurd budgets (none,
//! or one the hybrid loop's warm start fills), a runaway URDF.

mod common;

use common::fails;
use std::time::{Duration, Instant};

fn refused(toml: &str, extra: &[&str], want: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("c.toml");
    std::fs::write(&cfg, toml).unwrap();
    let out = tmp.path().join("run");
    let mut args = vec![
        "train",
        "es-sac",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let t = Instant::now();
    let stderr = fails(&args);
    assert!(
        t.elapsed() < Duration::from_secs(20),
        "took {:?}",
        t.elapsed()
    );
    assert!(stderr.contains(want), "missing {want:?} in: {stderr}");
    assert!(!out.join("metrics.jsonl").exists(), "nothing written");
}

#[test]
fn huge_population_is_refused_naming_it() {
    refused("[es]\npopulation = 1000000000\n", &[], "es.population");
}

#[test]
fn huge_networks_are_refused_naming_the_layer() {
    refused(
        "[network.actor]\nfc = [100000, 100000]\n",
        &[],
        "actor.fc[0]",
    );
    // Widths within bounds whose product cannot fit: the estimate names the largest part.
    // 100 layers of 16,000: about 26 G parameters per critic, beyond any machine's memory.
    let layers = vec!["16000"; 100].join(", ");
    refused(
        &format!(
            "[network.critic]\njoint_fc = [{layers}]\nobs_fc = []\nact_fc = []\n\
             recurrent = false\n"
        ),
        &[],
        "of memory but",
    );
}

#[test]
fn impossible_budgets_are_refused() {
    refused(
        "[rl]\nbatch_size = 512\nbuffer_size = 100\n",
        &[],
        "rl.batch_size",
    );
    refused("", &["--generations", "1000000000000"], "generations");
    refused("", &["--steps", "0"], "max_env_steps = 0");
    // Below the hybrid loop's warm start (1,000 random steps before the first generation).
    refused("", &["--steps", "10"], "rl.warm_start = 1000");
    refused("", &["--steps", "1000"], "rl.warm_start = 1000");
}

#[test]
fn a_runaway_urdf_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mut urdf = String::from("<robot name=\"chain\">\n<link name=\"l0\"/>\n");
    for i in 1..10_000 {
        urdf.push_str(&format!(
            "<link name=\"l{i}\"/><joint name=\"j{i}\" type=\"fixed\"><parent link=\"l{}\"/>\
             <child link=\"l{i}\"/></joint>\n",
            i - 1
        ));
    }
    urdf.push_str("</robot>\n");
    let path = tmp.path().join("chain.urdf");
    std::fs::write(&path, urdf).unwrap();
    refused("", &["--urdf", path.to_str().unwrap()], "10000 links");
}
