//! `esrl record`: one deterministic rollout of a trained walking policy to an MCAP file that
//! Foxglove opens as a moving 3D robot with plottable channels (topics in
//! `esrl_eval::recording`).

use crate::args::{EnvKind, RecordArgs};
use anyhow::{bail, Context, Result};
use esrl_agents::ActMode;
use esrl_eval::{animated_svg, load_run_pick, metadata, walk_episode, Pick, Recorder};
use esrl_run::run_dir::{check_output, write_atomic};
use esrl_sim::Env;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Runs `esrl record`.
pub fn run(args: &RecordArgs) -> Result<()> {
    check_output(&args.out, args.force)?;
    let extension = args
        .out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let svg = match extension.as_deref() {
        Some("svg") => true,
        Some("mcap") => false,
        _ => bail!(
            "--out {}: name the file FILE.mcap (a recording for Foxglove) or FILE.svg (an \
             animated side view); the extension says which to write",
            args.out.display()
        ),
    };
    let pick = if args.last { Pick::Last } else { Pick::Kept };
    let loaded = load_run_pick(&args.path, pick)?;
    eprintln!("recording {}", crate::eval::which_policy(&loaded));
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
    let mut policy = loaded.agent.policy();
    policy.reset();
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let act =
        |obs: &[f32], action: &mut [f32]| policy.act(obs, ActMode::Deterministic, &mut rng, action);
    let (ep, what, skipped) = if svg {
        let ep = walk_episode(&mut env, args.seed, act, |_, _, _| Ok(()))?;
        write_atomic(&args.out, animated_svg(&ep.stick, 320.0).as_bytes())?;
        let what = format!(
            "{} side-view frames ({:.1} s, an SVG animation: open it in a browser)",
            ep.stick.frames.len(),
            ep.stick.time.last().copied().unwrap_or(0.0)
        );
        (ep, what, 0)
    } else {
        let mut recorder = Recorder::create(&args.out, &env, metadata(&loaded, args.seed))?;
        let ep = walk_episode(&mut env, args.seed, act, |env, action, step| {
            recorder.frame(env, action, step)
        })?;
        let skipped = recorder.skipped();
        let stats = recorder.finish()?;
        let what = format!(
            "{} steps ({:.2} s simulated), {} messages",
            stats.frames,
            stats.frames as f64 * f64::from(env.control_period()),
            stats.messages
        );
        (ep, what, skipped)
    };
    let r = &ep.rollout;
    eprintln!(
        "wrote {}: {what}; return {:.2}, distance {:.2} m, {}",
        args.out.display(),
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
