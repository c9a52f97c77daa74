//! JSON values ↔ Python objects, so that serde structs of the Rust crates cross the boundary
//! without a second schema.
//!
//! JSON → Python: objects → `dict` (key order kept), strings, booleans, `null` → `None`,
//! integers → `int`, other numbers → `float`. With `arrays = true`, a non-empty array of numbers
//! (nulls allowed: they become NaN) becomes a NumPy array (`int64` when every entry is an
//! integer, else `float64`), and a non-empty array of equally long non-empty number arrays a 2-D
//! `float64` array; every other array stays a `list`.
//!
//! Python → JSON: `dict` (string keys), `list`/`tuple`, `str`, `bool`, `int`, `float`, `None`,
//! NumPy arrays and scalars (through `tolist()`). NaN and ±inf become `null`, i.e. "missing".

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

use crate::errors::value_error;

fn number_to_py<'py>(py: Python<'py>, n: &Number) -> PyResult<Bound<'py, PyAny>> {
    Ok(if let Some(i) = n.as_i64() {
        i.into_pyobject(py)?.into_any()
    } else if let Some(u) = n.as_u64() {
        u.into_pyobject(py)?.into_any()
    } else {
        n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
    })
}

/// A number array as `f64` values (null → NaN), or `None` if an entry is not a number/null or
/// no entry is a number.
pub fn numeric_column(values: &[Value]) -> Option<Vec<f64>> {
    let mut any_number = false;
    let mut out = Vec::with_capacity(values.len());
    for v in values {
        match v {
            Value::Number(n) => {
                any_number = true;
                out.push(n.as_f64().unwrap_or(f64::NAN));
            }
            Value::Null => out.push(f64::NAN),
            _ => return None,
        }
    }
    any_number.then_some(out)
}

/// The entries as `i64` if every one is an integer that fits.
pub fn integer_column(values: &[Value]) -> Option<Vec<i64>> {
    values.iter().map(|v| v.as_i64()).collect()
}

fn array_to_py<'py>(py: Python<'py>, values: &[Value]) -> PyResult<Bound<'py, PyAny>> {
    if !values.is_empty() {
        if let Some(ints) = integer_column(values) {
            return Ok(PyArray1::from_vec(py, ints).into_any());
        }
        if let Some(floats) = numeric_column(values) {
            return Ok(PyArray1::from_vec(py, floats).into_any());
        }
        // A rectangular table of numbers: `[step][column]`.
        let rows: Option<Vec<Vec<f64>>> = values
            .iter()
            .map(|v| match v {
                Value::Array(row) if !row.is_empty() => numeric_column(row),
                _ => None,
            })
            .collect();
        if let Some(rows) = rows {
            if rows.iter().all(|r| r.len() == rows[0].len()) {
                if let Ok(a) = PyArray2::from_vec2(py, &rows) {
                    return Ok(a.into_any());
                }
            }
        }
    }
    let list = PyList::empty(py);
    for v in values {
        list.append(json_to_py(py, v, true)?)?;
    }
    Ok(list.into_any())
}

/// Converts a JSON value to Python (see the module docs for `arrays`).
pub fn json_to_py<'py>(
    py: Python<'py>,
    value: &Value,
    arrays: bool,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => number_to_py(py, n)?,
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) if arrays => array_to_py(py, items)?,
        Value::Array(items) => {
            let list = PyList::empty(py);
            for v in items {
                list.append(json_to_py(py, v, false)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => map_to_py(py, map, arrays)?.into_any(),
    })
}

/// Converts a JSON object to a Python `dict` (see the module docs for `arrays`).
pub fn map_to_py<'py>(
    py: Python<'py>,
    map: &Map<String, Value>,
    arrays: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (k, v) in map {
        dict.set_item(k, json_to_py(py, v, arrays)?)?;
    }
    Ok(dict)
}

/// Converts a Python object to JSON; `what` names it in errors (e.g. `agents[0].seeds`).
pub fn py_to_json(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Value> {
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = obj.extract::<u64>() {
            return Ok(Value::from(u));
        }
        let f: f64 = obj.extract()?;
        return Ok(Number::from_f64(f).map_or(Value::Null, Value::Number));
    }
    if obj.is_instance_of::<PyFloat>() {
        let f: f64 = obj.extract()?;
        return Ok(Number::from_f64(f).map_or(Value::Null, Value::Number));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.extract::<String>()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                value_error(format!("{what}: dictionary keys must be str, got {k:?}"))
            })?;
            let value = py_to_json(&v, &format!("{what}.{key}"))?;
            map.insert(key, value);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut out = Vec::new();
        for (i, item) in obj.try_iter()?.enumerate() {
            out.push(py_to_json(&item?, &format!("{what}[{i}]"))?);
        }
        return Ok(Value::Array(out));
    }
    // NumPy arrays and scalars (and anything else that knows how to become plain Python).
    if obj.hasattr("tolist")? {
        let plain = obj.call_method0("tolist")?;
        if !plain.is(obj) {
            return py_to_json(&plain, what);
        }
    }
    Err(value_error(format!(
        "{what}: cannot convert a value of type {} (expected dict, list, str, number, bool or None)",
        obj.get_type().name()?
    )))
}
