//! The observation of the walking task: its layout ([`ObsLayout`]), its fixed scaling, the
//! vector itself and a name per index (module docs of [`walk`](super), "Observation").

use std::ops::Range;

use rapier3d::prelude::{Rotation, Vector};
use serde::Serialize;

use super::OrientationFrame;
use crate::model::RobotModel;
use crate::sim::RobotSim;

/// What an observation reads, in its order: the torso, the actuated and passive joints, the
/// feet, and the factor of each index.
pub(super) struct Sources<'a> {
    /// The torso link.
    pub(super) torso: usize,
    /// Torso origin height in the standing pose, m.
    pub(super) standing_height: f64,
    /// Actuated joints, in action order.
    pub(super) actuated: &'a [usize],
    /// Passive joints, in URDF order.
    pub(super) passive: &'a [usize],
    /// Left and right foot links.
    pub(super) feet: [usize; 2],
    /// Body weight, N (foot forces are divided by it).
    pub(super) weight: f32,
    /// Per-index factor.
    pub(super) scale: &'a [f32],
    /// What the torso orientation is measured against.
    pub(super) orientation_frame: OrientationFrame,
}

/// Index ranges of the observation vector (see the module docs for units and frames).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ObsLayout {
    /// Torso height error.
    pub height_error: usize,
    /// Torso lateral offset.
    pub lateral_offset: usize,
    /// Torso quaternion x, y, z, w.
    pub orientation: Range<usize>,
    /// Torso linear velocity, body frame.
    pub linear_velocity: Range<usize>,
    /// Torso angular velocity, body frame.
    pub angular_velocity: Range<usize>,
    /// Torso linear acceleration, body frame.
    pub acceleration: Range<usize>,
    /// Actuated joint angles.
    pub joint_angles: Range<usize>,
    /// Actuated joint velocities.
    pub joint_velocities: Range<usize>,
    /// Passive joint angles.
    pub passive_angles: Range<usize>,
    /// Passive joint velocities.
    pub passive_velocities: Range<usize>,
    /// Left, right foot normal force / body weight.
    pub foot_forces: Range<usize>,
    /// Previous action.
    pub previous_action: Range<usize>,
    /// Gait clock (sin 2πφ, cos 2πφ), when [`WalkConfig::gait_clock`](super::WalkConfig::gait_clock)
    /// is set.
    pub clock: Option<Range<usize>>,
    /// Total length.
    pub len: usize,
}

impl ObsLayout {
    pub(super) fn new(n_a: usize, n_p: usize, clock: bool) -> Self {
        let mut at = 2;
        let mut take = |n: usize| {
            let r = at..at + n;
            at += n;
            r
        };
        let orientation = take(4);
        let linear_velocity = take(3);
        let angular_velocity = take(3);
        let acceleration = take(3);
        let joint_angles = take(n_a);
        let joint_velocities = take(n_a);
        let passive_angles = take(n_p);
        let passive_velocities = take(n_p);
        let foot_forces = take(2);
        let previous_action = take(n_a);
        let clock = clock.then(|| take(2));
        Self {
            height_error: 0,
            lateral_offset: 1,
            orientation,
            linear_velocity,
            angular_velocity,
            acceleration,
            joint_angles,
            joint_velocities,
            passive_angles,
            passive_velocities,
            foot_forces,
            previous_action,
            clock,
            len: at,
        }
    }

    /// The factor each index is multiplied by when `normalize_obs` is on (module docs).
    pub(super) fn scale(&self) -> Vec<f32> {
        let mut s = vec![1.0; self.len];
        s[self.height_error] = 10.0;
        s[self.lateral_offset] = 10.0;
        for (range, f) in [
            (&self.angular_velocity, 0.5),
            (&self.acceleration, 0.1),
            (&self.joint_velocities, 0.1),
            (&self.passive_velocities, 0.5),
        ] {
            s[range.clone()].fill(f);
        }
        s
    }
}

