//! Reproduces the physics table of the crate docs: for each joint-limit model and step
//! setting (Rapier steps per 25 ms control period × solver iterations per Rapier step), the
//! torso drift of the 60 s PD-standing test; the worst joint-limit overshoot of the
//! joint-limit test as seen once per control period and its peak between control periods,
//! and the hold distance; the limit-pressing stance of `tests/rigid_stance.rs` (how many of
//! the 30 stances, armature 0.1 and 0.5, stay up for 60 s, the worst travel of those, and the
//! mean hip/knee speed while they stand); and the throughput with random actions.
//!
//! `cargo run --release -p esrl-sim --example physics_table` runs the documented rows;
//! `-- MODEL SUBSTEPS ITERATIONS [BAND_DEGREES]` (e.g. `-- fade 4 1 1`) runs one.

// The fixtures of the physics tests (the humanoid held in the air).
#[path = "../tests/common/mod.rs"]
mod common;

use esrl_sim::bench::bench_walk;
use esrl_sim::{Env, LimitModel, RobotSim, RobotState, WalkConfig, WalkEnv};

fn config(model: LimitModel, substeps: u32, iterations: u32) -> WalkConfig {
    let mut c = WalkConfig::default();
    c.physics.joint_limits = model;
    c.physics.substeps = substeps;
    c.physics.solver_iterations = iterations;
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

/// Worst overshoot past a limit seen once per control period, its peak over every Rapier
/// step, and the worst distance from the limit while held (last 0.5 s of each 1.5 s phase,
/// per control period), degrees, of the actuated joints driven at full effort through
/// full-range swings with the torso held in the air (the scenario of `tests/joint_limits.rs`).
fn limits(config: WalkConfig) -> (f64, f64, f64) {
    let (model, actuated, setup) = common::held_humanoid(&config);
    let mut q = vec![0.0; model.joints().len()];
    for &j in &actuated {
        let [lo, hi] = model.joints()[j].limits.unwrap();
        q[j] = 0.5 * (lo + hi);
    }
    let state = RobotState {
        base_position: [0.0, 0.0, 1.5],
        q,
        qd: vec![],
    };
    let mut sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
    let substeps = config.physics.substeps as usize;
    let steps = (1.5 / config.control_period).round() as usize;
    let hold_from = steps - (0.5 / config.control_period).round() as usize;
    let (mut over, mut peak, mut held) = (0.0f64, 0.0f64, 0.0f64);
    let past = |sim: &RobotSim, j: usize| {
        let [lo, hi] = model.joints()[j].limits.unwrap();
        let q = sim.joint_position(j) as f64;
        (lo - q).max(q - hi).to_degrees()
    };
    for direction in [-1.0f32, 1.0, -1.0] {
        for step in 0..steps {
            for &j in &actuated {
                sim.set_joint_torque(j, direction * model.joints()[j].effort as f32);
            }
            for _ in 0..substeps {
                sim.step();
                for &j in &actuated {
                    peak = peak.max(past(&sim, j));
                }
            }
            for &j in &actuated {
                over = over.max(past(&sim, j));
                if step >= hold_from {
                    let [lo, hi] = model.joints()[j].limits.unwrap();
                    let limit = if direction < 0.0 { lo } else { hi };
                    let q = sim.joint_position(j) as f64;
                    held = held.max((q - limit).abs().to_degrees());
                }
            }
        }
    }
    (over, peak, held)
}

/// The limit-pressing stance `[1, −1, ankle, 1, −1, ankle]` (hips into +30°, knees into 5°)
/// for 60 s from several reset seeds and ankle actions, with actuator armature 0.1 and 0.5:
/// (stances that stayed up, of how many; the worst horizontal travel from t = 1 s of those;
/// the mean |q̇| of hips and knees over the upright stances' last 59 s).
fn pressing(config: WalkConfig) -> (usize, usize, f32, f32) {
    let (mut up, mut total, mut worst) = (0, 0, 0.0f32);
    let (mut speed, mut samples) = (0.0f64, 0usize);
    for (armature, seed) in [0.1f32, 0.5]
        .into_iter()
        .flat_map(|a| [1, 2, 3].map(|s| (a, s)))
    {
        let mut c = config.clone();
        c.physics.actuator_armature = armature;
        let mut env = WalkEnv::new(c).unwrap();
        for ankle in [-1.0f32, -0.6, -0.3, 0.0, 0.5] {
            total += 1;
            env.reset(seed);
            let action = [1.0, -1.0, ankle, 1.0, -1.0, ankle];
            let (mut start, mut end) = ([0.0f32; 3], [0.0f32; 3]);
            let (mut s_sum, mut n) = (0.0f64, 0usize);
            let mut fell = false;
            for step in 1..=2400 {
                let s = env.step(&action);
                let g = s.info.gait.as_ref().unwrap();
                if step == 40 {
                    start = g.torso_position;
                }
                end = g.torso_position;
                if step > 40 {
                    for k in [0, 1, 3, 4] {
                        s_sum += g.joint_velocity[k].abs() as f64;
                        n += 1;
                    }
                }
                if s.terminated {
                    fell = true;
                    break;
                }
            }
            if !fell {
                up += 1;
                worst = worst.max((end[0] - start[0]).hypot(end[1] - start[1]));
                speed += s_sum;
                samples += n;
            }
        }
    }
    let speed = if samples > 0 {
        (speed / samples as f64) as f32
    } else {
        f32::NAN
    };
    (up, total, worst, speed)
}

fn row(model: LimitModel, substeps: u32, iterations: u32, band: Option<f32>) {
    let mut c = config(model, substeps, iterations);
    if let Some(b) = band {
        c.physics.limit_band = b.to_radians();
    }
    let drift = standing(c.clone()).map_or("fell".to_owned(), |d| format!("{:.1} cm", d * 100.0));
    let (over, peak, held) = limits(c.clone());
    let (up, total, travel, speed) = pressing(c.clone());
    let bench = bench_walk(&c, 10_000, 0).unwrap();
    let (travel, speed) = if up > 0 {
        (format!("{travel:.2} m"), format!("{speed:.2} rad/s"))
    } else {
        ("–".to_owned(), "–".to_owned())
    };
    println!(
        "| `{}` | {substeps} × {iterations} | {drift} | {over:.1}° | {peak:.1}° | {held:.1}° | {up} of {total} | {travel} | {speed} | {:.0} |",
        format!("{model:?}").to_lowercase(),
        bench.steps_per_s
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    println!("| limits | Rapier steps × iterations | 60 s PD standing, max drift | overshoot, per control step | overshoot, peak between | held | limit-pressing stances up 60 s | their worst travel, 59 s | their hip/knee speed | steps/s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    if args.len() >= 3 {
        let model = match args[0].as_str() {
            "hard" => LimitModel::Hard,
            "fade" => LimitModel::Fade,
            "soft" => LimitModel::Soft,
            other => {
                eprintln!("unknown limit model `{other}` (hard, fade, soft)");
                std::process::exit(2);
            }
        };
        let n = |i: usize| args[i].parse::<u32>().unwrap_or(1);
        row(model, n(1), n(2), args.get(3).and_then(|b| b.parse().ok()));
        return;
    }
    for (model, substeps, iterations) in [
        (LimitModel::Hard, 1, 16),
        (LimitModel::Hard, 1, 4),
        (LimitModel::Hard, 4, 1),
        (LimitModel::Fade, 1, 4),
        (LimitModel::Fade, 2, 1),
        (LimitModel::Fade, 3, 1),
        (LimitModel::Fade, 4, 1),
        (LimitModel::Fade, 5, 1),
        (LimitModel::Fade, 8, 1),
        (LimitModel::Soft, 4, 1),
    ] {
        row(model, substeps, iterations, None);
    }
    let env = WalkEnv::new(WalkConfig::default()).unwrap();
    println!("obs_dim {}", env.obs_dim());
}
