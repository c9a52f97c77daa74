//! The run folder: resolved config, per-generation/episode metrics, checkpoints, summary.
//!
//! ```text
//! RUN/
//!   config.toml        resolved configuration (written once, atomically)
//!   metrics.jsonl      one JSON object per generation (ES-X) or episode (plain X)
//!   metrics.csv        the same rows as CSV, header from the first row's keys
//!   checkpoint/        latest checkpoint (safetensors + state.json), replaced atomically
//!   summary.json       run-level metrics, rewritten after every row
//! ```
//!
//! Every file except the two metric logs is written to a temporary name and renamed, so a kill
//! leaves either the old or the new version, never half of one. The logs are appended and
//! flushed row by row; on resume they are cut back to the rows the checkpoint knew about, so a
//! resumed run's logs equal those of an uninterrupted run.

use crate::bail;
use crate::error::{Context, Result};
use serde::Serialize;
use serde_json::{Map, Value};
use std::fs::{self, File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically: a sibling temporary file, fsync, then rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    let tmp = dir.join(format!(".{name}.tmp"));
    {
        let mut f = File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        f.write_all(bytes)
            .with_context(|| format!("writing {}", tmp.display()))?;
        f.sync_all().ok();
    }
    fs::rename(&tmp, path).with_context(|| format!("renaming into {}", path.display()))?;
    Ok(())
}

/// Serialises `value` as pretty JSON and writes it atomically.
pub fn write_json_atomic<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    write_atomic(path, text.as_bytes())
}

/// Checks that a command may write its output file at `path`: nothing is there, or, with
/// `force`, a regular file is. Devices (`/dev/null`), pipes, sockets, folders and symbolic
/// links are never replaced (the file is written beside and renamed over the path, which
/// would replace them), and an existing file is replaced only when asked.
pub fn check_output(path: &Path, force: bool) -> Result<()> {
    let Ok(meta) = fs::symlink_metadata(path) else {
        return Ok(());
    };
    let kind = meta.file_type();
    if kind.is_symlink() {
        bail!(
            "{} is a symbolic link; give the file's own path (links are not replaced)",
            path.display()
        );
    }
    if kind.is_dir() {
        bail!("{} is a folder; give a file name", path.display());
    }
    if !kind.is_file() {
        bail!(
            "{} exists and is not a regular file (a device, pipe or socket): it is never \
             replaced; choose another path",
            path.display()
        );
    }
    if !force {
        bail!(
            "{} exists; --force replaces it, or choose another path",
            path.display()
        );
    }
    Ok(())
}

