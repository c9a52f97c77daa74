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
        if !step.is_multiple_of(self.every) {
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

/// The robot's side view now, as an RGB image (`height` rows of `width` pixels, 3 bytes
/// each, row-major from the top): the parts of [`StickRecorder`] drawn from the link `poses`
/// (URDF link order, as `WalkEnv::link_poses`) of a robot with collision `geometry`,
/// `metres` high, the camera following the root link (the torso) along x with its lowest
/// row a little below the ground, the ground a grey line with a tick every metre. Left links
/// blue, right ones orange, others grey, as in [`animated_svg`]. For Gymnasium's
/// `render_mode="rgb_array"`.
pub fn render_rgb(
    geometry: &[LinkGeometry],
    poses: &[LinkPose],
    width: usize,
    height: usize,
    metres: f64,
) -> Vec<u8> {
    let mut img = vec![255u8; width * height * 3];
    if width == 0 || height == 0 {
        return img;
    }
    let mut recorder = StickRecorder::new(geometry, 1.0, 1.0);
    recorder.observe(1, 0.0, poses);
    let figure = recorder.finish();
    let px = height as f64 / metres;
    let centre = poses.first().map_or(0.0, |p| f64::from(p.translation[0]));
    let ground_row = height as f64 - 0.08 * height as f64;
    // World (x, z) to pixel (column, row).
    let to_px = |x: f64, z: f64| ((x - centre) * px + width as f64 / 2.0, ground_row - z * px);
    let mut paint = |c: usize, r: usize, rgb: [u8; 3]| {
        if c < width && r < height {
            let i = (r * width + c) * 3;
            img[i..i + 3].copy_from_slice(&rgb);
        }
    };
    // Ground and metre ticks.
    let g = ground_row.round().clamp(0.0, (height - 1) as f64) as usize;
    for c in 0..width {
        paint(c, g, [120, 120, 120]);
    }
    let first = (centre - width as f64 / px).floor() as i64;
    let last = (centre + width as f64 / px).ceil() as i64;
    for m in first..=last {
        let (c, _) = to_px(m as f64, 0.0);
        if c >= 0.0 {
            for r in g..(g + 6).min(height) {
                paint(c as usize, r, [120, 120, 120]);
            }
        }
    }
    let colour = |link: &str| {
        if link.contains("left") {
            [31, 119, 180]
        } else if link.contains("right") {
            [255, 127, 14]
        } else {
            [85, 85, 85]
        }
    };
    let Some(frame) = figure.frames.first() else {
        return img;
    };
    for (part, v) in figure.parts.iter().zip(frame) {
        let rgb = colour(&part.link);
        // Every shape as a test "is pixel (c, r) inside", over its bounding box.
        let pts: Vec<(f64, f64)> = v
            .chunks(2)
            .map(|p| to_px(f64::from(p[0]), f64::from(p[1])))
            .collect();
        let pad = match part.kind {
            PartKind::Line => (f64::from(part.radius) * px).max(1.0),
            PartKind::Circle => f64::from(part.radius) * px,
            PartKind::Box => 0.5,
        };
        let (c0, c1, r0, r1) = pts.iter().fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
        );
        let inside = |x: f64, y: f64| match part.kind {
            PartKind::Line => {
                let ((ax, ay), (bx, by)) = (pts[0], pts[1]);
                let (dx, dy) = (bx - ax, by - ay);
                let len2 = (dx * dx + dy * dy).max(1e-12);
                let t = (((x - ax) * dx + (y - ay) * dy) / len2).clamp(0.0, 1.0);
                let (ex, ey) = (ax + t * dx - x, ay + t * dy - y);
                ex * ex + ey * ey <= pad * pad
            }
            PartKind::Circle => {
                let (cx, cy) = pts[0];
                (x - cx).powi(2) + (y - cy).powi(2) <= pad * pad
            }
            PartKind::Box => {
                // Inside a convex quadrilateral: on the same side of all four edges.
                let side = |i: usize| {
                    let ((ax, ay), (bx, by)) = (pts[i], pts[(i + 1) % 4]);
                    (bx - ax) * (y - ay) - (by - ay) * (x - ax)
                };
                let s: Vec<f64> = (0..4).map(side).collect();
                s.iter().all(|&v| v >= -0.5) || s.iter().all(|&v| v <= 0.5)
            }
        };
        let clamp = |v: f64, n: usize| v.max(0.0).min(n as f64 - 1.0) as usize;
        let (cmin, cmax) = (
            clamp((c0 - pad).floor(), width),
            clamp((c1 + pad).ceil(), width),
        );
        let (rmin, rmax) = (
            clamp((r0 - pad).floor(), height),
            clamp((r1 + pad).ceil(), height),
        );
        if !(c0.is_finite() && r0.is_finite()) {
            continue;
        }
        for r in rmin..=rmax {
            for c in cmin..=cmax {
                if inside(c as f64 + 0.5, r as f64 + 0.5) {
                    paint(c, r, rgb);
                }
            }
        }
    }
    img
}

