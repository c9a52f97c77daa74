//! Range of motion and time at a limit of each actuated joint, and the torso's pitch.
//!
//! - **Range of motion** = 95th − 5th percentile of the joint angle over the episode's
//!   samples: the span the joint actually works in, robust to single-sample spikes (a
//!   limit overshoot on impact) that the plain min–max would report.
//! - **Percentiles** interpolate linearly between order statistics (Hyndman & Fan 1996,
//!   definition 7; NumPy's and R's default): for sorted values `v[0..n]` and `p ∈ [0, 1]`,
//!   `h = (n − 1)·p`, `P = v[⌊h⌋] + (h − ⌊h⌋)·(v[⌊h⌋+1] − v[⌊h⌋])`.
//! - **Time at a limit** = share of the samples with the angle within `margin` of the lower
//!   or the upper position limit (`q ≤ lower + margin` or `q ≥ upper − margin`); a joint
//!   resting on its stop, or pressed beyond it by the solver, counts.
//! - **Torso pitch** ([`torso_pitch`]): the angle of the torso's up axis from the vertical,
//!   seen from the side (in the x–z plane of the track: `atan2(u_x, u_z)` for the up axis
//!   `u`), forward lean positive, as a biomechanist's trunk flexion; its mean and 5th and
//!   95th percentiles over the episode.

use serde::{Deserialize, Serialize};

use crate::error::{check_finite_nonempty, MetricsError, Result};

/// The `p`-quantile (`p ∈ [0, 1]`) of `values`, interpolated as in the module docs.
///
/// ```
/// let v: Vec<f64> = (1..=101).map(f64::from).collect();
/// assert_eq!(esrl_metrics::percentile(&v, 0.05).unwrap(), 6.0);
/// assert_eq!(esrl_metrics::percentile(&[1.0, 2.0], 0.5).unwrap(), 1.5);
/// ```
pub fn percentile(values: &[f64], p: f64) -> Result<f64> {
    check_finite_nonempty(values, "values")?;
    if !(0.0..=1.0).contains(&p) {
        return Err(MetricsError::InvalidParameter {
            what: "p".into(),
            value: p.to_string(),
            why: "must be in [0, 1]".into(),
        });
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    Ok(percentile_sorted(&sorted, p))
}

fn percentile_sorted(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    match sorted.get(lo + 1) {
        Some(&next) => sorted[lo] + (h - lo as f64) * (next - sorted[lo]),
        None => sorted[lo],
    }
}

/// How one actuated joint moved over a rollout (angles in rad).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointMotion {
    /// Joint name.
    pub name: String,
    /// 5th percentile of the angle.
    pub p5: f64,
    /// 95th percentile of the angle.
    pub p95: f64,
    /// Range of motion `p95 − p5`.
    pub range: f64,
    /// Position limits `[lower, upper]`, `None` for a joint without limits.
    pub limits: Option<[f64; 2]>,
    /// Share of samples within the margin of the lower limit (`None` without limits).
    pub at_lower: Option<f64>,
    /// Share of samples within the margin of the upper limit (`None` without limits).
    pub at_upper: Option<f64>,
    /// Share of samples within the margin of either limit (`None` without limits).
    pub at_limit: Option<f64>,
}

/// Range of motion and time at a limit (within `margin` rad) of one joint's angles.
///
/// Errors: no angles, NaN/inf, limits with `lower > upper` or non-finite, a negative margin.
///
/// ```
/// // 10 samples, 3 of them within 1° of the upper limit 0.5 rad.
/// let q = [0.0, 0.1, 0.2, 0.3, 0.4, 0.45, 0.49, 0.495, 0.5, 0.2];
/// let m = esrl_metrics::joint_motion("hip", &q, Some([-1.0, 0.5]), 1f64.to_radians()).unwrap();
/// assert_eq!(m.at_upper, Some(0.3));
/// assert_eq!(m.at_limit, Some(0.3));
/// ```
pub fn joint_motion(
    name: &str,
    angles: &[f64],
    limits: Option<[f64; 2]>,
    margin: f64,
) -> Result<JointMotion> {
    check_finite_nonempty(angles, &format!("joint_angles[{name}]"))?;
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(MetricsError::InvalidParameter {
            what: "limit_margin".into(),
            value: margin.to_string(),
            why: "must be finite and ≥ 0".into(),
        });
    }
    if let Some([lo, hi]) = limits {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(MetricsError::InvalidParameter {
                what: format!("joint_limits[{name}]"),
                value: format!("[{lo}, {hi}]"),
                why: "must be finite with lower ≤ upper".into(),
            });
        }
    }
    let mut sorted = angles.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (p5, p95) = (
        percentile_sorted(&sorted, 0.05),
        percentile_sorted(&sorted, 0.95),
    );
    let n = angles.len() as f64;
    let share = |f: &dyn Fn(f64) -> bool| angles.iter().filter(|&&q| f(q)).count() as f64 / n;
    let (at_lower, at_upper, at_limit) = match limits {
        Some([lo, hi]) => (
            Some(share(&|q| q <= lo + margin)),
            Some(share(&|q| q >= hi - margin)),
            Some(share(&|q| q <= lo + margin || q >= hi - margin)),
        ),
        None => (None, None, None),
    };
    Ok(JointMotion {
        name: name.to_string(),
        p5,
        p95,
        range: p95 - p5,
        limits,
        at_lower,
        at_upper,
        at_limit,
    })
}

