//! Left↔right mirror symmetry of the walking task: the reflection of an observation and an
//! action through the torso's sagittal (x–z) plane, so that a transition and its mirror image
//! are both transitions of the task (Yu, Turk & Liu, "Learning Symmetric and Low-Energy
//! Locomotion", SIGGRAPH 2018, use the same map for mirrored data and a symmetry loss).
//!
//! The reflection `M = diag(1, −1, 1)` acts on each part of the observation
//! (module docs of [`walk`](super), "Observation") as:
//!
//! | part | mirror |
//! |---|---|
//! | height error | unchanged |
//! | lateral offset `y` | `−y` |
//! | orientation quaternion `(x, y, z, w)` | `(−x, y, −z, w)` (`R ↦ M R M`) |
//! | body linear velocity, acceleration `(x, y, z)` | `(x, −y, z)` (vectors) |
//! | body angular velocity `(x, y, z)` | `(−x, y, −z)` (a pseudovector: `ω ↦ −M ω`) |
//! | joint angles, velocities, previous action | each `left_*` joint takes its `right_*` partner's value, times the pair's sign |
//! | foot forces | left and right swapped |
//! | gait clock `(sin 2πφ, cos 2πφ)` | `(−sin, −cos)`: φ + ½, the clock's other foot |
//!
//! Joints pair by name: a joint whose name contains `left` pairs with the joint named with
//! `right` in its place, and the other way round; a joint with neither (a spine, a neck)
//! maps to itself. A pair's sign is +1 when the right joint's axis is the reflection of the
//! left one's (a pitch axis `(0, 1, 0)` on both sides; a roll axis `(1, 0, 0)` on the left
//! and `(−1, 0, 0)` on the right, as the embedded humanoid has them) and −1 when it is the
//! reflection's opposite; a self-paired joint's sign says whether its axis lies in the
//! sagittal plane's normal direction (pitch: +1) or in the plane (roll, yaw: −1). Axes are
//! compared in the parent link's frame at the joint's zero angle; a pair whose axes are
//! neither is refused, as is a `left` joint without its `right` partner.
//!
//! The reward of eq. 12, the gait clock's terms and the fall rule are symmetric under this
//! map on a symmetric robot, so a mirrored transition earns the same reward.

use super::setup::WalkShared;
use crate::error::SimError;
use crate::math;
use crate::model::RobotModel;

/// A signed permutation of the observation and of the action: entry `i` of the image is
/// `sign · x[source]` for the `(source, sign)` at `i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mirror {
    obs: Vec<(usize, f32)>,
    action: Vec<(usize, f32)>,
}

impl Mirror {
    /// The mirror image of an observation.
    pub fn obs(&self, obs: &[f32]) -> Vec<f32> {
        apply(&self.obs, obs)
    }

    /// The mirror image of an action.
    pub fn action(&self, action: &[f32]) -> Vec<f32> {
        apply(&self.action, action)
    }

    /// Mirrors an observation in place (`scratch` is overwritten).
    pub fn obs_in_place(&self, obs: &mut [f32], scratch: &mut Vec<f32>) {
        apply_in_place(&self.obs, obs, scratch);
    }

    /// Mirrors an action in place (`scratch` is overwritten).
    pub fn action_in_place(&self, action: &mut [f32], scratch: &mut Vec<f32>) {
        apply_in_place(&self.action, action, scratch);
    }

    /// `(source, sign)` of every observation index.
    pub fn obs_map(&self) -> &[(usize, f32)] {
        &self.obs
    }

    /// `(source, sign)` of every action index.
    pub fn action_map(&self) -> &[(usize, f32)] {
        &self.action
    }
}

fn apply(map: &[(usize, f32)], x: &[f32]) -> Vec<f32> {
    map.iter().map(|&(j, s)| s * x[j]).collect()
}

fn apply_in_place(map: &[(usize, f32)], x: &mut [f32], scratch: &mut Vec<f32>) {
    scratch.clear();
    scratch.extend_from_slice(x);
    for (i, &(j, s)) in map.iter().enumerate() {
        x[i] = s * scratch[j];
    }
}

