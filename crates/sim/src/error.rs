//! Errors of URDF loading and environment configuration.

use std::path::PathBuf;

/// Why a URDF was refused. Every variant names the link or joint at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum UrdfError {
    /// The file could not be read.
    #[error("cannot read URDF file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The text is not a URDF document urdf-rs can parse.
    #[error("URDF parse error: {0}")]
    Parse(String),
    /// The robot has no link.
    #[error("URDF has no <link>")]
    NoLinks,
    /// More links than a walking robot needs; a bound so that a runaway file (a generated
    /// 10,000-link chain) is refused at once instead of exhausting memory in the solver.
    #[error("URDF has {count} links; at most {max} are supported")]
    TooManyLinks {
        /// Links in the file.
        count: usize,
        /// The bound, [`crate::MAX_LINKS`].
        max: usize,
    },
    /// Two links share a name.
    #[error("duplicate link name `{0}`")]
    DuplicateLink(String),
    /// Two joints share a name.
    #[error("duplicate joint name `{0}`")]
    DuplicateJoint(String),
    /// A joint's parent is not a link of the robot.
    #[error("joint `{joint}`: unknown parent link `{link}`")]
    UnknownParent {
        /// The joint.
        joint: String,
        /// The missing link name.
        link: String,
    },
    /// A joint's child is not a link of the robot.
    #[error("joint `{joint}`: unknown child link `{link}`")]
    UnknownChild {
        /// The joint.
        joint: String,
        /// The missing link name.
        link: String,
    },
    /// A link is the child of more than one joint (the kinematic graph is not a tree).
    #[error("link `{link}` is the child of several joints: {joints:?}")]
    SeveralParents {
        /// The link.
        link: String,
        /// The joints naming it as their child.
        joints: Vec<String>,
    },
    /// The joints form a closed loop.
    #[error("kinematic cycle through link `{link}`")]
    Cycle {
        /// A link on the cycle.
        link: String,
    },
    /// More than one link has no parent joint.
    #[error("several root links (links with no parent joint): {roots:?}")]
    SeveralRoots {
        /// The parentless links.
        roots: Vec<String>,
    },
    /// Mass ≤ 0, a missing `<inertial>`, or an inertia tensor that is not positive definite.
    #[error("link `{link}`: non-physical inertial: {reason}")]
    NonPhysicalInertial {
        /// The link.
        link: String,
        /// What is wrong, with the values.
        reason: String,
    },
    /// A number is NaN or infinite where a finite value is required.
    #[error("{element} `{name}`: {field} is not finite ({value})")]
    NonFinite {
        /// `"link"` or `"joint"`.
        element: &'static str,
        /// Its name.
        name: String,
        /// The offending field, e.g. `inertial/origin/xyz`.
        field: String,
        /// The value.
        value: f64,
    },
    /// `<mesh>` geometry: only box, cylinder and sphere are simulated.
    #[error(
        "link `{link}`: mesh geometry `{filename}` is not supported (use box, cylinder or sphere)"
    )]
    MeshGeometry {
        /// The link.
        link: String,
        /// The mesh file named in the URDF.
        filename: String,
    },
    /// A primitive other than box, cylinder or sphere (e.g. URDF 1.2 capsule).
    #[error("link `{link}`: {kind} geometry is not supported (use box, cylinder or sphere)")]
    UnsupportedGeometry {
        /// The link.
        link: String,
        /// The geometry kind.
        kind: &'static str,
    },
    /// A box size, radius or length that is not strictly positive.
    #[error("link `{link}`: {field} must be > 0, got {value}")]
    InvalidGeometry {
        /// The link.
        link: String,
        /// The field, e.g. `box size`.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// Joint types other than revolute, continuous and fixed.
    #[error("joint `{joint}`: unsupported joint type `{kind}` (revolute, continuous and fixed are supported)")]
    UnsupportedJoint {
        /// The joint.
        joint: String,
        /// The URDF type.
        kind: String,
    },
    /// `lower ≥ upper` on a revolute joint.
    #[error(
        "joint `{joint}`: invalid limits lower = {lower}, upper = {upper} (need lower < upper)"
    )]
    InvalidLimits {
        /// The joint.
        joint: String,
        /// Lower limit, rad.
        lower: f64,
        /// Upper limit, rad.
        upper: f64,
    },
    /// A zero-length joint axis.
    #[error("joint `{joint}`: axis has zero length")]
    ZeroAxis {
        /// The joint.
        joint: String,
    },
    /// A negative effort, velocity, damping or friction.
    #[error("joint `{joint}`: {field} must be ≥ 0, got {value}")]
    Negative {
        /// The joint.
        joint: String,
        /// The field.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// A joint whose parent and child are the same link.
    #[error("joint `{joint}` connects link `{link}` to itself")]
    SelfJoint {
        /// The joint.
        joint: String,
        /// The link.
        link: String,
    },
    /// The root link has no mass (a fixed "world" anchor) but a floating base was requested.
    #[error("root link `{link}` has no mass, so it can only be used with a fixed base")]
    MasslessFloatingRoot {
        /// The root link.
        link: String,
    },
}

/// Errors of this crate: a refused URDF or a bad configuration value.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The URDF was refused.
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    /// A configuration field has an impossible value.
    #[error("invalid config field `{field}` = {value}: {reason}")]
    Config {
        /// The field path, e.g. `physics.substeps`.
        field: String,
        /// The offending value, as text.
        value: String,
        /// What is expected.
        reason: String,
    },
    /// The config names a link or joint the model does not have, or one that cannot play the role.
    #[error("config field `{field}`: {reason}")]
    Model {
        /// The field path, e.g. `actuated_joints`.
        field: String,
        /// What is wrong.
        reason: String,
    },
}
