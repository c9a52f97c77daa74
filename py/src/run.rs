//! Reading run folders (`config.toml`, `metrics.jsonl` / `metrics.csv`, `summary.json`) and
//! evaluation files (`eval.json`) written by the `esrl` CLI.

use std::path::{Path, PathBuf};

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::{Map, Value};

use crate::convert::{integer_column, json_to_py, map_to_py, numeric_column};
use crate::errors::{io_error, not_found, value_error};

/// File names inside a run folder (as in `crates/cli/src/run_dir.rs`).
const CONFIG: &str = "config.toml";
const JSONL: &str = "metrics.jsonl";
const CSV: &str = "metrics.csv";
const SUMMARY: &str = "summary.json";
const EVAL: &str = "eval.json";

fn read_text(path: &Path) -> PyResult<String> {
    std::fs::read_to_string(path).map_err(|e| io_error(path, &e))
}

fn check_run_dir(path: &Path) -> PyResult<()> {
    if !path.exists() {
        return Err(not_found(format!("{}: no such run folder", path.display())));
    }
    if !path.is_dir() {
        return Err(pyo3::exceptions::PyNotADirectoryError::new_err(format!(
            "{}: not a run folder (expected a directory holding {CONFIG} and {JSONL})",
            path.display()
        )));
    }
    Ok(())
}

fn parse_config(path: &Path) -> PyResult<Map<String, Value>> {
    let text = read_text(path)?;
    let table: toml::Table = toml::from_str(&text)
        .map_err(|e| value_error(format!("{}: invalid TOML: {e}", path.display())))?;
    match serde_json::to_value(table) {
        Ok(Value::Object(map)) => Ok(map),
        Ok(_) => Err(value_error(format!("{}: not a TOML table", path.display()))),
        Err(e) => Err(value_error(format!("{}: {e}", path.display()))),
    }
}

