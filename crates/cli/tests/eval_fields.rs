//! Contract: `esrl eval` on a smoke-trained ES-SAC run writes `RUN/eval.json` with every field
//! the Python package reads (run, agent, episodes with seed/return/length/q0/gait/trace, mean),
//! with values that agree with the episode's own trace (recomputed here), deterministic across
//! invocations and the same whether given the run or its checkpoint folder; the gait cycle's
//! support phases and each joint's time at a limit agree with the trace's contact flags and
//! joint angles, the torso pitch agrees with the side view's torso, and the side view has a
//! frame every 0.1 s; with a gait clock each episode keeps the phase its reset drew;
//! `--default-starts` (and a study's `[eval] default_starts = true`) evaluates from the task's
//! standard starts; `--json` prints the same object; `--record` writes one MCAP per episode; a
//! pendulum run has returns only.

mod common;

use common::{esrl, ok_output as ok, read_json, smoke};
use serde_json::Value;

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("expected an array, got {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

const GAIT_KEYS: [&str; 22] = [
    "track_length",
    "track_time",
    "mean_forward_velocity",
    "mean_abs_lateral",
    "mean_vertical",
    "mean_abs_vertical",
    "actuator_names",
    "mean_abs_torque",
    "mean_abs_power",
    "mean_abs_torque_overall",
    "mean_abs_power_overall",
    "knee_torque_asymmetry",
    "foot_names",
    "mean_foot_force",
    "distance",
    "fell",
    "steps",
    "duration",
    "track_length",
    "cycle",
    "joints",
    "torso_pitch",
];

#[test]
fn eval_json_has_every_field_and_agrees_with_its_trace() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let r = run.to_str().unwrap();
    smoke("es-sac", &run, &[]);
    let rec = tmp.path().join("rec");
    let out = ok(&[
        "eval",
        r,
        "--last",
        "--episodes",
        "2",
        "--seed",
        "3",
        "--record",
        rec.to_str().unwrap(),
    ]);
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("left_knee"),
        "table lists actuators:\n{table}"
    );
    let eval = read_json(&run.join("eval.json"));
    assert_eq!(eval["agent"], "es-sac");
    assert!(eval["run"].as_str().unwrap().ends_with("run"));
    let episodes = eval["episodes"].as_array().unwrap();
    assert_eq!(episodes.len(), 2);
    for (k, e) in episodes.iter().enumerate() {
        assert_eq!(e["seed"].as_u64(), Some(3 + k as u64));
        assert!(e["return"].as_f64().unwrap().is_finite());
        assert!(e["q0"].as_f64().unwrap().is_finite());
        let len = e["length"].as_u64().unwrap() as usize;
        assert!(len > 0);
        // The return split by reward term: the walking task's terms, summing to the return
        // up to the single-precision rounding of each step's reward.
        let terms = e["return_terms"].as_object().unwrap();
        for key in ["forward", "alive", "power"] {
            assert!(
                terms.contains_key(key),
                "return_terms.{key} missing: {terms:?}"
            );
        }
        let total: f64 = terms.values().map(|v| v.as_f64().unwrap()).sum();
        let ret = e["return"].as_f64().unwrap();
        assert!((total - ret).abs() <= 1e-5 * len as f64, "{total} vs {ret}");
        let g = &e["gait"];
        for key in GAIT_KEYS {
            assert!(g.get(key).is_some(), "gait.{key} missing: {g}");
        }
        let tr = &e["trace"];
        let time = floats(&tr["time"]);
        let (x, y, z) = (floats(&tr["x"]), floats(&tr["y"]), floats(&tr["z_error"]));
        let v = floats(&tr["forward_velocity"]);
        assert_eq!(time.len(), len, "one trace sample per step");
        for a in [&x, &y, &z, &v] {
            assert_eq!(a.len(), len);
        }
        // Sim time after step i is (i + 1) × 25 ms.
        for (i, t) in time.iter().enumerate() {
            assert!((t - (i + 1) as f64 * 0.025).abs() < 1e-5, "time[{i}] = {t}");
        }
        // The metrics recomputed by hand from the trace.
        assert_eq!(g["steps"].as_u64(), Some(len as u64));
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + b.abs());
        assert!(close(g["distance"].as_f64().unwrap(), x[len - 1] - x[0]));
        let lat = mean(&y.iter().map(|v| v.abs()).collect::<Vec<_>>());
        assert!(close(g["mean_abs_lateral"].as_f64().unwrap(), lat));
        assert!(close(g["mean_vertical"].as_f64().unwrap(), mean(&z)));
        assert!(close(
            g["mean_forward_velocity"].as_f64().unwrap(),
            mean(&v)
        ));
        let tau = floats(&g["mean_abs_torque"]);
        assert_eq!(tau.len(), 6);
        assert!(close(
            g["mean_abs_torque_overall"].as_f64().unwrap(),
            mean(&tau)
        ));
        // A 1 s smoke episode cannot cover 50 m.
        assert!(g["track_time"].is_null());
        let ended = e["terminated"].as_bool().unwrap() || e["truncated"].as_bool().unwrap();
        assert!(ended);
        assert_eq!(g["fell"].as_bool(), e["terminated"].as_bool());
        assert!(rec.join(format!("episode-{k:03}.mcap")).is_file());

        // Phases recounted from the contact flags of the trace.
        let contact = tr["contact"].as_array().unwrap();
        assert_eq!(contact.len(), len);
        let flags: Vec<(bool, bool)> = contact
            .iter()
            .map(|c| (c[0].as_u64() == Some(1), c[1].as_u64() == Some(1)))
            .collect();
        let share = |f: &dyn Fn(&(bool, bool)) -> bool| {
            flags.iter().filter(|c| f(c)).count() as f64 / len as f64
        };
        let c = &g["cycle"];
        assert!(close(
            c["double_support"].as_f64().unwrap(),
            share(&|c| c.0 && c.1)
        ));
        assert!(close(
            c["flight"].as_f64().unwrap(),
            share(&|c| !c.0 && !c.1)
        ));
        let touchdowns = |foot: usize| {
            let on = |i: usize| if foot == 0 { flags[i].0 } else { flags[i].1 };
            (1..len).filter(|&i| on(i) && !on(i - 1)).count() as f64
        };
        assert_eq!(floats(&c["touchdowns"]), vec![touchdowns(0), touchdowns(1)]);
        let class = c["gait_class"].as_str().unwrap();
        assert!(
            ["walk", "run", "hop", "shuffle", "stand", "fall"].contains(&class),
            "{class}"
        );
        assert_eq!(c["gait_classes"][class].as_u64(), Some(1));

        // Time at a limit recounted from the (rounded) joint angles, 1° margin.
        let names = tr["joint_names"].as_array().unwrap();
        assert_eq!(names.len(), 6);
        let angles = tr["joint_angle"].as_array().unwrap();
        assert_eq!(angles.len(), len);
        let joints = g["joints"].as_array().unwrap();
        for (j, joint) in joints.iter().enumerate() {
            assert_eq!(joint["name"], names[j]);
            let [lo, hi] = [0, 1].map(|b| tr["joint_limits"][j][b].as_f64().unwrap());
            let q: Vec<f64> = angles.iter().map(|r| r[j].as_f64().unwrap()).collect();
            let m = 1f64.to_radians();
            // Angles are stored to 1e-4 rad: a sample that close to the margin may differ.
            let near = q
                .iter()
                .filter(|&&q| ((q - lo - m).abs() < 1e-4) || ((hi - m - q).abs() < 1e-4))
                .count() as f64;
            let at = q.iter().filter(|&&q| q <= lo + m || q >= hi - m).count() as f64;
            let got = joint["at_limit"].as_f64().unwrap() * len as f64;
            assert!((got - at).abs() <= near, "{}: {got} vs {at}", joint["name"]);
            assert!(joint["range"].as_f64().unwrap() >= 0.0);
        }

        // The torso pitch: its summary recomputed from the trace, and each sample against
        // the side view's drawing of the torso (part 1, the box from the waist up: the
        // angle of its centre line from the vertical, forward positive) at the same step.
        let pitch = floats(&tr["torso_pitch"]);
        assert_eq!(pitch.len(), len);
        assert!(close(
            g["torso_pitch"]["mean"].as_f64().unwrap(),
            mean(&pitch)
        ));
        let frames = tr["stick"]["frames"].as_array().unwrap();
        assert!(!frames.is_empty(), "an episode of {len} steps has frames");
        for (f, frame) in frames.iter().enumerate() {
            let b = floats(&frame[1]); // corners x, z: top front, bottom front, bottom back, top back
            let (dx, dz) = (b[0] + b[6] - b[2] - b[4], b[1] + b[7] - b[3] - b[5]);
            let drawn = dx.atan2(dz);
            let at = pitch[4 * f + 3];
            assert!(
                (drawn - at).abs() < 0.01,
                "frame {f}: drawn {drawn}, traced {at}"
            );
        }

        // The side view: one frame every 4 steps (0.1 s), 11 parts for the humanoid.
        let stick = &tr["stick"];
        assert_eq!(stick["time"].as_array().unwrap().len(), len / 4);
        let parts = stick["parts"].as_array().unwrap();
        assert_eq!(parts.len(), 11);
        for frame in stick["frames"].as_array().unwrap() {
            for (part, coords) in parts.iter().zip(frame.as_array().unwrap()) {
                let n = match part["kind"].as_str().unwrap() {
                    "line" => 4,
                    "box" => 8,
                    _ => 2,
                };
                assert_eq!(coords.as_array().unwrap().len(), n);
            }
        }
    }
    let m = &eval["mean"];
    let returns: Vec<f64> = episodes
        .iter()
        .map(|e| e["return"].as_f64().unwrap())
        .collect();
    assert!((m["return"].as_f64().unwrap() - mean(&returns)).abs() < 1e-9);
    assert_eq!(m["episodes"].as_u64(), Some(2));
    for key in ["return_sd", "length", "q0", "falls", "finished", "gait"] {
        assert!(m.get(key).is_some(), "mean.{key} missing");
    }
    let d: Vec<f64> = episodes
        .iter()
        .map(|e| e["gait"]["distance"].as_f64().unwrap())
        .collect();
    assert!((m["gait"]["distance"].as_f64().unwrap() - mean(&d)).abs() < 1e-9);
    let forward: Vec<f64> = episodes
        .iter()
        .map(|e| e["return_terms"]["forward"].as_f64().unwrap())
        .collect();
    assert!((m["return_terms"]["forward"].as_f64().unwrap() - mean(&forward)).abs() < 1e-9);
    assert!(
        table.contains("return by term (per step): "),
        "the table names what pays:\n{table}"
    );

    // The checkpoint folder gives the same numbers; --json prints the file's object.
    let out = ok(&[
        "eval",
        run.join("checkpoint").to_str().unwrap(),
        "--episodes",
        "2",
        "--seed",
        "3",
        "--json",
    ]);
    let printed: Value = serde_json::from_slice(&out.stdout).expect("--json prints one object");
    let again = read_json(&run.join("eval.json"));
    assert_eq!(printed, again);
    assert_eq!(again["episodes"], eval["episodes"], "deterministic");
}

