//! Recording a walking rollout to an MCAP file that Foxglove opens as a moving 3D robot with
//! plottable channels (`esrl record`, `esrl eval --record`).
//!
//! | topic | fields |
//! |---|---|
//! | `/scene` | `foxglove.SceneUpdate`: each link's collision primitives (torso grey-blue, arms green, left leg blue, right leg red, feet darker) and the track |
//! | `/tf` | `foxglove.FrameTransforms`: `world` → every link, each step |
//! | `/esrl/joints/angle` | one per actuated joint (rad) |
//! | `/esrl/joints/velocity` | one per actuated joint (rad/s) |
//! | `/esrl/joints/torque` | one per actuated joint (N·m) |
//! | `/esrl/joints/power` | one per actuated joint, τ·ω averaged over the control period (W) |
//! | `/esrl/action` | one per actuated joint, the policy's action in [−1, 1] |
//! | `/esrl/feet/contact_force` | one per foot link (N) |
//! | `/esrl/reward` | `total` and every reward term of the environment |
//! | `/esrl/torso` | `x`, `y`, `z`, `forward_velocity`, `height_error` |
//!
//! Timestamps are simulated time since reset (the timeline starts at the Unix epoch): step k
//! (from 1) is at k × control period. Field names are the URDF names with any character other
//! than ASCII letters, digits and `_` replaced by `_`. A step whose state is not finite (the
//! simulation blew up; the environment ends the episode there) is not recorded.

use crate::load::LoadedRun;
use esrl_record::{
    Frame, Geometry, LinkVisual, Pose, RecordOptions, RecordingStats, RolloutWriter, ScalarTopic,
    Scene, Shape,
};
use esrl_run::{bail, Context, Error, Result};
use esrl_sim::{Env, ShapeGeometry, Step, WalkEnv};
use std::collections::{BTreeMap, HashSet};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Topic of the joint angles.
pub const ANGLE_TOPIC: &str = "/esrl/joints/angle";
/// Topic of the joint velocities.
pub const VELOCITY_TOPIC: &str = "/esrl/joints/velocity";
/// Topic of the joint torques.
pub const TORQUE_TOPIC: &str = "/esrl/joints/torque";
/// Topic of the joint power.
pub const POWER_TOPIC: &str = "/esrl/joints/power";
/// Topic of the policy's actions.
pub const ACTION_TOPIC: &str = "/esrl/action";
/// Topic of the foot contact forces.
pub const CONTACT_TOPIC: &str = "/esrl/feet/contact_force";
/// Topic of the reward and its terms.
pub const REWARD_TOPIC: &str = "/esrl/reward";
/// Topic of the torso position and velocity.
pub const TORSO_TOPIC: &str = "/esrl/torso";

/// What part of the body a link belongs to, guessed from its name (for colours).
fn link_colour(name: &str) -> [f64; 4] {
    let n = name.to_ascii_lowercase();
    let has = |words: &[&str]| words.iter().any(|w| n.contains(w));
    let left = n.starts_with("l_") || n.contains("left");
    let right = n.starts_with("r_") || n.contains("right");
    let foot = has(&["foot", "toe", "sole"]);
    if has(&["arm", "shoulder", "elbow", "hand", "wrist"]) {
        if right {
            [0.25, 0.6, 0.3, 1.0]
        } else {
            [0.35, 0.75, 0.4, 1.0]
        }
    } else if foot
        || has(&[
            "thigh", "shank", "shin", "calf", "leg", "hip", "knee", "ankle",
        ])
    {
        let base = if right {
            [0.85, 0.3, 0.25]
        } else if left {
            [0.25, 0.45, 0.9]
        } else {
            [0.6, 0.4, 0.7]
        };
        let k = if foot { 0.6 } else { 1.0 };
        [base[0] * k, base[1] * k, base[2] * k, 1.0]
    } else {
        [0.55, 0.6, 0.7, 1.0]
    }
}

