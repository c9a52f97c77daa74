//! A validated robot model: URDF → checked links, joints and shapes, ready to instantiate in
//! any number of Rapier worlds.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::UrdfError;
use crate::math::{self, Iso, M3, V3};

/// The humanoid of SPEC §1, embedded in the binary (`assets/humanoid.urdf`).
pub const HUMANOID_URDF: &str = include_str!("../../../assets/humanoid.urdf");

/// A collision primitive, in the URDF's conventions (cylinders along their local z axis).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// A box with full side lengths `size` (m) along local x, y, z.
    Box {
        /// Full side lengths, m.
        size: [f32; 3],
    },
    /// A cylinder along local z.
    Cylinder {
        /// Radius, m.
        radius: f32,
        /// Full length along z, m.
        length: f32,
    },
    /// A sphere.
    Sphere {
        /// Radius, m.
        radius: f32,
    },
}

/// One collision shape of a link with its pose in the link frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapeGeometry {
    /// The primitive.
    pub shape: Shape,
    /// Origin of the shape in the link frame, m.
    pub translation: [f32; 3],
    /// Orientation of the shape in the link frame, quaternion `[x, y, z, w]`.
    pub rotation: [f32; 4],
}

/// The collision geometry of one link (what recordings draw).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinkGeometry {
    /// Link name, as in the URDF.
    pub link: String,
    /// Its collision shapes (may be empty).
    pub shapes: Vec<ShapeGeometry>,
}

/// The world pose of one link frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinkPose {
    /// Link name, as in the URDF.
    pub name: String,
    /// Link frame origin in the world, m.
    pub translation: [f32; 3],
    /// Link frame orientation in the world, quaternion `[x, y, z, w]`.
    pub rotation: [f32; 4],
}

/// Joint types the simulator builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// Hinge with position limits.
    Revolute,
    /// Hinge without limits.
    Continuous,
    /// Rigid attachment (no degree of freedom).
    Fixed,
}

/// A validated link.
#[derive(Clone, Debug)]
pub struct LinkModel {
    /// Name, as in the URDF.
    pub name: String,
    /// Mass, kg (0 only for a massless root used with a fixed base).
    pub mass: f64,
    /// Centre of mass in the link frame, m.
    pub com: [f64; 3],
    /// Inertia tensor about the centre of mass, expressed in the link frame (the URDF tensor
    /// rotated by the `<inertial><origin rpy>`), kg·m².
    pub inertia: [[f64; 3]; 3],
    pub(crate) shapes: Vec<(Iso, Shape)>,
}

impl LinkModel {
    /// Collision shapes with their poses in the link frame.
    pub fn geometry(&self) -> LinkGeometry {
        LinkGeometry {
            link: self.name.clone(),
            shapes: self
                .shapes
                .iter()
                .map(|(iso, shape)| {
                    let q = math::mat_to_quat(&iso.r);
                    ShapeGeometry {
                        shape: *shape,
                        translation: iso.t.map(|v| v as f32),
                        rotation: q.map(|v| v as f32),
                    }
                })
                .collect(),
        }
    }
}

/// A validated joint.
#[derive(Clone, Debug)]
pub struct JointModel {
    /// Name, as in the URDF.
    pub name: String,
    /// Type.
    pub kind: JointKind,
    /// Index of the parent link in [`RobotModel::links`].
    pub parent: usize,
    /// Index of the child link in [`RobotModel::links`].
    pub child: usize,
    /// Unit joint axis in the joint (= child link) frame.
    pub axis: [f64; 3],
    /// Position limits `[lower, upper]`, rad, for a revolute joint with finite limits.
    pub limits: Option<[f64; 2]>,
    /// `<limit effort>`, N·m (infinite when the URDF gives none).
    pub effort: f64,
    /// `<dynamics damping>`, N·m·s/rad.
    pub damping: f64,
    /// `<dynamics friction>` (dry friction), N·m.
    pub friction: f64,
    pub(crate) origin: Iso,
}

