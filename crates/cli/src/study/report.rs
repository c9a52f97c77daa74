//! `esrl study report`: the records of a study folder tabulated, per arm with interval
//! estimates, arm against arm, run by run, and as the paper's Table 1.

use super::{held_study, read_eval, Handover, Study, StudyEval};
use anyhow::{bail, Context, Result};
use esrl_eval::{goal_rows, goal_set, Disturbance, EvalReport, GoalRows, GOAL_SHARE};
use esrl_metrics::{
    actuator_markdown, bootstrap, gait_classes_text, iqm_interval, joint_markdown, mean_sd,
    probability_of_improvement_interval, summarize_method, table1, table1_markdown, wilson,
    AgentRuns, GaitClass, Interval, SeedResult, BOOTSTRAP_REPS, Z95,
};
use esrl_run::run_dir::{write_atomic, write_json_atomic};
use esrl_run::{RunDir, Summary};
use serde::Serialize;
use serde_json::{json, Value};
use std::fs;
use std::path::Path;

/// The walking bar on an evaluation: more than half of the episodes `walk` and at least
/// 80 % reach the line.
fn at_bar(r: &EvalReport) -> bool {
    let n = r.mean.episodes as f64;
    let walks = r
        .mean
        .gait
        .as_ref()
        .and_then(|g| g.cycle.as_ref())
        .map_or(0, |c| {
            c.gait_classes.get(&GaitClass::Walk).copied().unwrap_or(0)
        });
    r.mean.finished as f64 >= 0.8 * n - 1e-9 && walks as f64 > 0.5 * n
}

/// One recorded run, as the report reads it.
struct Record {
    arm: usize,
    seed: u64,
    curve: Vec<f64>,
    q0: Option<f64>,
    summary: Summary,
    eval: EvalReport,
}

/// The per-run row of the report.
#[derive(Debug, Clone, Serialize)]
struct RunRow {
    arm: String,
    seed: u64,
    at_bar: bool,
    classes: String,
    finished: usize,
    falls: usize,
    episodes: usize,
    track_time: Option<f64>,
    speed: f64,
    sway: f64,
    knee_asymmetry: f64,
    knee_flexion_deg: Option<f64>,
    double_support: Option<f64>,
    /// Mean torso pitch, degrees, forward lean positive (records evaluated before esrl
    /// measured it have none).
    torso_pitch_deg: Option<f64>,
    /// Whether the run checked policies against the walking bar while it trained.
    checked: bool,
    steps_to_walk: Option<f64>,
    time_to_walk_s: Option<f64>,
    env_steps: u64,
    wall_s: f64,
    /// Seconds the run's walking checks took (`check_s` of its summary; of the kept attempt
    /// where the run started over), part of `wall_s`; none for a run without checks.
    check_s: Option<f64>,
    best_win_50: f64,
    /// The seed of the attempt that was kept, when `[restart]` started the run over.
    #[serde(skip_serializing_if = "Option::is_none")]
    restarted_as: Option<u64>,
}

/// Largest 95th-percentile knee angle of the two knees, degrees: how far the swing knee
/// flexes.
fn knee_flexion(r: &EvalReport) -> Option<f64> {
    let g = r.mean.gait.as_ref()?;
    g.joints
        .iter()
        .filter(|j| j.name.contains("knee"))
        .map(|j| j.p95.to_degrees())
        .reduce(f64::max)
}