/// The observation after a step (or a reset): the module docs' table, in its order, each
/// entry multiplied by its scale factor. `acceleration` is the torso's world acceleration
/// over the last control period, `previous_action` the clamped action of the last step,
/// `phase` the gait clock's phase when there is a clock.
pub(super) fn observe(
    s: &Sources,
    sim: &RobotSim,
    previous_action: &[f32],
    acceleration: Vector,
    phase: Option<f32>,
) -> Vec<f32> {
    let pose = sim.link_pose(s.torso);
    let inv = pose.rotation.inverse();
    let v = inv * sim.link_origin_velocity(s.torso);
    let w = inv * sim.link_angular_velocity(s.torso);
    let a = inv * acceleration;
    let q = observed_orientation(s.orientation_frame, sim, pose.rotation);
    let mut obs = Vec::with_capacity(s.scale.len());
    obs.push(pose.translation.z - s.standing_height as f32);
    obs.push(pose.translation.y);
    obs.extend([q.x, q.y, q.z, q.w]);
    obs.extend(v.to_array());
    obs.extend(w.to_array());
    obs.extend(a.to_array());
    obs.extend(s.actuated.iter().map(|&j| sim.joint_position(j)));
    obs.extend(s.actuated.iter().map(|&j| sim.joint_velocity(j)));
    obs.extend(s.passive.iter().map(|&j| sim.joint_position(j)));
    obs.extend(s.passive.iter().map(|&j| sim.joint_velocity(j)));
    obs.extend(
        s.feet
            .iter()
            .map(|&f| sim.ground_normal_force(f) / s.weight),
    );
    obs.extend(previous_action.iter().copied());
    if let Some(phi) = phase {
        let angle = std::f32::consts::TAU * phi;
        obs.extend([angle.sin(), angle.cos()]);
    }
    for (o, f) in obs.iter_mut().zip(s.scale) {
        *o *= f;
    }
    obs
}

/// The torso orientation `q` (in the ground's frame, the simulation's world) as the
/// observation reports it: unchanged in the ground's frame or on flat ground; in gravity's
/// frame on a slope `s` (gravity `g·(−sin s, 0, −cos s)`), turned by `−s` about the lateral
/// axis, the rotation that takes the tilted gravity to `(0, 0, −g)`.
fn observed_orientation(frame: OrientationFrame, sim: &RobotSim, q: Rotation) -> Rotation {
    let g = sim.world().gravity;
    if frame == OrientationFrame::Ground || g.x == 0.0 {
        return q;
    }
    let slope = (-g.x).atan2(-g.z);
    Rotation::from_rotation_y(-slope) * q
}

/// A name for every observation index, e.g. `joint_angle/left_knee`; `clock` adds the gait
/// clock's `clock/sin`, `clock/cos`.
pub(super) fn names(
    model: &RobotModel,
    s: &Sources,
    foot_links: &[String],
    clock: bool,
) -> Vec<String> {
    let joint = |j: &usize| model.joints()[*j].name.clone();
    let mut names = vec!["height_error".to_owned(), "lateral_offset".to_owned()];
    names.extend(["x", "y", "z", "w"].map(|c| format!("orientation/{c}")));
    names.extend(["x", "y", "z"].map(|c| format!("linear_velocity/{c}")));
    names.extend(["x", "y", "z"].map(|c| format!("angular_velocity/{c}")));
    names.extend(["x", "y", "z"].map(|c| format!("acceleration/{c}")));
    names.extend(
        s.actuated
            .iter()
            .map(|j| format!("joint_angle/{}", joint(j))),
    );
    names.extend(
        s.actuated
            .iter()
            .map(|j| format!("joint_velocity/{}", joint(j))),
    );
    names.extend(
        s.passive
            .iter()
            .map(|j| format!("passive_angle/{}", joint(j))),
    );
    names.extend(
        s.passive
            .iter()
            .map(|j| format!("passive_velocity/{}", joint(j))),
    );
    names.extend(foot_links.iter().map(|f| format!("foot_force/{f}")));
    names.extend(
        s.actuated
            .iter()
            .map(|j| format!("previous_action/{}", joint(j))),
    );
    if clock {
        names.extend(["clock/sin", "clock/cos"].map(String::from));
    }
    names
}
