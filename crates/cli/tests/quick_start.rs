//! Contract: the README's quick start works top to bottom in one folder, as a new user runs
//! it (with smoke-sized budgets): the default training, its evaluation and an SVG of it,
//! the quick preset and the pendulum, each into its own folder, none colliding.

mod common;

use common::esrl_in;

#[test]
fn the_quick_start_runs_in_order() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let steps: &[&[&str]] = &[
        &["train", "es-sac", "--steps", "3000", "--no-progress"],
        &["eval", "runs/es-sac-s0", "--episodes", "2"],
        &["record", "runs/es-sac-s0", "--out", "walk.svg"],
        &[
            "train",
            "es-sac",
            "--preset",
            "quick",
            "--generations",
            "2",
            "--no-progress",
        ],
        &[
            "train",
            "sac",
            "--env",
            "pendulum",
            "--episodes",
            "7",
            "--no-progress",
        ],
    ];
    for args in steps {
        let out = esrl_in(dir, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    for f in [
        "runs/es-sac-s0/checks.jsonl",
        "runs/es-sac-s0/best/eval.json",
        "walk.svg",
        "runs/es-sac-quick-s0/metrics.csv",
        "runs/sac-pendulum-s0/metrics.csv",
    ] {
        assert!(dir.join(f).is_file(), "{f} is missing");
    }
}
