//! Prints `esrl_nn::bench::run` results: `cargo run --release -p esrl-nn --example nn_bench [obs_dim] [reps]`.

fn main() {
    let mut args = std::env::args().skip(1);
    let mut cfg = esrl_nn::bench::BenchConfig::default();
    if let Some(v) = args.next().and_then(|s| s.parse().ok()) {
        cfg.obs_dim = v;
    }
    if let Some(v) = args.next().and_then(|s| s.parse().ok()) {
        cfg.reps = v;
    }
    match esrl_nn::bench::run(&cfg) {
        Ok(r) => println!("{r:#?}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
