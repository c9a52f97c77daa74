//! What a step earns and whether it ends the episode: the terms of paper eq. 12 and their
//! options, the fall, off-course and success rules (module docs of [`walk`](super),
//! "Reward" and "Episode").

use rapier3d::prelude::{Pose, Rotation, Vector};

use super::config::WalkConfig;

/// The torso after a step, as the reward and the episode rules see it.
pub(super) struct Torso {
    /// World pose of the torso link frame.
    pub(super) pose: Pose,
    /// Forward (world x) velocity of its origin, m/s.
    pub(super) vx: f32,
    /// Height error `z − z_stand`, m.
    pub(super) z: f32,
}

/// The actuators over the step: the clamped action, and per actuated joint the mean
/// delivered torque, the mean `|τ·ω|` and the effort limit.
pub(super) struct Effort<'a> {
    pub(super) action: &'a [f32],
    pub(super) torque: &'a [f32],
    pub(super) abs_power: &'a [f32],
    pub(super) limit: &'a [f32],
}

/// The feet after a step: their ground normal forces (N, left and right), the gait
/// clock's phase (when the config has a clock) and how many contact or air phases this step
/// ended shorter than the clock's `min_phase` (chatter).
pub(super) struct Feet {
    pub(super) force: [f32; 2],
    /// Each foot's link-origin height above its standing height, m.
    pub(super) height: [f32; 2],
    pub(super) phase: f32,
    pub(super) short_phases: u32,
}

/// Each foot's contact state and the control steps it has lasted, for the chatter term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct FootPhases {
    down: [bool; 2],
    steps: [u32; 2],
}

impl FootPhases {
    /// At reset, with the feet `down` or not: the phases in progress count as long (their
    /// start is not known).
    pub(super) fn reset(down: [bool; 2]) -> Self {
        Self {
            down,
            steps: [u32::MAX; 2],
        }
    }

    /// Advances one control step to the feet `down` now; returns how many phases (contact
    /// or air) this step ended after fewer than `min_steps` steps.
    pub(super) fn advance(&mut self, down: [bool; 2], min_steps: u32) -> u32 {
        let mut short = 0;
        for (i, &now) in down.iter().enumerate() {
            if now == self.down[i] {
                self.steps[i] = self.steps[i].saturating_add(1);
            } else {
                short += u32::from(self.steps[i] < min_steps);
                self.down[i] = now;
                self.steps[i] = 1;
            }
        }
        short
    }
}

