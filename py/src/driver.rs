//! Training driven from Python with the population rolled out elsewhere (`esrl_rs.ray`).
//!
//! - `plan_train(agent, ...)`: a `train` command's options resolved by the same code as
//!   `esrl train` (`esrl_run::plan`): a new run, or a run folder continued.
//! - `Driver(plan, evaluate)`: the run's training session (`esrl_run::Session`, the same
//!   files and checkpoints as `esrl train`) whose hybrid loop hands each generation's genomes,
//!   as bytes, to the Python callable `evaluate(list[bytes]) -> list[bytes]`. Each `step()`
//!   runs one generation (or episode) with the interpreter released; the callable is called
//!   from a training thread.
//! - `Worker(config_toml)`: the other end, `rollout(genome_bytes) -> evaluation_bytes`.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use esrl_es::{Traffic, Transport, WireEvaluator, Worker};
use esrl_run::{build, AgentKind, EnvKind, Opening, Overrides, Preset, Session, TrainConfig};
use esrl_run::{TrainPlan, TrainRequest};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use crate::errors::{esrl_error, run_error, value_error};

/// A resolved `train` command: configuration, run folder, new or resumed.
#[pyclass(name = "TrainPlan", module = "esrl_rs._native", frozen)]
pub struct PyTrainPlan {
    plan: TrainPlan,
}

#[pymethods]
impl PyTrainPlan {
    /// The agent's name (`es-sac`, …).
    #[getter]
    fn agent(&self) -> &'static str {
        self.plan.cfg.agent.name()
    }

    /// Whether the agent has a population (ES-SAC, ES-TD3, ES-DDPG).
    #[getter]
    fn hybrid(&self) -> bool {
        self.plan.cfg.agent.is_hybrid()
    }

    /// The run's `config.toml` text: what a worker needs to build its policy and environment.
    #[getter]
    fn config_toml(&self) -> PyResult<String> {
        self.plan.cfg.to_toml().map_err(run_error)
    }

    /// The run folder.
    #[getter]
    fn root(&self) -> PathBuf {
        self.plan.root.clone()
    }

    /// Whether the run continues from its folder.
    #[getter]
    fn resume(&self) -> bool {
        self.plan.resume
    }

    /// What to tell the user before it starts.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.plan.notes.clone()
    }

    /// Rows the budget asks for: generations (hybrid) or episodes (plain).
    #[getter]
    fn total(&self) -> usize {
        if self.plan.cfg.agent.is_hybrid() {
            self.plan.cfg.generations
        } else {
            self.plan.cfg.episodes
        }
    }

    /// The environment-step budget, if any.
    #[getter]
    fn max_env_steps(&self) -> Option<u64> {
        self.plan.cfg.max_env_steps
    }

    /// Threads of the driver's updates (0: one per core).
    #[getter]
    fn threads(&self) -> usize {
        self.plan.cfg.threads
    }

    /// Seed of the run.
    #[getter]
    fn seed(&self) -> u64 {
        self.plan.cfg.seed
    }
}

fn parse_name<T>(
    what: &str,
    name: &str,
    parse: fn(&str) -> Option<T>,
    all: &[&str],
) -> PyResult<T> {
    parse(name)
        .ok_or_else(|| value_error(format!("{what} {name:?}: not one of {}", all.join(", "))))
}

/// Resolves a `train` command as `esrl train` does.
#[pyfunction]
#[pyo3(signature = (agent, *, seed=None, out=None, resume=None, preset=None, config=None,
    env=None, urdf=None, threads=None, generations=None, episodes=None, steps=None,
    until=None, init=None))]
