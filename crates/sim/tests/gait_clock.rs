//! Contract: `walk.gait_clock` (module docs of `walk`, [`GaitClock`]). The clock's stance
//! windows and contact reward match hand-computed values; with a clock the observation ends
//! with (sin 2πφ, cos 2πφ) of a phase that starts at a value drawn from the reset seed and
//! advances by Ts/period per step; each step's `gait_clock` reward term is the contact reward
//! of that phase and the feet's forces, and nothing on a fall; without a clock the
//! environment is unchanged (43 observations, the same resets). The chatter term pays
//! `−chatter` for each contact or air phase of a foot that ends shorter than `min_phase`,
//! counted here from the feet's forces step by step.

use esrl_sim::{Env, GaitClock, WalkConfig, WalkEnv};

#[test]
fn stance_windows_and_contact_reward_by_hand() {
    let c = GaitClock {
        period: 1.0,
        duty: 0.6,
        reward: 0.5,
        contact_force: 10.0,
        chatter: 0.0,
        min_phase: 0.1,
        clearance: 0.4,
        clearance_height: 0.05,
    };
    // Clearance: a swing foot 2.5 cm up earns half of its share, one at 8 cm all of it, a
    // foot in stance nothing; φ = 0.3 has the right foot in swing.
    assert!((c.clearance_reward(0.3, [0.08, 0.025]) - 0.4 * 0.5 / 2.0).abs() < 1e-6);
    assert!((c.clearance_reward(0.3, [0.0, 0.08]) - 0.4 / 2.0).abs() < 1e-6);
    assert_eq!(c.clearance_reward(0.3, [0.0, -0.01]), 0.0);
    assert_eq!(
        c.clearance_reward(0.05, [0.1, 0.1]),
        0.0,
        "double support: no swing foot"
    );
    // Left down for φ ∈ [0, 0.6); right down for (φ + 0.5) mod 1 ∈ [0, 0.6), i.e. φ ∈
    // [0, 0.1) ∪ [0.5, 1): double support on [0, 0.1) and [0.5, 0.6).
    assert_eq!(c.stance(0.05), [true, true]);
    assert_eq!(c.stance(0.3), [true, false]);
    assert_eq!(c.stance(0.55), [true, true]);
    assert_eq!(c.stance(0.7), [false, true]);
    assert_eq!(c.stance(1.3), [true, false], "the phase wraps");
    // Both feet as the clock wants: +0.5; both wrong: −0.5; one of two: 0.
    assert_eq!(c.contact_reward(0.3, [50.0, 0.0]), 0.5);
    assert_eq!(c.contact_reward(0.3, [0.0, 50.0]), -0.5);
    assert_eq!(c.contact_reward(0.05, [50.0, 5.0]), 0.0);
    assert_eq!(
        c.contact_reward(0.7, [9.0, 11.0]),
        0.5,
        "10 N is the threshold"
    );
}

