//! Contract: a checkpoint is verified before it is trusted. A file edited or corrupted after
//! it was written (manifest or chunk hash), a `state.json` that contradicts the config or the
//! metrics, or a `config.toml` changed since the checkpoint is refused with a message naming
//! it, and nothing in the run folder is lost; so is a checkpoint whose manifest was removed.
//! `eval` checks the manifest too, and refuses weights that are not finite. Identical content gives byte-identical checkpoint files, and each transition of
//! the replay buffer is written once, not at every checkpoint.

mod common;

use common::{esrl, fails, ok};
use std::path::Path;

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

fn train(dir: &Path) {
    ok(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--seed",
        "1",
        "--generations",
        "4",
        "--threads",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
}

fn edit_json(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

/// A copy of `base`, changed by `tamper`, must refuse `--resume` with `want` in the message
/// and keep its metrics.
fn refused(base: &Path, name: &str, tamper: impl FnOnce(&Path), want: &str) {
    let dir = base.parent().unwrap().join(name);
    copy_dir(base, &dir);
    tamper(&dir);
    let before = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    let stderr = fails(&[
        "train",
        "es-sac",
        "--resume",
        dir.to_str().unwrap(),
        "--generations",
        "6",
    ]);
    assert!(
        stderr.contains(want),
        "{name}: missing {want:?} in: {stderr}"
    );
    let after = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
    assert_eq!(before, after, "{name}: no metrics row lost");
}

#[test]
fn tampered_checkpoints_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let base = tmp.path().join("base");
    train(&base);
    let state = |d: &Path| d.join("checkpoint/state.json");
    refused(
        &base,
        "rows",
        |d| edit_json(&state(d), |v| v["rows"] = 2.into()),
        "state.json does not match its SHA-256",
    );
    // A checkpoint of this format without its manifest (as a tamperer would delete it) is
    // refused outright.
    refused(
        &base,
        "manifest",
        |d| std::fs::remove_file(d.join("checkpoint/manifest.json")).unwrap(),
        "manifest.json is missing",
    );
    // A checkpoint of the format before manifests (version 1) has none: its contents are
    // still checked.
    let unsigned = |d: &Path| {
        std::fs::remove_file(d.join("checkpoint/manifest.json")).unwrap();
        edit_json(&state(d), |v| v["version"] = 1.into());
    };
    refused(
        &base,
        "rows-unsigned",
        |d| {
            unsigned(d);
            edit_json(&state(d), |v| v["rows"] = 2.into());
        },
        "`rows` = 2",
    );
    refused(
        &base,
        "steps-unsigned",
        |d| {
            unsigned(d);
            edit_json(&state(d), |v| v["env_steps"] = u64::MAX.into());
        },
        "env_steps",
    );
    refused(
        &base,
        "sigma-unsigned",
        |d| {
            unsigned(d);
            edit_json(&state(d), |v| v["sigma"] = (-5.0).into());
        },
        "`sigma` = -5",
    );
    refused(
        &base,
        "chunk",
        |d| {
            let chunk = std::fs::read_dir(d.join("replay"))
                .unwrap()
                .next()
                .unwrap()
                .unwrap()
                .path();
            let mut bytes = std::fs::read(&chunk).unwrap();
            let last = bytes.len() - 1;
            bytes[last] ^= 0x40;
            std::fs::write(&chunk, bytes).unwrap();
        },
        "does not match its SHA-256",
    );
    refused(
        &base,
        "config",
        |d| {
            let p = d.join("config.toml");
            let text = std::fs::read_to_string(&p).unwrap();
            std::fs::write(&p, text.replace("population = 3", "population = 4")).unwrap();
        },
        "es.population: 3 vs 4",
    );
    // The untouched copy still resumes.
    ok(&[
        "train",
        "es-sac",
        "--resume",
        base.to_str().unwrap(),
        "--generations",
        "6",
    ]);
}

#[test]
fn non_finite_weights_are_refused_by_eval() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    train(&run);
    let p = run.join("checkpoint/agent.safetensors");
    let mut tensors: Vec<esrl_nn::NamedTensor> =
        esrl_nn::load_tensors(&p).unwrap().into_values().collect();
    tensors.sort_by(|a, b| a.name.cmp(&b.name));
    let actor = tensors
        .iter_mut()
        .find(|t| t.name.starts_with("actor."))
        .unwrap();
    actor.data[0] = f32::NAN;
    esrl_nn::save_tensors(&p, &tensors, None).unwrap();
    // The manifest alone refuses the changed file; give it the new hash so that the
    // weights themselves are what is refused.
    let out = esrl(&["eval", run.join("checkpoint").to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("does not match its SHA-256"), "{stderr}");
    let hash = {
        use sha2::Digest;
        format!("{:x}", sha2::Sha256::digest(std::fs::read(&p).unwrap()))
    };
    edit_json(&run.join("checkpoint/manifest.json"), |v| {
        v["sha256"]["agent.safetensors"] = hash.into()
    });
    let out = esrl(&["eval", run.join("checkpoint").to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains("non-finite"), "{stderr}");
}

#[test]
fn identical_runs_write_identical_files_and_replay_is_written_once() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    train(&a);
    train(&b);
    for f in ["agent.safetensors", "actor.safetensors", "config.toml"] {
        assert_eq!(
            std::fs::read(a.join("checkpoint").join(f)).unwrap(),
            std::fs::read(b.join("checkpoint").join(f)).unwrap(),
            "{f}"
        );
    }
    let state: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("checkpoint/state.json")).unwrap())
            .unwrap();
    let chunks = state["replay"]["chunks"].as_array().unwrap();
    // Smoke checkpoints every generation: one chunk each, each transition written once.
    assert_eq!(chunks.len(), 4, "{chunks:?}");
    let written: u64 = chunks.iter().map(|c| c["len"].as_u64().unwrap()).sum();
    assert_eq!(written, state["env_steps"].as_u64().unwrap());
    let mut next = 0;
    for c in chunks {
        assert_eq!(c["start"].as_u64().unwrap(), next, "chunks are contiguous");
        next += c["len"].as_u64().unwrap();
        let file = a.join("replay").join(c["file"].as_str().unwrap());
        assert_eq!(
            std::fs::read(&file).unwrap(),
            std::fs::read(b.join("replay").join(c["file"].as_str().unwrap())).unwrap()
        );
    }
}
