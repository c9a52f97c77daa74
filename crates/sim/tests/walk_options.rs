//! Contract: the reward, termination and reset options of `WalkConfig` do what the module
//! docs of `walk` say, each checked against a hand-computed expectation, and their defaults
//! are the paper's behaviour: the alive bonus is not paid on the step that falls; the
//! squared-action and squared-torque penalties are `w·Σ a²` and `w·Σ (τ/τmax)²`, the tilt
//! penalty `w·tilt²`; the gated
//! forward term is paid only while the torso is upright and tall; the episode ends off course
//! past the lateral and yaw limits; resets start crouched, split or mixed with the documented
//! joint offsets, and the reset noise is the documented uniform draw.

// Index loops read like the vector formulas they implement.
#![allow(clippy::needless_range_loop)]

use esrl_sim::{
    Env, GaitSample, InitNoise, LimitModel, ResetPose, Step, UprightGate, WalkConfig, WalkEnv,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn gait(s: &Step) -> &GaitSample {
    s.info.gait.as_ref().unwrap()
}

fn term(s: &Step, name: &str) -> Option<f32> {
    s.info
        .reward_terms
        .iter()
        .find(|t| t.0 == name)
        .map(|t| t.1)
}

/// Tilt of the torso z axis from vertical, from the quaternion `[x, y, z, w]`:
/// the z component of the rotated z axis is `1 − 2(x² + y²)`.
fn tilt(q: [f32; 4]) -> f32 {
    (1.0 - 2.0 * (q[0] * q[0] + q[1] * q[1]))
        .clamp(-1.0, 1.0)
        .acos()
}

/// Heading of the torso x axis, from the quaternion: `atan2(2(xy + wz), 1 − 2(y² + z²))`.
fn yaw(q: [f32; 4]) -> f32 {
    let [x, y, z, w] = q;
    (2.0 * (x * y + w * z)).atan2(1.0 - 2.0 * (y * y + z * z))
}

#[test]
fn the_alive_bonus_is_not_paid_on_the_step_that_falls() {
    let mut env = WalkEnv::new(WalkConfig::default()).unwrap();
    env.reset(0);
    for _ in 0..400 {
        let s = env.step(&[0.0; 6]);
        if s.terminated {
            assert!(gait(&s).fell);
            assert_eq!(term(&s, "alive"), Some(0.0));
            return;
        }
        assert_eq!(term(&s, "alive"), Some(0.025));
    }
    panic!("the unpowered robot did not fall within 10 s");
}

#[test]
fn squared_action_and_torque_penalties() {
    let action = [0.5, -1.0, 0.2, 0.0, 0.0, 2.0];
    // Clamped: 0.25 + 1 + 0.04 + 0 + 0 + 1 = 2.29.
    let sum_sq = 2.29f32;
    let mut config = WalkConfig::default();
    let mut env = WalkEnv::new(config.clone()).unwrap();
    env.reset(1);
    let s = env.step(&action);
    assert_eq!(term(&s, "action_sq"), None, "no term at weight 0");
    assert_eq!(term(&s, "torque_sq"), None, "no term at weight 0");

    config.reward.action_sq = 0.02;
    config.reward.torque_sq = 0.1;
    // Hard limits: the delivered torque is exactly a·τmax, so Σ (τ/τmax)² = Σ a².
    config.physics.joint_limits = LimitModel::Hard;
    let mut env = WalkEnv::new(config).unwrap();
    env.reset(1);
    for _ in 0..3 {
        let s = env.step(&action);
        let a = term(&s, "action_sq").unwrap();
        let t = term(&s, "torque_sq").unwrap();
        assert!((a + 0.02 * sum_sq).abs() < 1e-6, "action_sq {a}");
        assert!((t + 0.1 * sum_sq).abs() < 1e-5, "torque_sq {t}");
        let total: f32 = s.info.reward_terms.iter().map(|t| t.1).sum();
        assert!((total - s.reward).abs() < 1e-6);
    }
}

#[test]
fn the_tilt_penalty_is_w_times_the_squared_tilt() {
    // A pose that leans and falls: the tilt grows from about 0 to past the fall's 45°.
    let action = [0.3, 0.2, -0.6, 0.3, 0.2, -0.6];
    let mut config = WalkConfig::default();
    let mut env = WalkEnv::new(config.clone()).unwrap();
    env.reset(2);
    assert_eq!(
        term(&env.step(&action), "tilt_sq"),
        None,
        "no term at weight 0"
    );

    config.reward.tilt_sq = 2.0;
    let mut env = WalkEnv::new(config).unwrap();
    env.reset(2);
    let mut largest = 0.0f32;
    for _ in 0..80 {
        let s = env.step(&action);
        let t = tilt(gait(&s).torso_rotation);
        let got = term(&s, "tilt_sq").unwrap();
        assert!(
            (got + 2.0 * t * t).abs() < 1e-5,
            "tilt_sq {got} at tilt {t}"
        );
        let total: f32 = s.info.reward_terms.iter().map(|t| t.1).sum();
        assert!((total - s.reward).abs() < 1e-5);
        largest = largest.max(t);
        if s.terminated {
            break;
        }
    }
    assert!(largest > 0.3, "the pose never leaned: {largest} rad");
}

#[test]
fn the_gated_forward_term_is_paid_only_upright_and_tall() {
    let action = [0.3, 0.2, -0.6, 0.3, 0.2, -0.6];
    let run = |gate: Option<UprightGate>| -> Vec<(f32, f32, [f32; 4], f32)> {
        let mut config = WalkConfig::default();
        config.reward.forward_gate = gate;
        let mut env = WalkEnv::new(config).unwrap();
        env.reset(2);
        let mut out = Vec::new();
        for _ in 0..60 {
            let s = env.step(&action);
            let g = gait(&s);
            out.push((
                term(&s, "forward").unwrap(),
                g.forward_velocity,
                g.torso_rotation,
                g.height_error,
            ));
            if s.terminated {
                break;
            }
        }
        out
    };
    // A gate that never closes changes nothing.
    let open = run(Some(UprightGate {
        max_tilt: 3.0,
        max_height_drop: 10.0,
    }));
    for (f, v, _, _) in &open {
        assert_eq!(f, v);
    }
    let tight = UprightGate {
        max_tilt: 0.05,
        max_height_drop: 0.02,
    };
    let gated = run(Some(tight.clone()));
    let (mut paid, mut unpaid) = (0, 0);
    for (f, v, q, z) in &gated {
        if tilt(*q) <= tight.max_tilt && *z >= -tight.max_height_drop {
            assert_eq!(f, v);
            paid += 1;
        } else {
            assert_eq!(*f, 0.0);
            unpaid += 1;
        }
    }
    assert!(paid > 0 && unpaid > 0, "paid {paid}, unpaid {unpaid}");
}

#[test]
fn the_capped_forward_term_pays_speed_up_to_the_cap() {
    let action = [0.3, 0.2, -0.6, 0.3, 0.2, -0.6];
    let cap = 0.05;
    let mut config = WalkConfig::default();
    config.reward.forward = 2.0;
    config.reward.forward_cap = Some(cap);
    let mut env = WalkEnv::new(config.clone()).unwrap();
    env.reset(2);
    let (mut above, mut below) = (0, 0);
    for _ in 0..60 {
        let s = env.step(&action);
        let (f, v) = (term(&s, "forward").unwrap(), gait(&s).forward_velocity);
        if v > cap {
            assert_eq!(f, 2.0 * cap, "vx {v}");
            above += 1;
        } else {
            assert_eq!(f, 2.0 * v);
            below += 1;
        }
        if s.terminated {
            break;
        }
    }
    assert!(above > 0 && below > 0, "above {above}, below {below}");
    config.reward.forward_cap = Some(0.0);
    let e = WalkEnv::new(config).err().expect("a cap of 0 is refused");
    assert!(e.to_string().contains("reward.forward_cap"), "{e}");
}

#[test]
fn speed_above_the_cap_costs_what_forward_over_cap_asks() {
    let action = [0.3, 0.2, -0.6, 0.3, 0.2, -0.6];
    let (cap, k) = (0.05f32, 1.5f32);
    let mut config = WalkConfig::default();
    config.reward.forward = 2.0;
    config.reward.forward_cap = Some(cap);
    config.reward.forward_over_cap = k;
    let mut plain = config.clone();
    plain.reward.forward_over_cap = 0.0;
    let (mut env, mut free) = (
        WalkEnv::new(config.clone()).unwrap(),
        WalkEnv::new(plain).unwrap(),
    );
    env.reset(2);
    free.reset(2);
    let (mut above, mut below) = (0, 0);
    for _ in 0..60 {
        let (s, f0) = (env.step(&action), free.step(&action));
        let (f, v) = (term(&s, "forward").unwrap(), gait(&s).forward_velocity);
        // The same motion: only the forward term differs, and only above the cap.
        assert_eq!(v, gait(&f0).forward_velocity);
        if v > cap {
            // 2·(c − k·(v − c)), by hand.
            let want = 2.0 * (cap - k * (v - cap));
            assert!(
                (f - want).abs() <= 1e-6 * want.abs().max(1.0),
                "vx {v}: {f} vs {want}"
            );
            assert!(f < term(&f0, "forward").unwrap());
            above += 1;
        } else {
            assert_eq!(f, term(&f0, "forward").unwrap());
            below += 1;
        }
        if s.terminated {
            break;
        }
    }
    assert!(above > 0 && below > 0, "above {above}, below {below}");
    config.reward.forward_cap = None;
    let e = WalkEnv::new(config)
        .err()
        .expect("a price without a cap is refused");
    assert!(e.to_string().contains("reward.forward_over_cap"), "{e}");
}

#[test]
fn the_episode_ends_off_course_past_the_lateral_limit() {
    let mut config = WalkConfig::default();
    let max = 0.005;
    config.fall.max_lateral = Some(max);
    let mut env = WalkEnv::new(config).unwrap();
    env.reset(4);
    for step in 0..200 {
        let s = env.step(&[0.6, 0.0, 0.0, -0.6, 0.0, 0.0]);
        let g = gait(&s);
        if g.lateral_offset.abs() > max {
            assert!(
                s.terminated && g.off_course && !g.fell,
                "step {step}: {g:?}"
            );
            assert_eq!(term(&s, "alive"), Some(0.0));
            return;
        }
        assert!(
            !s.terminated,
            "step {step}: ended at |y| = {}",
            g.lateral_offset
        );
    }
    panic!("never left the lateral band");
}

#[test]
fn the_episode_ends_off_course_past_the_yaw_limit() {
    let mut config = WalkConfig::default();
    let max = 0.005;
    config.fall.max_yaw = Some(max);
    let mut env = WalkEnv::new(config).unwrap();
    env.reset(4);
    for step in 0..200 {
        let s = env.step(&[0.6, 0.0, 0.0, -0.6, 0.0, 0.0]);
        let g = gait(&s);
        let psi = yaw(g.torso_rotation);
        if psi.abs() > max {
            assert!(
                s.terminated && g.off_course && !g.fell,
                "step {step}: {g:?}"
            );
            assert_eq!(term(&s, "alive"), Some(0.0));
            return;
        }
        assert!(!s.terminated, "step {step}: ended at yaw {psi}");
    }
    panic!("never turned past the yaw limit");
}

/// Actuated joint angles right after a reset, degrees.
fn reset_angles(config: &WalkConfig, seed: u64) -> Vec<f32> {
    let mut env = WalkEnv::new(config.clone()).unwrap();
    let obs = env.reset(seed);
    let l = env.obs_layout().clone();
    let scale = env.obs_scale().to_vec();
    l.joint_angles
        .map(|i| (obs[i] / scale[i]).to_degrees())
        .collect()
}

fn quiet(pose: ResetPose) -> WalkConfig {
    let mut c = WalkConfig {
        init_noise: InitNoise {
            joint_angle: 0.0,
            joint_velocity: 0.0,
        },
        ..WalkConfig::default()
    };
    c.reset.pose = pose;
    c
}

fn assert_angles(got: &[f32], want: [f32; 6]) {
    for k in 0..6 {
        assert!((got[k] - want[k]).abs() < 1e-3, "{got:?} vs {want:?}");
    }
}

/// Standing −2°, 10°, −8°; crouch 10°: hips −12°, knees 30°, ankles −18°.
const CROUCH: [f32; 6] = [-12.0, 30.0, -18.0, -12.0, 30.0, -18.0];
const STAND: [f32; 6] = [-2.0, 10.0, -8.0, -2.0, 10.0, -8.0];
/// Split 10°: the leading leg's hip −12°, ankle +2°; the trailing leg's hip +8°, ankle −18°.
const LEFT_LEADS: [f32; 6] = [-12.0, 10.0, 2.0, 8.0, 10.0, -18.0];
const RIGHT_LEADS: [f32; 6] = [8.0, 10.0, -18.0, -12.0, 10.0, 2.0];

#[test]
fn reset_poses_have_the_documented_joint_angles() {
    assert_angles(&reset_angles(&quiet(ResetPose::Standing), 0), STAND);
    assert_angles(&reset_angles(&quiet(ResetPose::Crouch), 0), CROUCH);
    let split = quiet(ResetPose::Split);
    let (mut left, mut right) = (0, 0);
    for seed in 0..16 {
        let a = reset_angles(&split, seed);
        if a[0] < -5.0 {
            assert_angles(&a, LEFT_LEADS);
            left += 1;
        } else {
            assert_angles(&a, RIGHT_LEADS);
            right += 1;
        }
    }
    assert!(
        left > 0 && right > 0,
        "left leads {left}, right leads {right}"
    );
    let mixed = quiet(ResetPose::Mixed);
    let mut seen = [0; 3];
    for seed in 0..30 {
        let a = reset_angles(&mixed, seed);
        let which = [STAND, CROUCH, LEFT_LEADS, RIGHT_LEADS]
            .iter()
            .position(|w| (0..6).all(|k| (a[k] - w[k]).abs() < 1e-3))
            .unwrap_or_else(|| panic!("seed {seed}: {a:?} is none of the poses"));
        seen[which.min(2)] += 1;
    }
    assert!(
        seen.iter().all(|&n| n > 0),
        "standing, crouch, split: {seen:?}"
    );
    // Crouched and split resets start on the ground, upright.
    for pose in [ResetPose::Crouch, ResetPose::Split] {
        let mut env = WalkEnv::new(quiet(pose)).unwrap();
        env.reset(5);
        let s = env.step(&[0.0; 6]);
        assert!(!s.terminated);
        assert!(gait(&s).height_error < 0.0, "{pose:?} starts lower");
    }
}

#[test]
fn reset_noise_is_the_documented_uniform_draw() {
    let noise = InitNoise {
        joint_angle: 0.1,
        joint_velocity: 0.5,
    };
    let config = WalkConfig {
        init_noise: noise.clone(),
        normalize_obs: false,
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(config).unwrap();
    let seed = 9;
    let obs = env.reset(seed);
    let model = env.model().clone();
    let layout = env.obs_layout().clone();
    // Per movable joint in URDF order: angle then velocity, each half-width × U(−1, 1).
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut dq = vec![0.0f64; model.joints().len()];
    let mut dqd = vec![0.0f64; model.joints().len()];
    for (j, joint) in model.joints().iter().enumerate() {
        if joint.is_movable() {
            dq[j] = noise.joint_angle as f64 * rng.random_range(-1.0..=1.0);
            dqd[j] = noise.joint_velocity as f64 * rng.random_range(-1.0..=1.0);
        }
    }
    let stand = env.standing_pose();
    let mut largest = 0.0f64;
    for (k, name) in env.actuated_joint_names().iter().enumerate() {
        let j = model.joint_index(name).unwrap();
        let [lo, hi] = model.joints()[j].limits.unwrap();
        let want = (stand[k] as f64 + dq[j]).clamp(lo, hi);
        let got = obs[layout.joint_angles.start + k] as f64;
        assert!((got - want).abs() < 1e-5, "{name}: {got} vs {want}");
        let got_v = obs[layout.joint_velocities.start + k] as f64;
        assert!(
            (got_v - dqd[j]).abs() < 1e-4,
            "{name}: q̇ {got_v} vs {}",
            dqd[j]
        );
        largest = largest.max(dq[j].abs());
    }
    assert!(
        largest > 0.05,
        "a draw this wide should move some joint by > 0.05 rad"
    );
}
