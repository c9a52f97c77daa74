//! Prints `esrl_nn::bench::run` as one JSON line (the network part of `esrl bench nn
//! --json`): `cargo run --release -p esrl-nn --example nn_bench -- [obs_dim] [reps]`.

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut cfg = esrl_nn::bench::BenchConfig::default();
    let nums: Vec<usize> = args.iter().filter_map(|s| s.parse().ok()).collect();
    if let Some(&v) = nums.first() {
        cfg.obs_dim = v;
    }
    if let Some(&v) = nums.get(1) {
        cfg.reps = v;
    }
    match esrl_nn::bench::run(&cfg) {
        Ok(r) => println!("{}", serde_json::to_string(&r).unwrap_or_default()),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
