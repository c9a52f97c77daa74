//! The scene to draw: links made of primitive shapes, and their poses per frame.

use serde::{Deserialize, Serialize};

use crate::error::{RecordError, Result};

/// A rigid transform: translation (m) and unit quaternion `[x, y, z, w]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Translation `[x, y, z]` (m).
    pub translation: [f64; 3],
    /// Rotation as a quaternion `[x, y, z, w]` (normalised when written; must not be zero).
    pub rotation: [f64; 4],
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// No translation, no rotation.
    pub const IDENTITY: Pose = Pose {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };

    /// A pure translation.
    pub fn from_translation(translation: [f64; 3]) -> Self {
        Self {
            translation,
            rotation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    /// The point `p` (in this pose's child frame) expressed in its parent frame: R·p + t.
    pub fn transform_point(&self, p: [f64; 3]) -> [f64; 3] {
        let [qx, qy, qz, qw] = self.rotation;
        // v' = v + 2w(q×v) + 2 q×(q×v), q the vector part of a unit quaternion.
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let q = [qx, qy, qz];
        let c1 = cross(q, p);
        let c2 = cross(q, c1);
        [
            p[0] + 2.0 * qw * c1[0] + 2.0 * c2[0] + self.translation[0],
            p[1] + 2.0 * qw * c1[1] + 2.0 * c2[1] + self.translation[1],
            p[2] + 2.0 * qw * c1[2] + 2.0 * c2[2] + self.translation[2],
        ]
    }

    /// Checks finiteness and a non-zero quaternion; returns the pose with a unit quaternion.
    pub(crate) fn normalized(&self) -> std::result::Result<Pose, String> {
        if self.translation.iter().any(|v| !v.is_finite()) {
            return Err(format!("non-finite translation {:?}", self.translation));
        }
        if self.rotation.iter().any(|v| !v.is_finite()) {
            return Err(format!("non-finite rotation {:?}", self.rotation));
        }
        let norm = self.rotation.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm < 1e-9 {
            return Err(format!("zero quaternion {:?}", self.rotation));
        }
        Ok(Pose {
            translation: self.translation,
            rotation: self.rotation.map(|v| v / norm),
        })
    }
}

/// Primitive geometry, dimensions in metres. Cylinders and capsules run along their local z
/// axis (as in URDF).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Geometry {
    /// A box with edge lengths `size = [x, y, z]`.
    Box {
        /// Edge lengths (m).
        size: [f64; 3],
    },
    /// A cylinder of `radius` and `length` along z.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length along z (m).
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A capsule: a cylinder of `length` along z capped by two spheres of `radius` centred on
    /// its end faces (total length `length + 2·radius`). Foxglove has no capsule primitive, so
    /// it is drawn as one cylinder and two spheres.
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylindrical part (m).
        length: f64,
    },
}

/// One primitive shape of a link, placed in the link's frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Shape {
    /// The geometry.
    pub geometry: Geometry,
    /// Pose of the shape's centre in the link frame (URDF `<origin>`).
    pub pose: Pose,
    /// Colour `[r, g, b, a]`, each in 0..=1.
    pub rgba: [f64; 4],
}

/// A rigid link: a named frame with the shapes drawn in it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinkVisual {
    /// Link name, used as the Foxglove frame id and entity id (must not be `world`).
    pub name: String,
    /// Shapes in the link frame.
    pub shapes: Vec<Shape>,
}

/// Everything drawn: moving links plus static shapes in the `world` frame (ground, track).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Links, in the order of [`Frame::link_poses`](crate::Frame::link_poses).
    pub links: Vec<LinkVisual>,
    /// Static shapes in the `world` frame.
    pub world_shapes: Vec<Shape>,
}

impl Scene {
    /// Adds a flat track along +x to the world shapes: a grey ground slab from x = −2 m to
    /// `length + 5` m, 4 m wide, top face at z = 0, with white start (x = 0) and finish
    /// (x = `length`) lines and a thin centre line at y = 0.
    pub fn with_track(mut self, length: f64) -> Self {
        let ground_len = length + 7.0;
        let slab = Shape {
            geometry: Geometry::Box {
                size: [ground_len, 4.0, 0.02],
            },
            pose: Pose::from_translation([ground_len / 2.0 - 2.0, 0.0, -0.01]),
            rgba: [0.55, 0.57, 0.6, 1.0],
        };
        let line = |x: f64| Shape {
            geometry: Geometry::Box {
                size: [0.05, 4.0, 0.002],
            },
            pose: Pose::from_translation([x, 0.0, 0.001]),
            rgba: [1.0, 1.0, 1.0, 1.0],
        };
        let centre = Shape {
            geometry: Geometry::Box {
                size: [length, 0.02, 0.002],
            },
            pose: Pose::from_translation([length / 2.0, 0.0, 0.001]),
            rgba: [0.8, 0.8, 0.8, 1.0],
        };
        self.world_shapes
            .extend([slab, line(0.0), line(length), centre]);
        self
    }

    /// Checks names (non-empty, unique, not `world`), dimensions (finite, > 0; a capsule's
    /// cylindrical length may be 0), colours (finite, in 0..=1) and poses.
    pub fn validate(&self) -> Result<()> {
        let mut seen = std::collections::HashSet::new();
        for (i, link) in self.links.iter().enumerate() {
            let label = format!("links[{i}] `{}`", link.name);
            let bad = |why: String| RecordError::InvalidScene {
                what: label.clone(),
                why,
            };
            if link.name.is_empty() {
                return Err(bad("empty link name".into()));
            }
            if link.name == crate::WORLD_FRAME {
                return Err(bad(format!("`{}` is the fixed frame", crate::WORLD_FRAME)));
            }
            if !seen.insert(link.name.as_str()) {
                return Err(bad("duplicate link name".into()));
            }
            for (j, shape) in link.shapes.iter().enumerate() {
                validate_shape(shape, &format!("{label} shapes[{j}]"))?;
            }
        }
        for (j, shape) in self.world_shapes.iter().enumerate() {
            validate_shape(shape, &format!("world_shapes[{j}]"))?;
        }
        Ok(())
    }
}

fn validate_shape(shape: &Shape, label: &str) -> Result<()> {
    let bad = |field: &str, why: String| RecordError::InvalidScene {
        what: format!("{label} {field}"),
        why,
    };
    let positive = |field: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(bad(field, format!("{v} must be finite and > 0")))
        }
    };
    match shape.geometry {
        Geometry::Box { size } => {
            for (axis, v) in ["x", "y", "z"].iter().zip(size) {
                positive(&format!("size.{axis}"), v)?;
            }
        }
        Geometry::Cylinder { radius, length } => {
            positive("radius", radius)?;
            positive("length", length)?;
        }
        Geometry::Sphere { radius } => positive("radius", radius)?,
        Geometry::Capsule { radius, length } => {
            positive("radius", radius)?;
            if !(length.is_finite() && length >= 0.0) {
                return Err(bad("length", format!("{length} must be finite and ≥ 0")));
            }
        }
    }
    if shape.rgba.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(bad("rgba", format!("{:?} must be in 0..=1", shape.rgba)));
    }
    shape.pose.normalized().map_err(|why| bad("pose", why))?;
    Ok(())
}

/// One recorded step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Simulated time since reset (ns); must increase strictly from frame to frame.
    pub time_ns: u64,
    /// World pose of each link, in the order of [`Scene::links`].
    pub link_poses: Vec<Pose>,
    /// Values of each scalar topic, in the order of the topics given to the writer, each with
    /// one value per field of that topic.
    pub scalars: Vec<Vec<f64>>,
}
