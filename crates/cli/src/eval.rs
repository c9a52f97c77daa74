//! `esrl eval`: evaluates a trained policy with `esrl_eval` (deterministic rollouts on the
//! track, the gait metrics of SPEC §6, `RUN/eval.json`) and prints it as tables.

use crate::args::{EnvKind, EvalArgs};
use anyhow::{bail, Result};
use esrl_eval::{
    card, card_markdown, eval_path, evaluate_with, goal_markdown, goal_rows, load_run_pick,
    standard_set, Disturbance, EvalOptions, EvalReport, LoadedRun, Pick,
};
use esrl_metrics::{format_number, gait_classes_text, GaitCycle, GaitMetrics, JointMotion};
use esrl_run::checkpoint::{BestInfo, BEST_INFO};
use esrl_run::run_dir::{check_output, write_json_atomic};
use esrl_sim::OrientationFrame;

/// Runs `esrl eval`.
pub fn run(args: &EvalArgs) -> Result<()> {
    if args.episodes == 0 {
        bail!("--episodes 0: evaluate at least one episode");
    }
    if let Some(out) = &args.out {
        check_output(out, args.force)?;
    }
    if let Some(dir) = args.record.as_deref().filter(|d| d.exists() && !d.is_dir()) {
        bail!(
            "--record {}: not a folder (the recordings go into DIR/episode-NNN.mcap)",
            dir.display()
        );
    }
    let perturb = args
        .perturb
        .iter()
        .map(|p| Disturbance::parse(p))
        .collect::<esrl_run::Result<Vec<_>>>()?;
    let pick = if args.last { Pick::Last } else { Pick::Kept };
    let mut loaded = load_run_pick(&args.path, pick)?;
    eprintln!("evaluating {}", which_policy(&loaded));
    if args.undisturbed {
        if loaded.config.walk.perturb.is_none() {
            eprintln!("--undisturbed: the run trained without disturbances");
        } else {
            eprintln!("without the run's training-time disturbances ([walk.perturb])");
        }
        loaded = loaded.undisturbed()?;
    }
    if args.default_starts {
        eprintln!(
            "from the task's default starts (walk.init_noise and walk.reset at their defaults)"
        );
        loaded = loaded.default_starts()?;
    }
    if let Some(frame) = &args.orientation_frame {
        let mut walk = loaded.config.walk.clone();
        walk.orientation_frame = match frame.as_str() {
            "gravity" => OrientationFrame::Gravity,
            _ => OrientationFrame::Ground,
        };
        loaded = loaded.with_walk(walk)?;
    }
    if !perturb.is_empty() {
        let mut walk = loaded.config.walk.clone();
        for d in &perturb {
            d.apply(&mut walk);
        }
        eprintln!(
            "under {}",
            perturb
                .iter()
                .map(|d| {
                    let (v, unit) = d.magnitude();
                    format!("{} {v} {unit}", d.name())
                })
                .collect::<Vec<_>>()
                .join(", ")
        );
        loaded = loaded.with_walk(walk)?;
    }
    crate::signals::install();
    let stop = || crate::signals::requested().is_some();
    let options = EvalOptions {
        traces: args.traces,
        stop: Some(&stop),
    };
    let mut report = evaluate_with(
        &loaded,
        args.seed,
        args.episodes,
        args.record.as_deref(),
        &options,
    )?;
    report.perturb = perturb;
    report.undisturbed = args.undisturbed;
    report.default_starts = args.default_starts;
    if args.robustness {
        eprintln!(
            "robustness card: {} disturbances × {} episodes",
            standard_set().len(),
            args.episodes
        );
        let rows = card(
            &loaded,
            args.seed,
            args.episodes,
            &standard_set(),
            Some(&stop),
        )?;
        let goal = goal_rows(&rows);
        println!("{}\n{}\n", card_markdown(&rows), goal_markdown(&goal));
        report.robustness = Some(rows);
        report.robustness_goal = Some(goal);
    }
    if report.episodes.len() < report.requested {
        eprintln!(
            "stopped: {} of {} episodes evaluated; the report holds those",
            report.episodes.len(),
            report.requested
        );
    }
    let out = args.out.clone().unwrap_or_else(|| eval_path(&loaded));
    write_json_atomic(&out, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", render_table(&report));
    }
    eprintln!("wrote {}", out.display());
    if let Some(dir) = &args.record {
        eprintln!(
            "recorded {} episode(s) to {}/episode-NNN.mcap",
            report.episodes.len(),
            dir.display()
        );
    }
    Ok(())
}