#[test]
fn the_clock_is_observed_and_rewarded_step_by_step() {
    let clock = GaitClock {
        period: 0.8,
        ..GaitClock::default()
    };
    let cfg = WalkConfig {
        gait_clock: Some(clock.clone()),
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(cfg.clone()).unwrap();
    assert_eq!(env.obs_dim(), 45);
    let mut starts = Vec::new();
    for seed in [0, 1, 2] {
        let obs = env.reset(seed);
        let phi0 = env.phase();
        starts.push(phi0);
        let angle = std::f32::consts::TAU * phi0;
        assert!((obs[43] - angle.sin()).abs() < 1e-6 && (obs[44] - angle.cos()).abs() < 1e-6);
        for k in 1..=40 {
            let step = env.step(&[0.0; 6]);
            let want = (phi0 + k as f32 * cfg.control_period / 0.8).rem_euclid(1.0);
            let phi = env.phase();
            assert!(
                (phi - want).abs() < 1e-4 || (phi - want).abs() > 1.0 - 1e-4,
                "step {k}: φ {phi} vs {want}"
            );
            let angle = std::f32::consts::TAU * phi;
            assert!((step.obs[43] - angle.sin()).abs() < 1e-5);
            assert!((step.obs[44] - angle.cos()).abs() < 1e-5);
            assert_eq!(
                env.reset_phase(),
                phi0,
                "the start phase stays the episode's"
            );
            let g = step.info.gait.as_ref().unwrap();
            let term = step
                .info
                .reward_terms
                .iter()
                .find(|t| t.0 == "gait_clock")
                .unwrap()
                .1;
            let expect = if g.fell {
                0.0
            } else {
                clock.contact_reward(phi, g.foot_force)
            };
            assert_eq!(term, expect, "step {k}");
            if step.terminated {
                break;
            }
        }
    }
    assert!(
        starts[0] != starts[1] && starts[1] != starts[2],
        "{starts:?}"
    );
}

#[test]
fn without_a_clock_nothing_changes() {
    let mut plain = WalkEnv::new(WalkConfig::default()).unwrap();
    let mut clocked = WalkEnv::new(WalkConfig {
        gait_clock: Some(GaitClock::default()),
        ..WalkConfig::default()
    })
    .unwrap();
    assert_eq!(plain.obs_dim(), 43);
    for seed in [3, 4] {
        let a = plain.reset(seed);
        let b = clocked.reset(seed);
        assert_eq!(a[..], b[..43], "same initial state");
        let sa = plain.step(&[0.1; 6]);
        let sb = clocked.step(&[0.1; 6]);
        assert_eq!(sa.obs[..], sb.obs[..43], "same dynamics");
        assert!(sa.info.reward_terms.iter().all(|t| t.0 != "gait_clock"));
    }
}

#[test]
fn chatter_is_paid_for_each_short_phase_when_it_ends() {
    let clock = GaitClock {
        chatter: 0.7,
        min_phase: 0.1,
        ..GaitClock::default()
    };
    let cfg = WalkConfig {
        gait_clock: Some(clock.clone()),
        ..WalkConfig::default()
    };
    let min_steps = 4; // 0.1 s / 0.025 s
    assert_eq!(clock.min_phase_steps(cfg.control_period), min_steps);
    let mut env = WalkEnv::new(cfg).unwrap();
    let (mut paid, mut transitions) = (0, 0);
    for seed in 0..4u64 {
        env.reset(seed);
        // The phase in progress at reset has no known start: it is never short.
        let mut down = env.foot_forces().map(|f| f > 10.0);
        let mut length = [u32::MAX; 2];
        for k in 0..200 {
            // Legs kicked back and forth fast enough to lift and drop the feet.
            let s = if (k / 3) % 2 == 0 { 1.0 } else { -1.0 };
            let step = env.step(&[s, -s, s, -s, s, -s]);
            let g = step.info.gait.as_ref().unwrap();
            let mut short = 0;
            for i in 0..2 {
                let now = g.foot_force[i] > 10.0;
                if now == down[i] {
                    length[i] = length[i].saturating_add(1);
                } else {
                    transitions += 1;
                    short += u32::from(length[i] < min_steps);
                    down[i] = now;
                    length[i] = 1;
                }
            }
            let term = step
                .info
                .reward_terms
                .iter()
                .find(|t| t.0 == "chatter")
                .unwrap()
                .1;
            let expect = if g.fell { 0.0 } else { -0.7 * short as f32 };
            assert_eq!(term, expect, "seed {seed}, step {k}");
            paid += usize::from(term != 0.0);
            if step.terminated || step.truncated {
                break;
            }
        }
    }
    assert!(
        transitions > 0 && paid > 0,
        "{transitions} transitions, {paid} paid"
    );
}

#[test]
fn clearance_is_paid_for_the_swing_foot_height_step_by_step() {
    let clock = GaitClock {
        clearance: 0.5,
        ..GaitClock::default()
    };
    let cfg = WalkConfig {
        gait_clock: Some(clock.clone()),
        action: esrl_sim::ActionMode::Target,
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(cfg).unwrap();
    env.reset(1);
    let (mut paid, mut some) = (0, false);
    for k in 0..60 {
        // Lift the left leg: hip and knee flexed, so its foot rises off the ground.
        let a = if k < 30 {
            [-0.8, 0.8, 0.0, 0.0, 0.0, 0.0]
        } else {
            [0.0; 6]
        };
        let phase = env.phase();
        let step = env.step(&a);
        let term = step
            .info
            .reward_terms
            .iter()
            .find(|t| t.0 == "clearance")
            .unwrap()
            .1;
        let feet = env.foot_heights();
        let want = if step.terminated {
            0.0
        } else {
            clock.clearance_reward(env.phase(), feet)
        };
        assert!(
            (term - want).abs() < 1e-6,
            "step {k} at φ {phase}: {term} vs {want}"
        );
        paid += usize::from(term > 0.0);
        some |= feet[0] > 0.02;
    }
    assert!(some && paid > 0, "the lifted foot earned clearance");
    // Off, there is no such term.
    let mut plain = WalkEnv::new(WalkConfig::default()).unwrap();
    plain.reset(1);
    assert!(plain
        .step(&[0.0; 6])
        .info
        .reward_terms
        .iter()
        .all(|t| t.0 != "clearance"));
}
