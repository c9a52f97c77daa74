//! Writes the ES mean θ of a run's checkpoint as a policy folder (the checkpoint's agent
//! with the mean as its genome), so `esrl eval` can evaluate the mean beside the kept
//! individual.
//!
//! ```sh
//! cargo run --release -p esrl-run --example es_mean_policy -- RUN OUT_NAME
//! ```
//!
//! Writes `RUN/OUT_NAME/` in `RUN/best/`'s layout.

use esrl_run::{build, checkpoint, TrainConfig};
use std::path::PathBuf;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [run, name] = args.as_slice() else {
        return Err("usage: es_mean_policy RUN OUT_NAME".into());
    };
    let run = PathBuf::from(run);
    let dir = run.join("checkpoint");
    let cfg = TrainConfig::load(&dir.join("config.toml"))?;
    let envs = build::envs(cfg.env, &cfg.walk)?;
    let mut agent = build::agent(&cfg, &envs)?;
    checkpoint::load_agent(&dir, &mut agent)?;
    let tensors = checkpoint::read_tensors(&dir)?;
    let mean = tensors
        .get("es.mean")
        .ok_or("the checkpoint holds no es.mean")?;
    agent.set_genome(mean)?;
    let info: checkpoint::BestInfo =
        serde_json::from_str(&std::fs::read_to_string(run.join("best/best.json"))?)?;
    checkpoint::save_policy(&run, name, &cfg, &agent, &info)?;
    println!("{}: the ES mean written to {name}/", run.display());
    Ok(())
}