/// Which policy `loaded` is, in words: the kept policy `RUN/best/` (with the row and steps
/// that produced it and how it was chosen), or a checkpoint.
pub fn which_policy(loaded: &LoadedRun) -> String {
    let dir = loaded.checkpoint.display();
    let info = std::fs::read_to_string(loaded.checkpoint.join(BEST_INFO))
        .ok()
        .and_then(|t| serde_json::from_str::<BestInfo>(&t).ok());
    match info {
        Some(b) => {
            let how = match &b.check {
                Some(c) => format!("chosen by the walking check: {}", c.describe()),
                None => format!("chosen by its training fitness {:.1}", b.fitness),
            };
            let other = if loaded.run != loaded.checkpoint {
                format!(
                    "; `--last` for the last checkpoint of {}",
                    loaded.run.display()
                )
            } else {
                String::new()
            };
            let unit = if loaded.config.agent.is_hybrid() {
                "generation"
            } else {
                "episode"
            };
            let what = if loaded.checkpoint.file_name()
                == Some(std::ffi::OsStr::new(esrl_run::checkpoint::FIRST_WALK))
            {
                "the first walk at any speed"
            } else {
                "the kept policy"
            };
            let mean = if b.mean {
                " (the ES mean θ after it)"
            } else {
                ""
            };
            if b.start {
                return format!(
                    "{dir}: the kept policy is the one the run started from (`init`): none it \
                     trained ranked above it, {how}{other}"
                );
            }
            format!(
                "{dir}: {what} of {unit} {}{mean} ({} env steps), {how}{other}",
                b.generation, b.env_steps
            )
        }
        None => format!("{dir}: the policy of this checkpoint"),
    }
}

fn opt_number(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), format_number)
}

