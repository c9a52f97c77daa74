//! Contract: unusable scenes, topics and frames are refused with an error naming the item,
//! a refused frame writes nothing and leaves the recording usable, and files appear under
//! their final name only when finished.

mod common;

use std::io::Cursor;

use esrl_record::{
    read_channel, read_channel_file, write_recording, Geometry, LinkVisual, Pose, RecordError,
    RecordOptions, RolloutWriter, ScalarTopic, Scene, Shape, TRANSFORMS_TOPIC,
};

fn new_writer(
    scene: &Scene,
    topics: &[ScalarTopic],
) -> esrl_record::Result<RolloutWriter<Cursor<Vec<u8>>>> {
    RolloutWriter::new(
        Cursor::new(Vec::new()),
        scene,
        topics,
        RecordOptions::default(),
    )
}

fn error_text(r: esrl_record::Result<RolloutWriter<Cursor<Vec<u8>>>>) -> String {
    match r {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_scenes() {
    let mut s = common::scene();
    s.links[2].name = "left_thigh".into();
    let e = error_text(new_writer(&s, &[]));
    assert!(
        e.contains("links[2] `left_thigh`") && e.contains("duplicate"),
        "{e}"
    );

    let mut s = common::scene();
    s.links[0].name = "world".into();
    assert!(error_text(new_writer(&s, &[])).contains("fixed frame"));

    let mut s = common::scene();
    s.links[3].shapes[0].geometry = Geometry::Cylinder {
        radius: -0.05,
        length: 0.4,
    };
    let e = error_text(new_writer(&s, &[]));
    assert_eq!(
        e,
        "scene: links[3] `left_foot` shapes[0] radius: -0.05 must be finite and > 0"
    );

    let mut s = common::scene();
    s.links[0].shapes[1].rgba = [1.0, 1.5, 0.0, 1.0];
    assert!(error_text(new_writer(&s, &[])).contains("rgba"));

    let mut s = common::scene();
    s.world_shapes[0].pose.rotation = [0.0; 4];
    let e = error_text(new_writer(&s, &[]));
    assert!(
        e.contains("world_shapes[0] pose") && e.contains("zero quaternion"),
        "{e}"
    );
}

#[test]
fn bad_topics() {
    let s = common::scene();
    let cases = [
        (ScalarTopic::new("reward", &["a"]), "start with `/`"),
        (ScalarTopic::new("/r", &["1a"]), "field `1a`"),
        (ScalarTopic::new("/r", &["left knee"]), "field `left knee`"),
        (ScalarTopic::new("/r", &["timestamp"]), "reserved"),
        (ScalarTopic::new("/r", &["a", "a"]), "duplicate field"),
        (ScalarTopic::new("/tf", &["a"]), "used twice"),
    ];
    for (topic, expected) in cases {
        let e = error_text(new_writer(&s, &[topic]));
        assert!(e.contains(expected), "{e}");
    }
    let twice: Vec<ScalarTopic> = common::topics()
        .into_iter()
        .chain(common::topics())
        .collect();
    let e = error_text(new_writer(&s, &twice));
    assert!(
        e.contains("/esrl/joints/angle") && e.contains("used twice"),
        "{e}"
    );
}

#[test]
fn bad_frames_are_refused_and_nothing_is_written() {
    let mut w = new_writer(&common::scene(), &common::topics()).unwrap();
    w.write_frame(&common::frame(0)).unwrap();

    let mut f = common::frame(1);
    f.scalars[3][0] = f64::NAN;
    let e = w.write_frame(&f).unwrap_err();
    assert!(matches!(e, RecordError::InvalidFrame { frame: 1, .. }));
    assert!(e.to_string().contains("/esrl/reward.total"), "{e}");

    let mut f = common::frame(1);
    f.link_poses.pop();
    assert!(w
        .write_frame(&f)
        .unwrap_err()
        .to_string()
        .contains("6 poses for 7 links"));

    let mut f = common::frame(1);
    f.link_poses[4].translation[1] = f64::INFINITY;
    assert!(w
        .write_frame(&f)
        .unwrap_err()
        .to_string()
        .contains("link_poses[4]"));

    let mut f = common::frame(1);
    f.scalars[2].push(1.0);
    assert!(w
        .write_frame(&f)
        .unwrap_err()
        .to_string()
        .contains("3 values for 2 fields"));

    let mut f = common::frame(1);
    f.scalars.pop();
    assert!(w
        .write_frame(&f)
        .unwrap_err()
        .to_string()
        .contains("3 value lists for 4 topics"));

    let e = w.write_frame(&common::frame(0)).unwrap_err();
    assert!(
        e.to_string().contains("not after the previous frame"),
        "{e}"
    );

    // Still usable: the next good frame goes in, and only good frames are in the file.
    w.write_frame(&common::frame(1)).unwrap();
    assert_eq!(w.frames(), 2);
    let (cursor, stats) = w.finish().unwrap();
    assert_eq!(stats.messages, 1 + 2 * 5);
    let tf = read_channel(&cursor.into_inner(), TRANSFORMS_TOPIC).unwrap();
    assert_eq!(tf.iter().map(|m| m.sequence).collect::<Vec<_>>(), [0, 1]);
}

#[test]
fn files_are_written_atomically() {
    let dir = std::env::temp_dir().join(format!("esrl-record-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rollout.mcap");
    let partial = dir.join("rollout.mcap.partial");

    let frames: Vec<_> = (0..10).map(common::frame).collect();
    let stats = write_recording(
        &path,
        &common::scene(),
        &common::topics(),
        &frames,
        RecordOptions::default(),
    )
    .unwrap();
    assert_eq!(stats.frames, 10);
    assert!(path.exists() && !partial.exists());
    assert_eq!(
        read_channel_file(&path, TRANSFORMS_TOPIC).unwrap().len(),
        10
    );

    // An unfinished writer never appears under the final name.
    let other = dir.join("unfinished.mcap");
    let mut w = RolloutWriter::create(
        &other,
        &common::scene(),
        &common::topics(),
        RecordOptions::default(),
    )
    .unwrap();
    w.write_frame(&common::frame(0)).unwrap();
    drop(w);
    assert!(!other.exists());
    assert!(dir.join("unfinished.mcap.partial").exists());

    let missing = read_channel_file(&dir.join("nope.mcap"), "/tf").unwrap_err();
    assert!(matches!(missing, RecordError::Io { .. }) && missing.to_string().contains("nope.mcap"));
    let unknown = read_channel_file(&path, "/nope").unwrap_err();
    assert!(
        unknown.to_string().contains("no channel `/nope`") && unknown.to_string().contains("/tf")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn empty_link_is_fine_and_bad_shapes_name_their_field() {
    let scene = Scene {
        links: vec![LinkVisual {
            name: "base".into(),
            shapes: vec![Shape {
                geometry: Geometry::Box {
                    size: [0.1, 0.0, 0.1],
                },
                pose: Pose::IDENTITY,
                rgba: [0.0, 0.0, 0.0, 1.0],
            }],
        }],
        world_shapes: vec![],
    };
    let e = error_text(new_writer(&scene, &[]));
    assert!(e.contains("shapes[0] size.y"), "{e}");
}