impl JointModel {
    /// Whether the joint has a degree of freedom.
    pub fn is_movable(&self) -> bool {
        self.kind != JointKind::Fixed
    }

    /// The joint origin in the parent link frame: translation (m) and quaternion `[x, y, z, w]`.
    pub fn origin(&self) -> ([f64; 3], [f64; 4]) {
        (self.origin.t, math::mat_to_quat(&self.origin.r))
    }
}

/// Largest URDF file read, bytes (16 MiB; the humanoid is 14 kB).
pub const MAX_URDF_BYTES: u64 = 16 << 20;

/// Deepest element nesting of a URDF that is parsed (a URDF has 4 or 5 levels: robot, link,
/// visual, geometry, box); deeper XML is refused before the recursive parser sees it.
pub const MAX_XML_DEPTH: usize = 64;

/// Reads a text file that must be a regular file of at most `limit` bytes: devices such as
/// `/dev/zero`, pipes and oversized files are refused with an I/O error that says so,
/// before anything large is read.
pub fn read_text_file(path: &Path, limit: u64) -> std::io::Result<String> {
    use std::io::{Error, ErrorKind, Read};
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a device, pipe or folder)",
        ));
    }
    if meta.len() > limit {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "{} bytes, more than the {limit} this file may have",
                meta.len()
            ),
        ));
    }
    let mut text = String::new();
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!("more than the {limit} bytes this file may have"),
        ));
    }
    Ok(text)
}

/// The deepest element nesting of an XML text, counted without parsing: `<name` opens,
/// `</name` and `/>` close; comments, processing instructions, declarations and CDATA are
/// skipped. (Close enough for a bound: attribute values holding `/>` could only lower it.)
fn xml_depth(text: &str) -> usize {
    let b = text.as_bytes();
    let (mut depth, mut max, mut i) = (0usize, 0usize, 0usize);
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &text[i..];
        let skip_to = |end: &str| rest.find(end).map_or(b.len(), |k| i + k + end.len());
        if rest.starts_with("<!--") {
            i = skip_to("-->");
        } else if rest.starts_with("<![CDATA[") {
            i = skip_to("]]>");
        } else if rest.starts_with("<?") || rest.starts_with("<!") {
            i = skip_to(">");
        } else if rest.starts_with("</") {
            depth = depth.saturating_sub(1);
            i = skip_to(">");
        } else {
            let end = skip_to(">");
            let self_closing = end >= 2 && b[end - 2] == b'/';
            if !self_closing {
                depth += 1;
                max = max.max(depth);
            }
            i = end;
        }
    }
    max
}

/// Most links a URDF may have (the humanoid has 14; a few hundred covers any legged robot).
pub const MAX_LINKS: usize = 256;

/// A robot parsed from URDF and validated: a tree of links with physical inertials and
/// primitive collision shapes, joined by revolute, continuous or fixed joints.
///
/// Parse once, share with [`Arc`], build as many worlds as needed.
#[derive(Clone, Debug)]
pub struct RobotModel {
    name: String,
    links: Vec<LinkModel>,
    joints: Vec<JointModel>,
    root: usize,
    /// Joint indices ordered so that every joint comes after the joint of its parent link.
    joint_order: Vec<usize>,
    /// For each link, the joint whose child it is (None for the root).
    parent_joint: Vec<Option<usize>>,
}

impl RobotModel {
    /// The embedded humanoid ([`HUMANOID_URDF`]).
    pub fn humanoid() -> Result<Self, UrdfError> {
        Self::from_urdf_str(HUMANOID_URDF)
    }

    /// The embedded humanoid, shared. It is parsed once per process.
    pub fn humanoid_shared() -> Result<Arc<Self>, UrdfError> {
        static CACHE: std::sync::OnceLock<Arc<RobotModel>> = std::sync::OnceLock::new();
        if let Some(m) = CACHE.get() {
            return Ok(m.clone());
        }
        let m = Arc::new(Self::humanoid()?);
        Ok(CACHE.get_or_init(|| m).clone())
    }

