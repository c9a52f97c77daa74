//! `esrl_rs.metrics`: the learning-curve, gait, gait-cycle and Table 1 functions of `esrl-metrics` on
//! NumPy arrays (SPEC §6). Every function is a direct call into the Rust crate; errors arrive as
//! `ValueError` with the crate's message.

use esrl_metrics as m;
use numpy::{AllowTypeChange, PyArray1, PyArrayLike1};
use pyo3::prelude::*;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::convert::{json_to_py, py_to_json};
use crate::errors::{metrics_error, value_error};

/// A 1-D array-like of numbers, converted to `float64`.
pub type Curve<'py> = PyArrayLike1<'py, f64, AllowTypeChange>;

fn to_vec(curve: &Curve<'_>) -> Vec<f64> {
    curve.as_array().iter().copied().collect()
}

/// Any iterable of 1-D array-likes (a list of arrays, a 2-D array, ...) as `f64` vectors.
fn curves_to_vecs(curves: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<f64>>> {
    let mut out = Vec::new();
    for (i, item) in curves.try_iter()?.enumerate() {
        let item = item?;
        let curve: Curve<'_> = item
            .extract()
            .map_err(|e| value_error(format!("curves[{i}]: not a 1-D array of numbers: {e}")))?;
        out.push(to_vec(&curve));
    }
    Ok(out)
}

/// Serialises a Rust value into Python (dicts, lists, NumPy arrays for number vectors).
pub fn to_py<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_value(value).map_err(|e| value_error(e.to_string()))?;
    json_to_py(py, &json, true)
}

/// Deserialises a Rust value from a Python object; `what` names the argument in errors.
pub fn from_py<T: DeserializeOwned>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
    let json = py_to_json(obj, what)?;
    serde_json::from_value(json).map_err(|e| value_error(format!("{what}: {e}")))
}

/// AUC: the sum of the curve.
#[pyfunction]
pub fn auc(curve: Curve<'_>) -> PyResult<f64> {
    m::auc(&to_vec(&curve)).map_err(metrics_error)
}

/// nAUC: AUC divided by the curve's length.
#[pyfunction]
pub fn nauc(curve: Curve<'_>) -> PyResult<f64> {
    m::nauc(&to_vec(&curve)).map_err(metrics_error)
}

/// Mean Q₀ of a run: the mean of the finite values, `None` when there are none.
#[pyfunction]
pub fn q0_mean(q0: Curve<'_>) -> Option<f64> {
    m::q0_mean(&to_vec(&q0))
}

/// Final-50: mean of the last 50 values (all values if fewer).
#[pyfunction]
pub fn final_50(curve: Curve<'_>) -> PyResult<f64> {
    m::final_50(&to_vec(&curve)).map_err(metrics_error)
}

/// Mean of the last `window` values (all values if fewer).
#[pyfunction]
pub fn final_mean(curve: Curve<'_>, window: usize) -> PyResult<f64> {
    m::final_mean(&to_vec(&curve), window).map_err(metrics_error)
}

/// Best-Win-50: best mean of 50 consecutive values (mean of all values if fewer).
#[pyfunction]
pub fn best_win_50(curve: Curve<'_>) -> PyResult<f64> {
    m::best_win_50(&to_vec(&curve)).map_err(metrics_error)
}

/// Best mean of `window` consecutive values (mean of all values if fewer).
#[pyfunction]
pub fn best_window_mean(curve: Curve<'_>, window: usize) -> PyResult<f64> {
    m::best_window_mean(&to_vec(&curve), window).map_err(metrics_error)
}

/// Trailing means (MATLAB `movmean(c, [w-1 0])`), one per curve value.
#[pyfunction]
#[pyo3(signature = (curve, window = m::WINDOW))]
pub fn trailing_means<'py>(
    py: Python<'py>,
    curve: Curve<'py>,
    window: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let means = m::trailing_means(&to_vec(&curve), window).map_err(metrics_error)?;
    Ok(PyArray1::from_vec(py, means))
}