#[allow(clippy::too_many_arguments)]
fn plan_train(
    py: Python<'_>,
    agent: &str,
    seed: Option<u64>,
    out: Option<PathBuf>,
    resume: Option<PathBuf>,
    preset: Option<&str>,
    config: Option<PathBuf>,
    env: Option<&str>,
    urdf: Option<PathBuf>,
    threads: Option<usize>,
    generations: Option<usize>,
    episodes: Option<usize>,
    steps: Option<u64>,
    until: Option<&str>,
    init: Option<PathBuf>,
) -> PyResult<PyTrainPlan> {
    let agents: Vec<&str> = AgentKind::ALL.iter().map(|a| a.name()).collect();
    let presets: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
    let envs: Vec<&str> = EnvKind::ALL.iter().map(|e| e.name()).collect();
    let agent = parse_name("agent", agent, AgentKind::parse, &agents)?;
    let preset = match preset {
        Some(p) => parse_name("preset", p, Preset::parse, &presets)?,
        None => Preset::default(),
    };
    let env = env
        .map(|e| parse_name("env", e, EnvKind::parse, &envs))
        .transpose()?;
    let stop_at_walk = match until {
        None => None,
        Some("walk") => Some(true),
        Some("budget") => Some(false),
        Some(other) => {
            return Err(value_error(format!(
                "until={other:?}: must be \"walk\" or \"budget\""
            )))
        }
    };
    let request = TrainRequest {
        agent,
        seed,
        out,
        resume,
        overrides: Overrides {
            preset,
            config,
            env,
            urdf,
            threads,
            generations,
            episodes,
            steps,
            stop_at_walk,
            init,
        },
    };
    let plan = py.detach(|| esrl_run::plan(&request)).map_err(run_error)?;
    Ok(PyTrainPlan { plan })
}

/// Calls the Python `evaluate` callable with a generation's genome bytes.
#[derive(Debug)]
struct PyTransport {
    evaluate: Py<PyAny>,
}

impl Transport for PyTransport {
    fn roll_out(&self, genomes: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, String> {
        Python::attach(|py| {
            let list = PyList::new(py, genomes.iter().map(|g| PyBytes::new(py, g)))
                .map_err(|e| e.to_string())?;
            let back = self
                .evaluate
                .bind(py)
                .call1((list,))
                .map_err(|e| describe(py, &e))?;
            let mut out = Vec::with_capacity(genomes.len());
            for item in back.try_iter().map_err(|e| describe(py, &e))? {
                let item = item.map_err(|e| describe(py, &e))?;
                let bytes = item.cast::<PyBytes>().map_err(|_| {
                    format!(
                        "evaluate returned a {} where bytes were expected",
                        item.get_type().name().map_or("?".into(), |n| n.to_string())
                    )
                })?;
                out.push(bytes.as_bytes().to_vec());
            }
            Ok(out)
        })
    }
}

/// A Python exception as one line: its type and message.
fn describe(py: Python<'_>, e: &PyErr) -> String {
    let kind = e
        .get_type(py)
        .name()
        .map_or_else(|_| "exception".into(), |n| n.to_string());
    format!("{kind}: {}", e.value(py))
}

/// A training session whose populations roll out through a Python callable.
#[pyclass(name = "Driver", module = "esrl_rs._native")]
pub struct PyDriver {
    session: Mutex<Session>,
    evaluator: Arc<WireEvaluator<PyTransport>>,
    opening: Opening,
}

impl PyDriver {
    fn session(&self) -> PyResult<MutexGuard<'_, Session>> {
        self.session
            .lock()
            .map_err(|_| esrl_error("the training session failed earlier; resume the run"))
    }
}

#[pymethods]
impl PyDriver {
    /// Opens the run of `plan` (new, resumed or started over) and runs its warm start;
    /// `evaluate(list[bytes]) -> list[bytes]` rolls out each generation's genomes.
    #[new]
    fn new(py: Python<'_>, plan: &PyTrainPlan, evaluate: Py<PyAny>) -> PyResult<Self> {
        if !evaluate.bind(py).is_callable() {
            return Err(value_error("evaluate: must be callable"));
        }
        let evaluator = Arc::new(WireEvaluator::new(PyTransport { evaluate }));
        let plan = plan.plan.clone();
        let shared = evaluator.clone();
        let (session, opening) = py
            .detach(move || -> esrl_run::Result<(Session, Opening)> {
                let cfg: &TrainConfig = &plan.cfg;
                let envs = build::envs(cfg.env, &cfg.walk)?;
                cfg.check_memory(envs.obs_dim, envs.act_dim, envs.max_episode_steps)?;
                Session::open(cfg, &plan.root, &envs, shared, plan.resume)
            })
            .map_err(run_error)?;
        Ok(Self {
            session: Mutex::new(session),
            evaluator,
            opening,
        })
    }

