//! A trained policy loaded from a run folder's checkpoint (`esrl train`), acting and rolling
//! out deterministically in Rust — the same networks, weights and loop as `esrl eval`.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use esrl::args::EnvKind;
use esrl::config::TrainConfig;
use esrl_agents::{ActMode, Agent, Policy};
use esrl_metrics::{gait_metrics, GaitOptions, GaitStep, GaitTrace};
use esrl_sim::{Env, Pendulum, WalkEnv};
use numpy::{AllowTypeChange, PyArray1, PyArrayLike1};
use pyo3::exceptions::{PyFileNotFoundError, PyPermissionError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::convert::json_to_py;
use crate::errors::{esrl_error, not_found, panic_message, value_error};

/// An `anyhow` error from the CLI library: I/O kinds are kept, the rest is a `ValueError`
/// (bad config, checkpoint that does not match it), with the whole context chain.
fn cli_error(error: anyhow::Error) -> PyErr {
    let message = format!("{error:#}");
    match error
        .chain()
        .find_map(|e| e.downcast_ref::<std::io::Error>())
        .map(std::io::Error::kind)
    {
        Some(std::io::ErrorKind::NotFound) => PyFileNotFoundError::new_err(message),
        Some(std::io::ErrorKind::PermissionDenied) => PyPermissionError::new_err(message),
        _ => value_error(message),
    }
}

/// The run folder and the checkpoint folder for a path that is either.
fn locate(path: &Path) -> PyResult<(PathBuf, PathBuf)> {
    if !path.exists() {
        return Err(not_found(format!(
            "{}: no such run or checkpoint folder",
            path.display()
        )));
    }
    if path.join("config.toml").is_file() {
        let ckpt = esrl::checkpoint::find(path).ok_or_else(|| {
            not_found(format!(
                "{} has no complete checkpoint (checkpoint/ with state.json and \
                 agent.safetensors)",
                path.display()
            ))
        })?;
        return Ok((path.to_path_buf(), ckpt));
    }
    if path.join("agent.safetensors").is_file() {
        if let Some(run) = path.parent().filter(|r| r.join("config.toml").is_file()) {
            return Ok((run.to_path_buf(), path.to_path_buf()));
        }
    }
    Err(value_error(format!(
        "{} is neither a run folder (with config.toml) nor a checkpoint folder inside one \
         (with agent.safetensors)",
        path.display()
    )))
}

struct Inner {
    agent: Agent,
    policy: Policy,
    rng: ChaCha8Rng,
}

/// A trained agent: its deterministic policy (`tanh(μ)`), its critics' Q₀ and its
/// environment, ready for rollouts.
#[pyclass(module = "esrl_rs._native")]
pub struct PolicyCore {
    inner: Mutex<Inner>,
    config: TrainConfig,
    run: PathBuf,
    checkpoint: PathBuf,
    obs_dim: usize,
    act_dim: usize,
}

impl PolicyCore {
    fn make_env(&self) -> PyResult<Box<dyn Env>> {
        Ok(match self.config.env {
            EnvKind::Walk => {
                Box::new(WalkEnv::new(self.config.walk.clone()).map_err(crate::errors::sim_error)?)
            }
            EnvKind::Pendulum => Box::new(Pendulum::new()),
        })
    }

    /// Locks the agent for a short, GIL-holding call (`act`, `q0`, `reset`). Safe against
    /// deadlock because `rollout` takes and releases the lock entirely without the GIL.
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Inner>> {
        self.inner
            .lock()
            .map_err(|_| esrl_error("policy is poisoned by an earlier panic"))
    }

    fn check_obs(&self, obs: &[f32]) -> PyResult<()> {
        if obs.len() != self.obs_dim {
            return Err(value_error(format!(
                "obs: length {}, expected {}",
                obs.len(),
                self.obs_dim
            )));
        }
        Ok(())
    }
}

/// What one rollout produced.
struct Rollout {
    ret: f64,
    length: usize,
    terminated: bool,
    truncated: bool,
    q0: f64,
    trace: Option<GaitTrace>,
}

#[pymethods]
impl PolicyCore {
    /// Loads a run folder (its newest complete checkpoint) or a checkpoint folder inside one.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let (run, checkpoint) = locate(&path)?;
        let config = TrainConfig::load(&run.join("config.toml")).map_err(cli_error)?;
        let (obs_dim, act_dim) = match config.env {
            EnvKind::Walk => {
                let env = WalkEnv::new(config.walk.clone()).map_err(crate::errors::sim_error)?;
                (env.obs_dim(), env.act_dim())
            }
            EnvKind::Pendulum => {
                let env = Pendulum::new();
                (env.obs_dim(), env.act_dim())
            }
        };
        let mut agent = py
            .detach(|| {
                Agent::new(
                    esrl::train::algo_of(config.agent),
                    obs_dim,
                    act_dim,
                    &config.network,
                    &config.rl,
                    config.seed,
                )
            })
            .map_err(|e| value_error(format!("{}: building the agent: {e}", run.display())))?;
        esrl::checkpoint::load_agent(&checkpoint, &mut agent).map_err(cli_error)?;
        let policy = agent.policy();
        Ok(Self {
            inner: Mutex::new(Inner {
                agent,
                policy,
                rng: ChaCha8Rng::seed_from_u64(0),
            }),
            config,
            run,
            checkpoint,
            obs_dim,
            act_dim,
        })
    }

    /// The agent (`es-sac`, `sac`, ...).
    #[getter]
    fn agent(&self) -> &'static str {
        self.config.agent.name()
    }

    /// The environment (`walk` or `pendulum`).
    #[getter]
    fn env(&self) -> &'static str {
        match self.config.env {
            EnvKind::Walk => "walk",
            EnvKind::Pendulum => "pendulum",
        }
    }

    /// The run folder.
    #[getter]
    fn run(&self) -> String {
        self.run.display().to_string()
    }

    /// The checkpoint folder the weights came from.
    #[getter]
    fn checkpoint(&self) -> String {
        self.checkpoint.display().to_string()
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

    /// The run's `WalkConfig` as a dict (also for pendulum runs, where it is unused).
    #[getter]
    fn walk_config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json =
            serde_json::to_value(&self.config.walk).map_err(|e| value_error(e.to_string()))?;
        json_to_py(py, &json, false)
    }

    /// Zeroes the recurrent state (call at the start of every episode).
    fn reset(&self) -> PyResult<()> {
        self.lock()?.policy.reset();
        Ok(())
    }

    /// The deterministic action `tanh(μ)` for `obs`, advancing the recurrent state.
    fn act<'py>(
        &self,
        py: Python<'py>,
        obs: PyArrayLike1<'py, f32, AllowTypeChange>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let obs: Vec<f32> = obs.as_array().iter().copied().collect();
        self.check_obs(&obs)?;
        let mut guard = self.lock()?;
        let inner = &mut *guard;
        let mut action = vec![0.0f32; self.act_dim];
        inner
            .policy
            .act(&obs, ActMode::Deterministic, &mut inner.rng, &mut action);
        Ok(PyArray1::from_vec(py, action))
    }

    /// Q₀: the critics' estimate (minimum) at `obs` for the deterministic action, from a zero
    /// recurrent state.
    fn q0(&self, obs: PyArrayLike1<'_, f32, AllowTypeChange>) -> PyResult<f64> {
        let obs: Vec<f32> = obs.as_array().iter().copied().collect();
        self.check_obs(&obs)?;
        Ok(self.lock()?.agent.q0(&obs))
    }

    /// One deterministic episode from `reset(seed)` in the run's environment (as `esrl eval`):
    /// `{"seed", "return", "length", "terminated", "truncated", "q0"}`, plus for walking runs
    /// `"trace"` (`time`, `x`, `y`, `z_error`, `forward_velocity`) and `"gait"` (the gait
    /// metrics of esrl-metrics on the run's track length).
    fn rollout<'py>(&self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyDict>> {
        let mut env = self.make_env()?;
        let walk = self.config.env == EnvKind::Walk;
        let names = (
            self.config.walk.actuated_joints.clone(),
            self.config.walk.foot_links.to_vec(),
        );
        // The lock is taken and released without the GIL (see `lock`).
        let r = py
            .detach(|| {
                let mut guard = self.inner.lock().map_err(|_| None)?;
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    rollout(&mut *env, &mut guard, seed, walk.then_some(names))
                }))
                .map_err(|p| Some(panic_message(p.as_ref())))
            })
            .map_err(|e| match e {
                None => esrl_error("policy is poisoned by an earlier panic"),
                Some(m) => esrl_error(format!("the simulator panicked during a rollout: {m}")),
            })?;
        let out = PyDict::new(py);
        out.set_item("seed", seed)?;
        out.set_item("return", r.ret)?;
        out.set_item("length", r.length)?;
        out.set_item("terminated", r.terminated)?;
        out.set_item("truncated", r.truncated)?;
        out.set_item("q0", r.q0)?;
        if let Some(trace) = r.trace {
            let series = serde_json::json!({
                "time": trace.time, "x": trace.torso_x, "y": trace.torso_y,
                "z_error": trace.torso_z_error, "forward_velocity": trace.forward_velocity,
            });
            out.set_item("trace", json_to_py(py, &series, true)?)?;
            let options = GaitOptions {
                track_length: f64::from(self.config.walk.track_length),
                ..GaitOptions::default()
            };
            let gait = match gait_metrics(&trace, &options) {
                Ok(g) => {
                    let json = serde_json::to_value(g).map_err(|e| value_error(e.to_string()))?;
                    json_to_py(py, &json, true)?
                }
                Err(_) => py.None().into_bound(py),
            };
            out.set_item("gait", gait)?;
        }
        Ok(out)
    }
}