/// Pads each column to its widest cell (right-aligned, first column left-aligned).
fn text_table(header: &[String], rows: &[Vec<String>]) -> String {
    let widths: Vec<usize> = (0..header.len())
        .map(|j| {
            rows.iter()
                .map(|r| r[j].chars().count())
                .chain([header[j].chars().count()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[String]| {
        let parts: Vec<String> = cells
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(j, (c, &w))| {
                let pad = " ".repeat(w.saturating_sub(c.chars().count()));
                if j == 0 {
                    format!("{c}{pad}")
                } else {
                    format!("{pad}{c}")
                }
            })
            .collect();
        parts.join("  ").trim_end().to_string() + "\n"
    };
    let mut out = line(header);
    out.push_str(&line(
        &widths.iter().map(|&w| "-".repeat(w)).collect::<Vec<_>>(),
    ));
    for r in rows {
        out.push_str(&line(r));
    }
    out
}

fn percent(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{:.1} %", 100.0 * v))
}

/// The gait-cycle table of `esrl eval`: one row per episode and the mean (empty without
/// contact data).
fn cycle_table(report: &EvalReport) -> String {
    let cycles: Vec<(String, &GaitCycle)> = report
        .episodes
        .iter()
        .enumerate()
        .filter_map(|(k, e)| Some((k.to_string(), e.gait.as_ref()?.cycle.as_ref()?)))
        .chain(
            report
                .mean
                .gait
                .as_ref()
                .and_then(|g| g.cycle.as_ref())
                .filter(|_| report.episodes.len() > 1)
                .map(|c| ("mean".to_string(), c)),
        )
        .collect();
    if cycles.is_empty() {
        return String::new();
    }
    let header: Vec<String> = [
        "episode",
        "gait",
        "touchdowns L/R",
        "alternation",
        "double sup.",
        "single sup.",
        "flight",
        "cadence (1/min)",
        "step (m)",
        "step SD (m)",
        "stride CV",
    ]
    .map(String::from)
    .to_vec();
    let rows: Vec<Vec<String>> = cycles
        .iter()
        .map(|(label, c)| {
            let gait = if label == "mean" {
                gait_classes_text(&c.gait_classes)
            } else {
                c.gait_class.to_string()
            };
            vec![
                label.clone(),
                gait,
                format!("{:.0}/{:.0}", c.touchdowns[0], c.touchdowns[1]),
                opt_number(c.alternation),
                percent(Some(c.double_support)),
                percent(Some(c.single_support)),
                percent(Some(c.flight)),
                format!("{:.1}", c.cadence),
                opt_number(c.step_length_mean),
                opt_number(c.step_length_sd),
                opt_number(c.stride_time_cv),
            ]
        })
        .collect();
    format!(
        "\ngait cycle (contact above {} N; classes and thresholds: esrl_metrics::GaitThresholds)\n{}",
        cycles[0].1.contact_force,
        text_table(&header, &rows)
    )
}

/// The human-readable report of `esrl eval`.
pub fn render_table(report: &EvalReport) -> String {
    let mut out = format!(
        "{} ({}, {}) — checkpoint {}\n",
        report.run,
        report.agent,
        report.env.name(),
        report.checkpoint
    );
    let walk = report.env == EnvKind::Walk;
    let mut header: Vec<String> = ["episode", "seed", "return", "steps", "Q0"]
        .map(String::from)
        .to_vec();
    if walk {
        let track = report
            .track_length
            .map_or_else(|| "track".into(), |l| format!("{l} m time (s)"));
        header.extend(
            [
                &track,
                "fwd v (m/s)",
                "|lat| (m)",
                "vert (m)",
                "|vert| (m)",
                "|τ| (N·m)",
                "|P| (W)",
                "knee asym",
                "dist (m)",
                "fell",
            ]
            .map(String::from),
        );
    }
    let gait_cells = |g: Option<&GaitMetrics>| -> Vec<String> {
        match g {
            Some(g) => vec![
                opt_number(g.track_time),
                format_number(g.mean_forward_velocity),
                format_number(g.mean_abs_lateral),
                format_number(g.mean_vertical),
                format_number(g.mean_abs_vertical),
                format_number(g.mean_abs_torque_overall),
                format_number(g.mean_abs_power_overall),
                format_number(g.knee_torque_asymmetry),
                format_number(g.distance),
                if g.fell { "yes" } else { "no" }.into(),
            ],
            None => vec!["-".into(); 10],
        }
    };
    let mut rows: Vec<Vec<String>> = report
        .episodes
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let mut r = vec![
                k.to_string(),
                e.seed.to_string(),
                format_number(e.ret),
                e.length.to_string(),
                opt_number(e.q0),
            ];
            if walk {
                r.extend(gait_cells(e.gait.as_ref()));
            }
            r
        })
        .collect();
    if report.episodes.len() > 1 {
        let m = &report.mean;
        let ret = match m.return_sd {
            Some(sd) => format!("{} ± {}", format_number(m.ret), format_number(sd)),
            None => format_number(m.ret),
        };
        let mut r = vec![
            "mean".into(),
            String::new(),
            ret,
            format!("{:.1}", m.length),
            opt_number(m.q0),
        ];
        if walk {
            let mut cells = gait_cells(m.gait.as_ref());
            if let Some(last) = cells.last_mut() {
                *last = format!("{}/{}", m.falls, m.episodes);
            }
            r.extend(cells);
        }
        rows.push(r);
    }
    out.push_str(&text_table(&header, &rows));
    if walk {
        out.push_str(&cycle_table(report));
    }
    if let Some(g) = &report.mean.gait {
        out.push('\n');
        let header: Vec<String> = [
            "actuator",
            "mean |τ| (N·m)",
            "mean |P| (W)",
            "p5 (°)",
            "p95 (°)",
            "ROM (°)",
            "at limit",
        ]
        .map(String::from)
        .to_vec();
        let rows: Vec<Vec<String>> = g
            .actuator_names
            .iter()
            .enumerate()
            .map(|(j, n)| {
                let joint = g.joints.iter().find(|m| &m.name == n);
                let deg = |f: fn(&JointMotion) -> f64| {
                    joint.map_or_else(|| "-".into(), |m| format!("{:.1}", f(m).to_degrees()))
                };
                vec![
                    n.clone(),
                    opt_number(g.mean_abs_torque.get(j).copied()),
                    opt_number(g.mean_abs_power.get(j).copied()),
                    deg(|m| m.p5),
                    deg(|m| m.p95),
                    deg(|m| m.range),
                    percent(joint.and_then(|m| m.at_limit)),
                ]
            })
            .collect();
        out.push_str(&text_table(&header, &rows));
        if let Some(p) = &g.torso_pitch {
            out.push_str(&format!(
                "torso pitch (forward lean +): mean {:.1}°, p5 {:.1}°, p95 {:.1}°\n",
                p.mean.to_degrees(),
                p.p5.to_degrees(),
                p.p95.to_degrees()
            ));
        }
        if report.episodes.len() > 1 {
            out.push_str(&format!(
                "(means over {} episodes; {} reached the end of the track, {} fell)\n",
                report.mean.episodes, report.mean.finished, report.mean.falls
            ));
        }
    }
    out.push_str(&terms_line(report));
    out
}

/// The mean return split by reward term, largest share first, with each term per step:
/// `return by term (per step): forward 2408.1 (1.003), alive 600.0 (0.250), …`.
fn terms_line(report: &EvalReport) -> String {
    let m = &report.mean;
    if m.return_terms.is_empty() {
        return String::new();
    }
    let mut terms: Vec<(&String, f64)> = m.return_terms.iter().map(|(n, v)| (n, *v)).collect();
    terms.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    let per_step = |v: f64| v / m.length.max(1.0);
    let cells: Vec<String> = terms
        .iter()
        .map(|(n, v)| format!("{n} {} ({:.3})", format_number(*v), per_step(*v)))
        .collect();
    format!("return by term (per step): {}\n", cells.join(", "))
}
