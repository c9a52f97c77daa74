//! A trained policy loaded from a run folder's checkpoint through `esrl_eval`, the library
//! `esrl eval` runs: acting step by step from Python, and deterministic evaluations that are
//! `esrl eval` itself (same loader, same episode loop, same `eval.json` structure).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use esrl_agents::{ActMode, Policy};
use esrl_eval::{EvalReport, LoadedRun};
use numpy::{AllowTypeChange, PyArray1, PyArrayLike1};
use pyo3::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::errors::{esrl_error, not_found, panic_message, run_error, value_error};
use crate::metrics::to_py;

/// `FileNotFoundError` for what is missing (the folder, or its checkpoint); the rest of the
/// checks are the evaluation library's (`esrl_eval::locate`).
fn check_exists(path: &Path) -> PyResult<()> {
    if !path.exists() {
        return Err(not_found(format!(
            "{}: no such run or checkpoint folder",
            path.display()
        )));
    }
    // A run folder (a checkpoint folder also keeps a copy of config.toml, beside its weights,
    // and so does a policy folder that keeps the actor alone, a study record's `policy/`).
    let run_folder = path.join("config.toml").is_file()
        && !path.join("agent.safetensors").is_file()
        && !path.join("actor.safetensors").is_file();
    if run_folder && esrl_run::checkpoint::find(path).is_none() {
        return Err(not_found(format!(
            "{} has no complete checkpoint (checkpoint/ with state.json and agent.safetensors): \
             the run did not reach its first checkpoint",
            path.display()
        )));
    }
    Ok(())
}

/// The policy's step-by-step state (the recurrent state lives in `Policy`).
struct Stepper {
    policy: Policy,
    rng: ChaCha8Rng,
}

/// A trained agent: its deterministic policy (`tanh(μ)`), its critics' Q₀, and evaluations.
#[pyclass(module = "esrl_rs._native")]
pub struct PolicyCore {
    loaded: LoadedRun,
    stepper: Mutex<Stepper>,
    obs_dim: usize,
    act_dim: usize,
}

impl PolicyCore {
    /// Locks the step-by-step state for a short, GIL-holding call (`act`, `reset`); nothing
    /// else takes this lock, so no thread waits for it while another needs the GIL.
    fn stepper(&self) -> PyResult<std::sync::MutexGuard<'_, Stepper>> {
        self.stepper
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

    /// `esrl_eval::evaluate` without the GIL, with panics caught.
    fn run_evaluation(
        &self,
        py: Python<'_>,
        seed: u64,
        episodes: usize,
        record: Option<&Path>,
    ) -> PyResult<EvalReport> {
        let loaded = &self.loaded;
        py.detach(|| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                esrl_eval::evaluate(loaded, seed, episodes, record)
            }))
        })
        .map_err(|p| {
            esrl_error(format!(
                "the simulator panicked during an evaluation: {}",
                panic_message(p.as_ref())
            ))
        })?
        .map_err(run_error)
    }
}

#[pymethods]
impl PolicyCore {
    /// Loads a run folder (the policy it hands over: `RUN/best/` when it keeps one, as
    /// `esrl eval RUN`; `last`: its newest complete checkpoint, as `esrl eval --last`), or a
    /// checkpoint, `best/` or record `policy/` folder as given; `undisturbed`: on the run's
    /// task without its training-time disturbances (`[walk.perturb]`, as `esrl eval
    /// --undisturbed`); `default_starts`: from the task's standard starts (`walk.init_noise`
    /// and `walk.reset` at their defaults, as `esrl eval --default-starts`).
    #[staticmethod]
    #[pyo3(signature = (path, undisturbed=false, last=false, default_starts=false))]
    fn load(
        py: Python<'_>,
        path: PathBuf,
        undisturbed: bool,
        last: bool,
        default_starts: bool,
    ) -> PyResult<Self> {
        check_exists(&path)?;
        let pick = if last {
            esrl_eval::Pick::Last
        } else {
            esrl_eval::Pick::Kept
        };
        let mut loaded = py
            .detach(|| esrl_eval::load_run_pick(&path, pick))
            .map_err(run_error)?;
        if undisturbed {
            let mut walk = loaded.config.walk.clone();
            walk.perturb = esrl_sim::Perturb::default();
            loaded = loaded.with_walk(walk).map_err(run_error)?;
        }
        if default_starts {
            loaded = loaded.default_starts().map_err(run_error)?;
        }
        let (obs_dim, act_dim) = (loaded.agent.obs_dim(), loaded.agent.act_dim());
        let stepper = Stepper {
            policy: loaded.agent.policy(),
            rng: ChaCha8Rng::seed_from_u64(0),
        };
        Ok(Self {
            loaded,
            stepper: Mutex::new(stepper),
            obs_dim,
            act_dim,
        })
    }

    /// The agent (`es-sac`, `sac`, ...).
    #[getter]
    fn agent(&self) -> &'static str {
        self.loaded.config.agent.name()
    }

    /// The environment (`walk` or `pendulum`).
    #[getter]
    fn env(&self) -> &'static str {
        self.loaded.config.env.name()
    }

    /// The run folder.
    #[getter]
    fn run(&self) -> String {
        self.loaded.run.display().to_string()
    }

    /// The checkpoint folder the weights came from.
    #[getter]
    fn checkpoint(&self) -> String {
        self.loaded.checkpoint.display().to_string()
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
        to_py(py, &self.loaded.config.walk)
    }

    /// Zeroes the recurrent state (call at the start of every episode).
    fn reset(&self) -> PyResult<()> {
        self.stepper()?.policy.reset();
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
        let mut guard = self.stepper()?;
        let s = &mut *guard;
        let mut action = vec![0.0f32; self.act_dim];
        s.policy
            .act(&obs, ActMode::Deterministic, &mut s.rng, &mut action);
        Ok(PyArray1::from_vec(py, action))
    }

    /// Q₀: the critics' estimate (minimum) at `obs` for the deterministic action, from a zero
    /// recurrent state.
    fn q0(&self, obs: PyArrayLike1<'_, f32, AllowTypeChange>) -> PyResult<f64> {
        if !esrl_run::checkpoint::has_critics(&self.loaded.checkpoint) {
            return Err(value_error(format!(
                "{} keeps the actor alone (no agent.safetensors): it has no critics to give Q0",
                self.loaded.checkpoint.display()
            )));
        }
        let obs: Vec<f32> = obs.as_array().iter().copied().collect();
        self.check_obs(&obs)?;
        Ok(self.loaded.agent.q0(&obs))
    }

    /// `esrl eval` on this policy: `episodes` deterministic episodes with seeds `seed, seed +
    /// 1, ...` (in parallel), optionally recorded to `record/episode-NNN.mcap` (walking runs);
    /// returns the structure of `eval.json`.
    #[pyo3(signature = (seed = 0, episodes = 1, record = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        seed: u64,
        episodes: usize,
        record: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let report = self.run_evaluation(py, seed, episodes, record.as_deref())?;
        to_py(py, &report)
    }
}

/// Registers the class.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<PolicyCore>()
}
