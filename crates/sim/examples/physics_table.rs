//! Reproduces the "Physics step" table of the crate docs: for each solver-iteration count,
//! the torso drift of the 60 s PD-standing test, the worst joint-limit overshoot of the
//! joint-limit test (with and without actuator armature), the creep of a rigid stance, and the
//! throughput with random actions. `cargo run --release -p esrl-sim --example physics_table`

use std::sync::Arc;

use esrl_sim::bench::{bench_walk, rigid_stance_travel};
use esrl_sim::{Base, Env, RobotModel, RobotSim, RobotState, SimSetup, WalkConfig, WalkEnv};

fn config(iterations: u32, armature: f32) -> WalkConfig {
    let mut c = WalkConfig::default();
    c.physics.solver_iterations = iterations;
    c.physics.actuator_armature = armature;
    c
}

/// Max torso drift (m) over 60 s held by implicit PD servos, or None if it fell.
fn standing(config: WalkConfig) -> Option<f32> {
    let mut env = WalkEnv::new(config).ok()?;
    env.reset(7);
    let stand = env.standing_pose();
    for (k, n) in env.actuated_joint_names().to_vec().iter().enumerate() {
        let j = env.model().joint_index(n)?;
        env.sim_mut().set_joint_servo(j, stand[k], 2000.0, 100.0);
    }
    let start = env.sim().link_pose(env.model().root()).translation;
    let mut drift = 0.0f32;
    for _ in 0..2400 {
        let s = env.step(&[0.0; 6]);
        if s.terminated {
            return None;
        }
        drift = drift.max((env.sim().link_pose(env.model().root()).translation - start).length());
    }
    Some(drift)
}

/// Worst overshoot (degrees) of the actuated joints driven at full effort through full-range
/// swings with the torso held in the air (the scenario of `tests/joint_limits.rs`).
fn limits(config: WalkConfig) -> f64 {
    let model = Arc::new(RobotModel::humanoid().unwrap());
    let actuated: Vec<usize> = config
        .actuated_joints
        .iter()
        .map(|n| model.joint_index(n).unwrap())
        .collect();
    let mut armature = vec![0.0; model.joints().len()];
    let mut q = vec![0.0; model.joints().len()];
    for &j in &actuated {
        armature[j] = config.physics.actuator_armature;
        let [lo, hi] = model.joints()[j].limits.unwrap();
        q[j] = 0.5 * (lo + hi);
    }
    let setup = SimSetup {
        dt: config.control_period,
        physics: config.physics.clone(),
        base: Base::Fixed,
        ground: false,
        armature,
    };
    let state = RobotState {
        base_position: [0.0, 0.0, 1.5],
        q,
        qd: vec![],
    };
    let mut sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
    let mut worst = 0.0f64;
    for direction in [-1.0f32, 1.0, -1.0] {
        for _ in 0..60 {
            for &j in &actuated {
                sim.set_joint_torque(j, direction * model.joints()[j].effort as f32);
            }
            sim.step();
            for &j in &actuated {
                let [lo, hi] = model.joints()[j].limits.unwrap();
                let q = sim.joint_position(j) as f64;
                worst = worst.max((lo - q).max(q - hi).to_degrees());
            }
        }
    }
    worst
}

/// Creep of a rigid stance ([`rigid_stance_travel`]) with armature 0.5, the `quick`
/// preset's: the largest travel over the stances (ankle actions × reset seeds) that stayed
/// up, and how many did.
fn creep(iterations: u32) -> (f32, usize) {
    let mut env = WalkEnv::new(config(iterations, 0.5)).unwrap();
    let (mut worst, mut upright) = (0.0f32, 0);
    for seed in [1, 2, 3] {
        for ankle in [-1.0f32, -0.6, -0.3] {
            if let Some(d) = rigid_stance_travel(&mut env, seed, ankle) {
                upright += 1;
                worst = worst.max(d);
            }
        }
    }
    (worst, upright)
}

fn main() {
    println!("| solver iterations | standing drift | overshoot (armature 0.1) | overshoot (armature 0) | rigid-stance creep, 59 s | steps/s |");
    println!("|---|---|---|---|---|---|");
    for it in [1, 2, 3, 4, 8, 16, 32] {
        let drift =
            standing(config(it, 0.1)).map_or("fell".to_owned(), |d| format!("{:.1} cm", d * 100.0));
        let bench = bench_walk(&config(it, 0.1), 10_000, 0).unwrap();
        let (travel, upright) = creep(it);
        println!(
            "| {it} | {drift} | {:.1}° | {:.1}° | {travel:.2} m ({upright} of 9 upright) | {:.0} |",
            limits(config(it, 0.1)),
            limits(config(it, 0.0)),
            bench.steps_per_s
        );
    }
    let env = WalkEnv::new(WalkConfig::default()).unwrap();
    println!("obs_dim {}", env.obs_dim());
}