    /// Reads and validates a URDF file (a regular file of at most [`MAX_URDF_BYTES`]).
    pub fn from_urdf_path(path: impl AsRef<Path>) -> Result<Self, UrdfError> {
        let path = path.as_ref();
        let text = read_text_file(path, MAX_URDF_BYTES).map_err(|source| UrdfError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_urdf_str(&text)
    }

    /// Parses and validates URDF text. Never panics; XML nested deeper than
    /// [`MAX_XML_DEPTH`] is refused before parsing (the parser recurses once per level).
    pub fn from_urdf_str(text: &str) -> Result<Self, UrdfError> {
        let depth = xml_depth(text);
        if depth > MAX_XML_DEPTH {
            return Err(UrdfError::Parse(format!(
                "elements nested {depth} deep; a URDF needs 4 or 5 levels and at most \
                 {MAX_XML_DEPTH} are read"
            )));
        }
        // urdf-rs and its XML parsers are third-party code fed with user input: a panic in
        // them must come back as an error, not abort the caller.
        let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text));
        let robot = match parsed {
            Ok(Ok(robot)) => robot,
            Ok(Err(e)) => return Err(UrdfError::Parse(e.to_string())),
            Err(_) => return Err(UrdfError::Parse("the URDF parser panicked".into())),
        };
        Self::from_urdf_robot(&robot)
    }

    /// Validates a robot already parsed by urdf-rs.
    pub fn from_urdf_robot(robot: &urdf_rs::Robot) -> Result<Self, UrdfError> {
        if robot.links.is_empty() {
            return Err(UrdfError::NoLinks);
        }
        if robot.links.len() > MAX_LINKS {
            return Err(UrdfError::TooManyLinks {
                count: robot.links.len(),
                max: MAX_LINKS,
            });
        }
        let mut index = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if index.insert(l.name.as_str(), i).is_some() {
                return Err(UrdfError::DuplicateLink(l.name.clone()));
            }
        }
        let mut joint_names = HashMap::new();
        for (i, j) in robot.joints.iter().enumerate() {
            if joint_names.insert(j.name.as_str(), i).is_some() {
                return Err(UrdfError::DuplicateJoint(j.name.clone()));
            }
        }

        let mut joints = Vec::with_capacity(robot.joints.len());
        for j in &robot.joints {
            joints.push(validate_joint(j, &index)?);
        }

        // Tree structure: one parent per link, one root, no cycle.
        let n = robot.links.len();
        let mut parent_joint: Vec<Option<usize>> = vec![None; n];
        for (ji, j) in joints.iter().enumerate() {
            if let Some(prev) = parent_joint[j.child] {
                return Err(UrdfError::SeveralParents {
                    link: robot.links[j.child].name.clone(),
                    joints: vec![joints[prev].name.clone(), j.name.clone()],
                });
            }
            parent_joint[j.child] = Some(ji);
        }
        let roots: Vec<usize> = (0..n).filter(|&l| parent_joint[l].is_none()).collect();
        if roots.len() > 1 {
            return Err(UrdfError::SeveralRoots {
                roots: roots.iter().map(|&l| robot.links[l].name.clone()).collect(),
            });
        }
        let Some(&root) = roots.first() else {
            // Every link has a parent: the joints close on themselves.
            return Err(UrdfError::Cycle {
                link: robot.links[0].name.clone(),
            });
        };
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (ji, j) in joints.iter().enumerate() {
            children[j.parent].push(ji);
        }
        let mut visited = vec![false; n];
        visited[root] = true;
        let mut joint_order = Vec::with_capacity(joints.len());
        let mut queue = std::collections::VecDeque::from([root]);
        while let Some(l) = queue.pop_front() {
            for &ji in &children[l] {
                let c = joints[ji].child;
                if !visited[c] {
                    visited[c] = true;
                    joint_order.push(ji);
                    queue.push_back(c);
                }
            }
        }
        if let Some(l) = (0..n).find(|&l| !visited[l]) {
            return Err(UrdfError::Cycle {
                link: robot.links[l].name.clone(),
            });
        }

        let mut links = Vec::with_capacity(n);
        for (i, l) in robot.links.iter().enumerate() {
            links.push(validate_link(l, i == root)?);
        }

        Ok(Self {
            name: robot.name.clone(),
            links,
            joints,
            root,
            joint_order,
            parent_joint,
        })
    }

    /// The robot's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// All links, in URDF order.
    pub fn links(&self) -> &[LinkModel] {
        &self.links
    }

    /// All joints, in URDF order.
    pub fn joints(&self) -> &[JointModel] {
        &self.joints
    }

    /// Index of the root link (the floating or fixed base).
    pub fn root(&self) -> usize {
        self.root
    }

    /// Joint indices, every joint after the joint of its parent link.
    pub fn joint_order(&self) -> &[usize] {
        &self.joint_order
    }

    /// The joint whose child is `link` (None for the root).
    pub fn parent_joint(&self, link: usize) -> Option<usize> {
        self.parent_joint[link]
    }

    /// Index of the link called `name`.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Index of the joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Sum of the link masses, kg.
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(|l| l.mass).sum()
    }

    /// Collision geometry of every link, in URDF link order.
    pub fn geometry(&self) -> Vec<LinkGeometry> {
        self.links.iter().map(LinkModel::geometry).collect()
    }

    /// Link frames in the world for a base pose and joint positions `q` (one per joint, URDF
    /// order, ignored for fixed joints).
    pub(crate) fn forward_kinematics(&self, base: &Iso, q: &[f64]) -> Vec<Iso> {
        let mut poses = vec![Iso::IDENTITY; self.links.len()];
        poses[self.root] = *base;
        for &ji in &self.joint_order {
            let j = &self.joints[ji];
            let motion = if j.is_movable() {
                math::axis_angle(j.axis, q.get(ji).copied().unwrap_or(0.0))
            } else {
                math::IDENTITY
            };
            poses[j.child] = poses[j.parent]
                .mul(&j.origin)
                .mul(&Iso::from_rotation(motion));
        }
        poses
    }

    /// Whole-body centre of mass in the world for a base pose and joint positions, m.
    pub(crate) fn center_of_mass(&self, base: &Iso, q: &[f64]) -> [f64; 3] {
        let poses = self.forward_kinematics(base, q);
        let mut c = [0.0; 3];
        let mut m = 0.0;
        for (l, p) in self.links.iter().zip(&poses) {
            c = math::add(c, math::scale(p.point(l.com), l.mass));
            m += l.mass;
        }
        if m > 0.0 {
            math::scale(c, 1.0 / m)
        } else {
            c
        }
    }

    /// Lowest world z of all collision shapes for the given link poses.
    pub(crate) fn lowest_point(&self, poses: &[Iso]) -> f64 {
        let mut lowest = f64::INFINITY;
        for (l, pose) in self.links.iter().zip(poses) {
            for (origin, shape) in &l.shapes {
                let iso = pose.mul(origin);
                let z = match *shape {
                    Shape::Box { size } => {
                        let mut m = f64::INFINITY;
                        for corner in 0..8 {
                            let p = [
                                if corner & 1 == 0 { -0.5 } else { 0.5 } * size[0] as f64,
                                if corner & 2 == 0 { -0.5 } else { 0.5 } * size[1] as f64,
                                if corner & 4 == 0 { -0.5 } else { 0.5 } * size[2] as f64,
                            ];
                            m = m.min(iso.point(p)[2]);
                        }
                        m
                    }
                    Shape::Sphere { radius } => iso.t[2] - radius as f64,
                    Shape::Cylinder { radius, length } => {
                        // Lowest point of a cylinder: end-cap centre minus the radius times the
                        // horizontal extent of the cap's tilt.
                        let a = [iso.r[0][2], iso.r[1][2], iso.r[2][2]];
                        let half = 0.5 * length as f64;
                        let cap = iso.t[2] - half * a[2].abs();
                        cap - radius as f64 * (1.0 - a[2] * a[2]).max(0.0).sqrt()
                    }
                };
                lowest = lowest.min(z);
            }
        }
        lowest
    }
}

