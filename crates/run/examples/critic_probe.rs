//! Looks inside a run's agent: the actor's pre-squash mean, standard deviation and sampled
//! log π, and each critic's Q on the replay buffer's transitions and on the actor's own
//! actions, as quantiles over 512 windows of 16 steps drawn from the replay buffer of
//! `RUN/checkpoint`.
//!
//! ```sh
//! cargo run --release -p esrl-run --example critic_probe -- RUN [CHECKPOINT_DIR]
//! ```
//!
//! `CHECKPOINT_DIR` defaults to `RUN/checkpoint`; `RUN/best` probes the kept policy's agent
//! (against the replay buffer of the run's last checkpoint). Windows run from a zero
//! recurrent state and ignore episode starts inside them: a diagnostic, not the update.

use esrl_nn::{Graph, Tensor};
use rand::SeedableRng;
use std::path::{Path, PathBuf};

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// Prints min, 1st, 50th, 99th percentile and max of `v`.
fn quantiles(name: &str, mut v: Vec<f32>) {
    v.sort_by(f32::total_cmp);
    let at = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
    println!(
        "{name:>10}: min {:>11.4e}  p1 {:>11.4e}  p50 {:>11.4e}  p99 {:>11.4e}  max {:>11.4e}",
        at(0.0),
        at(0.01),
        at(0.5),
        at(0.99),
        at(1.0)
    );
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(run) = args.first().map(Path::new) else {
        return Err("usage: critic_probe RUN [CHECKPOINT_DIR]".into());
    };
    let ckpt = args
        .get(1)
        .map_or_else(|| run.join("checkpoint"), PathBuf::from);
    let (cfg, _) = esrl_run::checkpoint::run_config(run)?;
    let envs = esrl_run::build::envs(cfg.env, &cfg.walk)?;
    let mut agent = esrl_run::build::agent(&cfg, &envs)?;
    esrl_run::checkpoint::load_agent(&ckpt, &mut agent)?;
    let buf = esrl_run::checkpoint::replay_buffer(&run.join("checkpoint"), &agent)?;
    let (o, a) = (agent.obs_dim(), agent.act_dim());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let b = 512;
    let batch = buf.sample_sequences(&mut rng, b, 8, 8);
    let rows = batch.window * b;
    let mut g = Graph::no_grad();
    let obs = g.constant(Tensor::from_slice(rows, o, &batch.obs));
    let out = agent.actor().forward(&mut g, obs, b, None);
    let sample = agent.actor().sample(&mut g, &out, &mut rng);
    quantiles("mean", g.value(out.mean).data().to_vec());
    quantiles("std", g.value(out.std).data().to_vec());
    quantiles("log_pi", g.value(sample.log_prob).data().to_vec());
    let own = g.value(sample.action).clone();
    for (k, critic) in agent.critics().iter().enumerate() {
        for (what, act) in [
            ("a", Tensor::from_slice(rows, a, &batch.action)),
            ("pi", own.clone()),
        ] {
            let mut g = Graph::no_grad();
            let (ov, av) = (
                g.constant(Tensor::from_slice(rows, o, &batch.obs)),
                g.constant(act),
            );
            let q = critic.forward(&mut g, ov, av, b, None).q;
            quantiles(&format!("Q{}(s,{what})", k + 1), g.value(q).data().to_vec());
        }
    }
    quantiles("reward", batch.reward.clone());
    println!("alpha {:.4}", agent.alpha());
    Ok(())
}
