//! Setting the task up on a model: which joints are actuated or passive, where the feet and
//! the standing pose are, the physics setup, and the seeded initial state of a reset (module
//! docs of [`walk`](super), "Reset").

use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::config::{ActionMode, ResetConfig, ResetPose, WalkConfig};
use super::observation::{ObsLayout, Sources};
use crate::error::{SimError, UrdfError};
use crate::math::Iso;
use crate::model::{JointKind, RobotModel};
use crate::sim::{Base, RobotState, SimSetup};

/// Everything a [`WalkEnv`](super::WalkEnv) shares with its siblings: the parsed model, the
/// config, and what the config's names resolve to in the model.
#[derive(Debug)]
pub(super) struct WalkShared {
    pub(super) model: Arc<RobotModel>,
    pub(super) config: WalkConfig,
    /// The torso: the model's root link.
    pub(super) torso: usize,
    /// Left and right foot links.
    pub(super) feet: [usize; 2],
    /// Actuated joints, in action order.
    pub(super) actuated: Vec<usize>,
    /// Movable joints that are not actuated, in URDF order.
    pub(super) passive: Vec<usize>,
    /// Effort limit per actuated joint, N·m.
    pub(super) effort: Vec<f32>,
    /// Per actuated joint: lower and upper limit, rad (±∞ without limits).
    pub(super) range: Vec<[f32; 2]>,
    /// Per actuated joint: the span of its `target` actions around standing, rad
    /// (`target.joint_range`, else `target.range`); `None`: ±1 reach the limits.
    pub(super) target_span: Vec<Option<f32>>,
    /// Standing pose, one entry per joint (URDF order).
    pub(super) standing_q: Vec<f64>,
    /// Torso origin height in the standing pose with the feet on the ground, m.
    pub(super) standing_height: f64,
    /// Each foot link origin's height in that pose, m.
    pub(super) foot_height: [f64; 2],
    /// Total mass × gravity, N.
    pub(super) weight: f32,
    pub(super) setup: SimSetup,
    /// Steps before truncation.
    pub(super) max_steps: usize,
    pub(super) layout: ObsLayout,
    /// Per-index observation factor (all 1 when `normalize_obs` is off).
    pub(super) obs_scale: Vec<f32>,
}

fn model_err(field: &str, reason: String) -> SimError {
    SimError::Model {
        field: field.into(),
        reason,
    }
}

impl WalkShared {
    /// Resolves `config` against `model`, refusing (with the field named) what cannot work:
    /// a massless torso, unknown, fixed, effortless or repeated actuated joints, unknown feet
    /// or standing-pose joints, a model with nothing to stand on, `target` actions on joints
    /// without limits, and leg poses on joints that are not (hip, knee, ankle) triples.
    pub(super) fn new(model: Arc<RobotModel>, config: WalkConfig) -> Result<Self, SimError> {
        config.validate()?;
        let torso = model.root();
        if model.links()[torso].mass <= 0.0 {
            return Err(UrdfError::MasslessFloatingRoot {
                link: model.links()[torso].name.clone(),
            }
            .into());
        }
        let actuated = actuated_joints(&model, &config)?;
        let passive: Vec<usize> = (0..model.joints().len())
            .filter(|j| model.joints()[*j].is_movable() && !actuated.contains(j))
            .collect();
        let feet = foot_links(&model, &config)?;
        let (standing_q, standing_height) = standing(&model, &config)?;
        let stand_poses = model.forward_kinematics(
            &Iso::from_translation([0.0, 0.0, standing_height]),
            &standing_q,
        );
        let foot_height = feet.map(|f| stand_poses[f].t[2]);
        let setup = sim_setup(&model, &config, &actuated);
        let max_steps = (config.episode_seconds / config.control_period)
            .round()
            .max(1.0) as usize;
        let effort = actuated
            .iter()
            .map(|&j| model.joints()[j].effort as f32)
            .collect();
        let range = joint_ranges(&model, &config, &actuated)?;
        let target_span = target_spans(&config)?;
        if config.reset.pose != ResetPose::Standing && actuated.len() % 3 != 0 {
            return Err(model_err(
                "reset.pose",
                format!(
                    "`crouch`, `split` and `mixed` read the actuated joints as (hip, knee, ankle) \
                     per leg, and {} joints are not a multiple of 3",
                    actuated.len()
                ),
            ));
        }
        let weight = (model.total_mass() * config.physics.gravity as f64) as f32;
        let layout = ObsLayout::new(actuated.len(), passive.len(), config.gait_clock.is_some());
        let obs_scale = if config.normalize_obs {
            layout.scale()
        } else {
            vec![1.0; layout.len]
        };
        Ok(Self {
            model,
            config,
            torso,
            feet,
            actuated,
            passive,
            effort,
            range,
            target_span,
            standing_q,
            standing_height,
            foot_height,
            weight,
            setup,
            max_steps,
            layout,
            obs_scale,
        })
    }

