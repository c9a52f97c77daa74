//! Contract: the scene becomes one frame-locked Foxglove entity per link (id = frame_id =
//! link name) with primitive sizes and poses as Foxglove defines them (cube size = edges,
//! sphere size = diameters, cylinder size = bounding box with length on z, capsule = cylinder +
//! two spheres), and every frame becomes `world → link` transforms equal to the input poses.

mod common;

use std::io::Cursor;

use esrl_record::{
    read_channel, Frame, Geometry, LinkVisual, Pose, RecordOptions, RolloutWriter, Scene, Shape,
    SCENE_TOPIC, TRANSFORMS_TOPIC,
};
use serde_json::Value;

fn write(scene: &Scene, frames: &[Frame]) -> Vec<u8> {
    let mut w = RolloutWriter::new(
        Cursor::new(Vec::new()),
        scene,
        &[],
        RecordOptions::default(),
    )
    .unwrap();
    for f in frames {
        w.write_frame(f).unwrap();
    }
    w.finish().unwrap().0.into_inner()
}

fn xyz(v: &Value) -> [f64; 3] {
    [
        v["x"].as_f64().unwrap(),
        v["y"].as_f64().unwrap(),
        v["z"].as_f64().unwrap(),
    ]
}

fn assert_close(a: [f64; 3], b: [f64; 3]) {
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < 1e-12, "{a:?} vs {b:?}");
    }
}

fn scene_message(scene: &Scene, poses: usize) -> Value {
    let frame = Frame {
        time_ns: 1,
        link_poses: vec![Pose::IDENTITY; poses],
        scalars: vec![],
    };
    let bytes = write(scene, &[frame]);
    let mut msgs = read_channel(&bytes, SCENE_TOPIC).unwrap();
    assert_eq!(msgs.len(), 1);
    msgs.remove(0).data
}

#[test]
fn one_frame_locked_entity_per_link() {
    let scene = common::scene();
    let m = scene_message(&scene, scene.links.len());
    let entities = m["entities"].as_array().unwrap();
    assert_eq!(entities.len(), scene.links.len() + 1, "links + world");
    for (e, link) in entities.iter().zip(&scene.links) {
        assert_eq!(e["id"], link.name.as_str());
        assert_eq!(e["frame_id"], link.name.as_str());
        assert_eq!(e["frame_locked"], true);
        assert_eq!(e["lifetime"], serde_json::json!({"sec": 0, "nsec": 0}));
    }
    let world = entities.last().unwrap();
    assert_eq!(world["frame_id"], "world");
    let cubes = world["cubes"].as_array().unwrap();
    assert_eq!(cubes.len(), 4, "ground slab, start, finish, centre line");
    assert_close(xyz(&cubes[2]["pose"]["position"]), [50.0, 0.0, 0.001]);
    assert!(m["deletions"].as_array().unwrap().is_empty());
}

#[test]
fn primitive_sizes_by_hand() {
    let scene = common::scene();
    let m = scene_message(&scene, scene.links.len());
    let torso = &m["entities"][0];
    assert_close(xyz(&torso["cubes"][0]["size"]), [0.2, 0.35, 0.6]);
    assert_close(xyz(&torso["spheres"][0]["size"]), [0.2, 0.2, 0.2]);
    assert_close(
        xyz(&torso["spheres"][0]["pose"]["position"]),
        [0.0, 0.0, 0.42],
    );
    assert_eq!(
        torso["cubes"][0]["color"],
        serde_json::json!({"r": 0.3, "g": 0.5, "b": 0.8, "a": 1.0})
    );

    // left_thigh: capsule r 0.06, cylinder part 0.3, centred at z = −0.2.
    let thigh = &m["entities"][1];
    assert_eq!(thigh["id"], "left_thigh");
    let cyl = &thigh["cylinders"][0];
    assert_close(xyz(&cyl["size"]), [0.12, 0.12, 0.3]);
    assert_close(xyz(&cyl["pose"]["position"]), [0.0, 0.0, -0.2]);
    assert_eq!(
        (cyl["bottom_scale"].as_f64(), cyl["top_scale"].as_f64()),
        (Some(1.0), Some(1.0))
    );
    let caps = thigh["spheres"].as_array().unwrap();
    assert_eq!(caps.len(), 2);
    assert_close(xyz(&caps[0]["pose"]["position"]), [0.0, 0.0, -0.35]);
    assert_close(xyz(&caps[1]["pose"]["position"]), [0.0, 0.0, -0.05]);
    assert_close(xyz(&caps[0]["size"]), [0.12, 0.12, 0.12]);

    // left_shank: a plain cylinder.
    assert_close(
        xyz(&m["entities"][2]["cylinders"][0]["size"]),
        [0.1, 0.1, 0.4],
    );
}

