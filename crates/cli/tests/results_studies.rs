//! Contract: the committed results are studies whose reports regenerate from their committed
//! records. For every study folder under `results/` with records, `esrl study report` on a
//! copy of its `study.toml`, `configs/` and `records/` writes exactly the committed
//! `report.md`, `report.csv` and `report.json`.

mod common;

use common::ok_output as ok;
use std::path::{Path, PathBuf};

const STUDIES: [&str; 8] = [
    "results/seeds",
    "results/walking/compare",
    "results/walking/compare-equal-gen",
    "results/walking/seeds",
    "results/walking/levers",
    "results/walking/screens",
    "results/compare-quick-g150",
    "results/compare-quick-equal-steps",
];

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
    let tmp = tempfile::tempdir().unwrap();
    for (k, study) in STUDIES.iter().enumerate() {
        let from = root.join(study);
        let to = tmp.path().join(k.to_string());
        std::fs::create_dir_all(&to).unwrap();
        std::fs::copy(from.join("study.toml"), to.join("study.toml")).unwrap();
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
