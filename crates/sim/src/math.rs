//! Small f64 rigid-transform helpers used for validation and forward kinematics before Rapier
//! (which works in f32) sees the model.

use rapier3d::math::{Pose, Rotation, Vector};

pub(crate) type V3 = [f64; 3];
pub(crate) type M3 = [[f64; 3]; 3];

pub(crate) const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

pub(crate) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[cfg(test)]
pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

pub(crate) fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

pub(crate) fn mat_vec(a: &M3, v: V3) -> V3 {
    [dot(a[0], v), dot(a[1], v), dot(a[2], v)]
}

pub(crate) fn transpose(a: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[j][i];
        }
    }
    out
}

/// URDF fixed-axis roll-pitch-yaw: `R = Rz(yaw) · Ry(pitch) · Rx(roll)`.
pub(crate) fn rpy_to_mat(rpy: V3) -> M3 {
    let (sr, cr) = rpy[0].sin_cos();
    let (sp, cp) = rpy[1].sin_cos();
    let (sy, cy) = rpy[2].sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// Rotation of `angle` about the unit vector `axis` (Rodrigues).
pub(crate) fn axis_angle(axis: V3, angle: f64) -> M3 {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let [x, y, z] = axis;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// A rotation taking the unit x axis onto the unit vector `axis`.
pub(crate) fn x_onto(axis: V3) -> M3 {
    let x = [1.0, 0.0, 0.0];
    let c = dot(x, axis);
    let k = cross(x, axis);
    let s = norm(k);
    if s < 1e-12 {
        if c > 0.0 {
            IDENTITY
        } else {
            axis_angle([0.0, 0.0, 1.0], std::f64::consts::PI)
        }
    } else {
        axis_angle(scale(k, 1.0 / s), s.atan2(c))
    }
}

/// Unit quaternion `[x, y, z, w]` of a rotation matrix (Shepperd's method).
pub(crate) fn mat_to_quat(m: &M3) -> [f64; 4] {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let q = if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        [
            (m[2][1] - m[1][2]) / s,
            (m[0][2] - m[2][0]) / s,
            (m[1][0] - m[0][1]) / s,
            0.25 * s,
        ]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt() * 2.0;
        [
            0.25 * s,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[2][1] - m[1][2]) / s,
        ]
    } else if m[1][1] > m[2][2] {
        let s = (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt() * 2.0;
        [
            (m[0][1] + m[1][0]) / s,
            0.25 * s,
            (m[1][2] + m[2][1]) / s,
            (m[0][2] - m[2][0]) / s,
        ]
    } else {
        let s = (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt() * 2.0;
        [
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            0.25 * s,
            (m[1][0] - m[0][1]) / s,
        ]
    };
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
}

/// A rigid transform in f64: `p_parent = r · p_child + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Iso {
    pub r: M3,
    pub t: V3,
}

impl Iso {
    pub const IDENTITY: Iso = Iso {
        r: IDENTITY,
        t: [0.0; 3],
    };

    pub fn new(t: V3, r: M3) -> Self {
        Self { r, t }
    }

    pub fn from_translation(t: V3) -> Self {
        Self { r: IDENTITY, t }
    }

    pub fn from_rotation(r: M3) -> Self {
        Self { r, t: [0.0; 3] }
    }

    pub fn mul(&self, other: &Iso) -> Iso {
        Iso {
            r: mat_mul(&self.r, &other.r),
            t: add(mat_vec(&self.r, other.t), self.t),
        }
    }

    pub fn point(&self, p: V3) -> V3 {
        add(mat_vec(&self.r, p), self.t)
    }

    pub fn to_pose(self) -> Pose {
        let q = mat_to_quat(&self.r);
        Pose::from_parts(
            Vector::new(self.t[0] as f32, self.t[1] as f32, self.t[2] as f32),
            Rotation::from_xyzw(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32).normalize(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_matches_hand_computed_yaw() {
        let r = rpy_to_mat([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let v = mat_vec(&r, [1.0, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-12 && (v[1] - 1.0).abs() < 1e-12);
        let r = rpy_to_mat([std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        let v = mat_vec(&r, [0.0, 1.0, 0.0]);
        assert!((v[2] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn x_onto_maps_x_to_axis() {
        for axis in [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, -1.0],
            [0.6, 0.0, 0.8],
        ] {
            let v = mat_vec(&x_onto(axis), [1.0, 0.0, 0.0]);
            assert!(norm(sub(v, axis)) < 1e-12, "{axis:?} -> {v:?}");
        }
    }

    #[test]
    fn quaternion_round_trip() {
        let m = rpy_to_mat([0.3, -0.7, 2.9]);
        let q = mat_to_quat(&m);
        let rq = Rotation::from_xyzw(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32);
        let v = rq * Vector::new(0.2, -0.5, 0.9);
        let w = mat_vec(&m, [0.2, -0.5, 0.9]);
        assert!((v.x as f64 - w[0]).abs() < 1e-6);
        assert!((v.y as f64 - w[1]).abs() < 1e-6);
        assert!((v.z as f64 - w[2]).abs() < 1e-6);
    }
}
