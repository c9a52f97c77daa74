//! Contract: the disturbances of robustness tests do what their docs say, against answers
//! computed by hand: a push changes the whole robot's momentum by `mass · dv`; a slope tilts
//! gravity so a free body accelerates along `g·(−sin s, 0, −cos s)`; `mass_scale` scales the
//! mass Rapier sees; `strength` scales the torque an action commands; `action_delay` hands
//! the joints the action of d steps before; `obs_noise` adds noise of the given spread that
//! repeats with the seed; pushes come every `push_every` s and move the torso by about the
//! push; a softer ground contact (`contact_frequency`) lets a standing robot sink by about
//! g/ω². With no disturbance the environment is what it was. On a slope, the orientation
//! observed in gravity's frame (`walk.orientation_frame = "gravity"`) points at the tilted
//! gravity as an IMU would; on flat ground both frames observe the same bits.

use std::sync::Arc;

use esrl_sim::{
    Base, Env, GaitClock, Perturb, PhysicsConfig, PushDirection, RobotModel, RobotSim, RobotState,
    SimSetup, WalkConfig, WalkEnv,
};

fn humanoid_sim(physics: PhysicsConfig, ground: bool) -> (RobotSim, Arc<RobotModel>) {
    let model = RobotModel::humanoid_shared().unwrap();
    let setup = SimSetup {
        dt: 0.00625,
        physics,
        base: Base::Floating,
        ground,
        armature: vec![],
    };
    let state = RobotState {
        base_position: [0.0, 0.0, 3.0],
        q: vec![0.0; model.joints().len()],
        qd: vec![0.0; model.joints().len()],
    };
    (RobotSim::new(model.clone(), &setup, &state).unwrap(), model)
}

/// Σ m·v over the links (the velocity of each link's centre of mass).
fn momentum(sim: &RobotSim, model: &RobotModel) -> [f64; 3] {
    let mut p = [0.0f64; 3];
    for (l, link) in model.links().iter().enumerate() {
        let (v, _) = sim.link_velocity(l);
        let m = link.mass;
        for (pk, vk) in p.iter_mut().zip(v.to_array()) {
            *pk += m * f64::from(vk);
        }
    }
    p
}

#[test]
fn a_push_adds_mass_times_the_velocity_change_to_the_momentum() {
    let physics = PhysicsConfig {
        gravity: 0.0,
        ..PhysicsConfig::default()
    };
    let (mut sim, model) = humanoid_sim(physics, false);
    let mass: f64 = model.links().iter().map(|l| l.mass).sum();
    sim.step();
    let before = momentum(&sim, &model);
    let dv = [0.5f32, -0.3, 0.0];
    sim.push_root(dv);
    sim.step();
    let after = momentum(&sim, &model);
    for k in 0..3 {
        let want = mass * f64::from(dv[k]);
        assert!(
            (after[k] - before[k] - want).abs() < 1e-3 * mass,
            "axis {k}: Δp = {} vs m·dv = {want}",
            after[k] - before[k]
        );
    }
}

#[test]
fn a_slope_tilts_gravity() {
    let s = 5.0f32.to_radians();
    let physics = PhysicsConfig {
        slope: s,
        ..PhysicsConfig::default()
    };
    let g = physics.gravity;
    let (mut sim, _) = humanoid_sim(physics, false);
    let c0 = sim.center_of_mass();
    for _ in 0..40 {
        sim.step();
    }
    let t = 40.0 * 0.00625f32;
    let d = sim.center_of_mass() - c0;
    // Symplectic Euler: ½ a t (t + h).
    let fall = |a: f32| 0.5 * a * t * (t + 0.00625);
    assert!((d.x - fall(-g * s.sin())).abs() < 2e-3, "x {}", d.x);
    assert!((d.z - fall(-g * s.cos())).abs() < 2e-3, "z {}", d.z);
    assert!(d.y.abs() < 1e-4);
}

#[test]
fn mass_scale_scales_what_rapier_weighs() {
    let (sim, model) = humanoid_sim(
        PhysicsConfig {
            mass_scale: 1.2,
            ..PhysicsConfig::default()
        },
        true,
    );
    let urdf: f64 = model.links().iter().map(|l| l.mass).sum();
    assert!((f64::from(sim.total_mass()) - 1.2 * urdf).abs() < 1e-3 * urdf);
}

