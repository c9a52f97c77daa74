//! A synthetic humanoid-like recording shared by the integration tests.

#![allow(dead_code)]

use esrl_record::{Frame, Geometry, LinkVisual, Pose, ScalarTopic, Scene, Shape};

pub const ACTUATORS: [&str; 6] = [
    "left_hip",
    "left_knee",
    "left_ankle",
    "right_hip",
    "right_knee",
    "right_ankle",
];

pub const STEPS: usize = 120;
pub const TS_NS: u64 = 25_000_000;

fn shape(geometry: Geometry, z: f64) -> Shape {
    Shape {
        geometry,
        pose: Pose::from_translation([0.0, 0.0, z]),
        rgba: [0.3, 0.5, 0.8, 1.0],
    }
}

/// torso (box + head sphere), thighs (capsules), shanks (cylinders), feet (boxes).
pub fn scene() -> Scene {
    let mut links = vec![LinkVisual {
        name: "torso".into(),
        shapes: vec![
            shape(
                Geometry::Box {
                    size: [0.2, 0.35, 0.6],
                },
                0.0,
            ),
            shape(Geometry::Sphere { radius: 0.1 }, 0.42),
        ],
    }];
    for side in ["left", "right"] {
        links.push(LinkVisual {
            name: format!("{side}_thigh"),
            shapes: vec![shape(
                Geometry::Capsule {
                    radius: 0.06,
                    length: 0.3,
                },
                -0.2,
            )],
        });
        links.push(LinkVisual {
            name: format!("{side}_shank"),
            shapes: vec![shape(
                Geometry::Cylinder {
                    radius: 0.05,
                    length: 0.4,
                },
                -0.2,
            )],
        });
        links.push(LinkVisual {
            name: format!("{side}_foot"),
            shapes: vec![shape(
                Geometry::Box {
                    size: [0.25, 0.1, 0.05],
                },
                -0.025,
            )],
        });
    }
    Scene {
        links,
        world_shapes: vec![],
    }
    .with_track(50.0)
}

pub fn topics() -> Vec<ScalarTopic> {
    vec![
        ScalarTopic::new("/esrl/joints/angle", &ACTUATORS),
        ScalarTopic::new("/esrl/joints/torque", &ACTUATORS),
        ScalarTopic::new("/esrl/contacts", &["left_foot", "right_foot"]),
        ScalarTopic::new(
            "/esrl/reward",
            &["total", "velocity", "lateral", "vertical", "power", "alive"],
        ),
    ]
}

/// Frame `i`: links walk forward at 1 m/s with a yaw wobble; scalars are simple functions of i.
pub fn frame(i: usize) -> Frame {
    let t = (i + 1) as f64 * TS_NS as f64 * 1e-9;
    let yaw = 0.1 * (3.0 * t).sin();
    let rotation = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
    let link_poses = (0..7)
        .map(|k| Pose {
            translation: [t, 0.01 * k as f64, 1.0 - 0.1 * k as f64],
            rotation,
        })
        .collect();
    let angles: Vec<f64> = (0..6).map(|j| 0.1 * j as f64 + t).collect();
    let torques: Vec<f64> = (0..6).map(|j| 10.0 * j as f64 - t).collect();
    Frame {
        time_ns: (i as u64 + 1) * TS_NS,
        link_poses,
        scalars: vec![
            angles,
            torques,
            vec![300.0 + i as f64, 400.0 - i as f64],
            vec![1.0, 1.0, -0.1, -0.2, -0.05, 0.025],
        ],
    }
}
