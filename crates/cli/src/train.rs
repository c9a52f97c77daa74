//! `esrl train`: builds the learner from the resolved config, runs it with a progress bar,
//! writes metrics row by row, checkpoints, and resumes.

use crate::args::{AgentKind, EnvKind, Preset, TrainArgs};
use crate::checkpoint::{self, CheckpointState, Learner};
use crate::config::TrainConfig;
use crate::run_dir::RunDir;
use crate::signals;
use anyhow::{bail, Context, Result};
use esrl_agents::{Agent, AgentError, Algo, Trainer};
use esrl_es::Hybrid;
use esrl_metrics::CurveSummary;
use esrl_sim::{Env, Pendulum, RobotModel, WalkEnv};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Builds one environment per call; shared by pool threads.
pub type EnvFactory = Arc<dyn Fn() -> Box<dyn Env> + Send + Sync>;

/// The environment factory of a config. Builds (and so validates) one environment up front,
/// so the factory itself cannot fail later.
pub fn env_factory(cfg: &TrainConfig) -> Result<EnvFactory> {
    match cfg.env {
        EnvKind::Pendulum => Ok(Arc::new(|| Box::new(Pendulum::new()) as Box<dyn Env>)),
        EnvKind::Walk => {
            let model = match &cfg.walk.urdf {
                Some(path) => Arc::new(RobotModel::from_urdf_path(path).map_err(|e| {
                    // The read error names the file itself; the others need it said.
                    match e {
                        esrl_sim::UrdfError::Io { .. } => anyhow::Error::new(e),
                        e => anyhow::Error::new(e).context(format!("in URDF {}", path.display())),
                    }
                })?),
                None => RobotModel::humanoid_shared().context("loading the embedded humanoid")?,
            };
            let walk = cfg.walk.clone();
            WalkEnv::from_model(model.clone(), walk.clone()).with_context(|| match &walk.urdf {
                Some(p) => format!("building the walking environment from {}", p.display()),
                None => "building the walking environment".into(),
            })?;
            Ok(Arc::new(move || {
                Box::new(
                    WalkEnv::from_model(model.clone(), walk.clone())
                        .expect("the same model and config built an environment before"),
                ) as Box<dyn Env>
            }))
        }
    }
}

/// The RL algorithm behind an agent kind.
pub fn algo_of(agent: AgentKind) -> Algo {
    match agent {
        AgentKind::EsSac | AgentKind::Sac => Algo::Sac,
        AgentKind::EsTd3 | AgentKind::Td3 => Algo::Td3,
        AgentKind::EsDdpg | AgentKind::Ddpg => Algo::Ddpg,
    }
}

/// A fresh learner for a config.
pub fn build_learner(cfg: &TrainConfig, make_env: &EnvFactory) -> Result<Learner> {
    let env = make_env();
    let agent = Agent::new(
        algo_of(cfg.agent),
        env.obs_dim(),
        env.act_dim(),
        &cfg.network,
        &cfg.rl,
        cfg.seed,
    )?;
    Ok(if cfg.agent.is_hybrid() {
        let mut hybrid = Hybrid::new(agent, cfg.es.clone(), cfg.inner_cycles, cfg.seed);
        hybrid.updates_per_step = cfg.updates_per_step;
        Learner::Hybrid(Box::new(hybrid))
    } else {
        Learner::Plain(Box::new(Trainer::new(agent, cfg.seed)))
    })
}

/// A plain agent's metrics row.
#[derive(Debug, Serialize)]
struct EpisodeRow {
    episode: usize,
    env_steps: u64,
    curve: f64,
    #[serde(rename = "return")]
    ret: f64,
    length: usize,
    terminated: bool,
    q0: f64,
    critic_loss: Option<f64>,
    actor_loss: Option<f64>,
    alpha: Option<f64>,
    updates: u64,
    wall_s: f64,
}

