//! Contract: a synthetic recording read back with the mcap crate has the schemas Foxglove
//! expects (names, encodings, embedded JSON text that Foxglove's parser accepts), one message
//! per recorded step on every per-step channel, strictly increasing timestamps, and messages
//! carrying every field their embedded schema requires.

mod common;

use std::collections::BTreeMap;
use std::io::Cursor;

use esrl_record::{
    foxglove_schema_problems, message_problems, read_scalars, RecordOptions, RolloutWriter,
    SCENE_TOPIC, TRANSFORMS_TOPIC,
};
use serde_json::Value;

fn record() -> Vec<u8> {
    let mut options = RecordOptions::default();
    options.metadata.insert("agent".into(), "es-sac".into());
    let mut w = RolloutWriter::new(
        Cursor::new(Vec::new()),
        &common::scene(),
        &common::topics(),
        options,
    )
    .unwrap();
    for i in 0..common::STEPS {
        w.write_frame(&common::frame(i)).unwrap();
    }
    let (cursor, stats) = w.finish().unwrap();
    assert_eq!(stats.frames, common::STEPS);
    assert_eq!(stats.messages, 1 + 5 * common::STEPS as u64);
    cursor.into_inner()
}

struct Channel {
    schema_name: String,
    schema_encoding: String,
    message_encoding: String,
    schema: Value,
    times: Vec<u64>,
    messages: Vec<Value>,
}

/// Reads every message with the mcap crate itself, grouped by topic.
fn read_back(bytes: &[u8]) -> BTreeMap<String, Channel> {
    let mut out: BTreeMap<String, Channel> = BTreeMap::new();
    for m in mcap::MessageStream::new(bytes).unwrap() {
        let m = m.unwrap();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        let c = out
            .entry(m.channel.topic.clone())
            .or_insert_with(|| Channel {
                schema_name: schema.name.clone(),
                schema_encoding: schema.encoding.clone(),
                message_encoding: m.channel.message_encoding.clone(),
                schema: serde_json::from_slice(&schema.data).unwrap(),
                times: vec![],
                messages: vec![],
            });
        c.times.push(m.log_time);
        assert_eq!(m.publish_time, m.log_time);
        c.messages.push(serde_json::from_slice(&m.data).unwrap());
    }
    out
}

#[test]
fn schemas_are_named_and_encoded_as_foxglove_expects() {
    let channels = read_back(&record());
    let names: Vec<(&str, &str)> = channels
        .iter()
        .map(|(t, c)| (t.as_str(), c.schema_name.as_str()))
        .collect();
    assert_eq!(
        names,
        [
            ("/esrl/contacts", "esrl.contacts"),
            ("/esrl/joints/angle", "esrl.joints.angle"),
            ("/esrl/joints/torque", "esrl.joints.torque"),
            ("/esrl/reward", "esrl.reward"),
            ("/scene", "foxglove.SceneUpdate"),
            ("/tf", "foxglove.FrameTransforms"),
        ]
    );
    for (topic, c) in &channels {
        assert_eq!(c.schema_encoding, "jsonschema", "{topic}");
        assert_eq!(c.message_encoding, "json", "{topic}");
        assert_eq!(c.schema["title"], c.schema_name.as_str(), "{topic}");
        let problems = foxglove_schema_problems(&c.schema);
        assert!(problems.is_empty(), "{topic}: {problems:?}");
    }
}

#[test]
fn one_message_per_step_with_increasing_times() {
    let channels = read_back(&record());
    for (topic, c) in &channels {
        let expected = if topic == SCENE_TOPIC {
            1
        } else {
            common::STEPS
        };
        assert_eq!(c.messages.len(), expected, "{topic}");
        assert!(c.times.windows(2).all(|w| w[0] < w[1]), "{topic}");
        assert_eq!(c.times[0], common::TS_NS, "{topic}");
        // The message's own timestamp agrees with the MCAP log time.
        for (m, &t) in c.messages.iter().zip(&c.times) {
            let stamp = if topic == TRANSFORMS_TOPIC {
                &m["transforms"][0]["timestamp"]
            } else if topic == SCENE_TOPIC {
                &m["entities"][0]["timestamp"]
            } else {
                &m["timestamp"]
            };
            let ns =
                stamp["sec"].as_u64().unwrap() * 1_000_000_000 + stamp["nsec"].as_u64().unwrap();
            assert_eq!(ns, t, "{topic}");
        }
    }
    assert_eq!(
        channels[TRANSFORMS_TOPIC].times.last(),
        Some(&(common::STEPS as u64 * common::TS_NS))
    );
}

#[test]
fn every_message_has_the_required_fields_of_its_schema() {
    let channels = read_back(&record());
    let mut checked = 0;
    for (topic, c) in &channels {
        for (i, m) in c.messages.iter().enumerate() {
            let problems = message_problems(&c.schema, m);
            assert!(problems.is_empty(), "{topic} message {i}: {problems:?}");
            checked += 1;
        }
    }
    assert_eq!(checked, 1 + 5 * common::STEPS);
}

#[test]
fn the_required_check_can_fail() {
    let channels = read_back(&record());
    let tf = &channels[TRANSFORMS_TOPIC];
    let mut m = tf.messages[3].clone();
    m["transforms"][2]["rotation"]
        .as_object_mut()
        .unwrap()
        .remove("w");
    m["transforms"][0]["child_frame_id"] = Value::from(7);
    let problems = message_problems(&tf.schema, &m);
    assert_eq!(
        problems,
        [
            "$.transforms[0].child_frame_id: 7 is not of type \"string\"",
            "$.transforms[2].rotation.w: required field missing",
        ]
    );
    let scene = &channels[SCENE_TOPIC];
    let mut m = scene.messages[0].clone();
    m["entities"][1]["cylinders"][0]
        .as_object_mut()
        .unwrap()
        .remove("size");
    assert_eq!(
        message_problems(&scene.schema, &m),
        ["$.entities[1].cylinders[0].size: required field missing"]
    );
    let reward = &channels["/esrl/reward"];
    let mut m = reward.messages[0].clone();
    m.as_object_mut().unwrap().remove("alive");
    assert_eq!(
        message_problems(&reward.schema, &m),
        ["$.alive: required field missing"]
    );
}

#[test]
fn foxglove_parser_rules_can_fail() {
    let bad: Value = serde_json::json!({
        "type": "object",
        "properties": {
            "ok": {"type": "number"},
            "untyped": {"description": "no type"},
            "nested": {"type": "object"},
            "list": {"type": "array", "items": {"type": "null"}}
        }
    });
    let mut problems = foxglove_schema_problems(&bad);
    problems.sort();
    assert_eq!(
        problems,
        [
            "$.list: unsupported array item type Some(\"null\")",
            "$.nested: object without properties",
            "$.untyped: unsupported type None",
        ]
    );
}

#[test]
fn scalar_values_and_metadata_read_back() {
    let bytes = record();
    let torque = read_scalars(&bytes, "/esrl/joints/torque").unwrap();
    assert_eq!(torque.fields, common::ACTUATORS);
    assert_eq!(torque.values.len(), common::STEPS);
    for (i, row) in torque.values.iter().enumerate() {
        assert_eq!(row, &common::frame(i).scalars[1]);
    }
    assert_eq!(torque.time_ns[9], 10 * common::TS_NS);
    // The metadata record is in the file's summary.
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    assert_eq!(summary.metadata_indexes.len(), 1);
    let meta = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).unwrap();
    assert_eq!(meta.name, "esrl");
    assert_eq!(meta.metadata["agent"], "es-sac");
}