/// An animated SVG of `figure` that any browser plays (SMIL, no script): the side view
/// `height_px` pixels high, the camera following the torso (the first part's first point)
/// along the track, one frame per recorded sample at its own time, looping. The ground is a
/// line with a tick every metre, so the walk's speed shows. Left links are drawn blue, right
/// ones orange, others grey.
pub fn animated_svg(figure: &StickFigure, height_px: f64) -> String {
    use std::fmt::Write;
    let (view_w, view_h) = (3.0, 2.2); // metres shown around the torso
    let scale = height_px / view_h;
    let n = figure.frames.len();
    let duration = f64::from(figure.time.last().copied().unwrap_or(0.0)).max(figure.interval);
    let key_times = (0..n)
        .map(|k| format!("{:.4}", f64::from(figure.time[k]) / duration))
        .collect::<Vec<_>>()
        .join(";");
    // Keep `keyTimes` valid (it must start at 0): the first frame at time 0.
    let key_times = if n > 0 && figure.time[0] > 0.0 {
        format!("0;{}", key_times.split_once(';').map_or("", |(_, r)| r))
    } else {
        key_times
    };
    let anim = |attr: &str, values: String| {
        format!(
            "<animate attributeName=\"{attr}\" dur=\"{duration:.3}s\" repeatCount=\"indefinite\" \
             calcMode=\"discrete\" keyTimes=\"{key_times}\" values=\"{values}\"/>"
        )
    };
    let colour = |link: &str| {
        if link.contains("left") {
            "#1f77b4"
        } else if link.contains("right") {
            "#ff7f0e"
        } else {
            "#555555"
        }
    };
    let track_end = figure
        .frames
        .iter()
        .filter_map(|f| f.first()?.first())
        .fold(0.0f32, |m, &x| m.max(x))
        .ceil() as i64
        + 2;
    let mut out = String::new();
    let _ = write!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" \
         viewBox=\"{x0} {y0} {vw} {vh}\">\n<rect x=\"{x0}\" y=\"{y0}\" width=\"{vw}\" \
         height=\"{vh}\" fill=\"white\"/>\n",
        w = view_w * scale,
        h = height_px,
        x0 = -view_w / 2.0,
        y0 = -(view_h - 0.2),
        vw = view_w,
        vh = view_h,
    );
    // The world, flipped so z is up, moved so the torso stays in the middle.
    let follow: Vec<String> = figure
        .frames
        .iter()
        .map(|f| {
            let x = f.first().and_then(|p| p.first()).copied().unwrap_or(0.0);
            format!("{:.3},0", -x)
        })
        .collect();
    let _ = writeln!(
        out,
        "<g><animateTransform attributeName=\"transform\" type=\"translate\" \
         dur=\"{duration:.3}s\" repeatCount=\"indefinite\" calcMode=\"discrete\" \
         keyTimes=\"{key_times}\" values=\"{}\"/>\n<g transform=\"scale(1,-1)\">",
        follow.join(";")
    );
    let _ = writeln!(
        out,
        "<line x1=\"-2\" y1=\"0\" x2=\"{track_end}\" y2=\"0\" stroke=\"#333\" \
         stroke-width=\"0.01\"/>"
    );
    for m in -2..=track_end {
        let _ = writeln!(
            out,
            "<line x1=\"{m}\" y1=\"0\" x2=\"{m}\" y2=\"-0.05\" stroke=\"#333\" \
             stroke-width=\"0.01\"/>"
        );
    }
    for (i, part) in figure.parts.iter().enumerate() {
        let c = colour(&part.link);
        let frames = figure.frames.iter().map(|f| &f[i]);
        let join =
            |f: &dyn Fn(&Vec<f32>) -> String| frames.clone().map(f).collect::<Vec<_>>().join(";");
        match part.kind {
            PartKind::Line => {
                let width = (2.0 * part.radius).max(0.01);
                let _ = writeln!(
                    out,
                    "<line stroke=\"{c}\" stroke-width=\"{width:.3}\" stroke-linecap=\"round\">{}{}{}{}</line>",
                    anim("x1", join(&|v| format!("{}", v[0]))),
                    anim("y1", join(&|v| format!("{}", v[1]))),
                    anim("x2", join(&|v| format!("{}", v[2]))),
                    anim("y2", join(&|v| format!("{}", v[3]))),
                );
            }
            PartKind::Box => {
                let _ = writeln!(
                    out,
                    "<polygon fill=\"{c}\" fill-opacity=\"0.6\" stroke=\"{c}\" stroke-width=\"0.005\">{}</polygon>",
                    anim(
                        "points",
                        join(&|v| {
                            v.chunks(2)
                                .map(|p| format!("{},{}", p[0], p[1]))
                                .collect::<Vec<_>>()
                                .join(" ")
                        })
                    ),
                );
            }
            PartKind::Circle => {
                let _ = writeln!(
                    out,
                    "<circle r=\"{:.3}\" fill=\"{c}\" fill-opacity=\"0.6\">{}{}</circle>",
                    part.radius,
                    anim("cx", join(&|v| format!("{}", v[0]))),
                    anim("cy", join(&|v| format!("{}", v[1]))),
                );
            }
        }
    }
    out.push_str("</g>\n</g>\n</svg>\n");
    out
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

    #[test]
    fn the_animation_has_one_value_per_frame_for_every_part() {
        let mut r = StickRecorder::new(&geometry(), 0.025, 0.1);
        for step in 1..=12 {
            r.observe(step, step as f64 * 0.025, &[pose()]);
        }
        let f = r.finish();
        assert_eq!(f.frames.len(), 3);
        let svg = animated_svg(&f, 300.0);
        assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(svg.trim_end().ends_with("</svg>"));
        // Box points, line x1/y1/x2/y2, circle cx/cy and the camera: 8 animations.
        assert_eq!(svg.matches("<animate").count(), 8);
        for values in svg.split("values=\"").skip(1) {
            let values = &values[..values.find('"').unwrap()];
            assert_eq!(values.split(';').count(), 3, "{values}");
        }
        assert!(svg.contains("keyTimes=\"0;0.6667;1.0000\""), "{svg}");
        assert_eq!(svg.matches('<').count(), svg.matches('>').count());
    }

    #[test]
    fn the_image_draws_each_part_where_it_is() {
        // The link at (1, 0.5, 0.1) pitched 90°, seen 2 m high on 200 × 200 pixels (100 px
        // per metre), the camera on the link's x = 1: world x = 1 is column 100, the ground
        // (z = 0) row 184.
        let img = render_rgb(&geometry(), &[pose()], 200, 200, 2.0);
        assert_eq!(img.len(), 200 * 200 * 3);
        let at = |c: usize, r: usize| {
            let i = (r * 200 + c) * 3;
            [img[i], img[i + 1], img[i + 2]]
        };
        let blue = [31, 119, 180];
        // The cylinder: world x 1.0…1.4 at z = 0.1 → columns 100…140, row 174.
        assert_eq!(at(120, 174), blue);
        // The sphere at world (2, 0.1), radius 0.1 → centre column 200 (off the right edge):
        // its left part from column 190.
        assert_eq!(at(195, 174), blue);
        // The box: x 0.96…1.0, z −0.05…0.15 → columns 96…100, rows 169…189.
        assert_eq!(at(98, 180), blue);
        assert_eq!(at(98, 165), [255, 255, 255], "above the box");
        // Far from every part: white; on the ground line: grey.
        assert_eq!(at(20, 40), [255, 255, 255]);
        assert_eq!(at(20, 184), [120, 120, 120]);
    }
}