fn run_row(study: &Study, rec: &Record) -> RunRow {
    let g = rec.eval.mean.gait.as_ref();
    let finishers: Vec<f64> = rec
        .eval
        .episodes
        .iter()
        .filter_map(|e| e.gait.as_ref()?.track_time)
        .collect();
    let figure = |k: &str| rec.summary.learner.get(k).and_then(Value::as_f64);
    // A run that started over counts its abandoned attempts in its cost.
    let restart_steps = figure("restart_env_steps").unwrap_or(0.0) as u64;
    let restart_wall = figure("restart_wall_s").unwrap_or(0.0);
    let checked = figure("checks").is_some_and(|c| c > 0.0);
    RunRow {
        arm: study.file.arms[rec.arm].name.clone(),
        seed: rec.seed,
        at_bar: at_bar(&rec.eval),
        classes: g
            .and_then(|g| g.cycle.as_ref())
            .map_or("-".into(), |c| gait_classes_text(&c.gait_classes)),
        finished: rec.eval.mean.finished,
        falls: rec.eval.mean.falls,
        episodes: rec.eval.mean.episodes,
        track_time: (!finishers.is_empty())
            .then(|| finishers.iter().sum::<f64>() / finishers.len() as f64),
        speed: g.map_or(f64::NAN, |g| g.mean_forward_velocity),
        sway: g.map_or(f64::NAN, |g| g.mean_abs_lateral),
        knee_asymmetry: g.map_or(f64::NAN, |g| g.knee_torque_asymmetry),
        knee_flexion_deg: knee_flexion(&rec.eval),
        double_support: g.and_then(|g| g.cycle.as_ref()).map(|c| c.double_support),
        torso_pitch_deg: g
            .and_then(|g| g.torso_pitch.as_ref())
            .map(|p| p.mean.to_degrees()),
        checked,
        steps_to_walk: figure("steps_to_walk"),
        time_to_walk_s: figure("time_to_walk_s"),
        env_steps: rec.summary.env_steps + restart_steps,
        wall_s: rec.summary.wall_s + restart_wall,
        check_s: figure("check_s").filter(|_| checked),
        best_win_50: rec.summary.curve.best_win_50,
        restarted_as: restarted_as(&rec.summary),
    }
}

/// The seed of the attempt a run kept, when `[restart]` started it over.
fn restarted_as(summary: &Summary) -> Option<u64> {
    let figure = |k: &str| summary.learner.get(k).and_then(Value::as_u64);
    figure("restarts").filter(|&n| n > 0)?;
    figure("attempt_seed")
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite())
        .map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// A share as per cent with its interval: "40 % [12–77 %]".
fn percent_interval(i: &Interval, digits: usize) -> String {
    format!(
        "{:.digits$} % [{:.digits$}–{:.digits$} %]",
        100.0 * i.estimate,
        100.0 * i.lo,
        100.0 * i.hi
    )
}

fn interval_text(i: &Interval, digits: usize, scale: f64) -> String {
    format!(
        "{:.digits$} [{:.digits$}, {:.digits$}]",
        i.estimate * scale,
        i.lo * scale,
        i.hi * scale
    )
}

pub(crate) fn report(dir: &Path, json_out: bool) -> Result<()> {
    let study = held_study(dir)?;
    let records = load_records(dir, &study)?;
    if records.is_empty() {
        bail!(
            "{} has no records yet (`{} study status {}` says where the runs are)",
            dir.display(),
            esrl_run::command(),
            dir.display()
        );
    }
    let rows: Vec<RunRow> = records.iter().map(|r| run_row(&study, r)).collect();
    let mut md = heading(dir, &study, records.len());
    let (arms_md, arms_json) = per_arm(&study, &rows)?;
    md.push_str(&arms_md);
    let (poi_md, poi_json) = improvement(&study, &rows)?;
    md.push_str(&poi_md);
    let (runs_md, csv) = every_run(&rows);
    md.push_str(&runs_md);
    let carded: Vec<CardedRun> = records
        .iter()
        .filter_map(|r| {
            Some(CardedRun {
                arm: study.file.arms[r.arm].name.clone(),
                seed: r.seed,
                goal: goal_rows(r.eval.robustness.as_ref()?),
            })
        })
        .collect();
    let (robust_md, robust_json) = robustness_section(&study, &carded)?;
    md.push_str(&robust_md);
    md.push_str(&table1_section(&study, &records)?);
    let mut figures = json!({"arms": arms_json, "improvement": poi_json, "runs": rows});
    if !carded.is_empty() {
        figures["robustness"] = json!({"arms": robust_json, "runs": carded});
    }
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    write_atomic(&dir.join("report.csv"), csv.as_bytes())?;
    write_json_atomic(&dir.join("report.json"), &figures)?;
    if json_out {
        println!("{}", serde_json::to_string_pretty(&figures)?);
    } else {
        print!("{md}");
    }
    eprintln!(
        "wrote {}, {} and {} (`python -m esrl_rs.report --study {}` draws them)",
        dir.join("report.md").display(),
        dir.join("report.csv").display(),
        dir.join("report.json").display(),
        dir.display()
    );
    Ok(())
}