/// First 0-based index whose trailing `window`-value mean reaches `target`; `None` if never.
#[pyfunction]
#[pyo3(signature = (curve, target, window = m::WINDOW))]
pub fn episodes_to_target(curve: Curve<'_>, target: f64, window: usize) -> PyResult<Option<usize>> {
    m::episodes_to_target_window(&to_vec(&curve), target, window).map_err(metrics_error)
}

/// Median (mean of the two middle values for an even count).
#[pyfunction]
pub fn median(values: Curve<'_>) -> PyResult<f64> {
    m::median(&to_vec(&values)).map_err(metrics_error)
}

/// A method's target: `fraction` × the median over its seeds of the best `window`-value mean.
#[pyfunction]
#[pyo3(signature = (curves, window = m::WINDOW, fraction = m::TARGET_FRACTION))]
pub fn method_target(curves: &Bound<'_, PyAny>, window: usize, fraction: f64) -> PyResult<f64> {
    m::method_target_with(&curves_to_vecs(curves)?, window, fraction).map_err(metrics_error)
}

/// The summary of one curve (the keys of `summary.json`); Episodes-to-Target needs `target`.
#[pyfunction]
#[pyo3(signature = (curve, target = None))]
pub fn curve_summary<'py>(
    py: Python<'py>,
    curve: Curve<'py>,
    target: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = m::CurveSummary::from_curve(&to_vec(&curve), target).map_err(metrics_error)?;
    to_py(py, &s)
}

/// Summaries of all seeds of one method, against the method's target (same order as `curves`).
#[pyfunction]
pub fn summarize_method<'py>(
    py: Python<'py>,
    curves: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = m::summarize_method(&curves_to_vecs(curves)?).map_err(metrics_error)?;
    to_py(py, &s)
}

/// Mean ± sample SD: `{"mean": float, "sd": float | None, "n": int}`.
#[pyfunction]
pub fn mean_sd<'py>(py: Python<'py>, values: Curve<'py>) -> PyResult<Bound<'py, PyAny>> {
    let s = m::mean_sd(&to_vec(&values)).map_err(metrics_error)?;
    to_py(py, &s)
}

/// The thresholds of the gait-cycle metrics: the defaults updated with `overrides` (a dict
/// with some of the keys of `esrl_metrics::GaitThresholds`; unknown keys are refused).
fn thresholds(overrides: Option<&Bound<'_, PyAny>>) -> PyResult<m::GaitThresholds> {
    let t: m::GaitThresholds = match overrides {
        Some(o) if !o.is_none() => from_py(o, "thresholds")?,
        _ => m::GaitThresholds::default(),
    };
    t.validate().map_err(metrics_error)?;
    Ok(t)
}

/// Gait metrics of one rollout from a trace dict (the fields of `esrl_metrics::GaitTrace`).
#[pyfunction]
#[pyo3(signature = (trace, track_length = 50.0, left_knee = "left_knee", right_knee = "right_knee", thresholds = None))]
pub fn gait_metrics<'py>(
    py: Python<'py>,
    trace: &Bound<'py, PyAny>,
    track_length: f64,
    left_knee: &str,
    right_knee: &str,
    thresholds: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let trace: m::GaitTrace = from_py(trace, "trace")?;
    let options = m::GaitOptions {
        track_length,
        left_knee: left_knee.into(),
        right_knee: right_knee.into(),
        thresholds: self::thresholds(thresholds)?,
    };
    let g = m::gait_metrics(&trace, &options).map_err(metrics_error)?;
    to_py(py, &g)
}

/// The default gait thresholds as a dict (keys of `esrl_metrics::GaitThresholds`).
#[pyfunction]
pub fn gait_thresholds<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
    to_py(py, &m::GaitThresholds::default())
}

