//! Loops the one SAC update that training runs ([`esrl_agents::Agent::update`]) for profiling:
//! `cargo run --release -p esrl-agents --example update_profile -- [lstm|mlp] [iters] [batch]`
//! (obs 31, act 6, 256 sequences × 8 steps or 256 transitions by default, as
//! `peers/torch_sac_step.py`).

use esrl_agents::{bench, Algo, NetConfig};

fn main() {
    let mut args = std::env::args().skip(1);
    let nets = match args.next().as_deref() {
        Some("mlp") => NetConfig::feed_forward(),
        _ => NetConfig::default(),
    };
    let iters: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(50);
    let batch: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(256);
    match bench::time_update(Algo::Sac, &nets, 31, 6, batch, iters, 1, 1) {
        Ok(t) => println!(
            "{:.3} ms/update median, {:.3} min, over {} updates",
            t.ms_per_update, t.min_ms, t.reps
        ),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
