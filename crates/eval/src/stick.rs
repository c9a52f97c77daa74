//! The robot seen from the side, sampled along an episode: what the stick-figure filmstrip of
//! `python -m esrl_rs.report` draws (`eval.json`, `episodes[k].trace.stick`).
//!
//! Every collision primitive of the URDF becomes one *part*, projected onto the world x–z
//! plane (x forward along the track, z up; the lateral y is dropped):
//!
//! - a cylinder → a `line` between the centres of its end faces, `[x0, z0, x1, z1]`;
//! - a box → a `box` quadrilateral, the four corners `c ± a ± b` (`[x0, z0, …, x3, z3]`, in
//!   order around it), where `a`, `b` are the two half-edge vectors whose x–z projections
//!   span the largest area: the box's outline for a link turned about the y axis only (the
//!   sagittal joints of the humanoid);
//! - a sphere → a `circle`, centre `[x, z]` with the part's `radius`.
//!
//! Frames are taken every `interval` seconds of simulated time (after the step that ends at a
//! multiple of it); coordinates are rounded to the millimetre, which keeps `eval.json` small
//! (about 60 numbers per frame for the humanoid) and is below a pixel of any figure.

use esrl_record::Pose;
use esrl_sim::{LinkGeometry, LinkPose, Shape};
use serde::{Deserialize, Serialize};

/// Seconds between frames by default: the filmstrip shows every 2nd to 5th frame (0.2–0.5 s)
/// and an animation plays them at 10 frames per second, in real time.
pub const DEFAULT_INTERVAL: f64 = 0.1;

/// What a part is drawn as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PartKind {
    /// A segment, 4 numbers per frame.
    Line,
    /// A quadrilateral, 8 numbers per frame.
    Box,
    /// A circle of the part's radius, 2 numbers per frame.
    Circle,
}

/// One drawn primitive.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StickPart {
    /// The link it belongs to (its name tells left from right).
    pub link: String,
    /// How it is drawn.
    pub kind: PartKind,
    /// Radius (m): of the circle, or of the cylinder (a line width).
    pub radius: f32,
}

/// The side view of one episode.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StickFigure {
    /// Seconds between frames.
    pub interval: f64,
    /// The parts, in the order of each frame's entries.
    pub parts: Vec<StickPart>,
    /// Simulated time of each frame, s since reset.
    pub time: Vec<f32>,
    /// `frames[k][part]`: the part's coordinates (m) in frame k, laid out as its kind says.
    pub frames: Vec<Vec<Vec<f32>>>,
}

/// One shape to project: link index, its pose in the link frame, the primitive.
struct ShapeRef {
    link: usize,
    pose: Pose,
    shape: Shape,
}

/// Collects [`StickFigure`] frames from link poses.
pub struct StickRecorder {
    shapes: Vec<ShapeRef>,
    every: usize,
    figure: StickFigure,
}

fn mm(v: f64) -> f32 {
    ((v * 1000.0).round() / 1000.0) as f32
}

impl StickRecorder {
    /// A recorder for the links' collision `geometry` (URDF link order, as
    /// `WalkEnv::geometry`), one frame every `interval` seconds at the `control_period`.
    pub fn new(geometry: &[LinkGeometry], control_period: f64, interval: f64) -> Self {
        let every = (interval / control_period).round().max(1.0) as usize;
        let mut shapes = Vec::new();
        let mut parts = Vec::new();
        for (link, g) in geometry.iter().enumerate() {
            for s in &g.shapes {
                let (kind, radius) = match s.shape {
                    Shape::Cylinder { radius, .. } => (PartKind::Line, radius),
                    Shape::Box { .. } => (PartKind::Box, 0.0),
                    Shape::Sphere { radius } => (PartKind::Circle, radius),
                };
                parts.push(StickPart {
                    link: g.link.clone(),
                    kind,
                    radius,
                });
                shapes.push(ShapeRef {
                    link,
                    pose: Pose {
                        translation: s.translation.map(f64::from),
                        rotation: s.rotation.map(f64::from),
                    },
                    shape: s.shape,
                });
            }
        }
        Self {
            shapes,
            every,
            figure: StickFigure {
                interval: every as f64 * control_period,
                parts,
                ..StickFigure::default()
            },
        }
    }

    /// Records a frame when `step` (control steps since reset, ≥ 1) is a multiple of the
    /// interval and every pose is finite.
    pub fn observe(&mut self, step: usize, time: f64, poses: &[LinkPose]) {
        if step % self.every != 0 {
            return;
        }
        let finite = poses.iter().all(|p| {
            p.translation
                .iter()
                .chain(&p.rotation)
                .all(|v| v.is_finite())
        });
        if !finite {
            return;
        }
        let frame = self
            .shapes
            .iter()
            .map(|s| {
                let p = &poses[s.link];
                let link = Pose {
                    translation: p.translation.map(f64::from),
                    rotation: p.rotation.map(f64::from),
                };
                project(&link, s)
            })
            .collect();
        self.figure.time.push(time as f32);
        self.figure.frames.push(frame);
    }

