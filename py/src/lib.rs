//! `esrl_rs._native`: the Rust core of the `esrl_rs` Python package (SPEC §7).
//!
//! Thin bindings over the workspace crates; the Python package `esrl_rs` (in `py/python`)
//! re-exports them with typed stubs:
//!
//! - `load_run`, `load_eval`: run folders and `eval.json` as dicts of NumPy arrays;
//! - `metrics.*`: `esrl-metrics` (AUC, nAUC, Final-50, Best-Win-50, Episodes-to-Target,
//!   mean ± SD, gait metrics, Table 1);
//! - `read_recording`, `read_recording_table`, `recording_channels`: MCAP recordings via
//!   `esrl-record`;
//! - `EnvCore`: `esrl-sim`'s `WalkEnv` and `Pendulum`, wrapped by the Gymnasium classes.
//!
//! Errors become `ValueError`, `FileNotFoundError`/`OSError` or `esrl_rs.EsrlError` with the
//! Rust message (see `errors`); simulator panics are caught and raised as `EsrlError`.
//!
//! - `plan_train`, `Driver`, `Worker`: training with the population rolled out by a Python
//!   callable (`esrl_rs.ray`), through the same run folder code as `esrl train`.
//! - `PolicyCore`: a trained policy from a run's checkpoint (via the `esrl` CLI library),
//!   acting and rolling out deterministically like `esrl eval`.

mod convert;
mod driver;
mod envs;
mod errors;
mod metrics;
mod policy;
mod recording;
mod run;

use pyo3::prelude::*;

/// The native module.
#[pymodule]
#[pyo3(name = "_native")]
fn native(module: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = module.py();
    // Rayon's global pool flushes subnormal floats like every pool of esrl's
    // (`esrl_nn::subnormal`); Python's own threads keep their mode.
    esrl_nn::subnormal::init_global_pool();
    module.add("EsrlError", py.get_type::<errors::EsrlError>())?;
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    module.add("HUMANOID_URDF", esrl_sim::HUMANOID_URDF)?;
    run::register(module)?;
    recording::register(module)?;
    envs::register(module)?;
    policy::register(module)?;
    driver::register(module)?;
    let metrics = PyModule::new(py, "metrics")?;
    metrics::register(&metrics)?;
    module.add_submodule(&metrics)?;
    Ok(())
}