#[test]
fn rotated_capsule_caps_follow_its_axis() {
    // Rotated +90° about y, the capsule's z axis points along +x.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let scene = Scene {
        links: vec![LinkVisual {
            name: "arm".into(),
            shapes: vec![Shape {
                geometry: Geometry::Capsule {
                    radius: 0.05,
                    length: 0.4,
                },
                pose: Pose {
                    translation: [1.0, 0.0, 0.0],
                    rotation: [0.0, h, 0.0, h],
                },
                rgba: [1.0, 0.0, 0.0, 0.5],
            }],
        }],
        world_shapes: vec![],
    };
    let m = scene_message(&scene, 1);
    let caps = m["entities"][0]["spheres"].as_array().unwrap();
    assert_close(xyz(&caps[0]["pose"]["position"]), [0.8, 0.0, 0.0]);
    assert_close(xyz(&caps[1]["pose"]["position"]), [1.2, 0.0, 0.0]);
    assert_eq!(
        m["entities"].as_array().unwrap().len(),
        1,
        "no world entity without shapes"
    );
}

#[test]
fn transforms_equal_the_input_poses() {
    let scene = common::scene();
    let frames: Vec<Frame> = (0..5)
        .map(|i| {
            let mut f = common::frame(i);
            f.scalars.clear();
            f
        })
        .collect();
    let bytes = write(&scene, &frames);
    let tf = read_channel(&bytes, TRANSFORMS_TOPIC).unwrap();
    assert_eq!(tf.len(), 5);
    for (msg, frame) in tf.iter().zip(&frames) {
        let ts = msg.data["transforms"].as_array().unwrap();
        assert_eq!(ts.len(), scene.links.len());
        for ((t, link), pose) in ts.iter().zip(&scene.links).zip(&frame.link_poses) {
            assert_eq!(t["parent_frame_id"], "world");
            assert_eq!(t["child_frame_id"], link.name.as_str());
            assert_close(xyz(&t["translation"]), pose.translation);
            let r = &t["rotation"];
            let q = [
                r["x"].as_f64(),
                r["y"].as_f64(),
                r["z"].as_f64(),
                r["w"].as_f64(),
            ];
            for (a, b) in q.iter().zip(pose.rotation) {
                assert!((a.unwrap() - b).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn quaternions_are_normalised() {
    let scene = Scene {
        links: vec![LinkVisual {
            name: "box".into(),
            shapes: vec![],
        }],
        world_shapes: vec![],
    };
    let frame = Frame {
        time_ns: 5,
        link_poses: vec![Pose {
            translation: [0.0; 3],
            rotation: [0.0, 0.0, 3.0, 4.0],
        }],
        scalars: vec![],
    };
    let bytes = write(&scene, &[frame]);
    let r = read_channel(&bytes, TRANSFORMS_TOPIC).unwrap()[0].data["transforms"][0]["rotation"]
        .clone();
    assert_eq!(
        r,
        serde_json::json!({"x": 0.0, "y": 0.0, "z": 0.6, "w": 0.8})
    );
}