    /// How the folder was found: `{"kind": "new" | "resumed" | "started-over", ...}`, a
    /// resumed run with its `checkpoint`, `rows` and `env_steps`.
    #[getter]
    fn opening<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match &self.opening {
            Opening::New => d.set_item("kind", "new")?,
            Opening::StartedOver => d.set_item("kind", "started-over")?,
            Opening::Resumed {
                checkpoint,
                rows,
                env_steps,
            } => {
                d.set_item("kind", "resumed")?;
                d.set_item("checkpoint", checkpoint.clone())?;
                d.set_item("rows", rows)?;
                d.set_item("env_steps", env_steps)?;
            }
        }
        Ok(d)
    }

    /// Rows done (resumed ones included).
    #[getter]
    fn rows(&self) -> PyResult<usize> {
        Ok(self.session()?.rows())
    }

    /// Rows the budget asks for.
    #[getter]
    fn total(&self) -> PyResult<usize> {
        Ok(self.session()?.total())
    }

    /// Environment steps so far.
    #[getter]
    fn env_steps(&self) -> PyResult<u64> {
        Ok(self.session()?.env_steps())
    }

    /// Training seconds so far, earlier sessions included.
    #[getter]
    fn wall_s(&self) -> PyResult<f64> {
        Ok(self.session()?.wall_s())
    }

    /// Whether the budget is spent.
    fn done(&self) -> PyResult<bool> {
        Ok(self.session()?.done())
    }

    /// Runs one row (a generation, or an episode of a plain agent) with the interpreter
    /// released and writes it; returns `{"rows", "curve", "best", "summary", "estimate",
    /// "restart"}`, `estimate` the line on the time left (`esrl train`'s) on the row that
    /// first gives a pace, else `None`; `restart` the line on an attempt `[restart]`
    /// abandoned before the row, else `None`.
    fn step<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        type Stepped = (esrl_run::RowDone, &'static str, Option<String>);
        let (row, unit, restart) = py
            .detach(|| -> PyResult<esrl_run::Result<Stepped>> {
                let mut session = self.session()?;
                Ok(session.step().map(|row| {
                    let restart = row.restarted.as_ref().and_then(|r| {
                        let rule = session.config().restart.as_ref()?;
                        Some(r.describe(rule, session.attempt().seed))
                    });
                    (row, session.unit(), restart)
                }))
            })?
            .map_err(run_error)?;
        let d = PyDict::new(py);
        d.set_item("rows", row.rows)?;
        d.set_item("curve", row.curve)?;
        d.set_item("best", row.best)?;
        d.set_item("summary", row.summary)?;
        d.set_item("estimate", row.estimate.map(|e| e.describe(unit)))?;
        d.set_item("restart", restart)?;
        Ok(d)
    }

    /// Writes the last checkpoint and the summary; `finished` says whether the budget was
    /// completed.
    fn finish(&self, py: Python<'_>, finished: bool) -> PyResult<()> {
        py.detach(|| -> PyResult<esrl_run::Result<()>> {
            let mut session = self.session()?;
            Ok(session.finish(finished))
        })?
        .map_err(run_error)
    }

    /// What crossed to the workers so far: `{"calls", "genomes", "bytes_out", "bytes_in"}`.
    #[getter]
    fn traffic<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let Traffic {
            calls,
            genomes,
            bytes_out,
            bytes_in,
        } = self.evaluator.traffic();
        let d = PyDict::new(py);
        d.set_item("calls", calls)?;
        d.set_item("genomes", genomes)?;
        d.set_item("bytes_out", bytes_out)?;
        d.set_item("bytes_in", bytes_in)?;
        Ok(d)
    }
}

/// Rolls out genomes of one run: built once per process from the run's `config.toml` text.
#[pyclass(name = "Worker", module = "esrl_rs._native", frozen)]
pub struct PyWorker {
    worker: Worker,
}

#[pymethods]
impl PyWorker {
    /// A worker for the run configured by `config_toml`.
    #[new]
    fn new(py: Python<'_>, config_toml: &str) -> PyResult<Self> {
        let worker = py
            .detach(|| {
                let cfg = TrainConfig::from_toml(config_toml)?;
                build::worker(&cfg)
            })
            .map_err(run_error)?;
        Ok(Self { worker })
    }

    /// Rolls the genome in `genome` (bytes from the driver) out on a fresh environment and
    /// returns its evaluation as bytes; the interpreter is released meanwhile.
    fn rollout<'py>(&self, py: Python<'py>, genome: &[u8]) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = py
            .detach(|| self.worker.rollout(genome))
            .map_err(|e| esrl_error(e.to_string()))?;
        Ok(PyBytes::new(py, &bytes))
    }
}

/// Adds the driver's classes and functions to the module.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<PyTrainPlan>()?;
    module.add_class::<PyDriver>()?;
    module.add_class::<PyWorker>()?;
    module.add_function(wrap_pyfunction!(plan_train, module)?)?;
    Ok(())
}