/// The torso held in the air (gravity off), so the legs swing freely: every step's mean
/// delivered torques for a fixed action sequence.
fn torques(perturb: Perturb, actions: &[[f32; 6]]) -> Vec<Vec<f32>> {
    let cfg = WalkConfig {
        perturb,
        physics: PhysicsConfig {
            gravity: 0.0,
            ..PhysicsConfig::default()
        },
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(cfg).unwrap();
    env.reset(0);
    actions
        .iter()
        .map(|a| env.step(a).info.gait.unwrap().joint_torque)
        .collect()
}

#[test]
fn strength_scales_the_commanded_torque_and_delay_postpones_it() {
    let actions: Vec<[f32; 6]> = (0..4)
        .map(|k| [0.1 * (k + 1) as f32, 0.2, 0.05, 0.0, 0.3, 0.05])
        .collect();
    let base = torques(Perturb::default(), &actions);
    let weak = torques(
        Perturb {
            strength: 0.5,
            ..Perturb::default()
        },
        &actions,
    );
    // From the same state (the first step) the torques halve exactly; after it the two
    // runs move apart, and a joint near its limit meets the `fade` model at another angle.
    for (x, y) in base[0].iter().zip(&weak[0]) {
        assert!((y - 0.5 * x).abs() < 1e-4 * x.abs().max(1.0), "{x} vs {y}");
    }
    let late = torques(
        Perturb {
            action_delay: 1,
            ..Perturb::default()
        },
        &actions,
    );
    assert!(
        late[0].iter().all(|t| t.abs() < 1e-6),
        "nothing before the first action"
    );
    for k in 1..actions.len() {
        assert_eq!(
            late[k],
            base[k - 1],
            "step {k} applies step {}'s action",
            k - 1
        );
    }
}

#[test]
fn observation_noise_has_its_spread_and_repeats_with_the_seed() {
    let clean = WalkEnv::new(WalkConfig::default()).unwrap().reset(5);
    let noisy_cfg = WalkConfig {
        perturb: Perturb {
            obs_noise: 0.1,
            ..Perturb::default()
        },
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(noisy_cfg).unwrap();
    let mut diffs = Vec::new();
    for _ in 0..20 {
        let noisy = env.reset(5);
        diffs.extend(noisy.iter().zip(&clean).map(|(a, b)| f64::from(a - b)));
    }
    // 20 identical resets: the same noise each time.
    assert!(diffs
        .chunks(clean.len())
        .all(|c| c == &diffs[..clean.len()]));
    let first = &diffs[..clean.len()];
    let sd = (first.iter().map(|d| d * d).sum::<f64>() / first.len() as f64).sqrt();
    // 43 draws of N(0, 0.1²): the sample SD lies within ±40 % with overwhelming probability.
    assert!((sd - 0.1).abs() < 0.04, "sample SD {sd}");
    let other = env.reset(6);
    assert_ne!(other, WalkEnv::new(WalkConfig::default()).unwrap().reset(6));
}

#[test]
fn pushes_kick_the_torso_every_push_every_seconds() {
    let cfg = WalkConfig {
        action: esrl_sim::ActionMode::Target,
        gait_clock: Some(GaitClock::default()),
        perturb: Perturb {
            push_speed: 0.5,
            push_every: 1.0,
            push_direction: PushDirection::Sagittal,
            ..Perturb::default()
        },
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(cfg).unwrap();
    let mut still = WalkEnv::new(WalkConfig {
        perturb: Perturb::default(),
        ..env.config().clone()
    })
    .unwrap();
    env.reset(2);
    still.reset(2);
    let mut kicks = Vec::new();
    for k in 1..=100 {
        let a = env.step(&[0.0; 6]).info.gait.unwrap();
        let b = still.step(&[0.0; 6]).info.gait.unwrap();
        let dv = a.forward_velocity - b.forward_velocity;
        if kicks.is_empty() && dv.abs() > 0.2 {
            kicks.push((k, dv));
        }
    }
    let (step, dv) = kicks[0];
    // The first push comes at 1 s ± ¼ s (steps 30–50 of 25 ms) and moves the torso by
    // about ±0.5 m/s.
    assert!((30..=51).contains(&step), "first push at step {step}");
    assert!((dv.abs() - 0.5).abs() < 0.2, "Δv {dv}");
}

#[test]
fn randomised_episodes_draw_friction_mass_and_strength_from_their_ranges() {
    let cfg = WalkConfig {
        perturb: Perturb {
            friction_range: Some([0.4, 1.2]),
            mass_range: Some([0.8, 1.2]),
            strength_range: Some([0.8, 1.2]),
            ..Perturb::default()
        },
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(cfg).unwrap();
    let nominal: f32 = env.model().links().iter().map(|l| l.mass as f32).sum();
    let mut masses = Vec::new();
    for seed in 0..12 {
        env.reset(seed);
        masses.push(env.sim().total_mass() / nominal);
    }
    assert!(
        masses.iter().all(|m| (0.8 - 1e-4..=1.2 + 1e-4).contains(m)),
        "{masses:?}"
    );
    let spread = masses.iter().cloned().fold(f32::MIN, f32::max)
        - masses.iter().cloned().fold(f32::MAX, f32::min);
    assert!(spread > 0.1, "the mass varies between episodes: {masses:?}");
    env.reset(3);
    let again = env.sim().total_mass() / nominal;
    assert_eq!(again, masses[3], "the same seed draws the same episode");
}

/// The standing robot's torso height after 2 s on ground of contact frequency `hz`, and the
/// lowest foot origin's, m.
fn standing_height(hz: f32) -> (f32, f32) {
    let mut cfg = WalkConfig {
        action: esrl_sim::ActionMode::Target,
        ..WalkConfig::default()
    };
    cfg.physics.contact_frequency = hz;
    standing_heights(cfg)
}

fn standing_heights(cfg: WalkConfig) -> (f32, f32) {
    let mut env = WalkEnv::new(cfg).unwrap();
    env.reset(0);
    for _ in 0..80 {
        env.step(&[0.0; 6]);
    }
    let poses = env.link_poses();
    let feet: Vec<usize> = env
        .config()
        .foot_links
        .iter()
        .map(|n| env.model().link_index(n).unwrap())
        .collect();
    let foot = feet
        .iter()
        .map(|&l| poses[l].translation[2])
        .fold(f32::MAX, f32::min);
    (poses[env.model().root()].translation[2], foot)
}

#[test]
fn a_softer_ground_lets_the_standing_robot_sink_by_about_g_over_omega_squared() {
    // A contact spring of natural frequency ω holding its load sinks by about g/ω² (a mass
    // on a spring: m·g = k·x, ω² = k/m); at Rapier's 60 Hz that is 0.07 mm, at 10 Hz 2.5 mm.
    // Rapier's contact points each carry more than their share of the effective mass, so
    // the measured sink is that times a factor of order one (1.5-1.7 here), never less.
    let sink = |hz: f32| {
        let (torso, foot) = standing_height(hz);
        assert!(
            torso > 0.85,
            "{hz} Hz: the robot stands (torso at {torso} m)"
        );
        foot
    };
    let g_over_w2 = |hz: f32| 9.81 / (2.0 * std::f32::consts::PI * hz).powi(2);
    let stiff = sink(60.0);
    for hz in [10.0f32, 20.0] {
        let extra = stiff - sink(hz);
        let expected = g_over_w2(hz) - g_over_w2(60.0);
        let ratio = extra / expected;
        assert!(
            (1.0..2.5).contains(&ratio),
            "{hz} Hz: the feet sink {:.2} mm deeper than at 60 Hz; g/ω² says {:.2} mm",
            1e3 * extra,
            1e3 * expected
        );
    }
}

#[test]
fn a_contact_frequency_range_draws_the_episode_s_ground() {
    let cfg = WalkConfig {
        action: esrl_sim::ActionMode::Target,
        perturb: Perturb {
            contact_frequency_range: Some([10.0, 10.0]),
            ..Perturb::default()
        },
        ..WalkConfig::default()
    };
    assert_eq!(standing_heights(cfg), standing_height(10.0));
    assert_ne!(standing_height(10.0), standing_height(60.0));
}

#[test]
fn randomised_episodes_draw_their_slope_in_degrees_from_the_range() {
    let cfg = WalkConfig {
        perturb: Perturb {
            slope_range: Some([-5.0, 5.0]),
            ..Perturb::default()
        },
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(cfg).unwrap();
    let g = env.config().physics.gravity;
    let mut slopes = Vec::new();
    for seed in 0..12 {
        env.reset(seed);
        // Gravity g·(−sin s, 0, −cos s): the slope from its components, in degrees.
        let gravity = env.sim().world().gravity;
        assert!((gravity.length() - g).abs() < 1e-4);
        slopes.push((-gravity.x).atan2(-gravity.z).to_degrees());
    }
    assert!(
        slopes
            .iter()
            .all(|s| (-5.0 - 1e-3..=5.0 + 1e-3).contains(s)),
        "{slopes:?}"
    );
    assert!(
        slopes.iter().any(|s| *s > 2.0) && slopes.iter().any(|s| *s < -2.0),
        "uphill and downhill episodes: {slopes:?}"
    );
    env.reset(3);
    let gravity = env.sim().world().gravity;
    assert_eq!(
        (-gravity.x).atan2(-gravity.z).to_degrees(),
        slopes[3],
        "the same seed draws the same slope"
    );
}

/// `R(q)ᵀ·v` for the unit quaternion `q = (x, y, z, w)`: `v` in the frame `q` rotates into.
fn rotate_back(q: &[f32], v: [f64; 3]) -> [f64; 3] {
    let u = [-f64::from(q[0]), -f64::from(q[1]), -f64::from(q[2])];
    let w = f64::from(q[3]);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let uv = cross(u, v);
    let uuv = cross(u, uv);
    [0, 1, 2].map(|k| v[k] + 2.0 * w * uv[k] + 2.0 * uuv[k])
}

/// The walking task on a slope of `deg` degrees, its torso orientation observed in `frame`.
fn on_slope(deg: f32, frame: esrl_sim::OrientationFrame) -> WalkEnv {
    let mut cfg = WalkConfig {
        orientation_frame: frame,
        ..WalkConfig::default()
    };
    cfg.physics.slope = deg.to_radians();
    WalkEnv::new(cfg).unwrap()
}

#[test]
fn in_gravitys_frame_the_observed_orientation_points_at_gravity_as_an_imu_on_a_slope_does() {
    use esrl_sim::OrientationFrame::{Gravity, Ground};
    for deg in [-5.0f32, 3.0] {
        let s = f64::from(deg.to_radians());
        let (mut ground, mut gravity) = (on_slope(deg, Ground), on_slope(deg, Gravity));
        let o = ground.obs_layout().orientation.clone();
        let actions = [0.3f32, -0.2, 0.1, -0.4, 0.5, -0.1];
        let (mut a, mut b) = (ground.reset(7), gravity.reset(7));
        for step in 0..30 {
            // Gravity in the torso's frame: from the ground-frame orientation and the tilted
            // gravity g·(−sin s, 0, −cos s), and from the gravity-frame one and (0, 0, −g).
            let want = rotate_back(&a[o.clone()], [-s.sin(), 0.0, -s.cos()]);
            let got = rotate_back(&b[o.clone()], [0.0, 0.0, -1.0]);
            for k in 0..3 {
                assert!(
                    (want[k] - got[k]).abs() < 1e-6,
                    "{deg}°, step {step}: gravity in the torso frame {got:?}, want {want:?}"
                );
            }
            // Upright against the ground is leaning by the slope against gravity.
            if step == 0 {
                assert!((got[0] + s.sin()).abs() < 0.05, "{deg}°: {got:?}");
            }
            // Every other entry is the same bit for bit.
            let rest = |v: &[f32]| [&v[..o.start], &v[o.end..]].concat();
            assert_eq!(rest(&a), rest(&b), "{deg}°, step {step}");
            a = ground.step(&actions).obs;
            b = gravity.step(&actions).obs;
        }
    }
}

#[test]
fn on_flat_ground_both_orientation_frames_observe_the_same_bits() {
    use esrl_sim::OrientationFrame::{Gravity, Ground};
    let (mut ground, mut gravity) = (on_slope(0.0, Ground), on_slope(0.0, Gravity));
    assert_eq!(ground.reset(3), gravity.reset(3));
    for k in 0..40 {
        let x = k as f32 * 0.1;
        let action = [x.sin(), x.cos(), -x.sin(), 0.5, -0.5, 0.2];
        assert_eq!(
            ground.step(&action).obs,
            gravity.step(&action).obs,
            "step {k}"
        );
    }
}
