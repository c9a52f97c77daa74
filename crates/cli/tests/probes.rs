//! Contract: the faults found by probing the command with hostile input are refused with a
//! message and a non-zero exit, never a panic, and nothing already written is lost:
//! `record`/`eval --out` never replace a device, a pipe, a link or an existing file (without
//! `--force`); a URDF nested thousands of levels deep and `--config`/`--urdf` reading a
//! device are refused at once; thread counts are bounded; a benchmark of zero steps or threads is refused; a run folder is trained by one
//! process at a time; `eval` uses the configuration a policy was trained with and refuses an
//! edited one; a budget below what a run has done leaves its `config.toml` alone; a config
//! file naming another agent, `--urdf` on the pendulum and duplicate foot links are errors;
//! a metrics write that fails names its file; and `eval` keeps the traces it was asked to.

mod common;

use common::{esrl, fails, ok, read_json, smoke};
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn outputs_never_replace_devices_pipes_links_or_files() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "2"]);
    // A device.
    let err = fails(&["record", s(&run), "--out", "/dev/null"]);
    assert!(err.contains("not a regular file"), "{err}");
    // A pipe.
    let fifo = tmp.path().join("fifo");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|st| st.success()) {
        let err = fails(&["record", s(&run), "--out", s(&fifo)]);
        assert!(err.contains("not a regular file"), "{err}");
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo_like());
    }
    // A symbolic link, and the file it points to.
    let target = tmp.path().join("keep.txt");
    std::fs::write(&target, "keep").unwrap();
    let link = tmp.path().join("link.mcap");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let err = fails(&["record", s(&run), "--out", s(&link)]);
    assert!(err.contains("symbolic link"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    // An existing file: refused, then replaced with --force.
    let err = fails(&["record", s(&run), "--out", s(&target)]);
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    let metrics = run.join("metrics.csv");
    let before = std::fs::read(&metrics).unwrap();
    fails(&["eval", s(&run), "--out", s(&metrics)]);
    assert_eq!(
        std::fs::read(&metrics).unwrap(),
        before,
        "metrics.csv untouched"
    );
    let out = tmp.path().join("walk.svg");
    ok(&["record", s(&run), "--out", s(&out)]);
    ok(&["record", s(&run), "--out", s(&out), "--force"]);
    assert!(std::fs::read_to_string(&out).unwrap().starts_with("<svg"));
}

/// `FileType::is_fifo` through the Unix extension trait.
trait FifoLike {
    fn is_fifo_like(&self) -> bool;
}

impl FifoLike for std::fs::FileType {
    fn is_fifo_like(&self) -> bool {
        use std::os::unix::fs::FileTypeExt;
        self.is_fifo()
    }
}

#[test]
fn deep_xml_and_devices_are_refused_before_they_are_read() {
    let tmp = tempfile::tempdir().unwrap();
    let deep = tmp.path().join("deep.urdf");
    let depth = 20_000;
    let text = format!(
        "<robot name=\"r\">{}{}</robot>",
        "<link>".repeat(depth),
        "</link>".repeat(depth)
    );
    std::fs::write(&deep, text).unwrap();
    let out = tmp.path().join("run");
    let err = fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--urdf",
        s(&deep),
        "--out",
        s(&out),
    ]);
    assert!(err.contains("nested 20001 deep"), "{err}");
    for flag in ["--urdf", "--config"] {
        let err = fails(&[
            "train",
            "es-sac",
            "--preset",
            "smoke",
            flag,
            "/dev/zero",
            "--out",
            s(&out),
        ]);
        assert!(err.contains("not a regular file"), "{flag}: {err}");
    }
}

#[test]
fn thread_counts_are_bounded() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let err = fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--threads",
        "10000",
        "--out",
        s(&out),
    ]);
    assert!(err.contains("threads = 10000"), "{err}");
    let cores = std::thread::available_parallelism().unwrap().get();
    let many = (4 * cores + 1).to_string();
    let err = fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--threads",
        &many,
        "--out",
        s(&out),
    ]);
    assert!(err.contains("more than 4 threads a core"), "{err}");
}

#[test]
fn a_benchmark_of_nothing_is_refused() {
    // `bench env --steps 0` printed "0 control steps/s" as if it had measured something.
    let err = fails(&["bench", "env", "--steps", "0"]);
    assert!(err.contains("--steps"), "{err}");
    // `bench es --threads 0` compared one thread with "0" (efficiency inf %).
    let err = fails(&["bench", "es", "--threads", "0"]);
    assert!(err.contains("--threads"), "{err}");
}

