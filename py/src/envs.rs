//! The Rust core of the Gymnasium environments `esrl_rs.WalkEnv` and `esrl_rs.Pendulum`.
//!
//! `EnvCore` owns one `esrl_sim::Env` and does the stepping; the Python classes around it add
//! the Gymnasium API (spaces, `np_random`, seeding). Panics inside the simulator are caught
//! and raised as `EsrlError`; the environment then needs a `reset` before the next `step`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

use esrl_eval::render_rgb;
use esrl_sim::{Env, Pendulum, WalkConfig, WalkEnv};
use numpy::{AllowTypeChange, PyArray1, PyArray3, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::convert::json_to_py;
use crate::errors::{esrl_error, panic_message, sim_error, value_error};
use crate::metrics::from_py;

/// The Rust environment.
enum Sim {
    Walk(Box<WalkEnv>),
    Pendulum(Pendulum),
}

/// The Rust environment and whether it may step.
struct Task {
    sim: Sim,
    /// Needs a reset before stepping (new, after the episode ended, or after a caught
    /// panic).
    needs_reset: bool,
}

impl Task {
    fn new(sim: Sim) -> Self {
        Self {
            sim,
            needs_reset: true,
        }
    }

    fn env(&mut self) -> &mut dyn Env {
        match &mut self.sim {
            Sim::Walk(w) => w.as_mut(),
            Sim::Pendulum(p) => p,
        }
    }
}

/// One environment. Thread-safe (a `Mutex` around the Rust env); the GIL is released while
/// the physics steps, so environments in different threads step in parallel.
#[pyclass(module = "esrl_rs._native")]
pub struct EnvCore {
    task: Mutex<Task>,
    name: &'static str,
    obs_dim: usize,
    act_dim: usize,
    control_period: f32,
    max_episode_steps: usize,
    obs_names: Vec<String>,
    action_names: Vec<String>,
    effort_limits: Vec<f32>,
    config: serde_json::Value,
}

/// Runs `f`, turning a panic into its message.
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| panic_message(payload.as_ref()))
}

fn panicked(what: &str, message: &str) -> PyErr {
    esrl_error(format!(
        "the simulator panicked during {what}: {message}; call reset() before stepping again"
    ))
}

/// Why a step could not run (built without the GIL, turned into exceptions with it).
enum StepFailure {
    NeedsReset,
    Poisoned,
    Panic(String),
}

impl EnvCore {
    /// Locks the environment. Called only while detached from the interpreter, and the guard
    /// never outlives the detached section, so a thread waiting for the lock never holds the
    /// GIL that the lock's holder needs (no deadlock between Python threads).
    fn lock(&self) -> Result<std::sync::MutexGuard<'_, Task>, StepFailure> {
        self.task.lock().map_err(|_| StepFailure::Poisoned)
    }

    fn failure(&self, what: &str, f: StepFailure) -> PyErr {
        match f {
            StepFailure::NeedsReset => esrl_error(format!(
                "{}: call reset() before step() (the environment is new, or its episode \
                 ended: terminated or truncated)",
                self.name
            )),
            StepFailure::Poisoned => esrl_error(format!(
                "{} environment is poisoned by an earlier panic",
                self.name
            )),
            StepFailure::Panic(m) => panicked(what, &m),
        }
    }
}

#[pymethods]
impl EnvCore {
    /// The walking humanoid; `config` is a dict of `WalkConfig` fields (any subset, unknown
    /// keys are errors).
    #[staticmethod]
    #[pyo3(signature = (config = None))]
    fn walk(config: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let config: WalkConfig = match config {
            Some(c) if !c.is_none() => from_py(c, "config")?,
            _ => WalkConfig::default(),
        };
        let json = serde_json::to_value(&config).map_err(|e| value_error(e.to_string()))?;
        let env = guarded(|| WalkEnv::new(config))
            .map_err(|m| panicked("construction", &m))?
            .map_err(sim_error)?;
        Ok(Self {
            name: "walk",
            obs_dim: env.obs_dim(),
            act_dim: env.act_dim(),
            control_period: env.control_period(),
            max_episode_steps: env.max_episode_steps(),
            obs_names: env.obs_names(),
            action_names: env.actuated_joint_names().to_vec(),
            effort_limits: env.effort_limits().to_vec(),
            config: json,
            task: Mutex::new(Task::new(Sim::Walk(Box::new(env)))),
        })
    }