/// The written records of `study`'s runs in `dir`, in the study's order.
fn load_records(dir: &Path, study: &Study) -> Result<Vec<Record>> {
    let mut records = Vec::new();
    for (k, (arm, seed, _)) in study.runs.iter().enumerate() {
        let rec_dir = dir.join("records").join(study.run_name(k));
        let Some(eval) = read_eval(&rec_dir)? else {
            continue;
        };
        let Some(summary) = Summary::read(&rec_dir)? else {
            continue;
        };
        let (curve, q0) = read_csv_curve(&rec_dir.join(RunDir::CSV))?;
        records.push(Record {
            arm: *arm,
            seed: *seed,
            curve,
            q0,
            summary,
            eval,
        });
    }
    Ok(records)
}

/// The title and what the numbers are.
fn heading(dir: &Path, study: &Study, recorded: usize) -> String {
    let own = study.file.arms.iter().any(|a| a.seeds.is_some());
    let shape = if own {
        // Arms with seeds of their own: how many each.
        let per_arm = study
            .file
            .arms
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let n = study.runs.iter().filter(|r| r.0 == i).count();
                format!("{} {n}", a.name)
            })
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "{} arm(s), seeds per arm ({per_arm})",
            study.file.arms.len()
        )
    } else {
        let planned = study.file.seeds.list().len();
        format!("{} arm(s) × {planned} seed(s)", study.file.arms.len())
    };
    format!(
        "# Study: {}\n\n{shape}; {} of {} runs recorded. Each run's \
         handed-over policy ({}) evaluated on {} deterministic episodes (reset seeds {}…){}. \
         The walking bar: `walk` in more than half of the episodes and at least 80 % past the 50 m \
         line. Intervals are 95 %: Wilson for rates, percentile bootstrap over runs (2,000 \
         resamples) for the IQM and the probability of improvement (Agarwal et al. 2021).\n\n",
        if study.file.description.is_empty() {
            dir.display().to_string()
        } else {
            study.file.description.clone()
        },
        recorded,
        study.runs.len(),
        match study.file.eval.policy {
            Handover::Kept => "its kept policy, RUN/best/",
            Handover::Last => "its last checkpoint",
        },
        study.file.eval.episodes,
        study.file.eval.seed,
        eval_conditions(&study.file.eval),
    )
}

/// How the study's evaluation differs from each run's own task, as a clause of the heading.
fn eval_conditions(eval: &StudyEval) -> String {
    let mut clauses = Vec::new();
    if eval.undisturbed {
        clauses.push(" on the plain task, without the runs' training-time disturbances");
    }
    if eval.default_starts {
        clauses.push(
            " from the task's standard starts (`walk.init_noise` and `walk.reset` at their \
             defaults), not the runs' own",
        );
    }
    clauses.join(",")
}

