//! Control steps per second of `WalkEnv` on one core with random actions (falls and resets
//! included): `cargo run --release -p esrl-sim --example bench_env -- [steps] [substeps]
//! [iterations] [hard|fade|soft] [torque|target]` (defaults: 20000 and the default config).

use esrl_sim::bench::bench_walk;
use esrl_sim::{ActionMode, LimitModel, WalkConfig};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: u64| -> u64 {
        args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default)
    };
    let mut config = WalkConfig::default();
    config.physics.substeps = arg(1, config.physics.substeps as u64) as u32;
    config.physics.solver_iterations = arg(2, config.physics.solver_iterations as u64) as u32;
    match args.get(3).map(String::as_str) {
        Some("hard") => config.physics.joint_limits = LimitModel::Hard,
        Some("fade") => config.physics.joint_limits = LimitModel::Fade,
        Some("soft") => config.physics.joint_limits = LimitModel::Soft,
        _ => {}
    }
    if args.get(4).map(String::as_str) == Some("target") {
        config.action = ActionMode::Target;
    }
    match bench_walk(&config, arg(0, 20_000) as usize, 0) {
        Ok(report) => println!("{report:#?}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
