//! Paper Table 1: per-agent mean ± sample SD across seeds, rendered as Markdown and CSV.
//!
//! Columns: the paper's (nAUC, AUC, Final-50, Best-Win-50, Episodes-to-Target, track time)
//! followed by the gait metrics of SPEC §6, the gait cycle (the gait classes of all evaluated
//! episodes, double support, flight, alternation, cadence, step length, stride-time CV, the
//! share of time the actuated joints spend at a limit) and the mean Q0. Per joint, the range of
//! motion and time at a limit are in [`joint_markdown`]. Quantities that only some seeds
//! have (Episodes-to-Target when a seed never reaches its target, track time when a rollout
//! does not finish, gait metrics of seeds without an evaluation) are aggregated over the seeds
//! that have them, and the cell says how many: `454.50 ± 40.31 (2/3)`; no seed at all gives
//! `-` (the paper's mark for "did not finish"). One value has no SD and is shown alone.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::curve::CurveSummary;
use crate::cycle::{GaitClass, GaitCycle};
use crate::error::{MetricsError, Result};
use crate::gait::GaitMetrics;
use crate::stats::{mean_sd, MeanSd};

/// What one seed of one agent contributed to the table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedResult {
    /// The run's learning-curve summary (computed against the method's target).
    pub summary: CurveSummary,
    /// The evaluation rollout's gait metrics, if the seed was evaluated.
    pub gait: Option<GaitMetrics>,
    /// Mean over episodes of Q0 (paper Fig. 5b), if the agent has a critic.
    pub q0_mean: Option<f64>,
}

impl From<(CurveSummary, Option<GaitMetrics>)> for SeedResult {
    fn from((summary, gait): (CurveSummary, Option<GaitMetrics>)) -> Self {
        Self {
            summary,
            gait,
            q0_mean: None,
        }
    }
}

/// All seeds of one agent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentRuns {
    /// Agent name as shown in the table (e.g. `es-sac`).
    pub agent: String,
    /// One entry per seed.
    pub seeds: Vec<SeedResult>,
}

/// One table cell: mean ± SD over the seeds that have the quantity.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// Statistics over the seeds that have a value; `None` if no seed has one.
    pub stat: Option<MeanSd>,
    /// Number of seeds of the agent (so `stat.n < seeds` means some lacked a value).
    pub seeds: usize,
}

impl Cell {
    /// Aggregates optional per-seed values; `what` names the column in errors (NaN, inf).
    pub fn from_values(values: &[Option<f64>], what: &str) -> Result<Self> {
        let present: Vec<f64> = values.iter().flatten().copied().collect();
        let stat = if present.is_empty() {
            None
        } else {
            Some(mean_sd(&present).map_err(|e| {
                match e {
                    MetricsError::NonFinite { value, .. } => MetricsError::NonFinite {
                        what: what.into(),
                        index: values
                            .iter()
                            .position(|v| v.is_some_and(|v| !v.is_finite()))
                            .unwrap_or(0),
                        value,
                    },
                    other => other,
                }
            })?)
        };
        Ok(Self {
            stat,
            seeds: values.len(),
        })
    }

    /// Markdown text: `m ± s`, `m` for one value, `-` for none, `(k/n)` appended when only k of
    /// n seeds have a value.
    pub fn to_markdown(&self) -> String {
        let Some(s) = self.stat else {
            return "-".into();
        };
        let mut text = match s.sd {
            Some(sd) => {
                let scale = s.mean.abs().max(sd.abs());
                format!(
                    "{} ± {}",
                    format_scaled(s.mean, scale),
                    format_scaled(sd, scale)
                )
            }
            None => format_number(s.mean),
        };
        if s.n < self.seeds {
            text.push_str(&format!(" ({}/{})", s.n, self.seeds));
        }
        text
    }
}

/// Human-readable number: 2 decimals from 1 to 1e5, 4 decimals below 1, scientific
/// (3 decimals) below 1e-3 and from 1e5 up; `0.00` for zero. In a `mean ± SD` cell both
/// numbers use the style of the larger magnitude of the two, so they line up.
pub fn format_number(x: f64) -> String {
    format_scaled(x, x.abs())
}

