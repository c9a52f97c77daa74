//! Foxglove-ready MCAP recordings of rollouts: a moving 3D robot plus plottable channels.
//!
//! A [`Scene`] lists the robot's links, each made of primitive [`Shape`]s (box, cylinder,
//! sphere, capsule) placed in the link frame, plus static shapes in the `world` frame; a
//! [`Frame`] gives, per control step, each link's world [`Pose`] and the values of declared
//! [`ScalarTopic`]s (joint angles, torques, power, contact forces, reward terms, ...).
//! [`RolloutWriter`] writes JSON messages (message encoding `json`, schema encoding
//! `jsonschema`, schema JSON text embedded in the file):
//!
//! | topic | schema | messages |
//! |---|---|---|
//! | [`SCENE_TOPIC`] `/scene` | `foxglove.SceneUpdate` | one, at the first frame: an entity per link, `id` = `frame_id` = link name, `frame_locked` so it moves with its frame (plus entity `world` for static shapes) |
//! | [`TRANSFORMS_TOPIC`] `/tf` | `foxglove.FrameTransforms` | one per frame: `world` → each link |
//! | each [`ScalarTopic`] | its own (e.g. `esrl.joints.torque`) | one per frame: `{"timestamp": {sec, nsec}, field: number, ...}` |
//!
//! Foxglove has no capsule primitive: a [`Geometry::Capsule`] is drawn as a cylinder and two
//! spheres. Open the file in Foxglove, add a 3D panel (display frame `world`) and a Plot panel
//! with paths like `/esrl/joints/torque.left_knee`.
//!
//! ```
//! use esrl_record::*;
//! use std::io::Cursor;
//!
//! let scene = Scene {
//!     links: vec![LinkVisual {
//!         name: "torso".into(),
//!         shapes: vec![Shape {
//!             geometry: Geometry::Box { size: [0.3, 0.2, 0.5] },
//!             pose: Pose::IDENTITY,
//!             rgba: [0.2, 0.4, 0.8, 1.0],
//!         }],
//!     }],
//!     world_shapes: vec![],
//! }
//! .with_track(50.0);
//! let topics = [ScalarTopic::new("/esrl/reward", &["total", "velocity"])];
//! let mut w = RolloutWriter::new(Cursor::new(Vec::new()), &scene, &topics, RecordOptions::default()).unwrap();
//! for step in 0..3u64 {
//!     w.write_frame(&Frame {
//!         time_ns: (step + 1) * 25_000_000,
//!         link_poses: vec![Pose::from_translation([0.1 * step as f64, 0.0, 1.0])],
//!         scalars: vec![vec![1.0, 0.5]],
//!     })
//!     .unwrap();
//! }
//! let (cursor, stats) = w.finish().unwrap();
//! assert_eq!(stats.messages, 1 + 3 + 3);
//! let bytes = cursor.into_inner();
//! assert_eq!(read_channel(&bytes, TRANSFORMS_TOPIC).unwrap().len(), 3);
//! assert_eq!(read_scalars(&bytes, "/esrl/reward").unwrap().values[2], vec![1.0, 0.5]);
//! ```
//!
//! Limitations: chunks are uncompressed (mcap is built without zstd/lz4); the scene is
//! published once, so shapes cannot change during a recording; values must be finite (a NaN
//! frame is refused rather than written as JSON `null`); the reader loads the whole file.

mod error;
mod messages;
mod reader;
mod scene;
mod schemas;
mod validate;
mod writer;

pub use error::{RecordError, Result};
pub use reader::{
    channels, read_channel, read_channel_file, read_file, read_scalars, ChannelInfo,
    RecordedMessage, ScalarSeries,
};
pub use scene::{Frame, Geometry, LinkVisual, Pose, Scene, Shape};
pub use schemas::{
    ScalarTopic, FRAME_TRANSFORMS_SCHEMA, FRAME_TRANSFORMS_SCHEMA_JSON, MESSAGE_ENCODING,
    SCENE_UPDATE_SCHEMA, SCENE_UPDATE_SCHEMA_JSON, SCHEMA_ENCODING,
};
pub use validate::{foxglove_schema_problems, message_problems};
pub use writer::{
    write_recording, RecordOptions, RecordingStats, RolloutWriter, METADATA_NAME, SCENE_TOPIC,
    TRANSFORMS_TOPIC, WORLD_FRAME,
};