/// "Per arm": runs at the bar with the Wilson interval, the IQM Best-Win-50 and the steps to
/// the first walk with bootstrap intervals; the same as JSON values.
fn per_arm(study: &Study, rows: &[RunRow]) -> Result<(String, Vec<Value>)> {
    let mut md = String::new();
    md.push_str(
        "## Per arm\n\n| arm | runs | at the bar | rate [95 %] | finished every episode [95 %] \
         | falls per episode [95 %] | IQM Best-Win-50 [95 %] | walked in training | IQM steps to \
         walk [95 %] |\n|---|---:|---:|---|---|---|---|---:|---|\n",
    );
    let mut arms_json = Vec::new();
    for (a, arm) in study.file.arms.iter().enumerate() {
        let mine: Vec<&RunRow> = rows.iter().filter(|r| r.arm == arm.name).collect();
        if mine.is_empty() {
            continue;
        }
        let n = mine.len();
        let k = mine.iter().filter(|r| r.at_bar).count();
        let rate = wilson(k, n, Z95)?;
        let bw: Vec<f64> = mine.iter().map(|r| r.best_win_50).collect();
        let bw_iqm = iqm_interval(&bw, 1 + a as u64)?;
        // A policy that finishes every start of the evaluation (issue 34's reliability), and
        // the share of starts that end in a fall: the mean of the runs' shares, its interval
        // from resampling runs (policies differ in how often they fall, so the episodes of
        // one run are not independent draws of the arm's).
        let clean = mine
            .iter()
            .filter(|r| r.episodes > 0 && r.finished == r.episodes)
            .count();
        let clean_rate = wilson(clean, n, Z95)?;
        let fall_shares: Vec<f64> = mine
            .iter()
            .map(|r| r.falls as f64 / r.episodes.max(1) as f64)
            .collect();
        let falls = bootstrap(
            &fall_shares,
            |v| Ok(mean_sd(v)?.mean),
            BOOTSTRAP_REPS,
            200 + a as u64,
        )?;
        let walked: Vec<f64> = mine.iter().filter_map(|r| r.steps_to_walk).collect();
        let steps_iqm = if walked.is_empty() {
            None
        } else {
            Some(iqm_interval(&walked, 100 + a as u64)?)
        };
        let rate_text = percent_interval(&rate, 0);
        // Runs made without the walking check cannot say when they first walked.
        let checked = mine.iter().filter(|r| r.checked).count();
        let walked_text = if checked == 0 {
            "– (no check)".to_string()
        } else {
            format!("{} of {checked}", walked.len())
        };
        md.push_str(&format!(
            "| {} | {n} | {k} | {rate_text} | {clean} of {n}: {} | {} | {} | {walked_text} | {} \
             |\n",
            arm.name,
            percent_interval(&clean_rate, 0),
            percent_interval(&falls, 1),
            interval_text(&bw_iqm, 0, 1.0),
            steps_iqm.map_or("–".into(), |i| interval_text(&i, 2, 1e-6) + " M"),
        ));
        arms_json.push(json!({
            "arm": arm.name,
            "runs": n,
            "at_bar": k,
            "rate": rate,
            "finished_every_episode": clean,
            "finished_every_episode_rate": clean_rate,
            "falls_per_episode": falls,
            "best_win_50_iqm": bw_iqm,
            "walked_in_training": walked.len(),
            "checked_in_training": checked,
            "steps_to_walk_iqm": steps_iqm,
        }));
    }
    Ok((md, arms_json))
}

/// A run whose record holds a robustness card, and the goal rows it meets.
#[derive(Debug, Clone, Serialize)]
struct CardedRun {
    arm: String,
    seed: u64,
    goal: GoalRows,
}