/// Formats `x` in the style that [`format_number`] picks for a number of magnitude `scale`.
fn format_scaled(x: f64, scale: f64) -> String {
    if scale == 0.0 {
        "0.00".into()
    } else if !(1e-3..1e5).contains(&scale) {
        format!("{x:.3e}")
    } else if scale < 1.0 {
        format!("{x:.4}")
    } else {
        format!("{x:.2}")
    }
}

/// One agent's row of Table 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Table1Row {
    /// Agent name.
    pub agent: String,
    /// Number of seeds.
    pub seeds: usize,
    /// nAUC.
    pub nauc: Cell,
    /// AUC.
    pub auc: Cell,
    /// Final-50.
    pub final_50: Cell,
    /// Best-Win-50.
    pub best_win_50: Cell,
    /// Episodes-to-Target over the seeds that reached the target.
    pub episodes_to_target: Cell,
    /// Track length of the evaluations (m), from the first seed evaluated.
    pub track_length: Option<f64>,
    /// Track time over the evaluated seeds that finished.
    pub track_time: Cell,
    /// Mean forward velocity.
    pub mean_forward_velocity: Cell,
    /// Mean |lateral|.
    pub mean_abs_lateral: Cell,
    /// Mean vertical deviation.
    pub mean_vertical: Cell,
    /// Mean |vertical| deviation.
    pub mean_abs_vertical: Cell,
    /// Mean |torque| over all actuators.
    pub mean_abs_torque: Cell,
    /// Mean |power| over all actuators.
    pub mean_abs_power: Cell,
    /// Knee torque asymmetry.
    pub knee_torque_asymmetry: Cell,
    /// Distance walked.
    pub distance: Cell,
    /// Evaluated seeds whose rollout fell.
    pub falls: usize,
    /// Evaluated seeds (seeds with gait metrics).
    pub gait_runs: usize,
    /// Mean Q0.
    pub q0_mean: Cell,
    /// Actuator names of the per-actuator cells (empty without gait metrics).
    pub actuator_names: Vec<String>,
    /// Mean |torque| per actuator.
    pub mean_abs_torque_per_actuator: Vec<Cell>,
    /// Mean |power| per actuator (paper Fig. 5d).
    pub mean_abs_power_per_actuator: Vec<Cell>,
    /// Evaluated episodes per gait class, over all seeds.
    #[serde(default)]
    pub gait_classes: BTreeMap<GaitClass, usize>,
    /// Fraction of time in double support.
    #[serde(default)]
    pub double_support: Cell,
    /// Fraction of time in single support.
    #[serde(default)]
    pub single_support: Cell,
    /// Fraction of time in flight.
    #[serde(default)]
    pub flight: Cell,
    /// Alternation of the touchdowns.
    #[serde(default)]
    pub alternation: Cell,
    /// Cadence, steps/min.
    #[serde(default)]
    pub cadence: Cell,
    /// Mean step length, m.
    #[serde(default)]
    pub step_length: Cell,
    /// Stride-time variability (SD / mean).
    #[serde(default)]
    pub stride_time_cv: Cell,
    /// Share of time at a limit, mean over the actuated joints that have limits.
    #[serde(default)]
    pub time_at_limit: Cell,
    /// Joint names of the per-joint cells (empty without joint angles).
    #[serde(default)]
    pub joint_names: Vec<String>,
    /// Range of motion (5th–95th percentile) per joint, rad.
    #[serde(default)]
    pub joint_range: Vec<Cell>,
    /// Share of time at a limit per joint.
    #[serde(default)]
    pub joint_at_limit: Vec<Cell>,
}

/// Aggregates each agent's seeds into a [`Table1Row`] (rows in input order).
///
/// Errors: an agent with no seeds, NaN/inf in any value, or seeds whose gait metrics list
/// different actuators.
pub fn table1(agents: &[AgentRuns]) -> Result<Vec<Table1Row>> {
    agents.iter().map(agent_row).collect()
}