#[test]
fn pendulum_eval_has_returns_only() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("p");
    let r = run.to_str().unwrap();
    smoke("sac", &run, &["--env", "pendulum"]);
    ok(&["eval", r, "--episodes", "2"]);
    let eval = read_json(&run.join("eval.json"));
    for e in eval["episodes"].as_array().unwrap() {
        assert!(e["gait"].is_null());
        assert!(e.get("trace").is_none());
        assert_eq!(
            e["length"].as_u64(),
            Some(200),
            "Pendulum-v1 truncates at 200"
        );
        assert!(
            e["return"].as_f64().unwrap() < 0.0,
            "pendulum rewards are ≤ 0"
        );
    }
    assert!(eval["mean"]["gait"].is_null());
    let out = esrl(&[
        "eval",
        r,
        "--record",
        tmp.path().join("rec").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("pendulum"));
}

#[test]
fn eval_json_keeps_the_start_phase_of_a_gait_clock() {
    let tmp = tempfile::tempdir().unwrap();
    let plain = tmp.path().join("plain");
    smoke("es-sac", &plain, &[]);
    ok(&["eval", plain.to_str().unwrap(), "--last", "--episodes", "1"]);
    let eval = read_json(&plain.join("eval.json"));
    assert!(
        eval["episodes"][0].get("start_phase").is_none(),
        "no clock, no start phase"
    );

    let overlay = tmp.path().join("clock.toml");
    std::fs::write(&overlay, "walk = { gait_clock = { period = 0.8 } }\n").unwrap();
    let run = tmp.path().join("clock");
    smoke("es-sac", &run, &["--config", overlay.to_str().unwrap()]);
    let r = run.to_str().unwrap();
    ok(&[
        "eval",
        r,
        "--last",
        "--episodes",
        "3",
        "--seed",
        "11",
        "--traces",
        "0",
    ]);
    let eval = read_json(&run.join("eval.json"));
    // The phase each seed's reset draws, from an environment built from the run's own
    // configuration, and the clock entries (sin 2πφ, cos 2πφ) of its first observation.
    let config = esrl_run::TrainConfig::load(&run.join("config.toml")).unwrap();
    let mut env = esrl_sim::WalkEnv::new(config.walk).unwrap();
    for (k, e) in eval["episodes"].as_array().unwrap().iter().enumerate() {
        let phase = e["start_phase"].as_f64().unwrap();
        let obs = esrl_sim::Env::reset(&mut env, 11 + k as u64);
        assert_eq!(phase, f64::from(env.reset_phase()), "episode {k}");
        let angle = std::f32::consts::TAU * phase as f32;
        let n = obs.len();
        assert!((obs[n - 2] - angle.sin()).abs() < 1e-6, "episode {k}");
        assert!((obs[n - 1] - angle.cos()).abs() < 1e-6, "episode {k}");
    }
}

