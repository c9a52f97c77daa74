//! Per-index observation statistics (mean, std, max |x|) of `WalkEnv` under zero and uniform
//! random actions, falls and resets included: the evidence behind
//! [`WalkEnv`](esrl_sim::WalkEnv)'s fixed observation scales.
//! `cargo run --release -p esrl-sim --example obs_stats -- [steps] [raw|scaled]`.

use esrl_sim::{Env, WalkConfig, WalkEnv};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let steps: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let scaled = args.get(1).map(|s| s == "scaled").unwrap_or(true);
    let config = WalkConfig {
        normalize_obs: scaled,
        ..WalkConfig::default()
    };
    let mut env = match WalkEnv::new(config) {
        Ok(env) => env,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let names = env.obs_names();
    let n = env.obs_dim();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    for policy in ["zero", "random"] {
        let mut sum = vec![0.0f64; n];
        let mut sq = vec![0.0f64; n];
        let mut max = vec![0.0f32; n];
        let mut obs = env.reset(0);
        let mut episodes = 1u64;
        for _ in 0..steps {
            let action: Vec<f32> = (0..env.act_dim())
                .map(|_| match policy {
                    "zero" => 0.0,
                    _ => rng.random_range(-1.0..=1.0),
                })
                .collect();
            for i in 0..n {
                sum[i] += obs[i] as f64;
                sq[i] += (obs[i] as f64).powi(2);
                max[i] = max[i].max(obs[i].abs());
            }
            let step = env.step(&action);
            obs = if step.terminated || step.truncated {
                episodes += 1;
                env.reset(episodes)
            } else {
                step.obs
            };
        }
        println!("policy {policy}: {steps} steps, {episodes} episodes");
        println!(
            "{:>3} {:<32} {:>9} {:>9} {:>9}",
            "i", "name", "mean", "std", "max|x|"
        );
        for i in 0..n {
            let m = sum[i] / steps as f64;
            let sd = (sq[i] / steps as f64 - m * m).max(0.0).sqrt();
            println!("{i:>3} {:<32} {m:>9.3} {sd:>9.3} {:>9.3}", names[i], max[i]);
        }
    }
}