/// Contact flags from a 1-D array of booleans or 0/1 numbers; `what` names it in errors.
fn contact_flags(values: &Curve<'_>, what: &str) -> PyResult<Vec<bool>> {
    values
        .as_array()
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if v == 0.0 {
                Ok(false)
            } else if v == 1.0 {
                Ok(true)
            } else {
                Err(value_error(format!(
                    "{what}[{i}] = {v}: contact flags must be booleans or 0/1 (threshold a force \
                     first, e.g. force > 10)"
                )))
            }
        })
        .collect()
}

/// Support phases, touchdowns, alternation, cadence and stride times of two contact traces.
#[pyfunction]
#[pyo3(signature = (left_contact, right_contact, dt, sync_window = None))]
pub fn gait_phases<'py>(
    py: Python<'py>,
    left_contact: Curve<'py>,
    right_contact: Curve<'py>,
    dt: f64,
    sync_window: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let left = contact_flags(&left_contact, "left_contact")?;
    let right = contact_flags(&right_contact, "right_contact")?;
    let window = sync_window.unwrap_or(m::GaitThresholds::default().sync_window);
    let p = m::gait_phases(&left, &right, dt, window).map_err(metrics_error)?;
    to_py(py, &p)
}

/// Step lengths from two contact traces and each foot's forward position (samples × 2).
#[pyfunction]
#[pyo3(signature = (left_contact, right_contact, foot_x, dt, sync_window = None))]
pub fn step_lengths<'py>(
    py: Python<'py>,
    left_contact: Curve<'py>,
    right_contact: Curve<'py>,
    foot_x: &Bound<'py, PyAny>,
    dt: f64,
    sync_window: Option<f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let left = contact_flags(&left_contact, "left_contact")?;
    let right = contact_flags(&right_contact, "right_contact")?;
    let rows = curves_to_vecs(foot_x)?;
    let x = rows
        .iter()
        .enumerate()
        .map(|(i, r)| match r.as_slice() {
            [l, r] => Ok([*l, *r]),
            _ => Err(value_error(format!(
                "foot_x[{i}]: {} values, expected 2 (left x, right x)",
                r.len()
            ))),
        })
        .collect::<PyResult<Vec<[f64; 2]>>>()?;
    let window = sync_window.unwrap_or(m::GaitThresholds::default().sync_window);
    let steps = m::step_lengths(&left, &right, &x, dt, window).map_err(metrics_error)?;
    Ok(PyArray1::from_vec(py, steps))
}

/// The gait class (`"walk"`, `"run"`, `"hop"`, `"shuffle"`, `"stand"`, `"fall"`) of the inputs
/// of `esrl_metrics::GaitClassInput` (a `gait_phases` dict plus `fell`, `step_length_mean`,
/// `foot_speed`).
#[pyfunction]
#[pyo3(signature = (inputs, thresholds = None))]
pub fn classify_gait(
    inputs: &Bound<'_, PyAny>,
    thresholds: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let input: m::GaitClassInput = from_py(inputs, "inputs")?;
    let t = self::thresholds(thresholds)?;
    Ok(m::classify_gait(&input, &t).name().to_string())
}

/// Range of motion (5th–95th percentile) and time within `margin` of a limit of one joint.
#[pyfunction]
#[pyo3(signature = (name, angles, limits = None, margin = None))]
pub fn joint_motion<'py>(
    py: Python<'py>,
    name: &str,
    angles: Curve<'py>,
    limits: Option<(f64, f64)>,
    margin: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let margin = margin.unwrap_or(m::GaitThresholds::default().limit_margin);
    let j = m::joint_motion(name, &to_vec(&angles), limits.map(|(a, b)| [a, b]), margin)
        .map_err(metrics_error)?;
    to_py(py, &j)
}

/// The `p`-quantile (`p` in [0, 1]) with linear interpolation (NumPy's default).
#[pyfunction]
pub fn percentile(values: Curve<'_>, p: f64) -> PyResult<f64> {
    m::percentile(&to_vec(&values), p).map_err(metrics_error)
}