/// The mean of several episodes' joint motions, joint by joint (matched by position; the
/// names and limits are the first episode's). Empty for no episodes.
pub fn mean_joint_motion(episodes: &[&[JointMotion]]) -> Vec<JointMotion> {
    let Some(first) = episodes.first() else {
        return Vec::new();
    };
    first
        .iter()
        .enumerate()
        .map(|(j, joint)| {
            let rows: Vec<&JointMotion> = episodes.iter().filter_map(|e| e.get(j)).collect();
            let n = rows.len() as f64;
            let m = |f: fn(&JointMotion) -> f64| rows.iter().map(|r| f(r)).sum::<f64>() / n;
            let opt = |f: fn(&JointMotion) -> Option<f64>| {
                let v: Vec<f64> = rows.iter().filter_map(|r| f(r)).collect();
                (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
            };
            JointMotion {
                name: joint.name.clone(),
                p5: m(|r| r.p5),
                p95: m(|r| r.p95),
                range: m(|r| r.range),
                limits: joint.limits,
                at_lower: opt(|r| r.at_lower),
                at_upper: opt(|r| r.at_upper),
                at_limit: opt(|r| r.at_limit),
            }
        })
        .collect()
}

/// How far the torso leaned over a rollout (rad, forward lean positive; module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TorsoPitch {
    /// Mean pitch.
    pub mean: f64,
    /// 5th percentile of the pitch.
    pub p5: f64,
    /// 95th percentile of the pitch.
    pub p95: f64,
}

/// The pitch (rad, forward lean positive) of a body with orientation `q` (unit quaternion
/// `[x, y, z, w]`, body to world, z up and x forward along the track): the angle of its up
/// axis `u` from the vertical in the track's x–z plane, `atan2(u_x, u_z)`. A roll about the
/// body's forward axis before the pitch leaves it unchanged; a body turned away from the
/// track by ψ shows about cos ψ of its lean.
///
/// ```
/// let t = 0.2f64; // turned 0.2 rad about +y: the top moves towards +x
/// let q = [0.0, (t / 2.0).sin(), 0.0, (t / 2.0).cos()];
/// assert!((esrl_metrics::pitch_of(q) - t).abs() < 1e-12);
/// ```
pub fn pitch_of([x, y, z, w]: [f64; 4]) -> f64 {
    // The body's z axis in the world: the third column of the rotation matrix.
    let up_x = 2.0 * (x * z + w * y);
    let up_z = 1.0 - 2.0 * (x * x + y * y);
    up_x.atan2(up_z)
}

/// Mean and 5th/95th percentiles of a rollout's torso pitch angles (rad).
///
/// Errors: no angles, NaN/inf.
///
/// ```
/// let p = esrl_metrics::torso_pitch(&[0.0, 0.1, 0.2, 0.3, 0.4]).unwrap();
/// assert!((p.mean - 0.2).abs() < 1e-12 && (p.p5 - 0.02).abs() < 1e-12);
/// ```
pub fn torso_pitch(angles: &[f64]) -> Result<TorsoPitch> {
    check_finite_nonempty(angles, "torso_pitch")?;
    let mut sorted = angles.to_vec();
    sorted.sort_by(f64::total_cmp);
    Ok(TorsoPitch {
        mean: angles.iter().sum::<f64>() / angles.len() as f64,
        p5: percentile_sorted(&sorted, 0.05),
        p95: percentile_sorted(&sorted, 0.95),
    })
}

/// The mean of several episodes' torso pitch summaries, figure by figure. `None` for none.
pub fn mean_torso_pitch(episodes: &[&TorsoPitch]) -> Option<TorsoPitch> {
    let n = episodes.len() as f64;
    let m = |f: fn(&TorsoPitch) -> f64| episodes.iter().map(|p| f(p)).sum::<f64>() / n;
    (!episodes.is_empty()).then(|| TorsoPitch {
        mean: m(|p| p.mean),
        p5: m(|p| p.p5),
        p95: m(|p| p.p95),
    })
}
