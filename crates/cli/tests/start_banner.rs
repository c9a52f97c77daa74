//! Contract: a training says what it starts before it starts: agent, preset, env, seed, the
//! budget, the run folder and how to stop and resume; then a pace estimate once measured,
//! and labelled log lines even with `--no-progress` (the default folder name is
//! `runs/<agent>-s<seed>`, the one `esrl compare` uses).

mod common;

use common::ok;

#[test]
fn banner_names_the_run_budget_folder_and_how_to_stop() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let o = out.to_str().unwrap();
    let stderr = ok(&[
        "train",
        "es-sac",
        "--preset",
        "smoke",
        "--seed",
        "3",
        "--generations",
        "4",
        "--no-progress",
        "--out",
        o,
    ]);
    for want in [
        "esrl train es-sac",
        "preset smoke",
        "env walk",
        "seed 3",
        "4 generations × 3 individuals",
        "2 inner cycles",
        &format!("run:    {o}"),
        "Ctrl-C or SIGTERM",
        &format!("esrl train es-sac --resume {o}"),
        "pace:",
        "done: 4 rows",
    ] {
        assert!(stderr.contains(want), "missing {want:?} in:\n{stderr}");
    }
}

#[test]
fn default_run_folder_is_agent_and_seed() {
    let tmp = tempfile::tempdir().unwrap();
    let out = common::esrl_in(
        tmp.path(),
        &[
            "train",
            "sac",
            "--preset",
            "smoke",
            "--seed",
            "7",
            "--episodes",
            "1",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(tmp.path().join("runs/sac-s7/metrics.csv").is_file());
}