fn finite(element: &'static str, name: &str, field: &str, value: f64) -> Result<f64, UrdfError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(UrdfError::NonFinite {
            element,
            name: name.to_owned(),
            field: field.to_owned(),
            value,
        })
    }
}

fn finite3(element: &'static str, name: &str, field: &str, v: [f64; 3]) -> Result<V3, UrdfError> {
    for x in v {
        finite(element, name, field, x)?;
    }
    Ok(v)
}

fn pose(
    element: &'static str,
    name: &str,
    field: &str,
    p: &urdf_rs::Pose,
) -> Result<Iso, UrdfError> {
    let t = finite3(element, name, &format!("{field}/xyz"), p.xyz.0)?;
    let rpy = finite3(element, name, &format!("{field}/rpy"), p.rpy.0)?;
    Ok(Iso::new(t, math::rpy_to_mat(rpy)))
}

fn positive(link: &str, field: &'static str, value: f64) -> Result<f32, UrdfError> {
    finite("link", link, field, value)?;
    if value > 0.0 {
        Ok(value as f32)
    } else {
        Err(UrdfError::InvalidGeometry {
            link: link.to_owned(),
            field,
            value,
        })
    }
}

fn validate_link(l: &urdf_rs::Link, is_root: bool) -> Result<LinkModel, UrdfError> {
    let name = l.name.as_str();
    let inertial = &l.inertial;
    let origin = pose("link", name, "inertial/origin", &inertial.origin)?;
    let mass = finite("link", name, "inertial/mass", inertial.mass.value)?;
    let i = &inertial.inertia;
    let raw = [
        ("ixx", i.ixx),
        ("ixy", i.ixy),
        ("ixz", i.ixz),
        ("iyy", i.iyy),
        ("iyz", i.iyz),
        ("izz", i.izz),
    ];
    for (field, v) in raw {
        finite("link", name, &format!("inertial/inertia/{field}"), v)?;
    }
    let tensor: M3 = [
        [i.ixx, i.ixy, i.ixz],
        [i.ixy, i.iyy, i.iyz],
        [i.ixz, i.iyz, i.izz],
    ];
    let massless_anchor = mass == 0.0 && raw.iter().all(|(_, v)| *v == 0.0);
    if !(massless_anchor && is_root) {
        if mass <= 0.0 {
            return Err(UrdfError::NonPhysicalInertial {
                link: name.to_owned(),
                reason: format!("mass = {mass} kg (must be > 0; a missing <inertial> reads as 0)"),
            });
        }
        check_inertia(name, &tensor)?;
    }
    // Express the tensor in the link frame: I_link = R · I · Rᵀ.
    let inertia = math::mat_mul(
        &math::mat_mul(&origin.r, &tensor),
        &math::transpose(&origin.r),
    );

    let mut shapes = Vec::with_capacity(l.collision.len());
    for c in &l.collision {
        let iso = pose("link", name, "collision/origin", &c.origin)?;
        let shape = match &c.geometry {
            urdf_rs::Geometry::Box { size } => Shape::Box {
                size: [
                    positive(name, "box size", size[0])?,
                    positive(name, "box size", size[1])?,
                    positive(name, "box size", size[2])?,
                ],
            },
            urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
                radius: positive(name, "cylinder radius", *radius)?,
                length: positive(name, "cylinder length", *length)?,
            },
            urdf_rs::Geometry::Sphere { radius } => Shape::Sphere {
                radius: positive(name, "sphere radius", *radius)?,
            },
            urdf_rs::Geometry::Capsule { .. } => {
                return Err(UrdfError::UnsupportedGeometry {
                    link: name.to_owned(),
                    kind: "capsule",
                })
            }
            urdf_rs::Geometry::Mesh { filename, .. } => {
                return Err(UrdfError::MeshGeometry {
                    link: name.to_owned(),
                    filename: filename.clone(),
                })
            }
        };
        shapes.push((iso, shape));
    }
    Ok(LinkModel {
        name: name.to_owned(),
        mass,
        com: origin.t,
        inertia,
        shapes,
    })
}

