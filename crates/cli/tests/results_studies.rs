//! Contract: the committed results are studies whose reports regenerate from their committed
//! records. For every study folder under `results/` with records (found by walking the
//! folder: a `study.toml` beside a `records/`), `esrl study report` on a copy of its
//! `study.toml` (with the arms' config files beside it), `configs/` and `records/` writes
//! exactly the committed `report.md`, `report.csv` and `report.json`.

mod common;

use common::ok_output as ok;
use std::path::{Path, PathBuf};

/// Every folder under `dir` (recursively) with a `study.toml` and a `records/` folder.
fn studies_with_records(dir: &Path, found: &mut Vec<PathBuf>) {
    if dir.join("study.toml").is_file() && dir.join("records").is_dir() {
        found.push(dir.to_path_buf());
    }
    for entry in std::fs::read_dir(dir).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_dir() && entry.file_name() != "records" {
            studies_with_records(&entry.path(), found);
        }
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

#[test]
fn every_committed_study_report_regenerates_from_its_records() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut studies = Vec::new();
    studies_with_records(&root.join("results"), &mut studies);
    studies.sort();
    for known in ["results/seeds", "results/walking/compare", "results/levers"] {
        assert!(
            studies.contains(&root.join(known)),
            "{known} was not found among {studies:?}"
        );
    }
    let tmp = tempfile::tempdir().unwrap();
    for (k, from) in studies.iter().enumerate() {
        let study = from.strip_prefix(&root).unwrap().display();
        let to = tmp.path().join(k.to_string());
        std::fs::create_dir_all(&to).unwrap();
        // The study file and the arms' config files beside it.
        for entry in std::fs::read_dir(from).unwrap() {
            let path = entry.unwrap().path();
            if path.is_file() && path.extension().is_some_and(|e| e == "toml") {
                std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
            }
        }
        for dir in ["configs", "records"] {
            if from.join(dir).is_dir() {
                copy_dir(&from.join(dir), &to.join(dir));
            }
        }
        ok(&["study", "report", to.to_str().unwrap()]);
        for file in ["report.md", "report.csv", "report.json"] {
            let want = std::fs::read_to_string(from.join(file)).unwrap();
            let got = std::fs::read_to_string(to.join(file)).unwrap();
            assert!(
                got == want,
                "{study}/{file} does not regenerate from its records"
            );
        }
    }
}
