//! Contract: the humanoid's legs bend only in pitch (no hip or ankle roll), so sideways it is
//! a rigid body on the outer edges of its feet, and a lateral push tips it over exactly when
//! rigid-body mechanics says so. Held stiffly in its standing pose, both feet flat, a push of
//! `v` to the whole body (`RobotSim::push_root`) is caught by the ground at the outer edge of
//! the foot it moves towards: the angular momentum about that edge, `m·v·h`, is kept, and the
//! body turns about the edge with kinetic energy `(m·v·h)² / (2·I_edge)`. It goes over when
//! that exceeds the work `m·g·(r − h)` of lifting its centre of mass (height `h`, at `d`
//! from the edge) to above the edge (`r = √(h² + d²)`):
//!
//! ```text
//! v_tip = √(2·g·(r − h)·I_edge / m) / h,      I_edge = I_xx(about the centre of mass) + m·r²
//! ```
//!
//! computed here from the model's masses, inertias and foot boxes (about 0.51 m/s for the
//! embedded humanoid). The simulated robot stays up after a push of 0.95·v_tip and falls
//! after 1.05·v_tip (a point mass, without the body's own inertia, would tip at 0.92·v_tip).
//! No policy widens this base: the feet land only at hip width, and a walk is on one foot
//! most of the time, so 0.51 m/s bounds the lateral pushes a walk of this robot survives
//! (crouching lowers the centre of mass and raises the bound a little: 0.59 m/s at h = 0.8 m
//! by the same formula).

mod common;

use esrl_sim::{Env, Shape, WalkEnv};

const G: f64 = 9.81;

/// The environment with every actuated joint held at the standing pose by a stiff PD servo
/// (the one `standing.rs` stands a minute with), after 1 s of settling.
fn standing() -> WalkEnv {
    let mut env = common::pd_held_standing();
    let zero = vec![0.0; env.act_dim()];
    for _ in 0..40 {
        assert!(!env.step(&zero).terminated, "fell while settling");
    }
    env
}

/// The rigid-body tipping speed `v_tip` of the module doc, for the robot as it stands in
/// `env`: (v_tip, h, d).
fn tipping_speed(env: &WalkEnv) -> (f64, f64, f64) {
    let sim = env.sim();
    let model = env.model();
    let poses = sim.link_poses();
    let c = sim.center_of_mass();
    let mass: f64 = model.links().iter().map(|l| l.mass).sum();
    // I_xx about the centre of mass: each link's inertia turned into the world frame (its
    // xx element, from the first row of its rotation) plus the parallel-axis term.
    let mut ixx = 0.0;
    for (l, link) in model.links().iter().enumerate() {
        let [x, y, z, w] = poses[l].rotation.map(f64::from);
        let row = [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ];
        let mut own = 0.0;
        for (i, ri) in row.iter().enumerate() {
            for (j, rj) in row.iter().enumerate() {
                own += ri * link.inertia[i][j] * rj;
            }
        }
        let p = sim.link_center_of_mass(l);
        let (dy, dz) = (f64::from(p.y - c.y), f64::from(p.z - c.z));
        ixx += own + link.mass * (dy * dy + dz * dz);
    }
    // The outer edge of the feet: the foot boxes' widest point from the midline.
    let mut edge = 0.0f64;
    for name in &env.config().foot_links {
        let l = model.link_index(name).unwrap();
        for s in &model.links()[l].geometry().shapes {
            if let Shape::Box { size } = s.shape {
                let y = poses[l].translation[1].abs() + s.translation[1].abs() + size[1] / 2.0;
                edge = edge.max(f64::from(y));
            }
        }
    }
    assert!(edge > 0.0, "the feet have no boxes");
    let h = f64::from(c.z);
    let d = edge - f64::from(c.y).abs();
    let r = (h * h + d * d).sqrt();
    let i_edge = ixx + mass * r * r;
    ((2.0 * G * (r - h) * i_edge / mass).sqrt() / h, h, d)
}

/// Whether the robot, pushed sideways by `v` (m/s) from standing, is still up 4 s later
/// (not fallen by the environment's rule, torso roll never past 30°).
fn stays_up_after_push(v: f32) -> bool {
    let mut env = standing();
    env.sim_mut().push_root([0.0, v, 0.0]);
    let zero = vec![0.0; env.act_dim()];
    for _ in 0..160 {
        let s = env.step(&zero);
        let [x, y, z, w] = s.info.gait.unwrap().torso_rotation;
        let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
        if s.terminated || roll.abs() > 30f32.to_radians() {
            return false;
        }
    }
    true
}

#[test]
fn a_lateral_push_tips_the_standing_robot_over_at_the_rigid_body_bound() {
    let (v_tip, h, d) = tipping_speed(&standing());
    // The embedded humanoid: centre of mass about 0.99 m up, 0.15 m from the feet's outer
    // edge (hips 0.1 m off the midline, feet 9.6 cm wide).
    assert!(
        (0.9..1.1).contains(&h) && (0.12..0.18).contains(&d),
        "h {h}, d {d}"
    );
    assert!(
        stays_up_after_push((0.95 * v_tip) as f32),
        "fell after a push of 0.95 × {v_tip:.3} m/s"
    );
    assert!(
        !stays_up_after_push((1.05 * v_tip) as f32),
        "stayed up after a push of 1.05 × {v_tip:.3} m/s"
    );
}