fn table_rows(agents: &Bound<'_, PyAny>) -> PyResult<Vec<m::Table1Row>> {
    let agents: Vec<m::AgentRuns> = from_py(agents, "agents")?;
    m::table1(&agents).map_err(metrics_error)
}

/// Table 1 rows (one dict per agent) from `[{"agent": str, "seeds": [{"summary": {...},
/// "gait": {...} | None, "q0_mean": float | None}, ...]}, ...]`.
#[pyfunction]
pub fn table1<'py>(py: Python<'py>, agents: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    to_py(py, &table_rows(agents)?)
}

/// Table 1 as Markdown (same input as `table1`).
#[pyfunction]
pub fn table1_markdown(agents: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(m::table1_markdown(&table_rows(agents)?))
}

/// Table 1 as CSV (same input as `table1`).
#[pyfunction]
pub fn table1_csv(agents: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(m::table1_csv(&table_rows(agents)?))
}

/// Mean |torque| and |power| per actuator as Markdown (same input as `table1`).
#[pyfunction]
pub fn actuator_markdown(agents: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(m::actuator_markdown(&table_rows(agents)?))
}

/// Range of motion and time at a limit per joint as Markdown (same input as `table1`).
#[pyfunction]
pub fn joint_markdown(agents: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(m::joint_markdown(&table_rows(agents)?))
}

/// The number format of Table 1 cells.
#[pyfunction]
pub fn format_number(x: f64) -> String {
    m::format_number(x)
}

/// Registers the functions on the `metrics` submodule.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("WINDOW", m::WINDOW)?;
    module.add("TARGET_FRACTION", m::TARGET_FRACTION)?;
    module.add_function(wrap_pyfunction!(auc, module)?)?;
    module.add_function(wrap_pyfunction!(nauc, module)?)?;
    module.add_function(wrap_pyfunction!(q0_mean, module)?)?;
    module.add_function(wrap_pyfunction!(final_50, module)?)?;
    module.add_function(wrap_pyfunction!(final_mean, module)?)?;
    module.add_function(wrap_pyfunction!(best_win_50, module)?)?;
    module.add_function(wrap_pyfunction!(best_window_mean, module)?)?;
    module.add_function(wrap_pyfunction!(trailing_means, module)?)?;
    module.add_function(wrap_pyfunction!(episodes_to_target, module)?)?;
    module.add_function(wrap_pyfunction!(median, module)?)?;
    module.add_function(wrap_pyfunction!(method_target, module)?)?;
    module.add_function(wrap_pyfunction!(curve_summary, module)?)?;
    module.add_function(wrap_pyfunction!(summarize_method, module)?)?;
    module.add_function(wrap_pyfunction!(mean_sd, module)?)?;
    module.add_function(wrap_pyfunction!(gait_metrics, module)?)?;
    module.add_function(wrap_pyfunction!(gait_thresholds, module)?)?;
    module.add_function(wrap_pyfunction!(gait_phases, module)?)?;
    module.add_function(wrap_pyfunction!(step_lengths, module)?)?;
    module.add_function(wrap_pyfunction!(classify_gait, module)?)?;
    module.add_function(wrap_pyfunction!(joint_motion, module)?)?;
    module.add_function(wrap_pyfunction!(percentile, module)?)?;
    module.add_function(wrap_pyfunction!(joint_markdown, module)?)?;
    module.add_function(wrap_pyfunction!(table1, module)?)?;
    module.add_function(wrap_pyfunction!(table1_markdown, module)?)?;
    module.add_function(wrap_pyfunction!(table1_csv, module)?)?;
    module.add_function(wrap_pyfunction!(actuator_markdown, module)?)?;
    module.add_function(wrap_pyfunction!(format_number, module)?)?;
    Ok(())
}