/// Positive definite (Sylvester's criterion) and the triangle inequality on the principal
/// moments (a real body has `I₁ + I₂ ≥ I₃`), the latter with a 0.1 % tolerance for rounding.
fn check_inertia(link: &str, m: &M3) -> Result<(), UrdfError> {
    let d1 = m[0][0];
    let d2 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let d3 = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if !(d1 > 0.0 && d2 > 0.0 && d3 > 0.0) {
        return Err(UrdfError::NonPhysicalInertial {
            link: link.to_owned(),
            reason: format!(
                "inertia tensor is not positive definite (leading minors {d1:e}, {d2:e}, {d3:e})"
            ),
        });
    }
    let ev = symmetric_eigenvalues(m);
    let tol = 1e-3 * (ev[0] + ev[1] + ev[2]);
    for k in 0..3 {
        let (a, b, c) = (ev[k], ev[(k + 1) % 3], ev[(k + 2) % 3]);
        if a + b < c - tol {
            return Err(UrdfError::NonPhysicalInertial {
                link: link.to_owned(),
                reason: format!(
                    "principal moments {ev:?} violate the triangle inequality ({a} + {b} < {c})"
                ),
            });
        }
    }
    Ok(())
}

/// Eigenvalues of a symmetric 3×3 matrix (closed form, Smith 1961).
fn symmetric_eigenvalues(m: &M3) -> [f64; 3] {
    let p1 = m[0][1].powi(2) + m[0][2].powi(2) + m[1][2].powi(2);
    if p1 == 0.0 {
        return [m[0][0], m[1][1], m[2][2]];
    }
    let q = (m[0][0] + m[1][1] + m[2][2]) / 3.0;
    let p2 = (m[0][0] - q).powi(2) + (m[1][1] - q).powi(2) + (m[2][2] - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let mut b = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            b[i][j] = (m[i][j] - if i == j { q } else { 0.0 }) / p;
        }
    }
    let det_b = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
        - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    let r = (det_b / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let e1 = q + 2.0 * p * phi.cos();
    let e3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    [e1, 3.0 * q - e1 - e3, e3]
}

