//! Runs a policy's walking check (`[check]`, `esrl_run::check`) as its run would, from the
//! run's own check starts, optionally with more confirmation starts or another finish share:
//! whether a kept policy would still stop its run under a stricter bar.
//!
//! ```sh
//! cargo run --release -p esrl-run --example check_policy -- POLICY [CONFIRM_STARTS FINISH_SHARE]
//! ```
//!
//! `POLICY` is a folder with the run's `config.toml` and its agent (a run's `best/`, a
//! checkpoint, a record's `policy/`). Every start runs (`stop_early` off), so the counts are
//! over all of them.

use esrl_run::{build, check::Checker, checkpoint, TrainConfig};
use std::path::PathBuf;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: check_policy POLICY [CONFIRM_STARTS FINISH_SHARE]";
    let dir = PathBuf::from(args.first().ok_or(usage)?);
    let cfg = TrainConfig::load(&dir.join("config.toml"))?;
    let mut config = cfg.check.clone().ok_or("the policy's run has no [check]")?;
    if let [_, confirm, share] = args.as_slice() {
        config.confirm_starts = confirm.parse()?;
        config.finish_share = share.parse()?;
    } else if args.len() != 1 {
        return Err(usage.into());
    }
    config.stop_early = false;
    config.validate()?;
    let envs = build::envs(cfg.env, &cfg.walk)?;
    let mut agent = build::agent(&cfg, &envs)?;
    checkpoint::load_agent(&dir, &mut agent)?;
    let model = build::load_model(&cfg.walk)?;
    let checker = Checker::new(config, model, cfg.walk.clone(), cfg.seed);
    let result = checker.check(&agent, false, None)?;
    println!(
        "{} (seed {}): {}",
        dir.display(),
        cfg.seed,
        result.describe()
    );
    Ok(())
}