fn shape_of(s: &ShapeGeometry, rgba: [f64; 4]) -> Shape {
    let geometry = match s.shape {
        esrl_sim::Shape::Box { size } => Geometry::Box {
            size: size.map(f64::from),
        },
        esrl_sim::Shape::Cylinder { radius, length } => Geometry::Cylinder {
            radius: f64::from(radius),
            length: f64::from(length),
        },
        esrl_sim::Shape::Sphere { radius } => Geometry::Sphere {
            radius: f64::from(radius),
        },
    };
    Shape {
        geometry,
        pose: Pose {
            translation: s.translation.map(f64::from),
            rotation: s.rotation.map(f64::from),
        },
        rgba,
    }
}

/// The scene of a walking environment: every link's collision primitives plus the track.
pub fn scene_of(env: &WalkEnv) -> Scene {
    let links = env
        .geometry()
        .into_iter()
        .map(|g| {
            let rgba = link_colour(&g.link);
            LinkVisual {
                shapes: g.shapes.iter().map(|s| shape_of(s, rgba)).collect(),
                name: g.link,
            }
        })
        .collect();
    Scene {
        links,
        world_shapes: Vec::new(),
    }
    .with_track(f64::from(env.config().track_length))
}

/// Field names for a topic: non-identifier characters become `_`, a leading digit gets a `_`
/// prefix, `timestamp` becomes `timestamp_`, and repeats get `_2`, `_3`, ….
pub fn field_names<S: AsRef<str>>(names: &[S]) -> Vec<String> {
    let mut seen = HashSet::new();
    names
        .iter()
        .map(|n| {
            let mut f: String = n
                .as_ref()
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            if f.is_empty() || f.starts_with(|c: char| c.is_ascii_digit()) {
                f.insert(0, '_');
            }
            if f == "timestamp" {
                f.push('_');
            }
            let base = f.clone();
            let mut k = 2;
            while !seen.insert(f.clone()) {
                f = format!("{base}_{k}");
                k += 1;
            }
            f
        })
        .collect()
}

/// MCAP metadata of a recording of `loaded` from seed `seed`.
pub fn metadata(loaded: &LoadedRun, seed: u64) -> BTreeMap<String, String> {
    BTreeMap::from([
        ("agent".into(), loaded.config.agent.name().into()),
        ("run".into(), loaded.run.display().to_string()),
        ("checkpoint".into(), loaded.checkpoint.display().to_string()),
        ("run_seed".into(), loaded.config.seed.to_string()),
        ("episode_seed".into(), seed.to_string()),
        ("esrl_version".into(), env!("CARGO_PKG_VERSION").into()),
    ])
}

/// Writes a walking rollout to MCAP step by step: [`Recorder::frame`] after every step, then
/// [`Recorder::finish`]. The file appears under its name only when finished.
pub struct Recorder {
    path: PathBuf,
    scene: Scene,
    options: RecordOptions,
    joints: Vec<String>,
    feet: Vec<String>,
    period_ns: u64,
    writer: Option<RolloutWriter<BufWriter<File>>>,
    /// For each scene link, its index in `WalkEnv::link_poses()`.
    pose_index: Vec<usize>,
    skipped: usize,
}

