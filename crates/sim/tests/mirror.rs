//! Contract: `WalkEnv::mirror` (module `walk::mirror`) is the left↔right reflection of the
//! task. Mirroring an observation or an action twice is the identity; the standing pose's
//! observation is its own mirror image but for the gait clock, which moves on by half a
//! cycle; joints pair by name, not by position (a shuffled `actuated_joints` list still maps
//! `left_knee` to `right_knee`); and the physics agrees: from a symmetric start, mirrored
//! actions give mirrored observations step by step. A robot whose joint has no partner is
//! refused with the joint named.

use esrl_sim::{Env, GaitClock, InitNoise, WalkConfig, WalkEnv};

/// The walking task on the embedded humanoid with a gait clock; `noise` false starts exactly
/// in the (symmetric) standing pose.
fn env(noise: bool, actuated: Option<Vec<&str>>) -> WalkEnv {
    let mut cfg = WalkConfig {
        gait_clock: Some(GaitClock::default()),
        ..WalkConfig::default()
    };
    if !noise {
        cfg.init_noise = InitNoise {
            joint_angle: 0.0,
            joint_velocity: 0.0,
        };
    }
    if let Some(names) = actuated {
        cfg.actuated_joints = names.into_iter().map(String::from).collect();
    }
    WalkEnv::new(cfg).unwrap()
}

/// A deterministic spread of values in [−1, 1].
fn values(n: usize, salt: u32) -> Vec<f32> {
    (0..n)
        .map(|i| ((i as f32 * 0.618 + salt as f32 * 0.37).sin() * 1.7).clamp(-1.0, 1.0))
        .collect()
}

#[test]
fn mirroring_twice_is_the_identity() {
    let env = env(true, None);
    let m = env.mirror().unwrap();
    let obs = values(env.obs_dim(), 1);
    let act = values(env.act_dim(), 2);
    assert_eq!(m.obs(&m.obs(&obs)), obs);
    assert_eq!(m.action(&m.action(&act)), act);
    assert_ne!(
        m.obs(&obs),
        obs,
        "the mirror must change a generic observation"
    );
    let mut scratch = Vec::new();
    let mut in_place = obs.clone();
    m.obs_in_place(&mut in_place, &mut scratch);
    assert_eq!(in_place, m.obs(&obs));
}

#[test]
fn the_standing_pose_is_its_own_mirror_image_with_the_clock_half_a_cycle_on() {
    let mut env = env(false, None);
    let m = env.mirror().unwrap();
    for phase in [0.1f32, 0.3, 0.8] {
        env.set_start_phase(Some(phase));
        let obs = env.reset(0);
        env.set_start_phase(Some(phase + 0.5));
        let other = env.reset(0);
        let mirrored = m.obs(&obs);
        for (i, (a, b)) in mirrored.iter().zip(&other).enumerate() {
            assert!(
                (a - b).abs() < 1e-5,
                "index {i} ({}): mirrored {a} vs standing at φ + ½ {b}",
                env.obs_names()[i]
            );
        }
    }
}

#[test]
fn joints_pair_by_name_not_by_position() {
    let names = [
        "right_knee",
        "left_hip",
        "right_ankle",
        "left_knee",
        "right_hip",
        "left_ankle",
    ];
    let env = env(true, Some(names.to_vec()));
    let m = env.mirror().unwrap();
    for (i, &(source, sign)) in m.action_map().iter().enumerate() {
        let want = if names[i].starts_with("left") {
            names[i].replacen("left", "right", 1)
        } else {
            names[i].replacen("right", "left", 1)
        };
        assert_eq!(names[source], want, "action {i}");
        assert_eq!(sign, 1.0, "pitch joints keep their sign");
    }
    let obs_names = env.obs_names();
    let layout = env.obs_layout();
    for i in layout.joint_angles.clone() {
        let (source, _) = m.obs_map()[i];
        let a = obs_names[i].replace("left", "#").replace("right", "left");
        assert_eq!(obs_names[source], a.replace('#', "right"));
    }
    // The shoulders' roll axes are reflections of each other (x on the left, −x on the
    // right): a pair with sign +1.
    for i in layout.passive_angles.clone() {
        assert_eq!(m.obs_map()[i].1, 1.0, "{}", obs_names[i]);
    }
}

#[test]
fn mirrored_actions_give_mirrored_observations() {
    // Rapier's contact solver is not exactly symmetric (a zero action from the symmetric
    // standing pose drifts sideways by mm/s), and small differences grow, so the two runs
    // are compared over the first 0.3 s: on every index the mirror changes, the mirrored
    // run must be far closer to the mirror image than to the unmirrored observation (a
    // wrong sign or pair would make it farther).
    let mut a = env(false, None);
    let mut b = env(false, None);
    let m = a.mirror().unwrap();
    a.set_start_phase(Some(0.2));
    b.set_start_phase(Some(0.7));
    a.reset(3);
    b.reset(3);
    assert_eq!(
        (a.reset_phase(), b.reset_phase()),
        (0.2, 0.7),
        "the set phases"
    );
    let changed: Vec<usize> = (0..a.obs_dim())
        .filter(|&i| m.obs_map()[i] != (i, 1.0))
        .collect();
    let (mut mirrored, mut plain) = (0.0f64, 0.0f64);
    for t in 0..12 {
        // An asymmetric action sequence: the legs do different things, the body turns and
        // leans; the other run does its mirror image.
        let act: Vec<f32> = values(6, t).iter().map(|v| 0.3 * v).collect();
        let sa = a.step(&act);
        let sb = b.step(&m.action(&act));
        let image = m.obs(&sa.obs);
        for &i in &changed {
            mirrored += f64::from((image[i] - sb.obs[i]).abs());
            plain += f64::from((sa.obs[i] - sb.obs[i]).abs());
        }
    }
    assert!(
        mirrored < 0.25 * plain,
        "mirrored run off its mirror image by {mirrored:.3} (summed), against {plain:.3} \
         unmirrored"
    );
}

#[test]
fn a_joint_without_a_partner_is_refused() {
    let env = env(
        true,
        Some(vec![
            "left_hip",
            "left_knee",
            "left_ankle",
            "right_hip",
            "right_knee",
        ]),
    );
    let err = env.mirror().unwrap_err().to_string();
    assert!(
        err.contains("left_ankle") && err.contains("right_ankle"),
        "{err}"
    );
}
