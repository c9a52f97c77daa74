//! Contract: `esrl compare --agents es-sac,sac --seeds 2 --preset smoke` trains and evaluates
//! every agent × seed and writes table.md / table.csv with one row per agent, whose nAUC is
//! the mean over seeds of the nAUC recomputed here from each run's metrics.jsonl, and a
//! budget table with each run's length and environment steps from its summary.json; a second
//! invocation reuses the finished runs (no file of theirs is rewritten) and writes the same
//! table; unknown agent names fail with the list of valid ones.

mod common;

use common::{curve, esrl, ok_output as ok, read_json};
use std::path::Path;
use std::time::SystemTime;

fn nauc(run: &Path) -> f64 {
    let curve = curve(run);
    curve.iter().sum::<f64>() / curve.len() as f64
}

fn mtimes(dir: &Path) -> Vec<(String, SystemTime)> {
    let mut out = Vec::new();
    for run in ["es-sac-s0", "es-sac-s1", "sac-s0", "sac-s1"] {
        for f in [
            "metrics.jsonl",
            "summary.json",
            "checkpoint/state.json",
            "eval.json",
        ] {
            let p = dir.join(run).join(f);
            let t = std::fs::metadata(&p)
                .and_then(|m| m.modified())
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            out.push((format!("{run}/{f}"), t));
        }
    }
    out
}

#[test]
fn compare_writes_one_row_per_agent_and_reuses_finished_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let d = dir.to_str().unwrap();
    let args = [
        "compare",
        "--agents",
        "es-sac,sac",
        "--seeds",
        "2",
        "--preset",
        "smoke",
        "--out",
        d,
        "--no-progress",
        "--jobs",
        "2",
    ];
    let first = ok(&args);
    let stdout = String::from_utf8_lossy(&first.stdout).to_string();
    assert!(stdout.contains("| es-sac | 2 |"), "{stdout}");
    assert!(stdout.contains("| sac | 2 |"), "{stdout}");

    let md = std::fs::read_to_string(dir.join("table.md")).unwrap();
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| ")).collect();
    // Table 1, the actuator table and the joint table: one row per agent each.
    assert_eq!(
        rows.iter().filter(|l| l.starts_with("| es-sac |")).count(),
        3
    );
    assert_eq!(rows.iter().filter(|l| l.starts_with("| sac |")).count(), 3);
    assert!(md.contains("left_knee ROM (°)"), "{md}");
    assert!(md.contains("Best-Win-50") && md.contains("Episodes-to-Target"));
    // The budget table: one row per run, with the run's own generations/episodes and steps.
    assert!(md.contains("## Budget per run"), "{md}");
    for run in ["es-sac-s0", "es-sac-s1", "sac-s0", "sac-s1"] {
        let summary = read_json(&dir.join(run).join("summary.json"));
        let unit = if run.starts_with("es-") {
            "generations"
        } else {
            "episodes"
        };
        let row = format!(
            "| {run} | {} {unit} | {} |",
            summary["length"], summary["env_steps"]
        );
        assert!(md.contains(&row), "missing `{row}` in:\n{md}");
    }

    let csv = std::fs::read_to_string(dir.join("table.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "header + one row per agent:\n{csv}");
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for (line, agent) in lines[1..].iter().zip(["es-sac", "sac"]) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[0], agent);
        assert_eq!(cells[col("seeds")], "2");
        let want =
            (nauc(&dir.join(format!("{agent}-s0"))) + nauc(&dir.join(format!("{agent}-s1")))) / 2.0;
        let got: f64 = cells[col("nauc_mean")].parse().unwrap();
        assert!(
            (got - want).abs() < 1e-9 * (1.0 + want.abs()),
            "{agent}: {got} vs {want}"
        );
        assert_eq!(cells[col("gait_runs")], "2", "both seeds evaluated");
        assert_eq!(cells[col("q0_mean_n")], "2");
    }

    let before = mtimes(&dir);
    let second = ok(&args);
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(err.matches("reusing finished run").count(), 4, "{err}");
    assert!(!err.contains("training "), "nothing retrained: {err}");
    assert_eq!(
        mtimes(&dir),
        before,
        "finished runs and their evaluations are untouched"
    );
    assert_eq!(String::from_utf8_lossy(&second.stdout), stdout);
    assert_eq!(std::fs::read_to_string(dir.join("table.csv")).unwrap(), csv);
}

#[test]
fn unknown_agents_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let out = esrl(&[
        "compare",
        "--agents",
        "es-sac,nonsense",
        "--preset",
        "smoke",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown agent `nonsense`"), "{err}");
    assert!(
        err.contains("es-sac, es-td3, es-ddpg, sac, td3, ddpg"),
        "{err}"
    );
    assert!(!dir.exists(), "nothing trained or written");
}