    /// What the observation reads.
    pub(super) fn sources(&self) -> Sources<'_> {
        Sources {
            torso: self.torso,
            standing_height: self.standing_height,
            actuated: &self.actuated,
            passive: &self.passive,
            feet: self.feet,
            weight: self.weight,
            scale: &self.obs_scale,
            orientation_frame: self.config.orientation_frame,
        }
    }

    /// The standing pose at rest, feet on the ground.
    pub(super) fn standing_state(&self) -> RobotState {
        RobotState {
            base_position: [0.0, 0.0, self.standing_height],
            q: self.standing_q.clone(),
            qd: vec![0.0; self.standing_q.len()],
        }
    }

    /// The initial state of a reset with `seed`: the configured pose plus uniform noise on
    /// every movable joint, clamped into the limits, lowest point on the ground, at rest. The
    /// draws, from a ChaCha8 stream seeded with `seed`: for each movable joint in URDF order
    /// the angle then the velocity noise; then the `mixed` pose; then the leading leg of
    /// `split`; last, with a gait clock, the clock's starting phase (returned beside the state).
    pub(super) fn initial_state(&self, seed: u64) -> (RobotState, f32) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = &self.config.init_noise;
        let mut q = self.standing_q.clone();
        let mut qd = vec![0.0; q.len()];
        let mut dq = vec![0.0; q.len()];
        for (j, joint) in self.model.joints().iter().enumerate() {
            if !joint.is_movable() {
                continue;
            }
            dq[j] = noise.joint_angle as f64 * rng.random_range(-1.0..=1.0);
            qd[j] = noise.joint_velocity as f64 * rng.random_range(-1.0..=1.0);
        }
        // The pose draws come after the noise, so a `standing` reset draws the noise alone.
        let pose = match self.config.reset.pose {
            ResetPose::Mixed => {
                [ResetPose::Standing, ResetPose::Crouch, ResetPose::Split][rng.random_range(0..3)]
            }
            p => p,
        };
        let offsets = reset_offsets(&self.config.reset, pose, self.actuated.len(), &mut rng);
        for (k, &j) in self.actuated.iter().enumerate() {
            q[j] += offsets[k] as f64;
        }
        for (j, joint) in self.model.joints().iter().enumerate() {
            if !joint.is_movable() {
                continue;
            }
            q[j] += dq[j];
            if let Some([lo, hi]) = joint.limits {
                q[j] = q[j].clamp(lo, hi);
            }
        }
        let poses = self.model.forward_kinematics(&Iso::IDENTITY, &q);
        let state = RobotState {
            base_position: [0.0, 0.0, -self.model.lowest_point(&poses)],
            q,
            qd,
        };
        // The phase is drawn last, so a reset without a clock draws nothing for it.
        let phase = if self.config.gait_clock.is_some() {
            rng.random_range(0.0..1.0)
        } else {
            0.0
        };
        (state, phase)
    }
}

/// The actuated joints of `config`, in action order: each must exist, move, and have a
/// finite effort limit to scale actions by, and be listed once.
fn actuated_joints(model: &RobotModel, config: &WalkConfig) -> Result<Vec<usize>, SimError> {
    let field = "actuated_joints";
    let mut actuated = Vec::with_capacity(config.actuated_joints.len());
    for name in &config.actuated_joints {
        let Some(j) = model.joint_index(name) else {
            return Err(model_err(field, format!("the model has no joint `{name}`")));
        };
        let joint = &model.joints()[j];
        if joint.kind == JointKind::Fixed {
            return Err(model_err(field, format!("joint `{name}` is fixed")));
        }
        if !(joint.effort.is_finite() && joint.effort > 0.0) {
            return Err(model_err(
                field,
                format!(
                    "joint `{name}` needs a finite <limit effort> > 0 to scale actions, got {}",
                    joint.effort
                ),
            ));
        }
        if actuated.contains(&j) {
            return Err(model_err(field, format!("joint `{name}` is listed twice")));
        }
        actuated.push(j);
    }
    Ok(actuated)
}

/// The left and right foot links.
fn foot_links(model: &RobotModel, config: &WalkConfig) -> Result<[usize; 2], SimError> {
    let mut feet = [0; 2];
    for (k, name) in config.foot_links.iter().enumerate() {
        feet[k] = model
            .link_index(name)
            .ok_or_else(|| model_err("foot_links", format!("the model has no link `{name}`")))?;
    }
    if feet[0] == feet[1] {
        return Err(model_err(
            "foot_links",
            format!(
                "names `{}` twice: the left and right foot must be two links",
                config.foot_links[0]
            ),
        ));
    }
    Ok(feet)
}