fn validate_joint(
    j: &urdf_rs::Joint,
    index: &HashMap<&str, usize>,
) -> Result<JointModel, UrdfError> {
    let name = j.name.as_str();
    let kind = match j.joint_type {
        urdf_rs::JointType::Revolute => JointKind::Revolute,
        urdf_rs::JointType::Continuous => JointKind::Continuous,
        urdf_rs::JointType::Fixed => JointKind::Fixed,
        ref other => {
            return Err(UrdfError::UnsupportedJoint {
                joint: name.to_owned(),
                kind: format!("{other:?}").to_lowercase(),
            })
        }
    };
    let parent = *index
        .get(j.parent.link.as_str())
        .ok_or_else(|| UrdfError::UnknownParent {
            joint: name.to_owned(),
            link: j.parent.link.clone(),
        })?;
    let child = *index
        .get(j.child.link.as_str())
        .ok_or_else(|| UrdfError::UnknownChild {
            joint: name.to_owned(),
            link: j.child.link.clone(),
        })?;
    if parent == child {
        return Err(UrdfError::SelfJoint {
            joint: name.to_owned(),
            link: j.parent.link.clone(),
        });
    }
    let origin = pose("joint", name, "origin", &j.origin)?;
    let axis = finite3("joint", name, "axis/xyz", j.axis.xyz.0)?;
    let len = math::norm(axis);
    if kind != JointKind::Fixed && len < 1e-9 {
        return Err(UrdfError::ZeroAxis {
            joint: name.to_owned(),
        });
    }
    let axis = if len > 0.0 {
        math::scale(axis, 1.0 / len)
    } else {
        [1.0, 0.0, 0.0]
    };

    let lim = &j.limit;
    for (field, v) in [
        ("limit/lower", lim.lower),
        ("limit/upper", lim.upper),
        ("limit/effort", lim.effort),
        ("limit/velocity", lim.velocity),
    ] {
        if v.is_nan() {
            return Err(UrdfError::NonFinite {
                element: "joint",
                name: name.to_owned(),
                field: field.to_owned(),
                value: v,
            });
        }
    }
    for (field, v) in [
        ("limit effort", lim.effort),
        ("limit velocity", lim.velocity),
    ] {
        if v < 0.0 {
            return Err(UrdfError::Negative {
                joint: name.to_owned(),
                field,
                value: v,
            });
        }
    }
    let limits = if kind == JointKind::Revolute {
        if lim.lower.is_finite() && lim.upper.is_finite() {
            if lim.lower >= lim.upper {
                return Err(UrdfError::InvalidLimits {
                    joint: name.to_owned(),
                    lower: lim.lower,
                    upper: lim.upper,
                });
            }
            Some([lim.lower, lim.upper])
        } else if lim.lower == f64::NEG_INFINITY && lim.upper == f64::INFINITY {
            None
        } else {
            // One-sided infinite limits are legal URDF 1.2 but have no Rapier equivalent.
            return Err(UrdfError::InvalidLimits {
                joint: name.to_owned(),
                lower: lim.lower,
                upper: lim.upper,
            });
        }
    } else {
        None
    };
    let (damping, friction) = match &j.dynamics {
        Some(d) => (
            finite("joint", name, "dynamics/damping", d.damping)?,
            finite("joint", name, "dynamics/friction", d.friction)?,
        ),
        None => (0.0, 0.0),
    };
    for (field, v) in [
        ("dynamics damping", damping),
        ("dynamics friction", friction),
    ] {
        if v < 0.0 {
            return Err(UrdfError::Negative {
                joint: name.to_owned(),
                field,
                value: v,
            });
        }
    }
    Ok(JointModel {
        name: name.to_owned(),
        kind,
        parent,
        child,
        axis,
        limits,
        effort: lim.effort,
        damping,
        friction,
        origin,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROTATED: &str = r#"<robot name="r">
      <link name="a">
        <inertial>
          <origin xyz="0.1 0.2 0.3" rpy="0 0 1.5707963267948966"/>
          <mass value="2"/>
          <inertia ixx="1" ixy="0" ixz="0" iyy="2" iyz="0" izz="3"/>
        </inertial>
      </link>
    </robot>"#;

    #[test]
    fn inertial_rpy_rotates_the_tensor() {
        // A 90° yaw swaps the x and y principal axes: I_link = diag(2, 1, 3).
        let m = RobotModel::from_urdf_str(ROTATED).unwrap();
        let i = m.links()[0].inertia;
        let expect = [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]];
        for r in 0..3 {
            for c in 0..3 {
                assert!((i[r][c] - expect[r][c]).abs() < 1e-12, "{i:?}");
            }
        }
        assert_eq!(m.links()[0].com, [0.1, 0.2, 0.3]);
    }

    #[test]
    fn eigenvalues_of_a_general_symmetric_matrix() {
        // Rotated diag(1, 2, 3): eigenvalues are invariant.
        let r = math::rpy_to_mat([0.3, 0.5, -1.1]);
        let d = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]];
        let m = math::mat_mul(&math::mat_mul(&r, &d), &math::transpose(&r));
        let mut ev = symmetric_eigenvalues(&m);
        ev.sort_by(|a, b| a.total_cmp(b));
        for (e, x) in ev.iter().zip([1.0, 2.0, 3.0]) {
            assert!((e - x).abs() < 1e-9, "{ev:?}");
        }
    }

    #[test]
    fn humanoid_parses() {
        let m = RobotModel::humanoid().unwrap();
        assert_eq!(m.links()[m.root()].name, "torso");
        assert_eq!(m.links().len(), 11);
        assert_eq!(m.joints().len(), 10);
    }
}
