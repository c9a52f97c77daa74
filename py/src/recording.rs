//! MCAP recordings written by `esrl record`, read through `esrl-record`.

use std::path::PathBuf;

use numpy::{PyArray1, PyArray2};
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

/// Registers the functions.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_function(wrap_pyfunction!(read_recording, module)?)?;
    module.add_function(wrap_pyfunction!(read_recording_table, module)?)?;
    module.add_function(wrap_pyfunction!(recording_channels, module)?)?;
    Ok(())
}
