//! MCAP recordings written by `esrl record`, read through `esrl-record`.

use std::path::PathBuf;

use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::{record_error, value_error};

/// A scalar topic of a recording as columns: `{"time_ns": uint64 array (log time),
/// "time": float64 array (s), <field>: float64 array, ...}`, fields in declaration order.
#[pyfunction]
pub fn read_recording<'py>(
    py: Python<'py>,
    path: PathBuf,
    topic: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let bytes = esrl_record::read_file(&path).map_err(|e| record_error(&path, e))?;
    let series = esrl_record::read_scalars(&bytes, topic).map_err(|e| record_error(&path, e))?;
    let out = PyDict::new(py);
    for reserved in ["time", "time_ns"] {
        if series.fields.iter().any(|f| f == reserved) {
            return Err(value_error(format!(
                "{}: topic `{topic}` has a field named `{reserved}`, which clashes with the time \
                 column; use read_recording_table",
                path.display()
            )));
        }
    }
    let seconds: Vec<f64> = series.time_ns.iter().map(|&t| t as f64 * 1e-9).collect();
    out.set_item("time_ns", PyArray1::from_vec(py, series.time_ns.clone()))?;
    out.set_item("time", PyArray1::from_vec(py, seconds))?;
    for (j, field) in series.fields.iter().enumerate() {
        let column: Vec<f64> = series.values.iter().map(|row| row[j]).collect();
        out.set_item(field, PyArray1::from_vec(py, column))?;
    }
    Ok(out)
}

/// A scalar topic as one table: `{"topic": str, "fields": [str], "time_ns": uint64 array,
/// "values": float64 array (messages, fields)}`.
#[pyfunction]
pub fn read_recording_table<'py>(
    py: Python<'py>,
    path: PathBuf,
    topic: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let bytes = esrl_record::read_file(&path).map_err(|e| record_error(&path, e))?;
    let series = esrl_record::read_scalars(&bytes, topic).map_err(|e| record_error(&path, e))?;
    let out = PyDict::new(py);
    out.set_item("topic", &series.topic)?;
    out.set_item("fields", PyList::new(py, &series.fields)?)?;
    out.set_item("time_ns", PyArray1::from_vec(py, series.time_ns.clone()))?;
    let values = if series.values.is_empty() {
        PyArray2::<f64>::zeros(py, [0, series.fields.len()], false)
    } else {
        PyArray2::from_vec2(py, &series.values).map_err(|e| value_error(e.to_string()))?
    };
    out.set_item("values", values)?;
    Ok(out)
}

/// The channels of a recording: a list of `{"id", "topic", "message_encoding", "schema_name",
/// "schema_encoding", "message_count"}` (schema text left out).
#[pyfunction]
pub fn recording_channels<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyList>> {
    let bytes = esrl_record::read_file(&path).map_err(|e| record_error(&path, e))?;
    let channels = esrl_record::channels(&bytes).map_err(|e| record_error(&path, e))?;
    let list = PyList::empty(py);
    for c in channels {
        let d = PyDict::new(py);
        d.set_item("id", c.id)?;
        d.set_item("topic", c.topic)?;
        d.set_item("message_encoding", c.message_encoding)?;
        d.set_item("schema_name", c.schema_name)?;
        d.set_item("schema_encoding", c.schema_encoding)?;
        d.set_item("message_count", c.message_count)?;
        list.append(d)?;
    }
    Ok(list)
}

/// Writes scalar topics to an MCAP file that Foxglove plots: `topics` maps a topic name to
/// `{field: 1-D array}`, every column one value per entry of `time` (s since reset,
/// strictly increasing). The scene is the 50 m track without a robot. Returns the messages written.
#[pyfunction]
pub fn write_recording(
    path: PathBuf,
    topics: &Bound<'_, PyDict>,
    time: PyArrayLike1<'_, f64, AllowTypeChange>,
) -> PyResult<u64> {
    let time: Vec<f64> = time.as_array().iter().copied().collect();
    if let Some(i) = time.iter().position(|t| !(t.is_finite() && *t >= 0.0)) {
        return Err(value_error(format!(
            "time[{i}] = {}: must be finite and ≥ 0",
            time[i]
        )));
    }
    let mut declared = Vec::new();
    let mut columns: Vec<Vec<Vec<f64>>> = Vec::new();
    for (topic, fields) in topics.iter() {
        let topic: String = topic
            .extract()
            .map_err(|_| value_error("topics: keys must be topic names (str)"))?;
        let fields = fields
            .cast::<PyDict>()
            .map_err(|_| value_error(format!("topics[{topic:?}]: expected a dict of columns")))?;
        let mut names = Vec::new();
        let mut cols = Vec::new();
        for (name, values) in fields.iter() {
            let name: String = name
                .extract()
                .map_err(|_| value_error(format!("topics[{topic:?}]: field names must be str")))?;
            let values: PyArrayLike1<'_, f64, AllowTypeChange> = values.extract().map_err(|e| {
                value_error(format!(
                    "topics[{topic:?}][{name:?}]: not a 1-D array of numbers: {e}"
                ))
            })?;
            let values: Vec<f64> = values.as_array().iter().copied().collect();
            if values.len() != time.len() {
                return Err(value_error(format!(
                    "topics[{topic:?}][{name:?}]: length {}, expected {} (the length of time)",
                    values.len(),
                    time.len()
                )));
            }
            names.push(name);
            cols.push(values);
        }
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        declared.push(esrl_record::ScalarTopic::new(&topic, &refs));
        columns.push(cols);
    }
    let frames: Vec<esrl_record::Frame> = time
        .iter()
        .enumerate()
        .map(|(k, t)| esrl_record::Frame {
            time_ns: (t * 1e9).round() as u64,
            link_poses: Vec::new(),
            scalars: columns
                .iter()
                .map(|cols| cols.iter().map(|c| c[k]).collect())
                .collect(),
        })
        .collect();
    let scene = esrl_record::Scene {
        links: Vec::new(),
        world_shapes: Vec::new(),
    }
    .with_track(50.0);
    let stats = esrl_record::write_recording(
        &path,
        &scene,
        &declared,
        &frames,
        esrl_record::RecordOptions::default(),
    )
    .map_err(|e| record_error(&path, e))?;
    Ok(stats.messages)
}

/// Registers the functions.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_function(wrap_pyfunction!(read_recording, module)?)?;
    module.add_function(wrap_pyfunction!(read_recording_table, module)?)?;
    module.add_function(wrap_pyfunction!(recording_channels, module)?)?;
    module.add_function(wrap_pyfunction!(write_recording, module)?)?;
    Ok(())
}