/// The standing pose, one angle per joint (unlisted joints at 0, all clamped into their
/// limits), and the torso height that puts its lowest point on the ground.
fn standing(model: &RobotModel, config: &WalkConfig) -> Result<(Vec<f64>, f64), SimError> {
    for name in config.standing_pose.keys() {
        if model.joint_index(name).is_none() {
            return Err(model_err(
                &format!("standing_pose.{name}"),
                format!("the model has no joint `{name}`"),
            ));
        }
    }
    let standing_q: Vec<f64> = model
        .joints()
        .iter()
        .map(|j| {
            let q = config.standing_pose.get(&j.name).copied().unwrap_or(0.0) as f64;
            match j.limits {
                Some([lo, hi]) => q.clamp(lo, hi),
                None => q,
            }
        })
        .collect();
    let poses = model.forward_kinematics(&Iso::IDENTITY, &standing_q);
    let standing_height = -model.lowest_point(&poses);
    if !standing_height.is_finite() {
        return Err(model_err(
            "urdf",
            "the model has no collision shape to stand on".into(),
        ));
    }
    Ok((standing_q, standing_height))
}

/// The world every reset builds: a floating base on the ground, `substeps` Rapier steps per
/// control period, the actuator armature on the actuated joints.
fn sim_setup(model: &RobotModel, config: &WalkConfig, actuated: &[usize]) -> SimSetup {
    let mut armature = vec![0.0; model.joints().len()];
    for &j in actuated {
        armature[j] = config.physics.actuator_armature;
    }
    SimSetup {
        dt: config.control_period / config.physics.substeps as f32,
        physics: config.physics.clone(),
        base: Base::Floating,
        ground: true,
        armature,
    }
}

/// Per actuated joint (action order), the span of its `target` actions: its
/// `target.joint_range` entry, else `target.range`. A `joint_range` name that is not an
/// actuated joint is refused.
fn target_spans(config: &WalkConfig) -> Result<Vec<Option<f32>>, SimError> {
    let names = &config.actuated_joints;
    if let Some(unknown) = config
        .target
        .joint_range
        .keys()
        .find(|k| !names.contains(k))
    {
        return Err(model_err(
            "target.joint_range",
            format!(
                "`{unknown}` is not an actuated joint (they are: {})",
                names.join(", ")
            ),
        ));
    }
    Ok(names
        .iter()
        .map(|n| {
            config
                .target
                .joint_range
                .get(n)
                .copied()
                .or(config.target.range)
        })
        .collect())
}

/// Per actuated joint, its `[lower, upper]` limit (±∞ without limits); `target` actions need
/// both.
fn joint_ranges(
    model: &RobotModel,
    config: &WalkConfig,
    actuated: &[usize],
) -> Result<Vec<[f32; 2]>, SimError> {
    let range: Vec<[f32; 2]> = actuated
        .iter()
        .map(|&j| {
            model.joints()[j]
                .limits
                .map_or([f32::NEG_INFINITY, f32::INFINITY], |[lo, hi]| {
                    [lo as f32, hi as f32]
                })
        })
        .collect();
    if config.action == ActionMode::Target {
        if let Some(k) = range
            .iter()
            .position(|r| !r[0].is_finite() || !r[1].is_finite())
        {
            return Err(model_err(
                "action",
                format!(
                    "`target` maps actions onto joint ranges, and joint `{}` has no limits",
                    config.actuated_joints[k]
                ),
            ));
        }
    }
    Ok(range)
}

/// Offsets of the actuated joints from the standing pose for a reset `pose` (docs of
/// [`ResetConfig`]), joints read as (hip, knee, ankle) per leg.
fn reset_offsets(
    config: &ResetConfig,
    pose: ResetPose,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f32> {
    let mut d = vec![0.0f32; n];
    match pose {
        ResetPose::Standing | ResetPose::Mixed => {}
        ResetPose::Crouch => {
            let c = config.crouch;
            for leg in d.chunks_exact_mut(3) {
                leg.copy_from_slice(&[-c, 2.0 * c, -c]);
            }
        }
        ResetPose::Split => {
            let s = config.split;
            let lead = rng.random_range(0..n / 3);
            for (i, leg) in d.chunks_exact_mut(3).enumerate() {
                let sign = if i == lead { -1.0 } else { 1.0 };
                leg.copy_from_slice(&[sign * s, 0.0, -sign * s]);
            }
        }
    }
    d
}