/// `bench es --init DIR` times generations from a trained policy (a walking phase) with the
/// ES at its σ_min, and refuses a policy of another task or network.
#[test]
fn bench_es_times_generations_from_a_trained_policy() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "2"]);
    let out = common::stdout(&[
        "bench",
        "es",
        "--preset",
        "smoke",
        "--init",
        s(&run),
        "--json",
    ]);
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(r["init"].as_str().unwrap().ends_with("run"), "{r}");
    assert_eq!(
        r["sigma"].as_f64(),
        Some(0.01),
        "the smoke preset's sigma_min: {r}"
    );
    assert!(
        r["whole_env_steps_per_generation"].as_f64().unwrap() > 0.0,
        "{r}"
    );
    let plain = common::stdout(&["bench", "es", "--preset", "smoke", "--json"]);
    let plain: serde_json::Value = serde_json::from_str(&plain).unwrap();
    assert!(plain["init"].is_null(), "{plain}");
    let err = fails(&["bench", "es", "--preset", "walker", "--init", s(&run)]);
    assert!(err.contains("another task or network"), "{err}");
}

#[test]
fn one_process_trains_a_run_folder_at_a_time() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "1"]);
    // Hold the lock as a running training would.
    let lock = std::fs::OpenOptions::new()
        .write(true)
        .open(run.join(".lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let err = fails(&["train", "es-sac", "--resume", s(&run), "--generations", "3"]);
    assert!(err.contains("being trained by another process"), "{err}");
    drop(lock);
    ok(&["train", "es-sac", "--resume", s(&run), "--generations", "3"]);
}

#[test]
fn eval_uses_the_settings_a_policy_was_trained_with() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "2"]);
    let p = run.join("config.toml");
    let text = std::fs::read_to_string(&p).unwrap();
    std::fs::write(&p, text.replace("gravity = 9.81", "gravity = 5.0")).unwrap();
    for args in [vec!["eval", s(&run)], vec!["eval", s(&run), "--last"]] {
        let err = fails(&args);
        assert!(err.contains("walk.physics.gravity"), "{args:?}: {err}");
    }
    std::fs::write(&p, &text).unwrap();
    ok(&["eval", s(&run)]);
}

#[test]
fn a_budget_below_the_rows_done_leaves_the_run_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "4"]);
    let before = std::fs::read_to_string(run.join("config.toml")).unwrap();
    let err = fails(&["train", "es-sac", "--resume", s(&run), "--generations", "2"]);
    assert!(err.contains("has done 4 generations"), "{err}");
    assert_eq!(
        std::fs::read_to_string(run.join("config.toml")).unwrap(),
        before
    );
}

#[test]
fn settings_that_would_be_ignored_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let cfg = tmp.path().join("c.toml");
    std::fs::write(&cfg, "agent = \"sac\"\n").unwrap();
    let err = fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--config",
        s(&cfg),
        "--out",
        s(&out),
    ]);
    assert!(err.contains("agent = \"sac\""), "{err}");
    let err = fails(&[
        "train",
        "sac",
        "--env",
        "pendulum",
        "--urdf",
        "x.urdf",
        "--out",
        s(&out),
    ]);
    assert!(err.contains("--urdf"), "{err}");
    std::fs::write(
        &cfg,
        "[walk]\nfoot_links = [\"left_foot\", \"left_foot\"]\n",
    )
    .unwrap();
    let err = fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--config",
        s(&cfg),
        "--out",
        s(&out),
    ]);
    assert!(err.contains("foot_links"), "{err}");
    std::fs::write(&cfg, "inner_cycles = 100000000\n").unwrap();
    let err = fails(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--config",
        s(&cfg),
        "--out",
        s(&out),
    ]);
    assert!(err.contains("inner_cycles"), "{err}");
}

#[test]
fn a_failed_metrics_write_names_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    // The CSV log on a full disk: every write to it fails with "no space left on device".
    std::fs::create_dir_all(&run).unwrap();
    std::os::unix::fs::symlink("/dev/full", run.join("metrics.csv")).unwrap();
    let out = esrl(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--out",
        s(&run),
        "--no-progress",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("writing") && err.contains("metrics.csv"),
        "{err}"
    );
}

#[test]
fn eval_keeps_the_traces_it_is_asked_for() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    smoke("es-sac", &run, &["--generations", "1"]);
    let out = tmp.path().join("e.json");
    ok(&[
        "eval",
        s(&run),
        "--episodes",
        "5",
        "--traces",
        "2",
        "--out",
        s(&out),
    ]);
    let report = read_json(&out);
    let traced: Vec<bool> = report["episodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.get("trace").is_some())
        .collect();
    assert_eq!(traced, [true, true, false, false, false]);
    assert_eq!(report["requested"], 5);
    assert!(
        report["episodes"][4]["gait"].is_object(),
        "metrics without the trace"
    );
}
