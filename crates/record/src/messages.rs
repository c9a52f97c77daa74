//! Serde mirrors of the Foxglove messages that esrl writes (JSON encoding), built from a
//! [`Scene`] and [`Frame`]s.

use serde::Serialize;

use crate::scene::{Geometry, Pose, Scene};
use crate::WORLD_FRAME;

/// `time` / `duration` of the Foxglove schemas.
#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct Time {
    pub sec: u64,
    pub nsec: u32,
}

impl Time {
    pub fn from_ns(ns: u64) -> Self {
        Self {
            sec: ns / 1_000_000_000,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl From<[f64; 3]> for Vector3 {
    fn from([x, y, z]: [f64; 3]) -> Self {
        Self { x, y, z }
    }
}

#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl From<[f64; 4]> for Quaternion {
    fn from([x, y, z, w]: [f64; 4]) -> Self {
        Self { x, y, z, w }
    }
}

#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct PoseMsg {
    pub position: Vector3,
    pub orientation: Quaternion,
}

impl From<&Pose> for PoseMsg {
    fn from(p: &Pose) -> Self {
        Self {
            position: p.translation.into(),
            orientation: p.rotation.into(),
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct Color {
    pub r: f64,
    pub g: f64,
    pub b: f64,
    pub a: f64,
}

impl From<[f64; 4]> for Color {
    fn from([r, g, b, a]: [f64; 4]) -> Self {
        Self { r, g, b, a }
    }
}

/// `foxglove.CubePrimitive` and `foxglove.SpherePrimitive` share this shape.
#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct SizedPrimitive {
    pub pose: PoseMsg,
    pub size: Vector3,
    pub color: Color,
}

#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct CylinderPrimitive {
    pub pose: PoseMsg,
    pub size: Vector3,
    pub bottom_scale: f64,
    pub top_scale: f64,
    pub color: Color,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct KeyValuePair {
    pub key: String,
    pub value: String,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct SceneEntity {
    pub timestamp: Time,
    pub frame_id: String,
    pub id: String,
    pub lifetime: Time,
    pub frame_locked: bool,
    pub metadata: Vec<KeyValuePair>,
    pub cubes: Vec<SizedPrimitive>,
    pub spheres: Vec<SizedPrimitive>,
    pub cylinders: Vec<CylinderPrimitive>,
}

/// `foxglove.SceneEntityDeletion` (esrl never deletes, the list is always empty).
#[derive(Debug, Clone, Serialize)]
pub(crate) struct SceneEntityDeletion {}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct SceneUpdate {
    pub deletions: Vec<SceneEntityDeletion>,
    pub entities: Vec<SceneEntity>,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct FrameTransform<'a> {
    pub timestamp: Time,
    pub parent_frame_id: &'a str,
    pub child_frame_id: &'a str,
    pub translation: Vector3,
    pub rotation: Quaternion,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct FrameTransforms<'a> {
    pub transforms: Vec<FrameTransform<'a>>,
}

/// An entity for `shapes` drawn in `frame_id` (frame-locked, so it follows the frame).
fn entity(frame_id: &str, shapes: &[crate::Shape], time: Time) -> SceneEntity {
    let mut e = SceneEntity {
        timestamp: time,
        frame_id: frame_id.to_string(),
        id: frame_id.to_string(),
        lifetime: Time { sec: 0, nsec: 0 },
        frame_locked: true,
        metadata: Vec::new(),
        cubes: Vec::new(),
        spheres: Vec::new(),
        cylinders: Vec::new(),
    };
    for shape in shapes {
        // Scene::validate ran first, so normalisation cannot fail; keep the raw pose otherwise.
        let pose = shape.pose.normalized().unwrap_or(shape.pose);
        let color = Color::from(shape.rgba);
        let sphere = |centre: [f64; 3], radius: f64| SizedPrimitive {
            pose: PoseMsg::from(&Pose {
                translation: centre,
                rotation: pose.rotation,
            }),
            size: [2.0 * radius; 3].into(),
            color,
        };
        let cylinder = |radius: f64, length: f64| CylinderPrimitive {
            pose: PoseMsg::from(&pose),
            size: [2.0 * radius, 2.0 * radius, length].into(),
            bottom_scale: 1.0,
            top_scale: 1.0,
            color,
        };
        match shape.geometry {
            Geometry::Box { size } => e.cubes.push(SizedPrimitive {
                pose: PoseMsg::from(&pose),
                size: size.into(),
                color,
            }),
            Geometry::Sphere { radius } => e.spheres.push(sphere(pose.translation, radius)),
            Geometry::Cylinder { radius, length } => e.cylinders.push(cylinder(radius, length)),
            Geometry::Capsule { radius, length } => {
                if length > 0.0 {
                    e.cylinders.push(cylinder(radius, length));
                }
                for end in [-0.5 * length, 0.5 * length] {
                    e.spheres
                        .push(sphere(pose.transform_point([0.0, 0.0, end]), radius));
                }
            }
        }
    }
    e
}

/// The scene as one `foxglove.SceneUpdate`: one entity per link (id and frame = link name),
/// plus an entity `world` for the static shapes if there are any.
pub(crate) fn scene_update(scene: &Scene, time: Time) -> SceneUpdate {
    let mut entities: Vec<SceneEntity> = scene
        .links
        .iter()
        .map(|l| entity(&l.name, &l.shapes, time))
        .collect();
    if !scene.world_shapes.is_empty() {
        entities.push(entity(WORLD_FRAME, &scene.world_shapes, time));
    }
    SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}