impl Recorder {
    /// Prepares a recording of `env` into `path` (written when the first step arrives, as the
    /// reward terms are only known then).
    pub fn create(path: &Path, env: &WalkEnv, metadata: BTreeMap<String, String>) -> Result<Self> {
        if path.is_dir() {
            bail!(
                "{} is a folder; give a file name such as run.mcap",
                path.display()
            );
        }
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        let scene = scene_of(env);
        let names: Vec<String> = env.link_poses().into_iter().map(|p| p.name).collect();
        let pose_index = scene
            .links
            .iter()
            .map(|l| {
                names.iter().position(|n| *n == l.name).with_context(|| {
                    format!(
                        "link `{}` has geometry but no pose in the simulation",
                        l.name
                    )
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let period_ns = (f64::from(env.control_period()) * 1e9).round() as u64;
        if period_ns == 0 {
            bail!(
                "control_period = {} s is below 1 ns; cannot time-stamp the recording",
                env.control_period()
            );
        }
        Ok(Self {
            path: path.to_path_buf(),
            scene,
            options: RecordOptions {
                time_offset_ns: 0,
                metadata,
            },
            joints: field_names(env.actuated_joint_names()),
            feet: field_names(&env.config().foot_links),
            period_ns,
            writer: None,
            pose_index,
            skipped: 0,
        })
    }

    fn topics(&self, reward_terms: &[&str]) -> Vec<ScalarTopic> {
        let joints: Vec<&str> = self.joints.iter().map(String::as_str).collect();
        let feet: Vec<&str> = self.feet.iter().map(String::as_str).collect();
        let mut reward = vec!["total".to_string()];
        reward.extend(field_names(reward_terms));
        let reward = field_names(&reward);
        let reward: Vec<&str> = reward.iter().map(String::as_str).collect();
        vec![
            ScalarTopic::new(ANGLE_TOPIC, &joints),
            ScalarTopic::new(VELOCITY_TOPIC, &joints),
            ScalarTopic::new(TORQUE_TOPIC, &joints),
            ScalarTopic::new(POWER_TOPIC, &joints),
            ScalarTopic::new(ACTION_TOPIC, &joints),
            ScalarTopic::new(CONTACT_TOPIC, &feet),
            ScalarTopic::new(REWARD_TOPIC, &reward),
            ScalarTopic::new(
                TORSO_TOPIC,
                &["x", "y", "z", "forward_velocity", "height_error"],
            ),
        ]
    }

    fn open(&mut self, reward_terms: &[&str]) -> Result<&mut RolloutWriter<BufWriter<File>>> {
        if self.writer.is_none() {
            let topics = self.topics(reward_terms);
            let w = RolloutWriter::create(&self.path, &self.scene, &topics, self.options.clone())
                .map_err(Error::other)
                .with_context(|| format!("creating {}", self.path.display()))?;
            self.writer = Some(w);
        }
        self.writer.as_mut().context("the recording was not opened")
    }

    /// Records the step just taken by `env` with `action`.
    pub fn frame(&mut self, env: &WalkEnv, action: &[f32], step: &Step) -> Result<()> {
        let terms: Vec<&str> = step.info.reward_terms.iter().map(|t| t.0).collect();
        let Some(g) = &step.info.gait else {
            bail!("the environment reported no gait data; only walking rollouts can be recorded");
        };
        let poses = env.link_poses();
        let link_poses: Vec<Pose> = self
            .pose_index
            .iter()
            .map(|&i| Pose {
                translation: poses[i].translation.map(f64::from),
                rotation: poses[i].rotation.map(f64::from),
            })
            .collect();
        let v = |x: &[f32]| x.iter().map(|&a| f64::from(a)).collect::<Vec<f64>>();
        let mut reward = vec![f64::from(step.reward)];
        reward.extend(step.info.reward_terms.iter().map(|t| f64::from(t.1)));
        let p = g.torso_position;
        let frame = Frame {
            time_ns: env.steps() as u64 * self.period_ns,
            link_poses,
            scalars: vec![
                v(&g.joint_angle),
                v(&g.joint_velocity),
                v(&g.joint_torque),
                v(&g.joint_power),
                v(action),
                v(&g.foot_force),
                reward,
                vec![
                    f64::from(p[0]),
                    f64::from(p[1]),
                    f64::from(p[2]),
                    f64::from(g.forward_velocity),
                    f64::from(g.height_error),
                ],
            ],
        };
        let finite = frame.scalars.iter().flatten().all(|x| x.is_finite())
            && frame.link_poses.iter().all(|p| {
                p.translation
                    .iter()
                    .chain(&p.rotation)
                    .all(|x| x.is_finite())
            });
        if !finite {
            self.skipped += 1;
            return Ok(());
        }
        let path = self.path.clone();
        self.open(&terms)?
            .write_frame(&frame)
            .map_err(Error::other)
            .with_context(|| format!("writing step {} to {}", env.steps(), path.display()))
    }

    /// Steps left out because their state was not finite.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// Finishes the file and moves it to its name.
    pub fn finish(mut self) -> Result<RecordingStats> {
        let path = self.path.clone();
        // A rollout whose every step was skipped still gives a valid (empty) file.
        self.open(&[])?;
        let w = self.writer.take().context("the recording was not opened")?;
        w.finish_file()
            .map_err(Error::other)
            .with_context(|| format!("finishing {}", path.display()))
    }
}