/// "Robustness goal": per arm the runs whose card meets every goal row, and every one but
/// one, with Wilson intervals; per goal row the runs that meet it; each run's rows met and
/// missed. Nothing when no record has a card (`[eval] robustness_episodes`).
fn robustness_section(study: &Study, carded: &[CardedRun]) -> Result<(String, Vec<Value>)> {
    let mut json_arms = Vec::new();
    if carded.is_empty() {
        return Ok((String::new(), json_arms));
    }
    let (num, den) = GOAL_SHARE;
    let labels: Vec<String> = goal_set().into_iter().map(Disturbance::label).collect();
    let mut md = format!(
        "\n## Robustness goal\n\nEach run's handed-over policy on the robustness card ({} \
         episodes per disturbance, the reset seeds above). Goal rows: {}; a row is met when at \
         least {num} of {den} episodes finish 50 m or stay up. Rates with Wilson 95 % \
         intervals.\n\n| arm | runs carded | every goal row [95 %] | all but one [95 %] | goal \
         rows met per run |\n|---|---:|---|---|---|\n",
        study.file.eval.robustness_episodes,
        labels.join(", ")
    );
    let arms: Vec<&str> = study
        .file
        .arms
        .iter()
        .map(|a| a.name.as_str())
        .filter(|name| carded.iter().any(|r| r.arm == *name))
        .collect();
    for &arm in &arms {
        let mine: Vec<&CardedRun> = carded.iter().filter(|r| r.arm == arm).collect();
        let n = mine.len();
        // A card without the goal's rows (another set) meets none of it.
        let every = mine
            .iter()
            .filter(|r| r.goal.rows > 0 && r.goal.met == r.goal.rows)
            .count();
        let but_one = mine
            .iter()
            .filter(|r| r.goal.rows > 0 && r.goal.met + 1 >= r.goal.rows)
            .count();
        let (every_rate, but_one_rate) = (wilson(every, n, Z95)?, wilson(but_one, n, Z95)?);
        let met: Vec<String> = mine
            .iter()
            .map(|r| format!("{}/{}", r.goal.met, r.goal.rows))
            .collect();
        md.push_str(&format!(
            "| {arm} | {n} | {every} of {n}: {} | {but_one} of {n}: {} | {} |\n",
            percent_interval(&every_rate, 0),
            percent_interval(&but_one_rate, 0),
            met.join(", ")
        ));
        let rows: Vec<Value> = labels
            .iter()
            .map(|label| {
                let missed = mine
                    .iter()
                    .filter(|r| r.goal.missed.iter().any(|m| m.row == *label))
                    .count();
                json!({"row": label, "met": n - missed})
            })
            .collect();
        json_arms.push(json!({
            "arm": arm,
            "runs": n,
            "every_goal_row": every,
            "every_goal_row_rate": every_rate,
            "all_but_one": but_one,
            "all_but_one_rate": but_one_rate,
            "rows": rows,
        }));
    }
    md.push_str(&format!(
        "\n| goal row | {} |\n|---|{}\n",
        arms.join(" | "),
        "---:|".repeat(arms.len())
    ));
    for (i, label) in labels.iter().enumerate() {
        let cells: Vec<String> = json_arms
            .iter()
            .map(|a| format!("{} of {}", a["rows"][i]["met"], a["runs"]))
            .collect();
        md.push_str(&format!("| {label} | {} |\n", cells.join(" | ")));
    }
    md.push_str("\n| run | goal rows met | missed |\n|---|---:|---|\n");
    for r in carded {
        md.push_str(&format!(
            "| {}-s{} | {} of {} | {} |\n",
            r.arm,
            r.seed,
            r.goal.met,
            r.goal.rows,
            if r.goal.missed.is_empty() {
                "–".to_string()
            } else {
                let missed: Vec<String> = r.goal.missed.iter().map(|m| m.to_string()).collect();
                missed.join("; ")
            }
        ));
    }
    Ok((md, json_arms))
}

/// "Probability of improvement" of every arm over every other, on Best-Win-50 and on
/// meeting the bar (nothing with one arm).
fn improvement(study: &Study, rows: &[RunRow]) -> Result<(String, Vec<Value>)> {
    let mut md = String::new();
    let mut poi_json = Vec::new();
    if study.file.arms.len() > 1 {
        md.push_str(
            "\n## Probability of improvement\n\nP(a run of the row arm beats one of the column \
             arm), on Best-Win-50 / on meeting the bar, with 95 % intervals.\n\n",
        );
        let values = |name: &str, f: &dyn Fn(&RunRow) -> f64| -> Vec<f64> {
            rows.iter().filter(|r| r.arm == name).map(f).collect()
        };
        for (i, x) in study.file.arms.iter().enumerate() {
            for (j, y) in study.file.arms.iter().enumerate() {
                if i == j {
                    continue;
                }
                let (bx, by) = (
                    values(&x.name, &|r| r.best_win_50),
                    values(&y.name, &|r| r.best_win_50),
                );
                if bx.is_empty() || by.is_empty() {
                    continue;
                }
                let bar = |r: &RunRow| f64::from(u8::from(r.at_bar));
                let (sx, sy) = (values(&x.name, &bar), values(&y.name, &bar));
                let seed = 1000 + (i * 100 + j) as u64;
                let p_bw = probability_of_improvement_interval(&bx, &by, seed)?;
                let p_bar = probability_of_improvement_interval(&sx, &sy, seed + 7)?;
                md.push_str(&format!(
                    "- {} over {}: {} / {}\n",
                    x.name,
                    y.name,
                    interval_text(&p_bw, 2, 1.0),
                    interval_text(&p_bar, 2, 1.0)
                ));
                poi_json.push(json!({"arm": x.name, "over": y.name,
                    "best_win_50": p_bw, "at_bar": p_bar}));
            }
        }
    }
    Ok((md, poi_json))
}

