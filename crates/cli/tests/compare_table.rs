//! Contract: `esrl compare --agents es-sac,sac --seeds 2 --preset smoke` trains and evaluates
//! every agent × seed and writes table.md / table.csv with one row per agent, whose nAUC is
//! the mean over seeds of the nAUC recomputed here from each run's metrics.jsonl, and a
//! budget table with each run's length and environment steps from its summary.json; a second
//! invocation reuses the finished runs (no file of theirs is rewritten) and writes the same
//! table; while training, each run logs lines prefixed with its name; unknown agent names
//! fail with the list of valid ones. With `--eval-best` the ES
//! rows come from each ES run's kept policy (`RUN/best/eval.json`, the same numbers as `esrl
//! eval RUN/best`), the plain rows from the last checkpoint as before, and a repeat
//! re-evaluates nothing.

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

/// `esrl compare` of ES-SAC and SAC, 2 seeds each, on `smoke` into `out`, two at a time,
/// then `extra`.
fn smoke_compare<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "compare",
        "--agents",
        "es-sac,sac",
        "--seeds",
        "2",
        "--preset",
        "smoke",
        "--out",
        out,
        "--no-progress",
        "--jobs",
        "2",
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn compare_writes_one_row_per_agent_and_reuses_finished_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let d = dir.to_str().unwrap();
    let args = smoke_compare(d, &[]);
    let first = ok(&args);
    let stdout = String::from_utf8_lossy(&first.stdout).to_string();
    // Runs trained side by side report themselves by name, from their first row on.
    let log = String::from_utf8_lossy(&first.stderr);
    for (run, unit) in [
        ("es-sac-s0", "generations"),
        ("es-sac-s1", "generations"),
        ("sac-s0", "episodes"),
        ("sac-s1", "episodes"),
    ] {
        let line = log
            .lines()
            .find(|l| l.starts_with(&format!("[{run}] 1/")))
            .unwrap_or_else(|| panic!("no first-row line of {run} in:\n{log}"));
        assert!(
            line.contains(&format!(" {unit}, ")) && line.contains("env steps | best so far"),
            "{line}"
        );
    }
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

/// Column `name` of the agent's row of a table.csv.
fn csv_cell(csv: &str, agent: &str, name: &str) -> String {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == name).unwrap();
    let row = lines
        .find(|l| l.split(',').next() == Some(agent))
        .unwrap_or_else(|| panic!("no row {agent} in\n{csv}"));
    row.split(',').nth(col).unwrap().to_string()
}

#[test]
fn eval_best_tabulates_the_kept_policies_of_es_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cmp");
    let d = dir.to_str().unwrap();
    let args = smoke_compare(d, &["--eval-episodes", "2", "--eval-best"]);
    ok(&args);
    let md = std::fs::read_to_string(dir.join("table.md")).unwrap();
    assert!(
        md.contains("each ES run's kept policy (`RUN/best/`"),
        "{md}"
    );
    let csv = std::fs::read_to_string(dir.join("table.csv")).unwrap();
    // Each evaluated policy's mean, as `esrl eval` would write it.
    let mean_velocity = |report: &Path| {
        let r = read_json(report);
        assert_eq!(r["episodes"].as_array().unwrap().len(), 2);
        r["mean"]["gait"]["mean_forward_velocity"].as_f64().unwrap()
    };
    for (agent, file) in [("es-sac", "best/eval.json"), ("sac", "eval.json")] {
        let want = (mean_velocity(&dir.join(format!("{agent}-s0")).join(file))
            + mean_velocity(&dir.join(format!("{agent}-s1")).join(file)))
            / 2.0;
        let got: f64 = csv_cell(&csv, agent, "mean_forward_velocity_mean")
            .parse()
            .unwrap();
        assert!(
            (got - want).abs() < 1e-9 * (1.0 + want.abs()),
            "{agent}: {got} vs {want}"
        );
    }
    // The ES runs' last checkpoints were not evaluated, plain runs keep no best/.
    for run in ["es-sac-s0", "es-sac-s1"] {
        assert!(!dir.join(run).join("eval.json").exists(), "{run}");
    }
    assert!(!dir.join("sac-s0/best").exists());
    // `esrl eval RUN/best` gives the same report.
    let best = dir.join("es-sac-s0/best");
    let tabulated = read_json(&best.join("eval.json"));
    ok(&["eval", best.to_str().unwrap(), "--episodes", "2"]);
    assert_eq!(
        read_json(&best.join("eval.json"))["mean"],
        tabulated["mean"]
    );
    // A repeat reuses every evaluation.
    let stamp = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).unwrap();
    let before = stamp(&best.join("eval.json"));
    ok(&args);
    assert_eq!(stamp(&best.join("eval.json")), before);
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