/// Parses JSON Lines rows. A last line without its newline that does not parse is a row still
/// being written by a live run and is left out; any other bad line is an error naming it.
fn parse_jsonl(path: &Path) -> PyResult<Vec<Map<String, Value>>> {
    let text = read_text(path)?;
    let complete = text.ends_with('\n');
    let lines: Vec<&str> = text.lines().collect();
    let mut rows = Vec::with_capacity(lines.len());
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Value>(line) {
            Ok(Value::Object(map)) => rows.push(map),
            Ok(other) => {
                return Err(value_error(format!(
                    "{} line {}: expected a JSON object, got {}",
                    path.display(),
                    i + 1,
                    kind_of(&other)
                )))
            }
            Err(_) if !complete && i + 1 == lines.len() => {}
            Err(e) => {
                return Err(value_error(format!(
                    "{} line {}: {e}",
                    path.display(),
                    i + 1
                )))
            }
        }
    }
    Ok(rows)
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// Parses the CSV log (the fallback when `metrics.jsonl` is missing): empty cells are null,
/// numbers are numbers, `true`/`false` booleans, anything else a string.
fn parse_csv(path: &Path) -> PyResult<Vec<Map<String, Value>>> {
    let text = read_text(path)?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let Some(header) = lines.next() else {
        return Ok(Vec::new());
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut rows = Vec::new();
    for (i, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != columns.len() {
            return Err(value_error(format!(
                "{} line {}: {} cells, the header has {}",
                path.display(),
                i + 2,
                cells.len(),
                columns.len()
            )));
        }
        let mut row = Map::new();
        for (c, cell) in columns.iter().zip(cells) {
            let cell = cell.trim();
            let value = if cell.is_empty() {
                Value::Null
            } else if let Ok(n) = cell.parse::<i64>() {
                Value::from(n)
            } else if let Ok(x) = cell.parse::<f64>() {
                serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
            } else if cell == "true" || cell == "false" {
                Value::Bool(cell == "true")
            } else {
                Value::String(cell.to_string())
            };
            row.insert((*c).to_string(), value);
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Column name → values: `bool` arrays for boolean columns without gaps, `int64` arrays for
/// integer columns without gaps, `float64` arrays (null or missing → NaN; booleans → 0/1) for
/// other numeric columns, lists otherwise.
fn columns_to_py<'py>(
    py: Python<'py>,
    rows: &[Map<String, Value>],
) -> PyResult<(Bound<'py, PyDict>, Vec<String>)> {
    let mut names: Vec<String> = Vec::new();
    for row in rows {
        for k in row.keys() {
            if !names.iter().any(|n| n == k) {
                names.push(k.clone());
            }
        }
    }
    let dict = PyDict::new(py);
    for name in &names {
        let bools: Option<Vec<bool>> = rows
            .iter()
            .map(|r| r.get(name).and_then(Value::as_bool))
            .collect();
        if let Some(bools) = bools {
            dict.set_item(name, PyArray1::from_vec(py, bools))?;
            continue;
        }
        let values: Vec<Value> = rows
            .iter()
            .map(|r| match r.get(name) {
                Some(Value::Bool(b)) => Value::from(u8::from(*b)),
                Some(v) => v.clone(),
                None => Value::Null,
            })
            .collect();
        if let Some(ints) = integer_column(&values) {
            dict.set_item(name, PyArray1::from_vec(py, ints))?;
        } else if let Some(floats) = numeric_column(&values) {
            dict.set_item(name, PyArray1::from_vec(py, floats))?;
        } else if values.iter().all(Value::is_null) {
            dict.set_item(name, PyArray1::from_vec(py, vec![f64::NAN; values.len()]))?;
        } else {
            let list = PyList::empty(py);
            // A mixed column keeps each row's original value (booleans stay booleans).
            for row in rows {
                list.append(json_to_py(
                    py,
                    row.get(name).unwrap_or(&Value::Null),
                    false,
                )?)?;
            }
            dict.set_item(name, list)?;
        }
    }
    Ok((dict, names))
}

fn read_json(path: &Path) -> PyResult<Value> {
    let text = read_text(path)?;
    serde_json::from_str(&text).map_err(|e| value_error(format!("{}: {e}", path.display())))
}

/// Loads a run folder: `{"path", "config", "metrics", "columns", "rows", "summary",
/// "metrics_file"}`. `config.toml` and one of the metric logs are required; a missing
/// `summary.json` gives an empty summary (a run that has not finished its first row).
#[pyfunction]
pub fn load_run<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    check_run_dir(&path)?;
    let config = parse_config(&path.join(CONFIG))?;
    let jsonl = path.join(JSONL);
    let csv = path.join(CSV);
    let (rows, metrics_file) = if jsonl.is_file() {
        (parse_jsonl(&jsonl)?, jsonl)
    } else if csv.is_file() {
        (parse_csv(&csv)?, csv)
    } else {
        return Err(not_found(format!(
            "{}: no {JSONL} or {CSV} in the run folder",
            path.display()
        )));
    };
    let summary_path = path.join(SUMMARY);
    let summary = if summary_path.exists() {
        match read_json(&summary_path)? {
            Value::Object(map) => map,
            other => {
                return Err(value_error(format!(
                    "{}: expected a JSON object, got {}",
                    summary_path.display(),
                    kind_of(&other)
                )))
            }
        }
    } else {
        Map::new()
    };
    let (metrics, columns) = columns_to_py(py, &rows)?;
    let out = PyDict::new(py);
    out.set_item("path", path.display().to_string())?;
    out.set_item("config", map_to_py(py, &config, false)?)?;
    out.set_item("metrics", metrics)?;
    out.set_item("columns", columns)?;
    out.set_item("rows", rows.len())?;
    out.set_item("summary", map_to_py(py, &summary, false)?)?;
    out.set_item("metrics_file", metrics_file.display().to_string())?;
    Ok(out)
}

/// Loads `eval.json` (a path to the file or to the run folder holding it): `{"episodes":
/// [{"seed", "return", "gait": {...}, "trace": {name: array}}, ...], ...}` with number lists
/// as NumPy arrays. Extra keys are kept.
#[pyfunction]
pub fn load_eval<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let file = if path.is_dir() { path.join(EVAL) } else { path };
    let value = read_json(&file)?;
    let Value::Object(map) = value else {
        return Err(value_error(format!(
            "{}: expected a JSON object with `episodes`, got {}",
            file.display(),
            kind_of(&value)
        )));
    };
    match map.get("episodes") {
        Some(Value::Array(episodes)) => {
            if let Some(i) = episodes.iter().position(|e| !e.is_object()) {
                return Err(value_error(format!(
                    "{}: episodes[{i}] is {}, expected an object",
                    file.display(),
                    kind_of(&episodes[i])
                )));
            }
        }
        Some(other) => {
            return Err(value_error(format!(
                "{}: `episodes` is {}, expected an array",
                file.display(),
                kind_of(other)
            )))
        }
        None => {
            return Err(value_error(format!(
                "{}: no `episodes` key",
                file.display()
            )))
        }
    }
    let dict = map_to_py(py, &map, true)?;
    // `episodes` itself stays a list of dicts, whatever its contents look like.
    if let Some(Value::Array(episodes)) = map.get("episodes") {
        let list = PyList::empty(py);
        for e in episodes {
            list.append(json_to_py(py, e, true)?)?;
        }
        dict.set_item("episodes", list)?;
    }
    Ok(dict)
}

/// Registers the functions.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_function(wrap_pyfunction!(load_run, module)?)?;
    module.add_function(wrap_pyfunction!(load_eval, module)?)?;
    Ok(())
}