/// "Every run" as a Markdown table, and the same rows as `report.csv`.
fn every_run(rows: &[RunRow]) -> (String, String) {
    let mut md = String::new();
    md.push_str(
        "\n## Every run\n\n| run | at bar | gait classes | finished | falls | track time (s) | \
         speed (m/s) | sway (m) | knee asym. | knee flexion (°) | double support | torso pitch \
         (°) | steps to walk | env steps | wall (s) | checks (s) |\n|---|---|---|---:|---:|---:|---:\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut csv = String::from(
        "arm,seed,at_bar,classes,finished,falls,episodes,track_time,speed,sway,knee_asymmetry,\
         knee_flexion_deg,double_support,torso_pitch_deg,steps_to_walk,time_to_walk_s,env_steps,\
         wall_s,best_win_50,check_s\n",
    );
    for r in rows {
        md.push_str(&format!(
            "| {}-s{}{} | {} | {} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0} \
             | {} |\n",
            r.arm,
            r.seed,
            r.restarted_as
                .map_or(String::new(), |s| format!(" (restarted as seed {s})")),
            if r.at_bar { "yes" } else { "no" },
            r.classes,
            r.finished,
            r.episodes,
            r.falls,
            fmt(r.track_time, 1),
            fmt(Some(r.speed), 2),
            fmt(Some(r.sway), 3),
            fmt(Some(100.0 * r.knee_asymmetry), 1) + " %",
            fmt(r.knee_flexion_deg, 0),
            fmt(r.double_support.map(|d| 100.0 * d), 1) + " %",
            fmt(r.torso_pitch_deg, 1),
            r.steps_to_walk
                .map_or("–".into(), |s| format!("{:.2} M", s / 1e6)),
            r.env_steps,
            r.wall_s,
            fmt(r.check_s, 0)
        ));
        csv.push_str(&format!(
            "{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.arm,
            r.seed,
            r.at_bar,
            r.classes,
            r.finished,
            r.falls,
            r.episodes,
            fmt(r.track_time, 3),
            fmt(Some(r.speed), 4),
            fmt(Some(r.sway), 4),
            fmt(Some(r.knee_asymmetry), 4),
            fmt(r.knee_flexion_deg, 2),
            fmt(r.double_support, 4),
            fmt(r.torso_pitch_deg, 2),
            fmt(r.steps_to_walk, 0),
            fmt(r.time_to_walk_s, 1),
            r.env_steps,
            fmt(Some(r.wall_s), 1),
            fmt(Some(r.best_win_50), 2),
            fmt(r.check_s, 1),
        ));
    }
    (md, csv)
}

/// Table 1 of the arms (mean ± SD, as the paper; the one Table 1 writer), the actuators'
/// and joints' tables, and the footnote.
fn table1_section(study: &Study, records: &[Record]) -> Result<String> {
    let mut md = String::new();
    let mut agents = Vec::new();
    for (a, arm) in study.file.arms.iter().enumerate() {
        let mine: Vec<&Record> = records.iter().filter(|r| r.arm == a).collect();
        if mine.is_empty() {
            continue;
        }
        let curves: Vec<Vec<f64>> = mine.iter().map(|r| r.curve.clone()).collect();
        let summaries = summarize_method(&curves)?;
        agents.push(AgentRuns {
            agent: arm.name.clone(),
            seeds: summaries
                .into_iter()
                .zip(&mine)
                .map(|(summary, r)| SeedResult {
                    summary,
                    gait: r.eval.mean.gait.clone(),
                    q0_mean: r.q0,
                })
                .collect(),
        });
    }
    let table = table1(&agents)?;
    md.push_str("\n## Table 1 (mean ± sample SD across seeds)\n\n");
    md.push_str(&table1_markdown(&table));
    if table.iter().any(|r| r.gait_runs > 0) {
        md.push_str("\n## Mean |torque| and |power| per actuator (paper Fig. 5d)\n\n");
        md.push_str(&actuator_markdown(&table));
    }
    if table.iter().any(|r| !r.joint_names.is_empty()) {
        md.push_str(
            "\n## Range of motion (5th–95th percentile) and time within 1° of a limit per \
             joint\n\n",
        );
        md.push_str(&joint_markdown(&table));
    }
    md.push_str(
        "\nKnee flexion: the larger of the two knees' 95th-percentile angle; knee asym.: \
         |T_L − T_R| / ((T_L + T_R)/2) of the mean |knee torque|; steps to walk: environment \
         steps to the first policy the walking check found at the bar during training \
         (`checks.jsonl`); wall: training time as measured on the machine that ran it.\n",
    );
    if records.iter().any(|r| restarted_as(&r.summary).is_some()) {
        md.push_str(
            "A run that `[restart]` started over names the seed of the attempt it kept; its \
             steps to walk, env steps and wall count the attempts it abandoned.\n",
        );
    }
    Ok(md)
}

