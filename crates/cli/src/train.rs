//! `esrl train`: resolves the config, builds the learner, then loops over rows of the
//! training session (`esrl_run::Training`), printing the start banner, a progress bar or
//! log lines, the pace, and how to resume; stop signals end the loop at a row boundary.

use crate::args::{EnvKind, TrainArgs};
use crate::signals;
use anyhow::Result;
use esrl_run::human_duration;
use esrl_run::{build, Opening, Overrides, Session, TrainConfig, TrainRequest};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How a training reports progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Display {
    /// A progress bar on a terminal; log lines every 10 s when stderr is not a terminal.
    Bar,
    /// Log lines every 10 s (`--no-progress`), flushed as they go, so a redirected log
    /// follows the run.
    Log,
    /// One line per minute (and one after the first row), prefixed with the run folder's
    /// name, and nothing else: runs trained side by side by `esrl compare`, whose own lines
    /// say when each starts and finishes.
    Runs,
}

impl Display {
    /// Whether the banner, the pace estimate and the closing line are printed.
    fn verbose(self) -> bool {
        matches!(self, Display::Bar | Display::Log)
    }
}

/// How often `Display::Runs` prints a run's line, s.
const RUNS_LINE_EVERY_S: f64 = 60.0;

/// Runs `esrl train`. Returns the run folder, and whether the budget was completed (false
/// after a stop signal).
pub fn run(args: &TrainArgs) -> Result<(PathBuf, bool)> {
    let plan = esrl_run::plan(&TrainRequest {
        agent: args.agent,
        seed: args.seed,
        out: args.out.clone(),
        resume: args.resume.clone(),
        overrides: Overrides {
            init: args.init.clone(),
            ..args.opts.overrides()
        },
    })?;
    for note in &plan.notes {
        eprintln!("{note}");
    }
    let (cfg, root, resume) = (plan.cfg, plan.root, plan.resume);
    let display = if args.opts.no_progress {
        Display::Log
    } else {
        Display::Bar
    };
    let finished = train(&cfg, &root, resume, display)?;
    Ok((root, finished))
}

/// What a user should know before a run starts: what runs, how much, where, how to stop.
pub fn banner(cfg: &TrainConfig, root: &Path, resume: bool) -> String {
    let agent = cfg.agent.name();
    let budget = if cfg.agent.is_hybrid() {
        let updates = match cfg.updates_per_step {
            Some(r) => format!("{r} updates per env step"),
            None => format!("{} inner cycles per generation", cfg.inner_cycles),
        };
        format!(
            "{} generations × {} individuals × {} rollout(s), {updates}",
            cfg.generations, cfg.es.population, cfg.es.evaluations
        )
    } else {
        format!("{} episodes", cfg.episodes)
    };
    let steps = cfg
        .max_env_steps
        .map(|s| format!(", at most {s} env steps"))
        .unwrap_or_default();
    let typical = cfg.typical_time().map_or(String::new(), |t| {
        let changed = cfg.changed_from_preset();
        if changed.is_empty() {
            format!("\n  typical: {t} (the preset's whole budget)")
        } else {
            // Measured times are the preset's as it comes; a fine-tuning run or a changed
            // budget or task takes its own (its pace follows after the first generations).
            format!(
                "\n  typical: not measured for this run, which changes {}; the preset as it \
                 comes: {t}",
                changed.join(", ")
            )
        }
    });
    let restart = cfg.restart.as_ref().map_or(String::new(), |r| {
        if cfg.max_env_steps.is_some_and(|b| r.at_steps >= b) {
            // `walker-robust` moves the rule past its budget to keep training the loaded walk.
            return format!(
                "\n  restart: never in this run (the rule is judged at {} env steps, past the \
                 budget)",
                r.at_steps
            );
        }
        format!(
            "\n  restart: from seed + 1000 (at most {} time(s)) when no walk and no check past \
             {} m by {} env steps{}",
            r.max,
            r.min_distance,
            r.at_steps,
            match (r.whole_budget, cfg.max_env_steps) {
                (true, Some(b)) => format!("; the {b} env steps are the whole run's"),
                (false, Some(_)) => "; each attempt may take the env-step budget".into(),
                (_, None) => String::new(),
            }
        )
    });
    let init = cfg.init.as_ref().map_or(String::new(), |p| {
        // A trained run's σ has decayed toward σ_min; perturbations at a larger σ and one
        // sampled rollout each replace the loaded walk within a generation (results/fine-tune).
        let sigma = if cfg.agent.is_hybrid() && cfg.es.sigma > 1.5 * cfg.es.sigma_min {
            format!(
                "; the ES starts at σ = {}, a trained run's had decayed toward σ_min = {}: \
                 `es = {{ sigma = {} }}` keeps the loaded policy's neighbourhood",
                cfg.es.sigma, cfg.es.sigma_min, cfg.es.sigma_min
            )
        } else {
            String::new()
        };
        format!(
            "\n  init:   from the weights of {} (fine-tuning; RUN/init.json){sigma}",
            p.display()
        )
    });
    format!(
        "esrl train {agent} · preset {preset} · env {env} · seed {seed}{action}\n  \
         budget: {budget}{steps}{typical}{restart}{init}\n  \
         run:    {dir} (config.toml, metrics.csv, checkpoint/ every {every} rows)\n  \
         stop:   Ctrl-C or SIGTERM finishes the current {unit}, checkpoints and exits; \
         continue with `{esrl} train {agent} --resume {dir}`\n  \
         time:   an estimate follows once the first {unit}s are measured",
        esrl = esrl_run::command(),
        preset = cfg.preset.name(),
        env = cfg.env.name(),
        seed = cfg.seed,
        action = if resume { " · resuming" } else { "" },
        dir = root.display(),
        every = cfg.checkpoint_every,
        unit = if cfg.agent.is_hybrid() {
            "generation"
        } else {
            "episode"
        },
    )
}