#[test]
fn default_starts_evaluates_from_the_tasks_standard_resets() {
    let tmp = tempfile::tempdir().unwrap();
    // A run that trained from wide, mixed starts (crouched, split, standing).
    let overlay = tmp.path().join("wide.toml");
    std::fs::write(
        &overlay,
        "walk = { gait_clock = { period = 0.8 }, reset = { pose = \"mixed\" }, \
         init_noise = { joint_angle = 0.1, joint_velocity = 0.5 } }\n",
    )
    .unwrap();
    let run = tmp.path().join("wide");
    smoke("es-sac", &run, &["--config", overlay.to_str().unwrap()]);
    let r = run.to_str().unwrap();
    let own = tmp.path().join("own.json");
    let standard = tmp.path().join("standard.json");
    let args = ["--last", "--episodes", "4", "--seed", "20", "--traces", "0"];
    ok(&[&["eval", r, "--out", own.to_str().unwrap()], &args[..]].concat());
    ok(&[
        &[
            "eval",
            r,
            "--default-starts",
            "--out",
            standard.to_str().unwrap(),
        ],
        &args[..],
    ]
    .concat());
    let (own, standard) = (read_json(&own), read_json(&standard));
    assert!(own.get("default_starts").is_none());
    assert_eq!(standard["default_starts"], true);
    // Each episode's start, from environments built by hand: the run's own task, and the
    // same task with the default reset pose and joint noise.
    let config = esrl_run::TrainConfig::load(&run.join("config.toml")).unwrap();
    let mut wide = esrl_sim::WalkEnv::new(config.walk.clone()).unwrap();
    let plain_walk = esrl_sim::WalkConfig {
        init_noise: esrl_sim::InitNoise::default(),
        reset: esrl_sim::ResetConfig::default(),
        ..config.walk
    };
    let mut plain = esrl_sim::WalkEnv::new(plain_walk).unwrap();
    let mut differ = 0;
    for k in 0..4 {
        let seed = 20 + k as u64;
        let wide_obs = esrl_sim::Env::reset(&mut wide, seed);
        let plain_obs = esrl_sim::Env::reset(&mut plain, seed);
        let phase = |report: &Value| report["episodes"][k]["start_phase"].as_f64().unwrap();
        assert_eq!(phase(&own), f64::from(wide.reset_phase()), "episode {k}");
        assert_eq!(
            phase(&standard),
            f64::from(plain.reset_phase()),
            "episode {k}"
        );
        differ += usize::from(wide_obs != plain_obs);
    }
    assert_eq!(differ, 4, "the two tasks start from different states");
}