/// The verdict on one step.
pub(super) struct Outcome {
    /// Named terms, summing to `reward`.
    pub(super) terms: Vec<(&'static str, f32)>,
    /// The step's reward (0 when the state or the reward is not finite).
    pub(super) reward: f32,
    /// The torso fell (or the state stopped being finite).
    pub(super) fell: bool,
    /// The torso left the lateral band or turned past the yaw limit.
    pub(super) off_course: bool,
    /// The torso passed the end of the track.
    pub(super) success: bool,
}

/// The reward, fall, course and finish of a step: `finite` says whether the observation is
/// finite.
pub(super) fn step_outcome(
    config: &WalkConfig,
    torso: &Torso,
    finite: bool,
    e: &Effort,
    feet: &Feet,
) -> Outcome {
    let (pose, vx, z) = (torso.pose, torso.vx, torso.z);
    let y = pose.translation.y;
    let tilt = torso_tilt(pose.rotation);
    let fall = &config.fall;
    let fell = !finite || z < -fall.max_height_drop || tilt > fall.max_tilt;
    let off_course = !fell
        && (fall.max_lateral.is_some_and(|m| y.abs() > m)
            || fall
                .max_yaw
                .is_some_and(|m| torso_yaw(pose.rotation).abs() > m));
    let w = &config.reward;
    let upright = w
        .forward_gate
        .as_ref()
        .is_none_or(|g| tilt <= g.max_tilt && z >= -g.max_height_drop);
    let p_mean = e.abs_power.iter().sum::<f32>() / e.abs_power.len() as f32;
    let mut terms = vec![
        (
            "forward",
            if upright {
                w.forward
                    * w.forward_cap.map_or(vx, |c| {
                        if w.forward_over_cap > 0.0 && vx > c {
                            c - w.forward_over_cap * (vx - c)
                        } else {
                            vx.min(c)
                        }
                    })
            } else {
                0.0
            },
        ),
        ("lateral", -w.lateral * y * y),
        ("height", -w.height * z * z),
        ("power", -w.power * p_mean),
        ("alive", if fell || off_course { 0.0 } else { w.alive }),
    ];
    if w.action_sq != 0.0 {
        let a2: f32 = e.action.iter().map(|a| a * a).sum();
        terms.push(("action_sq", -w.action_sq * a2));
    }
    if let Some(clock) = &config.gait_clock {
        let r = if fell || off_course {
            0.0
        } else {
            clock.contact_reward(feet.phase, feet.force)
        };
        terms.push(("gait_clock", r));
        if clock.chatter != 0.0 {
            let c = if fell || off_course {
                0.0
            } else {
                -clock.chatter * feet.short_phases as f32
            };
            terms.push(("chatter", c));
        }
        if clock.clearance != 0.0 {
            let c = if fell || off_course {
                0.0
            } else {
                clock.clearance_reward(feet.phase, feet.height)
            };
            terms.push(("clearance", c));
        }
    }
    if w.torque_sq != 0.0 {
        let t2: f32 = e
            .torque
            .iter()
            .zip(e.limit)
            .map(|(t, l)| (t / l).powi(2))
            .sum();
        terms.push(("torque_sq", -w.torque_sq * t2));
    }
    if w.tilt_sq != 0.0 {
        terms.push(("tilt_sq", -w.tilt_sq * tilt * tilt));
    }
    let mut reward: f32 = terms.iter().map(|t| t.1).sum();
    let fell = fell || !reward.is_finite();
    if !finite || !reward.is_finite() {
        reward = 0.0;
    }
    let success = !fell && !off_course && pose.translation.x >= config.track_length;
    Outcome {
        terms,
        reward,
        fell,
        off_course,
        success,
    }
}

/// Angle between the torso's z axis and the world's, rad.
fn torso_tilt(rotation: Rotation) -> f32 {
    (rotation * Vector::Z).z.clamp(-1.0, 1.0).acos()
}

/// Heading of the torso: the angle of its x axis projected on the ground from world x, rad
/// (positive to the left); 0 when the x axis points straight up or down.
fn torso_yaw(rotation: Rotation) -> f32 {
    let x = rotation * Vector::X;
    if x.x == 0.0 && x.y == 0.0 {
        0.0
    } else {
        x.y.atan2(x.x)
    }
}

#[cfg(test)]
mod tests {
    use super::FootPhases;

    /// Counts by hand: the left foot lifts off for 1 step inside a stance (short air phase),
    /// then stands 4 steps (not short at 4), swings 5 and lands; the right foot taps the
    /// ground for 2 steps inside a swing (short contact), and its air phases around it
    /// are long or unknown.
    #[test]
    fn short_phases_are_counted_when_they_end() {
        let left = "TTTFTTTTFFFFFT";
        let right = "FFFFFTTFFFFFFF";
        let mut phases = FootPhases::reset([true, false]);
        let per_step: Vec<u32> = left
            .chars()
            .zip(right.chars())
            .map(|(l, r)| phases.advance([l == 'T', r == 'T'], 4))
            .collect();
        //                 T  T  T  F  T  T  T  T  F  F  F  F  F  T   (left)
        //                 F  F  F  F  F  T  T  F  F  F  F  F  F  F   (right)
        let expected = [0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0];
        assert_eq!(per_step, expected);
    }

    #[test]
    fn the_phase_in_progress_at_reset_is_never_short() {
        let mut phases = FootPhases::reset([true, true]);
        assert_eq!(phases.advance([false, false], 4), 0);
        // One step in the air, then down: that air phase was short.
        assert_eq!(phases.advance([true, true], 4), 2);
        // Off at 0 steps' threshold: nothing is short.
        assert_eq!(phases.advance([false, true], 0), 0);
    }
}
