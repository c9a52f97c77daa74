//! How long a joint-space PD controller acting through the agents' interface (one torque per
//! control period Ts, action = torque / effort limit) keeps the humanoid up: the reference for
//! what a learned policy has to beat by standing alone.
//! `cargo run --release -p esrl-sim --example pd_stand -- [actuator_armature] [substeps] [seed]`.

use esrl_sim::{Env, WalkConfig, WalkEnv};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut config = WalkConfig::default();
    if let Some(a) = args.first().and_then(|s| s.parse().ok()) {
        config.physics.actuator_armature = a;
    }
    if let Some(n) = args.get(1).and_then(|s| s.parse().ok()) {
        config.physics.substeps = n;
    }
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0);
    let mut env = match WalkEnv::new(config) {
        Ok(env) => env,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let stand = env.standing_pose();
    let effort = env.effort_limits().to_vec();
    let layout = env.obs_layout().clone();
    let scale = env.obs_scale().to_vec();
    println!("kp (N·m/rad)  kd (N·m·s/rad)  steps  seconds  return  fell");
    for kp in [0.0f32, 100.0, 200.0, 400.0, 800.0, 1600.0] {
        for kd in [0.0f32, 5.0, 10.0, 20.0, 40.0] {
            let mut obs = env.reset(seed);
            let (mut ret, mut steps) = (0.0, 0);
            let fell;
            loop {
                let action: Vec<f32> = (0..stand.len())
                    .map(|k| {
                        let qi = layout.joint_angles.start + k;
                        let vi = layout.joint_velocities.start + k;
                        let q = obs[qi] / scale[qi];
                        let qd = obs[vi] / scale[vi];
                        (kp * (stand[k] - q) - kd * qd) / effort[k]
                    })
                    .collect();
                let s = env.step(&action);
                ret += s.reward;
                steps += 1;
                obs = s.obs;
                if s.terminated || s.truncated {
                    fell = s.terminated;
                    break;
                }
            }
            println!(
                "{kp:>12} {kd:>15} {steps:>6} {:>8.2} {ret:>7.2} {fell}",
                steps as f32 * env.control_period()
            );
        }
    }
}
