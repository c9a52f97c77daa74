//! `esrl compare`: agents × seeds under one set of options, as a study. The command writes the
//! study file its options describe (one arm per agent, the options as each arm's settings) to
//! `DIR/study.toml`, runs it as `esrl study run` does (resumable, `--jobs` at a time) and
//! writes its report as `esrl study report` does: Table 1 with the gait columns, the
//! per-actuator and per-joint tables, the rate at the walking bar with its Wilson interval, the
//! IQM of the learning metrics with bootstrap intervals and the probability of improvement.
//!
//! ```text
//! DIR/
//!   study.toml              the study the options describe (`esrl study run` takes it too)
//!   runs/<agent>-s<seed>/   the run folders
//!   records/<agent>-s<seed>/ each run's record (module `study`)
//!   report.md, .csv, .json  the report
//! ```
//!
//! The same command again continues a stopped comparison; other options on the same `DIR` are
//! refused (the folder holds another study). Ctrl-C stops every training at its next
//! generation/episode boundary with a checkpoint, starts no other run and writes no report.

use crate::args::{AgentKind, CompareArgs, Until};
use anyhow::{bail, Context, Result};
use std::path::Path;

/// Parses `es-sac,sac,…`: every name must be an agent; repeats are dropped.
pub fn parse_agents(list: &str) -> Result<Vec<AgentKind>> {
    let valid = AgentKind::ALL.map(AgentKind::name).join(", ");
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let Some(agent) = AgentKind::parse(name) else {
            bail!("--agents: unknown agent `{name}`; valid agents are {valid}");
        };
        if !out.contains(&agent) {
            out.push(agent);
        }
    }
    if out.is_empty() {
        bail!("--agents `{list}` names no agent; valid agents are {valid}");
    }
    Ok(out)
}

/// The study file that `args` describe.
pub fn study_text(args: &CompareArgs) -> Result<String> {
    let agents = parse_agents(&args.agents)?;
    if args.seeds == 0 {
        bail!("--seeds 0: compare needs at least one seed per agent");
    }
    if args.eval_episodes == 0 {
        bail!("--eval-episodes 0: evaluate at least one episode per run");
    }
    let opts = &args.opts;
    let absolute = |p: &Path| {
        std::path::absolute(p)
            .with_context(|| format!("{}: cannot make the path absolute", p.display()))
    };
    let mut set = toml::Table::new();
    if let Some(env) = opts.env {
        set.insert("env".into(), env.name().into());
    }
    if let Some(urdf) = &opts.urdf {
        let mut walk = toml::Table::new();
        walk.insert(
            "urdf".into(),
            absolute(urdf)?.to_string_lossy().as_ref().into(),
        );
        set.insert("walk".into(), walk.into());
    }
    if let Some(until) = opts.until {
        set.insert("stop_at_walk".into(), (until == Until::Walk).into());
    }
    let count = |n: u64| toml::Value::Integer(i64::try_from(n).unwrap_or(i64::MAX));
    let mut arms = Vec::new();
    for agent in &agents {
        let mut arm = toml::Table::new();
        arm.insert("name".into(), agent.name().into());
        arm.insert("agent".into(), agent.name().into());
        arm.insert("preset".into(), opts.preset.name().into());
        if let Some(config) = &opts.config {
            let path = absolute(config)?;
            arm.insert("config".into(), path.to_string_lossy().as_ref().into());
        }
        if !set.is_empty() {
            arm.insert("set".into(), set.clone().into());
        }
        if let Some(s) = opts.steps {
            arm.insert("steps".into(), count(s));
        }
        if let Some(g) = opts.generations {
            arm.insert("generations".into(), count(g as u64));
        }
        if let Some(e) = opts.episodes {
            arm.insert("episodes".into(), count(e as u64));
        }
        arms.push(toml::Value::Table(arm));
    }
    let mut eval = toml::Table::new();
    eval.insert("episodes".into(), (args.eval_episodes as i64).into());
    eval.insert("seed".into(), (args.eval_seed as i64).into());
    eval.insert(
        "policy".into(),
        if args.eval_last { "last" } else { "kept" }.into(),
    );
    let mut file = toml::Table::new();
    file.insert(
        "description".into(),
        format!(
            "esrl compare: {} (preset {}), seeds 0 to {}",
            agents
                .iter()
                .map(|a| a.name())
                .collect::<Vec<_>>()
                .join(", "),
            opts.preset.name(),
            args.seeds - 1
        )
        .into(),
    );
    file.insert("seeds".into(), (args.seeds as i64).into());
    file.insert("eval".into(), eval.into());
    file.insert("arm".into(), toml::Value::Array(arms));
    Ok(format!(
        "# Written by `esrl compare`; `esrl study run` and `esrl study report` take it too.\n{}",
        toml::to_string(&file)?
    ))
}

/// Runs `esrl compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    let text = study_text(args)?;
    if args.jobs == Some(0) {
        bail!("--jobs 0: run at least one training at a time");
    }
    if args.opts.threads == Some(0) {
        bail!("--threads 0: use at least one thread per run");
    }
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    // The file `esrl study run` reads: the study folder's own copy when it is this study (a
    // continued comparison), else a new file beside it that the run then copies in.
    let held = out.join(crate::study::STUDY_FILE);
    let path = match std::fs::read_to_string(&held) {
        Ok(t) if t == text => held.clone(),
        Ok(_) => bail!(
            "{} holds another comparison (its study.toml differs from what these options \
             describe); pass the same options as before, or choose another --out",
            out.display()
        ),
        Err(_) => {
            let fresh = out.join("study.toml.new");
            esrl_run::run_dir::write_atomic(&fresh, text.as_bytes())?;
            fresh
        }
    };
    let ran = crate::study::run_study(
        &path,
        Some(out),
        args.jobs,
        None,
        args.opts.threads,
        args.opts.no_progress,
    );
    if path != held {
        std::fs::remove_file(&path).ok();
    }
    ran?;
    crate::study::report(out, false)
}