#[test]
fn a_study_evaluates_from_the_standard_starts_when_asked() {
    let tmp = tempfile::tempdir().unwrap();
    let study = tmp.path().join("wide.toml");
    std::fs::write(
        &study,
        r#"
seeds = [0]
[eval]
episodes = 3
traces = 0
default_starts = true
[[arm]]
name = "wide"
agent = "es-sac"
preset = "smoke"
generations = 1
set = { walk = { gait_clock = { period = 0.8 }, init_noise = { joint_angle = 0.1, joint_velocity = 0.5 } } }
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    ok(&[
        "study",
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-progress",
    ]);
    let record = out.join("records/wide-s0");
    let recorded = read_json(&record.join("eval.json"));
    assert_eq!(recorded["default_starts"], true);
    // The record's policy folder evaluated again, from the standard starts and from its own.
    let policy = record.join("policy");
    let eval = |extra: &[&str], name: &str| {
        let file = tmp.path().join(name);
        let mut args = vec![
            "eval",
            policy.to_str().unwrap(),
            "--episodes",
            "3",
            "--seed",
            "1000",
            "--traces",
            "0",
            "--out",
            file.to_str().unwrap(),
        ];
        args.extend(extra);
        ok(&args);
        common::episodes_without_q0(&read_json(&file))
    };
    let kept = common::episodes_without_q0(&recorded);
    let standard = eval(&["--default-starts"], "standard.json");
    assert!(
        kept == standard,
        "the record differs from `esrl eval --default-starts`"
    );
    assert!(
        eval(&[], "own.json") != standard,
        "the run's own starts are the standard ones"
    );
    ok(&["study", "report", out.to_str().unwrap()]);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("from the task's standard starts"),
        "{report}"
    );
    // Every run's torso pitch: the evaluation's mean, in degrees.
    let figures = read_json(&out.join("report.json"));
    let pitch = recorded["mean"]["gait"]["torso_pitch"]["mean"]
        .as_f64()
        .unwrap();
    assert_eq!(
        figures["runs"][0]["torso_pitch_deg"].as_f64().unwrap(),
        pitch.to_degrees()
    );
}