/// The episode loop of `esrl eval`: reset(seed), deterministic actions, stop at termination,
/// truncation or `max_episode_steps`; the walking gait log skips non-finite samples.
fn rollout(
    env: &mut dyn Env,
    inner: &mut Inner,
    seed: u64,
    names: Option<(Vec<String>, Vec<String>)>,
) -> Rollout {
    inner.policy.reset();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut obs = env.reset(seed);
    let q0 = inner.agent.q0(&obs);
    let mut trace = names.map(|(a, f)| GaitTrace::new(a, f));
    let mut action = vec![0.0f32; env.act_dim()];
    let limit = env.max_episode_steps().max(1);
    let f64s = |v: &[f32]| v.iter().map(|&x| f64::from(x)).collect::<Vec<f64>>();
    let mut out = Rollout {
        ret: 0.0,
        length: 0,
        terminated: false,
        truncated: false,
        q0,
        trace: None,
    };
    loop {
        inner
            .policy
            .act(&obs, ActMode::Deterministic, &mut rng, &mut action);
        let step = env.step(&action);
        out.ret += f64::from(step.reward);
        out.length += 1;
        if let (Some(t), Some(g)) = (trace.as_mut(), &step.info.gait) {
            t.fell |= g.fell;
            let finite = [g.time, g.lateral_offset, g.height_error, g.forward_velocity]
                .iter()
                .chain(&g.torso_position)
                .chain(&g.joint_torque)
                .chain(&g.joint_power)
                .chain(&g.foot_force)
                .all(|v| v.is_finite());
            if finite {
                t.push(&GaitStep {
                    time: f64::from(g.time),
                    torso_x: f64::from(g.torso_position[0]),
                    torso_y: f64::from(g.lateral_offset),
                    torso_z_error: f64::from(g.height_error),
                    forward_velocity: f64::from(g.forward_velocity),
                    torques: &f64s(&g.joint_torque),
                    powers: &f64s(&g.joint_power),
                    foot_forces: &f64s(&g.foot_force),
                });
                if g.success && t.success_time.is_none() {
                    t.success_time = Some(f64::from(g.time));
                }
            }
        }
        if step.terminated || step.truncated || out.length >= limit {
            out.terminated = step.terminated;
            out.truncated = !step.terminated;
            out.trace = trace;
            return out;
        }
        obs = step.obs;
    }
}

/// Registers the class.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<PolicyCore>()
}