fn agent_row(runs: &AgentRuns) -> Result<Table1Row> {
    let agent = &runs.agent;
    if runs.seeds.is_empty() {
        return Err(MetricsError::Empty {
            what: format!("agent `{agent}`: seeds"),
        });
    }
    let col = |name: &str, f: &dyn Fn(&SeedResult) -> Option<f64>| {
        let values: Vec<Option<f64>> = runs.seeds.iter().map(f).collect();
        Cell::from_values(&values, &format!("agent `{agent}`: {name}"))
    };
    let gait_col = |name: &str, f: &dyn Fn(&GaitMetrics) -> Option<f64>| {
        col(name, &|s: &SeedResult| s.gait.as_ref().and_then(f))
    };
    let gaits: Vec<&GaitMetrics> = runs.seeds.iter().filter_map(|s| s.gait.as_ref()).collect();
    let actuator_names = gaits
        .first()
        .map(|g| g.actuator_names.clone())
        .unwrap_or_default();
    if let Some(g) = gaits.iter().find(|g| g.actuator_names != actuator_names) {
        return Err(MetricsError::InvalidParameter {
            what: format!("agent `{agent}`: actuator_names"),
            value: format!("{:?}", g.actuator_names),
            why: format!("every seed must use the same actuators as the first, {actuator_names:?}"),
        });
    }
    let cycle_col = |name: &str, f: &dyn Fn(&GaitCycle) -> Option<f64>| {
        gait_col(name, &|g: &GaitMetrics| g.cycle.as_ref().and_then(f))
    };
    let mut gait_classes = BTreeMap::new();
    for c in gaits.iter().filter_map(|g| g.cycle.as_ref()) {
        for (&class, &n) in &c.gait_classes {
            *gait_classes.entry(class).or_insert(0) += n;
        }
    }
    let joint_names: Vec<String> = gaits
        .iter()
        .find(|g| !g.joints.is_empty())
        .map(|g| g.joints.iter().map(|j| j.name.clone()).collect())
        .unwrap_or_default();
    let per_joint = |name: &str, f: &dyn Fn(&crate::motion::JointMotion) -> Option<f64>| {
        joint_names
            .iter()
            .map(|joint| {
                gait_col(&format!("{name}[{joint}]"), &|g| {
                    g.joints.iter().find(|j| &j.name == joint).and_then(f)
                })
            })
            .collect::<Result<Vec<Cell>>>()
    };
    let per_actuator = |name: &str, f: &dyn Fn(&GaitMetrics) -> &Vec<f64>| {
        (0..actuator_names.len())
            .map(|j| {
                gait_col(&format!("{name}[{}]", actuator_names[j]), &|g| {
                    f(g).get(j).copied()
                })
            })
            .collect::<Result<Vec<Cell>>>()
    };
    Ok(Table1Row {
        agent: agent.clone(),
        seeds: runs.seeds.len(),
        nauc: col("nauc", &|s| Some(s.summary.nauc))?,
        auc: col("auc", &|s| Some(s.summary.auc))?,
        final_50: col("final_50", &|s| Some(s.summary.final_50))?,
        best_win_50: col("best_win_50", &|s| Some(s.summary.best_win_50))?,
        episodes_to_target: col("episodes_to_target", &|s| {
            s.summary.episodes_to_target.map(|e| e as f64)
        })?,
        track_length: gaits.first().map(|g| g.track_length),
        track_time: gait_col("track_time", &|g| g.track_time)?,
        mean_forward_velocity: gait_col("mean_forward_velocity", &|g| {
            Some(g.mean_forward_velocity)
        })?,
        mean_abs_lateral: gait_col("mean_abs_lateral", &|g| Some(g.mean_abs_lateral))?,
        mean_vertical: gait_col("mean_vertical", &|g| Some(g.mean_vertical))?,
        mean_abs_vertical: gait_col("mean_abs_vertical", &|g| Some(g.mean_abs_vertical))?,
        mean_abs_torque: gait_col("mean_abs_torque", &|g| Some(g.mean_abs_torque_overall))?,
        mean_abs_power: gait_col("mean_abs_power", &|g| Some(g.mean_abs_power_overall))?,
        knee_torque_asymmetry: gait_col("knee_torque_asymmetry", &|g| {
            Some(g.knee_torque_asymmetry)
        })?,
        distance: gait_col("distance", &|g| Some(g.distance))?,
        falls: gaits.iter().filter(|g| g.fell).count(),
        gait_runs: gaits.len(),
        q0_mean: col("q0_mean", &|s| s.q0_mean)?,
        mean_abs_torque_per_actuator: per_actuator("mean_abs_torque", &|g| &g.mean_abs_torque)?,
        mean_abs_power_per_actuator: per_actuator("mean_abs_power", &|g| &g.mean_abs_power)?,
        actuator_names,
        double_support: cycle_col("double_support", &|c| Some(c.double_support))?,
        single_support: cycle_col("single_support", &|c| Some(c.single_support))?,
        flight: cycle_col("flight", &|c| Some(c.flight))?,
        alternation: cycle_col("alternation", &|c| c.alternation)?,
        cadence: cycle_col("cadence", &|c| Some(c.cadence))?,
        step_length: cycle_col("step_length", &|c| c.step_length_mean)?,
        stride_time_cv: cycle_col("stride_time_cv", &|c| c.stride_time_cv)?,
        time_at_limit: gait_col("time_at_limit", &|g| {
            let shares: Vec<f64> = g.joints.iter().filter_map(|j| j.at_limit).collect();
            (!shares.is_empty()).then(|| shares.iter().sum::<f64>() / shares.len() as f64)
        })?,
        gait_classes,
        joint_range: per_joint("joint_range", &|j| Some(j.range))?,
        joint_at_limit: per_joint("joint_at_limit", &|j| j.at_limit)?,
        joint_names,
    })
}