    /// The frames recorded so far.
    pub fn finish(self) -> StickFigure {
        self.figure
    }
}

/// The world position of `p` given in the shape's frame.
fn world(link: &Pose, s: &ShapeRef, p: [f64; 3]) -> [f64; 3] {
    link.transform_point(s.pose.transform_point(p))
}

fn project(link: &Pose, s: &ShapeRef) -> Vec<f32> {
    let c = world(link, s, [0.0; 3]);
    match s.shape {
        Shape::Cylinder { length, .. } => {
            let h = f64::from(length) / 2.0;
            let a = world(link, s, [0.0, 0.0, h]);
            let b = world(link, s, [0.0, 0.0, -h]);
            vec![mm(a[0]), mm(a[2]), mm(b[0]), mm(b[2])]
        }
        Shape::Sphere { .. } => vec![mm(c[0]), mm(c[2])],
        Shape::Box { size } => {
            // Half-edge vectors in the world, projected on x–z; keep the pair that spans the
            // largest area (for a box turned about y only, its x and z edges).
            let edges: Vec<[f64; 2]> = (0..3)
                .map(|k| {
                    let mut e = [0.0; 3];
                    e[k] = f64::from(size[k]) / 2.0;
                    let w = world(link, s, e);
                    [w[0] - c[0], w[2] - c[2]]
                })
                .collect();
            let area = |(i, j): (usize, usize)| {
                (edges[i][0] * edges[j][1] - edges[i][1] * edges[j][0]).abs()
            };
            let (i, j) = [(0, 1), (0, 2), (1, 2)]
                .into_iter()
                .max_by(|&p, &q| area(p).total_cmp(&area(q)))
                .unwrap_or((0, 2));
            let (a, b) = (edges[i], edges[j]);
            [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)]
                .iter()
                .flat_map(|(sa, sb)| {
                    [
                        mm(c[0] + sa * a[0] + sb * b[0]),
                        mm(c[2] + sa * a[1] + sb * b[1]),
                    ]
                })
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use esrl_sim::ShapeGeometry;

    fn geometry() -> Vec<LinkGeometry> {
        vec![LinkGeometry {
            link: "left_foot".into(),
            shapes: vec![
                ShapeGeometry {
                    shape: Shape::Box {
                        size: [0.2, 0.1, 0.04],
                    },
                    translation: [0.05, 0.0, -0.02],
                    rotation: [0.0, 0.0, 0.0, 1.0],
                },
                ShapeGeometry {
                    shape: Shape::Cylinder {
                        radius: 0.05,
                        length: 0.4,
                    },
                    translation: [0.0, 0.0, 0.2],
                    rotation: [0.0, 0.0, 0.0, 1.0],
                },
                ShapeGeometry {
                    shape: Shape::Sphere { radius: 0.1 },
                    translation: [0.0, 0.3, 1.0],
                    rotation: [0.0, 0.0, 0.0, 1.0],
                },
            ],
        }]
    }

    /// A link at (1, 0.5, 0.1) pitched by 90° about y (its z axis along world +x).
    fn pose() -> LinkPose {
        let h = std::f32::consts::FRAC_1_SQRT_2;
        LinkPose {
            name: "left_foot".into(),
            translation: [1.0, 0.5, 0.1],
            rotation: [0.0, h, 0.0, h],
        }
    }

    #[test]
    fn parts_are_projected_by_hand() {
        let mut r = StickRecorder::new(&geometry(), 0.025, 0.1);
        r.observe(3, 0.075, &[pose()]);
        r.observe(4, 0.1, &[pose()]);
        let f = r.finish();
        assert_eq!(f.time, vec![0.1], "one frame every 4 steps");
        assert!((f.interval - 0.1).abs() < 1e-12);
        let kinds: Vec<PartKind> = f.parts.iter().map(|p| p.kind).collect();
        assert_eq!(kinds, [PartKind::Box, PartKind::Line, PartKind::Circle]);
        // Rotating by +90° about y maps local (x, z) to world (z, −x).
        // Box centre (0.05, −0.02) → (1 − 0.02, 0.1 − 0.05) = (0.98, 0.05); its local x
        // half-edge (0.1) becomes world −z, its z half-edge (0.02) world +x, the y edge
        // vanishes: corners (0.98 ± 0.02, 0.05 ∓ 0.1).
        let b = &f.frames[0][0];
        let want = [1.0, -0.05, 0.96, -0.05, 0.96, 0.15, 1.0, 0.15];
        for (got, want) in b.iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{b:?}");
        }
        // Cylinder from local z = 0 to 0.4 → world x from 1.0 to 1.4 at z = 0.1.
        let l = &f.frames[0][1];
        assert_eq!(l, &vec![1.4, 0.1, 1.0, 0.1]);
        // Sphere at local (0, 0.3, 1) → world (2, 0.8, 0.1): y is dropped.
        assert_eq!(f.frames[0][2], vec![2.0, 0.1]);
        assert_eq!(f.parts[2].radius, 0.1);
    }
}