/// Appends `value` as one line of the JSON Lines file `path`, flushed.
pub fn append_jsonl<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let line = serde_json::to_string(value)?;
    let mut f = OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    writeln!(f, "{line}").with_context(|| format!("writing {}", path.display()))?;
    f.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Cuts the JSON Lines file `path` back to its first `lines` lines (a resumed run's rows past
/// its checkpoint). A missing file is an empty one; one with fewer lines is refused.
pub fn truncate_jsonl(path: &Path, lines: usize) -> Result<()> {
    let kept: Vec<String> = if path.exists() {
        let f = File::open(path).with_context(|| format!("opening {}", path.display()))?;
        BufReader::new(f)
            .lines()
            .take(lines)
            .collect::<std::io::Result<_>>()
            .with_context(|| format!("reading {}", path.display()))?
    } else {
        Vec::new()
    };
    if kept.len() < lines {
        bail!(
            "{} has {} lines but the checkpoint expects {lines}",
            path.display(),
            kept.len()
        );
    }
    let mut text = kept.join("\n");
    if !kept.is_empty() {
        text.push('\n');
    }
    write_atomic(path, text.as_bytes())
}

/// A run folder being written.
#[derive(Debug)]
pub struct RunDir {
    root: PathBuf,
    jsonl: File,
    csv: File,
    columns: Option<Vec<String>>,
    rows: usize,
}

impl RunDir {
    /// File names inside a run folder.
    pub const CONFIG: &'static str = "config.toml";
    /// Metrics as JSON Lines.
    pub const JSONL: &'static str = "metrics.jsonl";
    /// Metrics as CSV.
    pub const CSV: &'static str = "metrics.csv";
    /// Run-level summary.
    pub const SUMMARY: &'static str = "summary.json";
    /// Checkpoint folder.
    pub const CHECKPOINT: &'static str = "checkpoint";

    /// Creates a fresh run folder. Refuses a folder that already holds metrics, so nothing
    /// already written is lost; use [`RunDir::resume`] to continue one.
    pub fn create(root: &Path, config_toml: &str) -> Result<Self> {
        if root.join(Self::JSONL).exists() || root.join(crate::restart::RESTARTS_FILE).exists() {
            let how = if root.join(Self::CHECKPOINT).exists() {
                "continues it from its last checkpoint"
            } else {
                "starts it over (it stopped before its first checkpoint)"
            };
            bail!(
                "{} already holds a run; `--resume {}` instead of `--out` {how}, or choose \
                 another --out",
                root.display(),
                root.display()
            );
        }
        fs::create_dir_all(root).with_context(|| format!("creating {}", root.display()))?;
        write_atomic(&root.join(Self::CONFIG), config_toml.as_bytes())?;
        Self::open(root, 0)
    }

    /// Reopens a run folder, keeping only its first `rows` metric rows (those covered by the
    /// checkpoint being resumed).
    pub fn resume(root: &Path, rows: usize) -> Result<Self> {
        let jsonl_path = root.join(Self::JSONL);
        let kept: Vec<String> = if jsonl_path.exists() {
            let f = File::open(&jsonl_path)
                .with_context(|| format!("opening {}", jsonl_path.display()))?;
            BufReader::new(f)
                .lines()
                .take(rows)
                .collect::<std::io::Result<_>>()
                .with_context(|| format!("reading {}", jsonl_path.display()))?
        } else {
            Vec::new()
        };
        if kept.len() < rows {
            bail!(
                "{} has {} rows but the checkpoint expects {rows}",
                jsonl_path.display(),
                kept.len()
            );
        }
        let mut jsonl_text = kept.join("\n");
        if !kept.is_empty() {
            jsonl_text.push('\n');
        }
        write_atomic(&jsonl_path, jsonl_text.as_bytes())?;
        // Rebuild the CSV from the kept JSON rows so both logs agree.
        let mut csv_text = String::new();
        let mut columns = None;
        for line in &kept {
            let row: Map<String, Value> = serde_json::from_str(line)
                .with_context(|| format!("parsing a row of {}", jsonl_path.display()))?;
            let cols = columns.get_or_insert_with(|| {
                let cols: Vec<String> = row.keys().cloned().collect();
                csv_text.push_str(&cols.join(","));
                csv_text.push('\n');
                cols
            });
            csv_text.push_str(&csv_line(cols, &row));
            csv_text.push('\n');
        }
        write_atomic(&root.join(Self::CSV), csv_text.as_bytes())?;
        let mut dir = Self::open(root, rows)?;
        dir.columns = columns;
        Ok(dir)
    }

    fn open(root: &Path, rows: usize) -> Result<Self> {
        let open = |name: &str| {
            let p = root.join(name);
            OpenOptions::new()
                .create(true)
                .append(true)
                .open(&p)
                .with_context(|| format!("opening {}", p.display()))
        };
        Ok(Self {
            root: root.to_path_buf(),
            jsonl: open(Self::JSONL)?,
            csv: open(Self::CSV)?,
            columns: None,
            rows,
        })
    }

    /// The folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Metric rows written so far (including those kept on resume).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The checkpoint folder.
    pub fn checkpoint_dir(&self) -> PathBuf {
        self.root.join(Self::CHECKPOINT)
    }

    /// Appends one metrics row (a serialisable struct with flat fields) to both logs.
    pub fn append<T: Serialize>(&mut self, row: &T) -> Result<()> {
        let Value::Object(map) = serde_json::to_value(row)? else {
            bail!("a metrics row must serialise to a JSON object");
        };
        let line = serde_json::to_string(&map)?;
        let (jsonl, csv) = (self.root.join(Self::JSONL), self.root.join(Self::CSV));
        let writing = |p: &Path| format!("writing {}", p.display());
        writeln!(self.jsonl, "{line}")
            .and_then(|()| self.jsonl.flush())
            .with_context(|| writing(&jsonl))?;
        let mut text = String::new();
        if self.columns.is_none() {
            let cols: Vec<String> = map.keys().cloned().collect();
            text = cols.join(",") + "\n";
            self.columns = Some(cols);
        }
        if let Some(cols) = &self.columns {
            text += &csv_line(cols, &map);
            text.push('\n');
        }
        self.csv
            .write_all(text.as_bytes())
            .and_then(|()| self.csv.flush())
            .with_context(|| writing(&csv))?;
        self.rows += 1;
        Ok(())
    }

    /// Writes `summary.json` atomically.
    pub fn write_summary<T: Serialize>(&self, summary: &T) -> Result<()> {
        write_json_atomic(&self.root.join(Self::SUMMARY), summary)
    }
}

/// One CSV line in the order of `cols`; missing or null values are empty cells.
fn csv_line(cols: &[String], row: &Map<String, Value>) -> String {
    cols.iter()
        .map(|c| match row.get(c) {
            None | Some(Value::Null) => String::new(),
            Some(Value::String(s)) => s.clone(),
            Some(v) => v.to_string(),
        })
        .collect::<Vec<_>>()
        .join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Row {
        generation: usize,
        curve: f64,
        q0: Option<f64>,
    }

    #[test]
    fn rows_go_to_both_logs_and_resume_truncates() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("run");
        let mut run = RunDir::create(&root, "seed = 1\n").unwrap();
        for g in 0..4 {
            run.append(&Row {
                generation: g,
                curve: g as f64 * 1.5,
                q0: (g % 2 == 0).then_some(2.0),
            })
            .unwrap();
        }
        drop(run);
        let csv = fs::read_to_string(root.join(RunDir::CSV)).unwrap();
        assert_eq!(csv.lines().next().unwrap(), "generation,curve,q0");
        assert_eq!(csv.lines().nth(2).unwrap(), "1,1.5,");
        assert!(
            RunDir::create(&root, "").is_err(),
            "must refuse to overwrite"
        );

        let mut run = RunDir::resume(&root, 2).unwrap();
        run.append(&Row {
            generation: 2,
            curve: 9.0,
            q0: None,
        })
        .unwrap();
        let jsonl = fs::read_to_string(root.join(RunDir::JSONL)).unwrap();
        assert_eq!(jsonl.lines().count(), 3);
        assert!(jsonl.lines().nth(2).unwrap().contains("9.0"));
        let csv = fs::read_to_string(root.join(RunDir::CSV)).unwrap();
        assert_eq!(csv.lines().count(), 4, "header + 3 rows");
        assert!(RunDir::resume(&root, 10).is_err());
    }

    #[test]
    fn atomic_write_replaces_whole_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "second");
        assert_eq!(
            fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temp file left"
        );
    }
}