/// The name of `name`'s mirror partner: `left` ↔ `right` (first occurrence), or itself.
fn partner_name(name: &str) -> String {
    if let Some(i) = name.find("left") {
        format!("{}right{}", &name[..i], &name[i + 4..])
    } else if let Some(i) = name.find("right") {
        format!("{}left{}", &name[..i], &name[i + 5..])
    } else {
        name.to_owned()
    }
}

/// A joint axis in its parent link's frame at zero angle.
fn parent_axis(model: &RobotModel, j: usize) -> [f64; 3] {
    let joint = &model.joints()[j];
    math::mat_vec(&joint.origin.r, joint.axis)
}

/// For each joint of `joints` (model indices), the position in `joints` of its partner and
/// the pair's sign (module docs).
fn joint_pairs(
    model: &RobotModel,
    joints: &[usize],
    field: &str,
) -> Result<Vec<(usize, f32)>, SimError> {
    let err = |reason: String| SimError::Model {
        field: field.into(),
        reason,
    };
    joints
        .iter()
        .map(|&j| {
            let name = &model.joints()[j].name;
            let partner = partner_name(name);
            let k = joints
                .iter()
                .position(|&o| model.joints()[o].name == partner)
                .ok_or_else(|| {
                    err(format!(
                        "mirroring needs `{name}`'s partner `{partner}` among these joints"
                    ))
                })?;
            let a = parent_axis(model, j);
            let b = parent_axis(model, joints[k]);
            // The reflection of the axis (a pseudovector) through the x–z plane.
            let reflected = [-a[0], a[1], -a[2]];
            let d = math::dot(reflected, b);
            if (d.abs() - 1.0).abs() > 1e-3 {
                return Err(err(format!(
                    "`{name}` and `{partner}` are not mirror images: axes {a:?} and {b:?} in \
                     their parent frames"
                )));
            }
            Ok((k, d.signum() as f32))
        })
        .collect()
}

/// The mirror of the task `s` (see the module docs).
pub(super) fn mirror(s: &WalkShared) -> Result<Mirror, SimError> {
    let layout = &s.layout;
    let actuated = joint_pairs(&s.model, &s.actuated, "actuated_joints")?;
    let passive = joint_pairs(&s.model, &s.passive, "passive joints")?;
    let mut obs: Vec<(usize, f32)> = (0..layout.len).map(|i| (i, 1.0)).collect();
    obs[layout.lateral_offset].1 = -1.0;
    let o = layout.orientation.start;
    obs[o].1 = -1.0;
    obs[o + 2].1 = -1.0;
    for r in [&layout.linear_velocity, &layout.acceleration] {
        obs[r.start + 1].1 = -1.0;
    }
    let w = layout.angular_velocity.start;
    obs[w].1 = -1.0;
    obs[w + 2].1 = -1.0;
    for (range, pairs) in [
        (&layout.joint_angles, &actuated),
        (&layout.joint_velocities, &actuated),
        (&layout.previous_action, &actuated),
        (&layout.passive_angles, &passive),
        (&layout.passive_velocities, &passive),
    ] {
        for (i, &(k, sign)) in pairs.iter().enumerate() {
            obs[range.start + i] = (range.start + k, sign);
        }
    }
    let feet = &s.config.foot_links;
    if partner_name(&feet[0]) != feet[1] {
        return Err(SimError::Model {
            field: "foot_links".into(),
            reason: format!(
                "mirroring needs the feet to be mirror partners by name (`left…` and \
                 `right…`), not `{}` and `{}`",
                feet[0], feet[1]
            ),
        });
    }
    let f = layout.foot_forces.start;
    obs[f] = (f + 1, 1.0);
    obs[f + 1] = (f, 1.0);
    if let Some(c) = &layout.clock {
        obs[c.start].1 = -1.0;
        obs[c.start + 1].1 = -1.0;
    }
    Ok(Mirror {
        obs,
        action: actuated,
    })
}