/// Trains `cfg` into `root` (a new folder, or an existing one when `resume`). Returns
/// whether the budget was completed (false when a stop signal ended it early, after a
/// checkpoint).
pub fn train(cfg: &TrainConfig, root: &Path, resume: bool, display: Display) -> Result<bool> {
    let envs = build::envs(cfg.env, &cfg.walk)?;
    cfg.check_memory(envs.obs_dim, envs.act_dim, envs.max_episode_steps)?;
    let evaluator = build::local_evaluator(&envs);
    let (mut training, opening) = Session::open(cfg, root, &envs, evaluator, resume)?;
    if let Opening::Resumed {
        checkpoint,
        rows,
        env_steps,
    } = &opening
    {
        if display.verbose() {
            eprintln!(
                "resuming {} from {} ({rows} rows, {env_steps} env steps)",
                root.display(),
                checkpoint.display(),
            );
        }
    }
    if display.verbose() {
        eprintln!("{}", banner(cfg, root, resume));
    }
    signals::install();

    let total = training.total();
    let unit = training.unit();
    let bar = progress_bar(total, training.rows(), display);
    let log = display.verbose() && bar.is_hidden();
    let mut last_log = Instant::now();
    let mut rows_at_start = training.rows();
    let mut finished = false;
    loop {
        if training.done() {
            finished = true;
            break;
        }
        if signals::requested().is_some() {
            break;
        }
        let row = match training.step() {
            Ok(row) => row,
            Err(e) => {
                bar.finish_and_clear();
                return Err(e.into());
            }
        };
        if let (Some(restart), Some(rule)) = (&row.restarted, &cfg.restart) {
            // The new attempt counts its rows from the start.
            rows_at_start = 0;
            let text = restart.describe(rule, training.attempt().seed);
            if bar.is_hidden() {
                eprintln!("{text}");
            } else {
                bar.println(text);
            }
        }
        bar.set_position(row.rows as u64);
        bar.set_message(format!("{} | best so far {:.1}", row.summary, row.best));
        let measured = row.rows - rows_at_start;
        if let (Some(estimate), true) = (&row.estimate, display.verbose()) {
            let text = estimate.describe(unit);
            if bar.is_hidden() {
                eprintln!("{text}");
            } else {
                bar.println(text);
            }
        }
        if display == Display::Runs
            && (measured == 1 || last_log.elapsed().as_secs_f64() > RUNS_LINE_EVERY_S)
        {
            let name = root.file_name().map_or_else(
                || root.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let steps = training.budget_steps();
            let budget = cfg.max_env_steps.map_or(String::new(), |b| format!("/{b}"));
            eprintln!(
                "[{name}] {}/{total} {unit}s, {steps}{budget} env steps | best so far {:.1} \
                 | {}",
                row.rows,
                row.best,
                human_duration(training.wall_s())
            );
            last_log = Instant::now();
        }
        if log && last_log.elapsed().as_secs_f64() > 10.0 {
            let steps = match cfg.max_env_steps {
                Some(b) => format!(" | {}/{b} env steps", training.budget_steps()),
                None => String::new(),
            };
            eprintln!(
                "[{}/{}] {} | best so far {:.1}{steps} | {}",
                row.rows,
                total,
                row.summary,
                row.best,
                human_duration(training.wall_s())
            );
            last_log = Instant::now();
        }
    }
    bar.finish_and_clear();
    training.finish(finished)?;
    if display.verbose() {
        if finished {
            eprintln!(
                "done: {} {unit}s, {} env steps, {} → {}",
                training.rows(),
                training.env_steps(),
                human_duration(training.wall_s()),
                root.display()
            );
            eprint!("{}", closing(cfg, root, &training));
        } else {
            eprintln!(
                "stopped after {} {unit}s; checkpoint written. Continue with: {} train {} \
                 --resume {}",
                training.rows(),
                esrl_run::command(),
                cfg.agent.name(),
                root.display()
            );
        }
    }
    Ok(finished)
}

/// What a finished run hands over and what to run next: the kept policy and how it was
/// chosen, when the first walk appeared, and the commands that evaluate and show it.
fn closing(cfg: &TrainConfig, root: &Path, training: &Session) -> String {
    let esrl = esrl_run::command();
    let dir = root.display();
    let best = root.join(esrl_run::checkpoint::BEST);
    let mut out = String::new();
    let attempt = training.attempt();
    if !attempt.earlier.is_empty() {
        let (steps, wall) = attempt.spent();
        out += &format!(
            "  restarts: {} attempt(s) abandoned ({steps} env steps, {} of training, in \
             {dir}/restarts/); below is the attempt of seed {}, with its own steps and \
             times (summary.json's steps_to_walk and time_to_walk_s add the abandoned ones)\n",
            attempt.earlier.len(),
            human_duration(wall),
            attempt.seed
        );
    }
    match (training.kept_check(), best.is_dir()) {
        (Some(k), _) => {
            out += &format!(
                "  kept:   {dir}/best/ ({} {}{}, {} env steps): {}\n",
                training.unit(),
                k.row,
                if k.mean {
                    ", the ES mean θ after it"
                } else {
                    ""
                },
                k.env_steps,
                k.result.describe()
            );
            match training.first_walk() {
                Some(w) => {
                    out += &format!(
                        "  walk:   the first policy at the walking bar came at {} {} ({} env \
                         steps, {} of training); every check is in {dir}/checks.jsonl\n",
                        training.unit(),
                        w.row,
                        w.env_steps,
                        human_duration(w.wall_s)
                    );
                }
                None => {
                    out += &format!(
                        "  walk:   no policy met the walking bar (walk in most of {} starts, \
                         {:.0} % of them past the line); the checks are in \
                         {dir}/checks.jsonl\n",
                        cfg.check.as_ref().map_or(10, |c| c.starts),
                        100.0 * cfg.check.as_ref().map_or(0.8, |c| c.finish_share)
                    );
                }
            }
            if let Some(margins) = cfg.check.as_ref().and_then(|c| c.margins()) {
                out += &match training.first_any_walk() {
                    Some(w) => format!(
                        "  first:  {dir}/first-walk/, the first policy at the walking bar \
                         without {margins}, came at {} {} ({} env steps, {} of training); \
                         `{esrl} eval {dir}/first-walk --episodes 10` shows it\n",
                        training.unit(),
                        w.row,
                        w.env_steps,
                        human_duration(w.wall_s),
                    ),
                    None => {
                        format!("  first:  no policy met the walking bar even without {margins}\n")
                    }
                };
            }
        }
        (None, true) => {
            out +=
                &format!("  kept:   {dir}/best/, the policy with the highest training fitness\n");
        }
        (None, false) => {}
    }
    if cfg.env == EnvKind::Walk {
        out += &format!(
            "next:\n  {esrl} eval {dir} --episodes 10            # the kept policy from 10 starts, \
             gait metrics\n  {esrl} record {dir} --out walk.svg        # watch it in a browser \
             (walk.mcap for Foxglove)\n"
        );
    } else {
        out += &format!("next:\n  {esrl} eval {dir} --episodes 10\n");
    }
    out
}

fn progress_bar(total: usize, done: usize, display: Display) -> ProgressBar {
    if display != Display::Bar || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:30} {pos}/{len} [{elapsed_precise} < {eta_precise}] {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(done as u64);
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use esrl_run::restart::RestartConfig;
    use esrl_run::{AgentKind, EnvKind, Preset};

    #[test]
    fn a_restart_rule_past_the_budget_is_said_never_to_fire() {
        let mut cfg = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::Walking);
        cfg.max_env_steps = Some(1_500_000);
        let line = |cfg: &TrainConfig| {
            banner(cfg, Path::new("run"), false)
                .lines()
                .find(|l| l.trim_start().starts_with("restart:"))
                .map(str::to_owned)
        };
        cfg.restart = Some(RestartConfig {
            at_steps: 2_000_000,
            ..RestartConfig::default()
        });
        let past = line(&cfg).expect("a restart line");
        assert!(
            past.contains("never in this run") && past.contains("2000000"),
            "{past}"
        );
        cfg.restart = Some(RestartConfig::default());
        let within = line(&cfg).expect("a restart line");
        assert!(within.contains("by 1000000 env steps"), "{within}");
        cfg.restart = None;
        assert_eq!(line(&cfg), None);
    }
}