/// `summary.json`: the curve metrics of SPEC §6 plus what the run did.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// Agent name.
    pub agent: String,
    /// Environment.
    pub env: EnvKind,
    /// Run seed.
    pub seed: u64,
    /// Curve metrics (AUC, nAUC, Final-50, Best-Win-50, Episodes-to-Target).
    #[serde(flatten)]
    pub curve: CurveSummary,
    /// Mean Q₀ over the curve.
    pub q0_mean: Option<f64>,
    /// Generations or episodes done.
    pub length: usize,
    /// Environment steps taken.
    pub env_steps: u64,
    /// Best curve value.
    pub best: f64,
    /// Wall-clock seconds of training.
    pub wall_s: f64,
    /// Whether the configured budget was completed.
    pub finished: bool,
    /// ES-X: share of the generations whose individual 0 was a trained actor in which that
    /// actor was the best individual.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rl_trained_best_share: Option<f64>,
    /// ES-X: the same share for being an elite.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rl_trained_elite_share: Option<f64>,
    /// ES-X: share of the generations in which the RL actor was replaced.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rl_replaced_share: Option<f64>,
}

/// Where a run goes by default: `runs/<agent>-s<seed>` on the walking env (the same name
/// `esrl compare` gives its runs), `runs/<agent>-<env>-s<seed>` on another env.
pub fn default_out(cfg: &TrainConfig) -> PathBuf {
    let name = match cfg.env {
        EnvKind::Walk => format!("{}-s{}", cfg.agent.name(), cfg.seed),
        EnvKind::Pendulum => format!("{}-pendulum-s{}", cfg.agent.name(), cfg.seed),
    };
    PathBuf::from("runs").join(name)
}

/// How a training reports progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Display {
    /// A progress bar on a terminal; log lines every 10 s when stderr is not a terminal.
    Bar,
    /// Log lines every 10 s (`--no-progress`), flushed as they go, so a redirected log
    /// follows the run.
    Log,
    /// Nothing but errors (runs trained side by side by `esrl compare`).
    Quiet,
}

/// Runs `esrl train`. Returns the run folder, and whether the budget was completed (false
/// after a stop signal).
pub fn run(args: &TrainArgs) -> Result<(PathBuf, bool)> {
    let (mut cfg, root, resume) = match &args.resume {
        Some(dir) => {
            let path = dir.join(RunDir::CONFIG);
            if !path.exists() {
                bail!(
                    "{} is not a run folder (it has no {}); start a new run with --out",
                    dir.display(),
                    RunDir::CONFIG
                );
            }
            let cfg = TrainConfig::load(&path)?;
            if cfg.agent != args.agent {
                bail!(
                    "{} is a {} run, not {}",
                    dir.display(),
                    cfg.agent.name(),
                    args.agent.name()
                );
            }
            (cfg, dir.clone(), true)
        }
        None => {
            let cfg = TrainConfig::resolve(args.agent, &args.opts, args.seed)?;
            let root = args.out.clone().unwrap_or_else(|| default_out(&cfg));
            (cfg, root, false)
        }
    };
    if resume {
        // Budget and thread flags may change a resumed run; the stored config follows, so
        // `--config RUN/config.toml` keeps repeating the run as it now is.
        let before = cfg.clone();
        if let Some(g) = args.opts.generations {
            cfg.generations = g;
        }
        if let Some(e) = args.opts.episodes {
            cfg.episodes = e;
        }
        if let Some(s) = args.opts.steps {
            cfg.max_env_steps = Some(s);
        }
        if let Some(t) = args.opts.threads {
            cfg.threads = t;
        }
        cfg.validate()?;
        if cfg != before {
            crate::run_dir::write_atomic(&root.join(RunDir::CONFIG), cfg.to_toml()?.as_bytes())?;
        }
    }
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
    let preset = crate::args::preset_name(cfg.preset);
    let env = match cfg.env {
        EnvKind::Walk => "walk",
        EnvKind::Pendulum => "pendulum",
    };
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
    let typical = match (cfg.preset, cfg.agent.is_hybrid(), cfg.env) {
        (Preset::Paper, true, EnvKind::Walk) => {
            "\n  time:   the paper's budget: hours (5–8 h for ES-SAC on 2 cores, by its own ETA); \
             `--preset quick` shows learning in a few minutes"
        }
        (Preset::Walking, _, EnvKind::Walk) => {
            "\n  time:   4 million env steps: about 1.5 h for ES-SAC on one core (results/walking)"
        }
        _ => "",
    };
    format!(
        "esrl train {agent} · preset {preset} · env {env} · seed {seed}{action}\n  \
         budget: {budget}{steps}{typical}\n  \
         run:    {dir} (config.toml, metrics.csv, checkpoint/ every {every} rows)\n  \
         stop:   Ctrl-C or SIGTERM finishes the current {unit}, checkpoints and exits; \
         continue with `esrl train {agent} --resume {dir}`\n  \
         time:   an estimate follows once the first {unit}s are measured",
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

/// "1 h 05 min", "4 min 10 s", "12 s".
pub fn human_duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..=59 => format!("{s} s"),
        60..=3599 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, (s % 3600) / 60),
    }
}