/// `hop 7, fall 2`: episodes per class, most frequent first (ties in [`GaitClass::ALL`]
/// order, most locomotive first); `-` for none.
pub fn gait_classes_text(counts: &BTreeMap<GaitClass, usize>) -> String {
    let mut list: Vec<(GaitClass, usize)> = GaitClass::ALL
        .iter()
        .rev()
        .filter_map(|c| counts.get(c).filter(|&&n| n > 0).map(|&n| (*c, n)))
        .collect();
    if list.is_empty() {
        return "-".into();
    }
    list.sort_by_key(|&(_, n)| std::cmp::Reverse(n));
    list.iter()
        .map(|(c, n)| format!("{c} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The Markdown columns after `Agent` and `Seeds`, with how to read each cell from a row.
/// Renders one Markdown cell of a row.
type MarkdownCell = fn(&Table1Row) -> String;

/// Reads one metric cell of a row.
type CellOf = fn(&Table1Row) -> &Cell;

fn markdown_columns(rows: &[Table1Row]) -> Vec<(String, MarkdownCell)> {
    let track = match rows.iter().find_map(|r| r.track_length) {
        Some(l) => format!("{} m Track Time (s)", trim_number(l)),
        None => "Track Time (s)".into(),
    };
    vec![
        ("nAUC".into(), |r| r.nauc.to_markdown()),
        ("AUC".into(), |r| r.auc.to_markdown()),
        ("Final-50".into(), |r| r.final_50.to_markdown()),
        ("Best-Win-50".into(), |r| r.best_win_50.to_markdown()),
        ("Episodes-to-Target".into(), |r| {
            r.episodes_to_target.to_markdown()
        }),
        (track, |r| r.track_time.to_markdown()),
        ("Fwd Velocity (m/s)".into(), |r| {
            r.mean_forward_velocity.to_markdown()
        }),
        ("Mean \\|Lateral\\| (m)".into(), |r| {
            r.mean_abs_lateral.to_markdown()
        }),
        ("Mean Vertical (m)".into(), |r| {
            r.mean_vertical.to_markdown()
        }),
        ("Mean \\|Vertical\\| (m)".into(), |r| {
            r.mean_abs_vertical.to_markdown()
        }),
        ("Mean \\|Torque\\| (N·m)".into(), |r| {
            r.mean_abs_torque.to_markdown()
        }),
        ("Mean \\|Power\\| (W)".into(), |r| {
            r.mean_abs_power.to_markdown()
        }),
        ("Knee Asymmetry".into(), |r| {
            r.knee_torque_asymmetry.to_markdown()
        }),
        ("Distance (m)".into(), |r| r.distance.to_markdown()),
        ("Falls".into(), |r| {
            if r.gait_runs == 0 {
                "-".into()
            } else {
                format!("{}/{}", r.falls, r.gait_runs)
            }
        }),
        ("Gait (episodes)".into(), |r| {
            gait_classes_text(&r.gait_classes)
        }),
        ("Double Support".into(), |r| r.double_support.to_markdown()),
        ("Flight".into(), |r| r.flight.to_markdown()),
        ("Alternation".into(), |r| r.alternation.to_markdown()),
        ("Cadence (steps/min)".into(), |r| r.cadence.to_markdown()),
        ("Step Length (m)".into(), |r| r.step_length.to_markdown()),
        ("Stride CV".into(), |r| r.stride_time_cv.to_markdown()),
        ("At Limit".into(), |r| r.time_at_limit.to_markdown()),
        ("Q0".into(), |r| r.q0_mean.to_markdown()),
    ]
}

/// `50` for 50.0, `42.5` for 42.5.
fn trim_number(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}

fn markdown_escape(text: &str) -> String {
    text.replace('|', "\\|")
}

/// Renders Table 1 as a GitHub-flavoured Markdown table (one line per agent, `\n` endings).
pub fn table1_markdown(rows: &[Table1Row]) -> String {
    let columns = markdown_columns(rows);
    let mut out = String::from("| Agent | Seeds |");
    for (name, _) in &columns {
        out.push_str(&format!(" {name} |"));
    }
    out.push_str("\n|---|---:|");
    out.push_str(&"---:|".repeat(columns.len()));
    out.push('\n');
    for row in rows {
        out.push_str(&format!(
            "| {} | {} |",
            markdown_escape(&row.agent),
            row.seeds
        ));
        for (_, cell) in &columns {
            out.push_str(&format!(" {} |", cell(row)));
        }
        out.push('\n');
    }
    out
}

/// Renders mean |torque| and mean |power| per actuator (paper Fig. 5d) as a Markdown table,
/// one line per agent; actuators are those of the first row that has any.
pub fn actuator_markdown(rows: &[Table1Row]) -> String {
    let names = rows
        .iter()
        .find(|r| !r.actuator_names.is_empty())
        .map(|r| r.actuator_names.clone())
        .unwrap_or_default();
    let mut out = String::from("| Agent |");
    for n in &names {
        out.push_str(&format!(" {} \\|τ\\| (N·m) |", markdown_escape(n)));
    }
    for n in &names {
        out.push_str(&format!(" {} \\|P\\| (W) |", markdown_escape(n)));
    }
    out.push_str("\n|---|");
    out.push_str(&"---:|".repeat(2 * names.len()));
    out.push('\n');
    for row in rows {
        out.push_str(&format!("| {} |", markdown_escape(&row.agent)));
        for cells in [
            &row.mean_abs_torque_per_actuator,
            &row.mean_abs_power_per_actuator,
        ] {
            for name in &names {
                let cell = row
                    .actuator_names
                    .iter()
                    .position(|n| n == name)
                    .and_then(|j| cells.get(j))
                    .map_or_else(|| "-".into(), Cell::to_markdown);
                out.push_str(&format!(" {cell} |"));
            }
        }
        out.push('\n');
    }
    out
}

/// Renders the range of motion (5th–95th percentile, degrees) and the share of time at a
/// limit of each actuated joint as a Markdown table, one line per agent; joints are those of
/// the first row that has any.
pub fn joint_markdown(rows: &[Table1Row]) -> String {
    let names = rows
        .iter()
        .find(|r| !r.joint_names.is_empty())
        .map(|r| r.joint_names.clone())
        .unwrap_or_default();
    let mut out = String::from("| Agent |");
    for n in &names {
        out.push_str(&format!(" {} ROM (°) |", markdown_escape(n)));
    }
    for n in &names {
        out.push_str(&format!(" {} at limit |", markdown_escape(n)));
    }
    out.push_str("\n|---|");
    out.push_str(&"---:|".repeat(2 * names.len()));
    out.push('\n');
    let degrees = |c: &Cell| Cell {
        stat: c.stat.map(|s| MeanSd {
            mean: s.mean.to_degrees(),
            sd: s.sd.map(f64::to_degrees),
            n: s.n,
        }),
        seeds: c.seeds,
    };
    for row in rows {
        out.push_str(&format!("| {} |", markdown_escape(&row.agent)));
        for (cells, deg) in [(&row.joint_range, true), (&row.joint_at_limit, false)] {
            for name in &names {
                let cell = row
                    .joint_names
                    .iter()
                    .position(|n| n == name)
                    .and_then(|j| cells.get(j))
                    .map_or_else(
                        || "-".into(),
                        |c| {
                            if deg {
                                degrees(c).to_markdown()
                            } else {
                                c.to_markdown()
                            }
                        },
                    );
                out.push_str(&format!(" {cell} |"));
            }
        }
        out.push('\n');
    }
    out
}

/// The CSV metric keys, in column order, with how to read each cell from a row.
const CSV_CELLS: &[(&str, CellOf)] = &[
    ("nauc", |r| &r.nauc),
    ("auc", |r| &r.auc),
    ("final_50", |r| &r.final_50),
    ("best_win_50", |r| &r.best_win_50),
    ("episodes_to_target", |r| &r.episodes_to_target),
    ("track_time", |r| &r.track_time),
    ("mean_forward_velocity", |r| &r.mean_forward_velocity),
    ("mean_abs_lateral", |r| &r.mean_abs_lateral),
    ("mean_vertical", |r| &r.mean_vertical),
    ("mean_abs_vertical", |r| &r.mean_abs_vertical),
    ("mean_abs_torque", |r| &r.mean_abs_torque),
    ("mean_abs_power", |r| &r.mean_abs_power),
    ("knee_torque_asymmetry", |r| &r.knee_torque_asymmetry),
    ("distance", |r| &r.distance),
    ("q0_mean", |r| &r.q0_mean),
    ("double_support", |r| &r.double_support),
    ("single_support", |r| &r.single_support),
    ("flight", |r| &r.flight),
    ("alternation", |r| &r.alternation),
    ("cadence", |r| &r.cadence),
    ("step_length", |r| &r.step_length),
    ("stride_time_cv", |r| &r.stride_time_cv),
    ("time_at_limit", |r| &r.time_at_limit),
];

fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// Renders Table 1 as CSV for machines: `agent,seeds`, then `<key>_mean,<key>_sd,<key>_n` for
/// each metric (keys as in [`Table1Row`]; empty when undefined; full precision), then
/// `track_length,falls,gait_runs,gait_classes` (`gait_classes` as `hop:7;fall:2`, most
/// frequent first). RFC 4180 quoting, `\n` line endings.
pub fn table1_csv(rows: &[Table1Row]) -> String {
    let mut header = vec!["agent".to_string(), "seeds".to_string()];
    for (key, _) in CSV_CELLS {
        for suffix in ["mean", "sd", "n"] {
            header.push(format!("{key}_{suffix}"));
        }
    }
    header.extend(["track_length", "falls", "gait_runs", "gait_classes"].map(String::from));
    let mut out = header.join(",");
    out.push('\n');
    for row in rows {
        let mut fields = vec![csv_field(&row.agent), row.seeds.to_string()];
        for (_, cell) in CSV_CELLS {
            let stat = cell(row).stat;
            fields.push(stat.map_or_else(String::new, |s| s.mean.to_string()));
            fields.push(
                stat.and_then(|s| s.sd)
                    .map_or_else(String::new, |sd| sd.to_string()),
            );
            fields.push(stat.map_or(0, |s| s.n).to_string());
        }
        fields.push(row.track_length.map_or_else(String::new, |l| l.to_string()));
        fields.push(row.falls.to_string());
        fields.push(row.gait_runs.to_string());
        let classes = gait_classes_text(&row.gait_classes);
        fields.push(if classes == "-" {
            String::new()
        } else {
            classes.replace(", ", ";").replace(' ', ":")
        });
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}
