//! Contract: a training says what it starts before it starts: agent, preset, env, seed, the
//! budget, the run folder and how to stop and resume; at the end what it did and the
//! commands that evaluate and show the result. The default folder is `runs/<agent>-s<seed>`
//! for the default preset and `runs/<agent>-<preset>-s<seed>` for another, so the quick
//! start's commands never share one.

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
        "done: 4 generations",
        &format!("eval {o} --episodes 10"),
        &format!("record {o} --out walk.svg"),
    ] {
        assert!(stderr.contains(want), "missing {want:?} in:\n{stderr}");
    }
}

#[test]
fn default_run_folders_are_agent_preset_and_seed_and_never_collide() {
    // The quick start's commands, one after another in one folder: the default preset goes
    // to runs/<agent>-s<seed>, any other to runs/<agent>-<preset>-s<seed>.
    let tmp = tempfile::tempdir().unwrap();
    for (extra, folder) in [
        (vec![], "runs/sac-s7"),
        (vec!["--preset", "smoke"], "runs/sac-smoke-s7"),
        (
            vec!["--preset", "smoke", "--env", "pendulum"],
            "runs/sac-smoke-pendulum-s7",
        ),
    ] {
        let mut args = vec!["train", "sac", "--seed", "7", "--episodes", "1"];
        args.extend(extra);
        let out = common::esrl_in(tmp.path(), &args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            tmp.path().join(folder).join("metrics.csv").is_file(),
            "{folder}"
        );
    }
    // The same command again names the folder and how to continue it.
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
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("runs/sac-smoke-s7 already holds a run")
            && stderr.contains("train sac --resume runs/sac-smoke-s7"),
        "{stderr}"
    );
}

#[test]
fn a_fine_tuning_run_says_where_it_starts_and_gets_its_own_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let common = ["--preset", "smoke", "--seed", "4", "--generations", "2"];
    let mut args = vec!["train", "es-sac"];
    args.extend(common);
    let out = common::esrl_in(tmp.path(), &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let source = "runs/es-sac-smoke-s4";
    args.extend(["--init", source]);
    let out = common::esrl_in(tmp.path(), &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The path is kept absolute, so the run continues from any working directory.
    let absolute = tmp.path().canonicalize().unwrap().join(source);
    assert!(
        stderr.contains(&format!(
            "init:   from the weights of {} (fine-tuning",
            absolute.display()
        )) || stderr.contains(&format!("{source} (fine-tuning")),
        "{stderr}"
    );
    // The smoke preset's σ (the paper's 0.25) is far above σ_min: the banner says so.
    assert!(stderr.contains("`es = { sigma = 0.01 }`"), "{stderr}");
    let tuned = tmp.path().join("runs/es-sac-smoke-init-s4");
    assert!(tuned.join("init.json").is_file());
    // The source's kept policy, not its last checkpoint.
    let record = common::read_json(&tuned.join("init.json"));
    assert!(
        record["folder"]
            .as_str()
            .unwrap()
            .ends_with(&format!("{source}/best")),
        "{record}"
    );
    assert!(tuned.join("init/agent.safetensors").is_file());
    // A resume keeps where the run started.
    let out = common::esrl_in(
        tmp.path(),
        &[
            "train",
            "es-sac",
            "--resume",
            "runs/es-sac-smoke-init-s4",
            "--init",
            source,
        ],
    );
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("cannot be used with"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