/// Trains `cfg` into `root` (a new folder, or an existing one when `resume`). Returns
/// whether the budget was completed (false when a stop signal ended it early, after a
/// checkpoint).
pub fn train(cfg: &TrainConfig, root: &Path, resume: bool, display: Display) -> Result<bool> {
    let make_env = env_factory(cfg)?;
    {
        let env = make_env();
        cfg.check_memory(env.obs_dim(), env.act_dim(), env.max_episode_steps())?;
    }
    let mut learner = build_learner(cfg, &make_env)?;
    let mut state = CheckpointState::fresh(&learner);
    let mut run = match (resume, checkpoint::find(root)) {
        (true, Some(dir)) => {
            state = checkpoint::load_state(&dir)?;
            checkpoint::check_config(&dir, cfg)?;
            checkpoint::check_state(root, &dir, &state, cfg)?;
            checkpoint::restore(&dir, &mut learner, &state)?;
            let run = RunDir::resume(root, state.rows)?;
            if display != Display::Quiet {
                eprintln!(
                    "resuming {} from {} ({} rows, {} env steps)",
                    root.display(),
                    dir.display(),
                    state.rows,
                    state.env_steps
                );
            }
            run
        }
        (true, None) => {
            // Killed before its first checkpoint: nothing to lose but the rows of an
            // unfinished first stretch, so the run starts over in its own folder.
            eprintln!(
                "{} has no checkpoint yet (stopped before its first one): starting it over from \
                 the beginning with its config.toml",
                root.display()
            );
            checkpoint::remove_best(root)?;
            let run = RunDir::resume(root, 0)?;
            crate::run_dir::write_atomic(&root.join(RunDir::CONFIG), cfg.to_toml()?.as_bytes())?;
            run
        }
        (false, _) => RunDir::create(root, &cfg.to_toml()?)?,
    };
    if display != Display::Quiet {
        eprintln!("{}", banner(cfg, root, resume));
    }

    let threads = if cfg.threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        cfg.threads
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("starting the rollout thread pool")?;

    signals::install();

    let (total, unit) = if cfg.agent.is_hybrid() {
        (cfg.generations, "generation")
    } else {
        (cfg.episodes, "episode")
    };
    let bar = progress_bar(total, state.rows, display);
    let log = display != Display::Quiet && bar.is_hidden();
    let mut last_log = Instant::now();
    let started = Instant::now();
    let rows_at_start = state.rows;
    let wall0 = state.wall_s;
    let mut finished = false;
    let mut eta_told = false;

    if let Learner::Hybrid(h) = &mut learner {
        let mut env = make_env();
        h.warm_start(env.as_mut());
    }
    let steps_at_start = learner.trainer().env_steps;

    let mut diverged: Option<AgentError> = None;
    loop {
        let done = state.rows;
        let budget_spent = cfg
            .max_env_steps
            .is_some_and(|b| learner.trainer().env_steps >= b);
        if done >= total || budget_spent {
            finished = true;
            break;
        }
        if signals::requested().is_some() {
            break;
        }
        let (row, curve, q0, msg) = match &mut learner {
            Learner::Hybrid(h) => match h.step(make_env.as_ref(), &pool) {
                Ok(r) => {
                    let wall = wall0 + started.elapsed().as_secs_f64();
                    let msg = format!(
                        "gen {}: best {:.1}, RL actor {:.1}{}, σ {:.3}",
                        r.generation,
                        r.best_fitness,
                        r.rl_fitness,
                        if r.rl_replaced { " (replaced)" } else { "" },
                        r.sigma
                    );
                    let mut v = serde_json::to_value(&r)?;
                    if let Some(m) = v.as_object_mut() {
                        m.insert("wall_s".into(), serde_json::json!(wall));
                    }
                    (v, r.curve, r.q0, msg)
                }
                Err(e) => {
                    diverged = Some(e);
                    break;
                }
            },
            Learner::Plain(t) => {
                let mut env = make_env();
                match t.episode(env.as_mut()) {
                    Ok(r) => {
                        let wall = wall0 + started.elapsed().as_secs_f64();
                        let msg = format!(
                            "episode {}: return {:.1}, {} steps",
                            r.episode, r.ret, r.length
                        );
                        let row = EpisodeRow {
                            episode: r.episode,
                            env_steps: r.env_steps,
                            curve: r.ret,
                            ret: r.ret,
                            length: r.length,
                            terminated: r.terminated,
                            q0: r.q0,
                            critic_loss: r.critic_loss,
                            actor_loss: r.actor_loss,
                            alpha: r.alpha,
                            updates: r.updates,
                            wall_s: wall,
                        };
                        (serde_json::to_value(&row)?, r.ret, r.q0, msg)
                    }
                    Err(e) => {
                        diverged = Some(e);
                        break;
                    }
                }
            }
        };
        if !curve.is_finite() {
            diverged = Some(AgentError::NonFinite {
                what: "return",
                update: learner.trainer().agent.updates(),
            });
            break;
        }
        run.append(&row)?;
        let previous_best = state
            .curve
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        if let Learner::Hybrid(h) = &learner {
            if curve > previous_best {
                let info = checkpoint::BestInfo {
                    generation: h.generation - 1,
                    fitness: curve,
                    env_steps: h.trainer.env_steps,
                };
                checkpoint::save_best(root, h, &info)?;
            }
        }
        state.rows += 1;
        state.curve.push(curve);
        state.q0.push(q0);
        let best = previous_best.max(curve);
        bar.set_position(state.rows as u64);
        bar.set_message(format!("{msg} | best so far {best:.1}"));
        let elapsed = started.elapsed().as_secs_f64();
        let measured = state.rows - rows_at_start;
        if !eta_told && display != Display::Quiet && (measured >= 3 || elapsed > 30.0) {
            eta_told = true;
            let left = total.saturating_sub(state.rows);
            let pace = elapsed / measured as f64;
            let by_rows = pace * left as f64;
            let steps_now = learner.trainer().env_steps;
            // A step budget ends the run first when the steps left take less time than the
            // rows left, at the step rate measured so far.
            let by_steps = cfg.max_env_steps.and_then(|b| {
                let rate = steps_now.saturating_sub(steps_at_start) as f64 / elapsed;
                let steps_left = b.saturating_sub(steps_now);
                let secs = steps_left as f64 / rate;
                (rate > 0.0 && secs < by_rows).then_some((secs, steps_left, rate))
            });
            let text = match by_steps {
                Some((secs, steps_left, rate)) => format!(
                    "pace: {rate:.0} env steps/s over the first {measured} {unit}s: about {} \
                     for the {steps_left} env steps left of the step budget (episodes \
                     lengthen as the policy learns to stay up; the step rate varies less)",
                    human_duration(secs)
                ),
                None => format!(
                    "pace: {:.1} s per {unit} over the first {measured}: about {} for the \
                     {left} left (episodes lengthen as the policy learns to stay up, so \
                     likely more)",
                    pace,
                    human_duration(by_rows)
                ),
            };
            if bar.is_hidden() {
                eprintln!("{text}");
            } else {
                bar.println(text);
            }
        }
        if log && last_log.elapsed().as_secs_f64() > 10.0 {
            let steps = match cfg.max_env_steps {
                Some(b) => format!(" | {}/{b} env steps", learner.trainer().env_steps),
                None => String::new(),
            };
            eprintln!(
                "[{}/{}] {msg} | best so far {best:.1}{steps} | {}",
                state.rows,
                total,
                human_duration(wall0 + elapsed)
            );
            last_log = Instant::now();
        }
        write_summary(
            &run,
            cfg,
            &learner,
            &state,
            wall0 + started.elapsed().as_secs_f64(),
            false,
        )?;
        if state.rows % cfg.checkpoint_every == 0 {
            save_checkpoint(
                root,
                cfg,
                &learner,
                &mut state,
                wall0 + started.elapsed().as_secs_f64(),
            )?;
        }
    }
    bar.finish_and_clear();
    let wall = wall0 + started.elapsed().as_secs_f64();
    if let Some(e) = diverged {
        bail!(
            "training stopped at row {}: {e}. The last good checkpoint in {} is kept; \
             lower the learning rates or the gradient clip and resume or restart.",
            state.rows,
            root.join(RunDir::CHECKPOINT).display()
        );
    }
    save_checkpoint(root, cfg, &learner, &mut state, wall)?;
    write_summary(&run, cfg, &learner, &state, wall, finished)?;
    if display != Display::Quiet {
        if finished {
            eprintln!(
                "done: {} rows, {} env steps, {} → {}",
                state.rows,
                learner.trainer().env_steps,
                human_duration(wall),
                root.display()
            );
        } else {
            eprintln!(
                "stopped after {} rows; checkpoint written. Continue with: esrl train {} --resume {}",
                state.rows,
                cfg.agent.name(),
                root.display()
            );
        }
    }
    Ok(finished)
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

fn save_checkpoint(
    root: &Path,
    cfg: &TrainConfig,
    learner: &Learner,
    state: &mut CheckpointState,
    wall: f64,
) -> Result<()> {
    let t = learner.trainer();
    let (updates, rng) = t.agent.counters();
    state.episodes = t.episodes;
    state.env_steps = t.env_steps;
    state.trainer_rng = t.rng.clone();
    state.agent_updates = updates;
    state.agent_rng = rng;
    state.episode_open = t.buffer.episode_open();
    state.wall_s = wall;
    if let Learner::Hybrid(h) = learner {
        state.generations = h.generation;
        state.sigma = Some(h.strategy.sigma);
        state.es_generation = Some(h.strategy.generation);
        state.rl_trained = Some(h.rl_trained);
        state.loop_stats = Some(h.stats.clone());
    }
    checkpoint::save(root, cfg, learner, state)
}

fn write_summary(
    run: &RunDir,
    cfg: &TrainConfig,
    learner: &Learner,
    state: &CheckpointState,
    wall: f64,
    finished: bool,
) -> Result<()> {
    if state.curve.is_empty() {
        return Ok(());
    }
    let curve = CurveSummary::from_curve(&state.curve, None)?;
    let stats = match learner {
        Learner::Hybrid(h) => Some(&h.stats),
        Learner::Plain(_) => None,
    };
    let summary = Summary {
        rl_trained_best_share: stats.and_then(|s| s.trained_best_share()),
        rl_trained_elite_share: stats.and_then(|s| s.trained_elite_share()),
        rl_replaced_share: stats.and_then(|s| s.replaced_share()),
        agent: cfg.agent.name().into(),
        env: cfg.env,
        seed: cfg.seed,
        curve,
        q0_mean: esrl_metrics::nauc(&state.q0).ok(),
        length: state.curve.len(),
        env_steps: learner.trainer().env_steps,
        best: state
            .curve
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max),
        wall_s: wall,
        finished,
    };
    run.write_summary(&summary)
}
