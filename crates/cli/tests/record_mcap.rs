//! Contract: `esrl record` of a smoke-trained run writes an MCAP file that reads back with
//! esrl-record's reader: the Foxglove schema names and encodings, one scene, one transform and
//! one message per scalar topic for every step of the rollout (as many as `esrl eval` counts
//! for the same seed), timestamps at k × 25 ms, every schema-required field present, the
//! reward terms summing to the total; a pendulum run is refused, and so is an output named
//! neither `.mcap` nor `.svg`.

use esrl_record::{
    channels, foxglove_schema_problems, message_problems, read_channel, read_file, read_scalars,
    FRAME_TRANSFORMS_SCHEMA, SCENE_TOPIC, SCENE_UPDATE_SCHEMA, TRANSFORMS_TOPIC,
};
use serde_json::Value;

mod common;

use common::{esrl, ok_output as ok, smoke};

const LINKS: [&str; 11] = [
    "torso",
    "left_shoulder",
    "left_arm",
    "left_thigh",
    "left_shank",
    "left_foot",
    "right_shoulder",
    "right_arm",
    "right_thigh",
    "right_shank",
    "right_foot",
];

const SCALAR_TOPICS: [&str; 8] = [
    "/esrl/joints/angle",
    "/esrl/joints/velocity",
    "/esrl/joints/torque",
    "/esrl/joints/power",
    "/esrl/action",
    "/esrl/feet/contact_force",
    "/esrl/reward",
    "/esrl/torso",
];

#[test]
fn recording_reads_back_with_foxglove_schemas() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let r = run.to_str().unwrap();
    smoke("td3", &run, &[]);
    let file = tmp.path().join("sub/rollout.mcap");
    ok(&["record", r, "--out", file.to_str().unwrap(), "--seed", "5"]);
    ok(&["eval", r, "--seed", "5"]);
    let eval = common::read_json(&run.join("eval.json"));
    let steps = eval["episodes"][0]["length"].as_u64().unwrap() as usize;
    assert!(steps > 0);

    let bytes = read_file(&file).unwrap();
    let chans = channels(&bytes).unwrap();
    let by_topic = |t: &str| {
        chans
            .iter()
            .find(|c| c.topic == t)
            .unwrap_or_else(|| panic!("no channel {t}"))
    };
    assert_eq!(
        by_topic(SCENE_TOPIC).schema_name.as_deref(),
        Some(SCENE_UPDATE_SCHEMA)
    );
    assert_eq!(
        by_topic(TRANSFORMS_TOPIC).schema_name.as_deref(),
        Some(FRAME_TRANSFORMS_SCHEMA)
    );
    assert_eq!(by_topic(SCENE_TOPIC).message_count, 1);
    assert_eq!(by_topic(TRANSFORMS_TOPIC).message_count, steps as u64);
    for t in SCALAR_TOPICS {
        let c = by_topic(t);
        assert_eq!(c.message_count, steps as u64, "{t}");
        assert_eq!(
            c.schema_name.as_deref(),
            Some(t.trim_start_matches('/').replace('/', ".").as_str())
        );
    }
    for c in &chans {
        assert_eq!(c.message_encoding, "json");
        assert_eq!(c.schema_encoding.as_deref(), Some("jsonschema"));
        let schema: Value = serde_json::from_str(c.schema.as_deref().unwrap()).unwrap();
        assert!(
            foxglove_schema_problems(&schema).is_empty(),
            "{}: {:?}",
            c.topic,
            foxglove_schema_problems(&schema)
        );
        let msgs = read_channel(&bytes, &c.topic).unwrap();
        assert_eq!(msgs.len() as u64, c.message_count);
        for m in &msgs {
            let problems = message_problems(&schema, &m.data);
            assert!(problems.is_empty(), "{}: {problems:?}", c.topic);
        }
        if c.topic != SCENE_TOPIC {
            // Step k (from 1) at k × 25 ms of simulated time.
            for (k, m) in msgs.iter().enumerate() {
                assert_eq!(m.log_time, (k as u64 + 1) * 25_000_000, "{}", c.topic);
            }
            assert!(msgs.windows(2).all(|w| w[0].log_time < w[1].log_time));
        }
    }

    // The scene draws every link in its own frame; the transforms move every link.
    let scene = &read_channel(&bytes, SCENE_TOPIC).unwrap()[0].data;
    let entities: Vec<&str> = scene["entities"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["frame_id"].as_str().unwrap())
        .collect();
    for l in LINKS {
        assert!(entities.contains(&l), "scene lacks {l}: {entities:?}");
    }
    let tf = &read_channel(&bytes, TRANSFORMS_TOPIC).unwrap()[0].data;
    let children: Vec<&str> = tf["transforms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["child_frame_id"].as_str().unwrap())
        .collect();
    assert_eq!(children.len(), LINKS.len());

    // Joint fields are the actuated joints; reward terms sum to the total.
    let torque = read_scalars(&bytes, "/esrl/joints/torque").unwrap();
    assert_eq!(
        torque.fields,
        [
            "left_hip",
            "left_knee",
            "left_ankle",
            "right_hip",
            "right_knee",
            "right_ankle"
        ]
    );
    let reward = read_scalars(&bytes, "/esrl/reward").unwrap();
    assert_eq!(
        reward.fields,
        ["total", "forward", "lateral", "height", "power", "alive"]
    );
    let mut ret = 0.0;
    for row in &reward.values {
        let terms: f64 = row[1..].iter().sum();
        assert!(
            (terms - row[0]).abs() < 1e-5,
            "terms {terms} vs total {}",
            row[0]
        );
        ret += row[0];
    }
    let eval_ret = eval["episodes"][0]["return"].as_f64().unwrap();
    assert!(
        (ret - eval_ret).abs() < 1e-6 * (1.0 + eval_ret.abs()),
        "{ret} vs {eval_ret}"
    );
    let torso = read_scalars(&bytes, "/esrl/torso").unwrap();
    let x_last = torso.values.last().unwrap()[0];
    let trace_x = eval["episodes"][0]["trace"]["x"].as_array().unwrap();
    assert_eq!(x_last, trace_x.last().unwrap().as_f64().unwrap());
}

#[test]
fn pendulum_runs_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("p");
    let r = run.to_str().unwrap();
    smoke("sac", &run, &["--env", "pendulum"]);
    let file = tmp.path().join("p.mcap");
    let out = esrl(&["record", r, "--out", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("pendulum run"), "{err}");
    assert!(!file.exists());
}

#[test]
fn an_output_that_is_neither_mcap_nor_svg_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("w");
    smoke("es-sac", &run, &[]);
    for name in ["walk.xyz", "walk", "walk.mcap.bak"] {
        let file = tmp.path().join(name);
        let out = esrl(&[
            "record",
            run.to_str().unwrap(),
            "--out",
            file.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("FILE.mcap") && err.contains("FILE.svg"),
            "{err}"
        );
        assert!(!file.exists(), "{name} was written");
    }
    // Either extension in capitals is taken.
    let file = tmp.path().join("walk.MCAP");
    let out = esrl(&[
        "record",
        run.to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    assert!(file.is_file());
}
