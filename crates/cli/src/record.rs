//! `esrl record`: one deterministic rollout of a trained walking policy to an MCAP file that
//! Foxglove opens as a moving 3D robot with plottable channels (topics in
//! `esrl_eval::recording`).

use crate::args::{EnvKind, RecordArgs};
use anyhow::{bail, Context, Result};
use esrl_agents::ActMode;
use esrl_eval::{load_run, metadata, walk_episode, Recorder};
use esrl_sim::Env;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Runs `esrl record`.
pub fn run(args: &RecordArgs) -> Result<()> {
    let loaded = load_run(&args.path)?;
    if loaded.config.env != EnvKind::Walk {
        bail!(
            "{} is a pendulum run: `esrl record` draws the walking humanoid and needs a walking \
             run (evaluate pendulum runs with `esrl eval`)",
            loaded.run.display()
        );
    }
    let mut env = loaded
        .walk_env()?
        .context("the walking run has no robot model")?;
    let mut recorder = Recorder::create(&args.out, &env, metadata(&loaded, args.seed))?;
    let mut policy = loaded.agent.policy();
    policy.reset();
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let ep = walk_episode(
        &mut env,
        args.seed,
        |obs, action| policy.act(obs, ActMode::Deterministic, &mut rng, action),
        |env, action, step| recorder.frame(env, action, step),
    )?;
    let skipped = recorder.skipped();
    let stats = recorder.finish()?;
    let r = &ep.rollout;
    eprintln!(
        "wrote {}: {} steps ({:.2} s simulated), {} messages; return {:.2}, distance {:.2} m, {}",
        args.out.display(),
        stats.frames,
        stats.frames as f64 * f64::from(env.control_period()),
        stats.messages,
        r.ret,
        ep.trace
            .torso_x
            .last()
            .zip(ep.trace.torso_x.first())
            .map_or(0.0, |(l, f)| l - f),
        if ep.trace.fell {
            "fell"
        } else if ep.trace.success_time.is_some() {
            "reached the end of the track"
        } else {
            "time limit"
        }
    );
    if skipped > 0 {
        eprintln!("({skipped} non-finite step(s) left out)");
    }
    Ok(())
}
