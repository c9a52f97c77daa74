//! Writes a synthetic 4-second recording (a box torso and two swinging capsule legs walking
//! along +x) to open in Foxglove: `cargo run --release -p esrl-record --example synthetic -- out.mcap`.

use std::path::PathBuf;

use esrl_record::{
    write_recording, Frame, Geometry, LinkVisual, Pose, RecordOptions, ScalarTopic, Scene, Shape,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "synthetic.mcap".into()),
    );
    let leg = |name: &str| LinkVisual {
        name: name.into(),
        shapes: vec![Shape {
            geometry: Geometry::Capsule {
                radius: 0.06,
                length: 0.8,
            },
            pose: Pose::from_translation([0.0, 0.0, -0.4]),
            rgba: [0.9, 0.5, 0.2, 1.0],
        }],
    };
    let scene = Scene {
        links: vec![
            LinkVisual {
                name: "torso".into(),
                shapes: vec![Shape {
                    geometry: Geometry::Box {
                        size: [0.2, 0.35, 0.6],
                    },
                    pose: Pose::IDENTITY,
                    rgba: [0.2, 0.4, 0.8, 1.0],
                }],
            },
            leg("left_leg"),
            leg("right_leg"),
        ],
        world_shapes: vec![],
    }
    .with_track(50.0);
    let topics = [ScalarTopic::new(
        "/esrl/joints/angle",
        &["left_hip", "right_hip"],
    )];
    let frames: Vec<Frame> = (1..=160u64)
        .map(|i| {
            let t = i as f64 * 0.025;
            let x = 1.0 * t;
            let swing = 0.4 * (2.0 * std::f64::consts::PI * t).sin();
            // Rotation by angle a about +y: quaternion [0, sin(a/2), 0, cos(a/2)].
            let hip = |a: f64| Pose {
                translation: [x, 0.0, 0.95],
                rotation: [0.0, (a / 2.0).sin(), 0.0, (a / 2.0).cos()],
            };
            let mut left = hip(swing);
            let mut right = hip(-swing);
            left.translation[1] = 0.1;
            right.translation[1] = -0.1;
            Frame {
                time_ns: i * 25_000_000,
                link_poses: vec![Pose::from_translation([x, 0.0, 1.25]), left, right],
                scalars: vec![vec![swing, -swing]],
            }
        })
        .collect();
    let stats = write_recording(&path, &scene, &topics, &frames, RecordOptions::default())?;
    println!(
        "{}: {} frames, {} messages",
        path.display(),
        stats.frames,
        stats.messages
    );
    Ok(())
}