    /// Gymnasium `Pendulum-v1` (action in [-1, 1], scaled to ±2 N·m).
    #[staticmethod]
    fn pendulum() -> Self {
        let env = Pendulum::new();
        Self {
            name: "pendulum",
            obs_dim: env.obs_dim(),
            act_dim: env.act_dim(),
            control_period: env.control_period(),
            max_episode_steps: env.max_episode_steps(),
            obs_names: vec!["cos_theta".into(), "sin_theta".into(), "theta_dot".into()],
            action_names: vec!["torque".into()],
            effort_limits: vec![esrl_sim::pendulum::MAX_TORQUE as f32],
            config: serde_json::Value::Object(Default::default()),
            task: Mutex::new(Task::new(Sim::Pendulum(env))),
        }
    }

    /// `"walk"` or `"pendulum"`.
    #[getter]
    fn name(&self) -> &'static str {
        self.name
    }

    /// Observation length.
    #[getter]
    fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action length.
    #[getter]
    fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// Control period, s.
    #[getter]
    fn control_period(&self) -> f32 {
        self.control_period
    }

    /// Steps after which an episode is truncated.
    #[getter]
    fn max_episode_steps(&self) -> usize {
        self.max_episode_steps
    }

    /// A name per observation index.
    #[getter]
    fn obs_names(&self) -> Vec<String> {
        self.obs_names.clone()
    }

    /// A name per action index (actuated joints).
    #[getter]
    fn action_names(&self) -> Vec<String> {
        self.action_names.clone()
    }

    /// Torque at action ±1 per actuator, N·m.
    #[getter]
    fn effort_limits(&self) -> Vec<f32> {
        self.effort_limits.clone()
    }

    /// The resolved configuration (walk: every `WalkConfig` field; pendulum: empty).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.config, false)
    }

    /// Resets with `seed` and returns the first observation (float32).
    fn reset<'py>(&self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let obs = py
            .detach(|| {
                let mut task = self.lock()?;
                let obs = guarded(|| task.env().reset(seed)).map_err(StepFailure::Panic)?;
                task.needs_reset = false;
                Ok(obs)
            })
            .map_err(|f| self.failure("reset", f))?;
        Ok(PyArray1::from_vec(py, obs))
    }

    /// One control step: `(obs, reward, terminated, truncated, info)`; `info` holds
    /// `reward_terms` (name → value, summing to the reward) and, for the walk task, `gait`.
    fn step<'py>(
        &self,
        py: Python<'py>,
        action: PyArrayLike1<'py, f32, AllowTypeChange>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let action: Vec<f32> = action.as_array().iter().copied().collect();
        if action.len() != self.act_dim {
            return Err(value_error(format!(
                "action: length {}, expected {} ({})",
                action.len(),
                self.act_dim,
                self.action_names.join(", ")
            )));
        }
        let step = py
            .detach(|| {
                let mut task = self.lock()?;
                if task.needs_reset {
                    return Err(StepFailure::NeedsReset);
                }
                let step = guarded(|| task.env().step(&action)).map_err(|m| {
                    task.needs_reset = true;
                    StepFailure::Panic(m)
                })?;
                // Gymnasium: after `terminated` or `truncated` the episode is over; stepping
                // on would simulate a fallen robot past its episode.
                if step.terminated || step.truncated {
                    task.needs_reset = true;
                }
                Ok(step)
            })
            .map_err(|f| self.failure("step", f))?;
        let info = PyDict::new(py);
        let terms = PyDict::new(py);
        for (name, value) in &step.info.reward_terms {
            terms.set_item(*name, *value as f64)?;
        }
        info.set_item("reward_terms", terms)?;
        if let Some(gait) = &step.info.gait {
            let json = serde_json::to_value(gait).map_err(|e| value_error(e.to_string()))?;
            info.set_item("gait", json_to_py(py, &json, true)?)?;
        }
        let obs = PyArray1::from_vec(py, step.obs);
        PyTuple::new(
            py,
            [
                obs.into_any(),
                (step.reward as f64).into_pyobject(py)?.into_any(),
                pyo3::types::PyBool::new(py, step.terminated)
                    .to_owned()
                    .into_any(),
                pyo3::types::PyBool::new(py, step.truncated)
                    .to_owned()
                    .into_any(),
                info.into_any(),
            ],
        )
    }

    /// The factor every observation index is multiplied by (`WalkConfig::normalize_obs`);
    /// all 1 for the pendulum.
    #[getter]
    fn obs_scale(&self, py: Python<'_>) -> PyResult<Vec<f32>> {
        py.detach(|| {
            let task = self.lock()?;
            Ok(match &task.sim {
                Sim::Walk(w) => w.obs_scale().to_vec(),
                Sim::Pendulum(_) => vec![1.0; self.obs_dim],
            })
        })
        .map_err(|f| self.failure("obs_scale", f))
    }

    /// The walking robot's state now, for rebuilding it in another engine: `base_position`
    /// (the torso link origin, m) and `base_quat` (`[x, y, z, w]`), `base_velocity` and
    /// `base_angular_velocity` (of the torso origin, world frame), `joint_names`, `q`, `qd`
    /// (every movable joint, URDF order), `phase` (the gait clock's), `standing_height` (the
    /// torso origin's, m), `foot_heights` (each foot origin's standing height, m) and
    /// `weight` (N). `ValueError` for the pendulum.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let state = py
            .detach(|| {
                let task = self.lock()?;
                let Sim::Walk(w) = &task.sim else {
                    return Ok(None);
                };
                let sim = w.sim();
                let model = w.model();
                let torso = model.root();
                let pose = sim.link_pose(torso);
                let movable: Vec<usize> = (0..model.joints().len())
                    .filter(|&j| model.joints()[j].is_movable())
                    .collect();
                Ok(Some(serde_json::json!({
                    "base_position": pose.translation.to_array(),
                    "base_quat": [pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w],
                    "base_velocity": sim.link_origin_velocity(torso).to_array(),
                    "base_angular_velocity": sim.link_angular_velocity(torso).to_array(),
                    "joint_names": movable.iter().map(|&j| model.joints()[j].name.clone()).collect::<Vec<_>>(),
                    "q": movable.iter().map(|&j| sim.joint_position(j)).collect::<Vec<_>>(),
                    "qd": movable.iter().map(|&j| sim.joint_velocity(j)).collect::<Vec<_>>(),
                    "phase": w.phase(),
                    "standing_height": w.standing_height(),
                    "foot_heights": w.standing_foot_heights(),
                    "weight": w.body_weight(),
                })))
            })
            .map_err(|f| self.failure("state", f))?
            .ok_or_else(|| value_error("the pendulum has no robot state (state is for the walk)"))?;
        let dict = json_to_py(py, &state, false)?;
        Ok(dict.cast_into::<PyDict>()?)
    }

    /// The walking robot seen from the side now: an RGB image `(height, width, 3)` of uint8,
    /// `metres` of the world high, the camera following the torso
    /// (`esrl_eval::render_rgb`). The pendulum has no picture (`ValueError`).
    #[pyo3(signature = (width = 480, height = 360, metres = 2.4))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
        metres: f64,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        if width == 0 || height == 0 || width > 4096 || height > 4096 {
            return Err(value_error(format!(
                "render size {width} × {height}: each side must be in 1..=4096"
            )));
        }
        if !(metres.is_finite() && metres > 0.0) {
            return Err(value_error(format!("metres = {metres}: must be > 0")));
        }
        let pixels = py
            .detach(|| {
                let mut task = self.lock()?;
                match &mut task.sim {
                    Sim::Walk(w) => Ok(Some(render_rgb(
                        &w.geometry(),
                        &w.link_poses(),
                        width,
                        height,
                        metres,
                    ))),
                    Sim::Pendulum(_) => Ok(None),
                }
            })
            .map_err(|f| self.failure("render", f))?
            .ok_or_else(|| value_error("the pendulum has no picture (render is for the walk)"))?;
        let array = numpy::ndarray::Array3::from_shape_vec((height, width, 3), pixels)
            .map_err(|e| value_error(e.to_string()))?;
        Ok(PyArray3::from_owned_array(py, array))
    }
}

/// Registers the class.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<EnvCore>()
}