/// The `curve` and mean `q0` columns of a record's `metrics.csv`.
fn read_csv_curve(path: &Path) -> Result<(Vec<f64>, Option<f64>)> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .with_context(|| format!("{} is empty", path.display()))?
        .split(',')
        .collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let c = col("curve").with_context(|| format!("{} has no curve column", path.display()))?;
    let q = col("q0");
    let (mut curve, mut q0) = (Vec::new(), Vec::new());
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let value = |i: usize| cells.get(i).and_then(|v| v.parse::<f64>().ok());
        curve.push(
            value(c).with_context(|| format!("{}: a row without a curve value", path.display()))?,
        );
        q0.extend(q.and_then(value));
    }
    Ok((curve, esrl_metrics::q0_mean(&q0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walking run of arm `a` over `episodes` starts, `finished` of them past the line and
    /// `falls` ending in a fall.
    fn row(seed: u64, finished: usize, falls: usize, episodes: usize) -> RunRow {
        RunRow {
            arm: "a".into(),
            seed,
            at_bar: true,
            classes: format!("walk {episodes}"),
            finished,
            falls,
            episodes,
            track_time: Some(38.0),
            speed: 1.3,
            sway: 0.02,
            knee_asymmetry: 0.05,
            knee_flexion_deg: Some(60.0),
            double_support: Some(0.1),
            torso_pitch_deg: Some(-8.0),
            checked: true,
            steps_to_walk: Some(2e6),
            time_to_walk_s: Some(900.0),
            env_steps: 3_000_000,
            wall_s: 1000.0,
            check_s: Some(120.4),
            best_win_50: 50.0,
            restarted_as: None,
        }
    }

    #[test]
    fn every_run_gives_the_checks_seconds_and_a_dash_for_a_run_without_checks() {
        let unchecked = RunRow {
            checked: false,
            check_s: None,
            ..row(1, 20, 0, 20)
        };
        let (md, csv) = every_run(&[row(0, 20, 0, 20), unchecked]);
        assert!(md.contains("| wall (s) | checks (s) |"), "{md}");
        assert!(md.contains("| 3000000 | 1000 | 120 |\n"), "{md}");
        assert!(md.contains("| 3000000 | 1000 | – |\n"), "{md}");
        let lines: Vec<&str> = csv.lines().collect();
        assert!(lines[0].ends_with(",best_win_50,check_s"), "{csv}");
        assert!(lines[1].ends_with(",1000.0,50.00,120.4"), "{csv}");
        assert!(lines[2].ends_with(",1000.0,50.00,–"), "{csv}");
    }

    /// A carded run of `arm` missing the goal rows `missed` (labels) out of 12.
    fn carded(arm: &str, seed: u64, missed: &[&str]) -> CardedRun {
        CardedRun {
            arm: arm.into(),
            seed,
            goal: GoalRows {
                rows: 12,
                met: 12 - missed.len(),
                missed: missed
                    .iter()
                    .map(|m| esrl_eval::GoalMiss {
                        row: m.to_string(),
                        up: 7,
                        episodes: 10,
                    })
                    .collect(),
                absent: Vec::new(),
            },
        }
    }

    #[test]
    fn the_robustness_section_counts_runs_meeting_every_goal_row_and_all_but_one() {
        let study = Study::parse(
            "seeds = 3\n[eval]\nrobustness_episodes = 10\n[[arm]]\nname = \"a\"\nagent = \
             \"es-sac\"\n[[arm]]\nname = \"b\"\nagent = \"es-sac\"\n[[arm]]\nname = \"c\"\n\
             agent = \"es-sac\"\n",
        )
        .unwrap();
        let lateral = "push_lateral 0.5 m/s";
        // Arm a: one run meets every row, one all but the lateral push, one misses two rows.
        // Arm b: one run, missing the lateral push. Arm c: no card, no line.
        let runs = [
            carded("a", 0, &[]),
            carded("a", 1, &[lateral]),
            carded("a", 2, &[lateral, "slope -5 °"]),
            carded("b", 0, &[lateral]),
        ];
        let (md, json) = robustness_section(&study, &runs).unwrap();
        assert_eq!(json.len(), 2, "{md}");
        assert_eq!(
            (&json[0]["every_goal_row"], &json[0]["all_but_one"]),
            (&1.into(), &2.into())
        );
        let every: Interval =
            serde_json::from_value(json[0]["every_goal_row_rate"].clone()).unwrap();
        assert_eq!(every, wilson(1, 3, Z95).unwrap());
        assert!(
            md.contains(
                "| a | 3 | 1 of 3: 33 % [6–79 %] | 2 of 3: 67 % [21–94 %] | 12/12, 11/12, 10/12 |"
            ),
            "{md}"
        );
        assert!(
            md.contains("| b | 1 | 0 of 1: 0 % [0–79 %] | 1 of 1: 100 % [21–100 %] | 11/12 |"),
            "{md}"
        );
        // Per goal row, per arm: the runs that meet it.
        assert!(md.contains("| goal row | a | b |"), "{md}");
        assert!(
            md.contains("| push_lateral 0.5 m/s | 1 of 3 | 0 of 1 |"),
            "{md}"
        );
        assert!(md.contains("| slope -5 ° | 2 of 3 | 1 of 1 |"), "{md}");
        assert!(md.contains("| friction 0.4 μ | 3 of 3 | 1 of 1 |"), "{md}");
        assert!(
            md.contains("| a-s2 | 10 of 12 | push_lateral 0.5 m/s: 7/10; slope -5 °: 7/10 |"),
            "{md}"
        );
        assert!(md.contains("| a-s0 | 12 of 12 | – |"), "{md}");
        // No card anywhere, no section.
        assert_eq!(robustness_section(&study, &[]).unwrap().0, "");
        // A card without the goal's rows meets none of it.
        let mut other = carded("c", 0, &[]);
        other.goal.rows = 0;
        other.goal.met = 0;
        let (_, json) = robustness_section(&study, &[other]).unwrap();
        assert_eq!(
            (&json[0]["every_goal_row"], &json[0]["all_but_one"]),
            (&0.into(), &0.into())
        );
    }

    #[test]
    fn per_arm_counts_the_runs_that_finish_every_episode_and_the_falls_per_episode() {
        let study = Study::parse("seeds = 3\n[[arm]]\nname = \"a\"\nagent = \"es-sac\"\n").unwrap();
        // Three runs of 20 episodes: one finishes all 20; one falls once (19 past the line);
        // one stops short of the line twice without falling (18). One run in three finishes
        // every episode; falls per episode (0 + 1/20 + 0) / 3 = 1/60.
        let rows = [row(0, 20, 0, 20), row(1, 19, 1, 20), row(2, 18, 0, 20)];
        let (md, json) = per_arm(&study, &rows).unwrap();
        let arm = &json[0];
        assert_eq!(arm["finished_every_episode"], 1);
        let rate: Interval =
            serde_json::from_value(arm["finished_every_episode_rate"].clone()).unwrap();
        assert_eq!(rate, wilson(1, 3, Z95).unwrap());
        let falls: Interval = serde_json::from_value(arm["falls_per_episode"].clone()).unwrap();
        assert!((falls.estimate - 1.0 / 60.0).abs() < 1e-15, "{falls:?}");
        // Resampling the runs: no falls when the falling run is never drawn (probability
        // (2/3)³ ≈ 0.30 a resample), 1/20 when it is drawn three times (1/27 ≈ 0.037).
        assert_eq!(falls.lo, 0.0, "{falls:?}");
        assert!((falls.hi - 0.05).abs() < 1e-15, "{falls:?}");
        assert!(
            md.contains("| 1 of 3: 33 % [6–79 %] | 1.7 % [0.0–5.0 %] |"),
            "{md}"
        );
    }
}
