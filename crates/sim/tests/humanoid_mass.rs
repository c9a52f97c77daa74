//! Contract: the embedded humanoid is the documented human (1.6–1.8 m, 50–75 kg, Winter's
//! segment fractions), Rapier sees exactly the URDF's masses and centre of mass, and every
//! inertial block equals the inertia of its collision primitives.
//!
//! The reference numbers are computed here straight from the URDF text with urdf-rs and by
//! hand (parallel-axis sums), not through the crate's model code.

// Index loops read like the vector formulas they implement.
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;
use std::sync::Arc;

use esrl_sim::{Base, PhysicsConfig, RobotModel, RobotSim, RobotState, SimSetup, HUMANOID_URDF};

fn robot() -> urdf_rs::Robot {
    urdf_rs::read_from_string(HUMANOID_URDF).unwrap()
}

/// Link origins at the zero pose: all joint rotations are zero in this URDF, so a link origin
/// is the sum of the joint offsets from the root.
fn zero_pose_origins(r: &urdf_rs::Robot) -> HashMap<String, [f64; 3]> {
    for j in &r.joints {
        assert_eq!(
            j.origin.rpy.0, [0.0; 3],
            "joint {} has a rotated origin",
            j.name
        );
    }
    for l in &r.links {
        assert_eq!(
            l.inertial.origin.rpy.0, [0.0; 3],
            "link {} inertial rpy",
            l.name
        );
    }
    let mut origins = HashMap::from([("torso".to_owned(), [0.0; 3])]);
    while origins.len() < r.links.len() {
        for j in &r.joints {
            if let Some(p) = origins.get(&j.parent.link).copied() {
                let o = j.origin.xyz.0;
                origins.insert(
                    j.child.link.clone(),
                    [p[0] + o[0], p[1] + o[1], p[2] + o[2]],
                );
            }
        }
    }
    origins
}

#[test]
fn rapier_mass_and_com_equal_the_urdf_sums() {
    let r = robot();
    let origins = zero_pose_origins(&r);
    let mut mass = 0.0;
    let mut com = [0.0; 3];
    for l in &r.links {
        let m = l.inertial.mass.value;
        let o = origins[&l.name];
        let c = l.inertial.origin.xyz.0;
        mass += m;
        for k in 0..3 {
            com[k] += m * (o[k] + c[k]);
        }
    }
    let com = com.map(|v| v / mass);

    let base = [0.3, -0.2, 1.0];
    let model = Arc::new(RobotModel::humanoid().unwrap());
    let setup = SimSetup {
        dt: 0.025,
        physics: PhysicsConfig::default(),
        base: Base::Floating,
        ground: false,
        armature: vec![],
    };
    let state = RobotState {
        base_position: base,
        q: vec![0.0; model.joints().len()],
        qd: vec![],
    };
    let sim = RobotSim::new(model.clone(), &setup, &state).unwrap();
    assert!(
        (sim.total_mass() as f64 - mass).abs() < 1e-4,
        "{} vs {mass}",
        sim.total_mass()
    );
    assert!((model.total_mass() - mass).abs() < 1e-9);
    let c = sim.center_of_mass();
    for (k, got) in [c.x, c.y, c.z].into_iter().enumerate() {
        let want = com[k] + base[k];
        assert!(
            (got as f64 - want).abs() < 1e-4,
            "COM axis {k}: {got} vs {want}"
        );
    }
    // Per link too.
    for (i, l) in r.links.iter().enumerate() {
        let o = origins[&l.name];
        let c = l.inertial.origin.xyz.0;
        let got = sim.link_center_of_mass(i);
        let want = [
            o[0] + c[0] + base[0],
            o[1] + c[1] + base[1],
            o[2] + c[2] + base[2],
        ];
        for (k, g) in [got.x, got.y, got.z].into_iter().enumerate() {
            assert!(
                (g as f64 - want[k]).abs() < 1e-4,
                "{} COM axis {k}: {g} vs {}",
                l.name,
                want[k]
            );
        }
    }
}

#[test]
fn proportions_are_human() {
    let r = robot();
    let origins = zero_pose_origins(&r);
    let mass: f64 = r.links.iter().map(|l| l.inertial.mass.value).sum();
    assert!((50.0..=75.0).contains(&mass), "mass {mass}");
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for l in &r.links {
        let o = origins[&l.name];
        for c in &l.collision {
            let z = o[2] + c.origin.xyz.0[2];
            let half = match &c.geometry {
                urdf_rs::Geometry::Box { size } => size.0[2] / 2.0,
                urdf_rs::Geometry::Sphere { radius } => *radius,
                urdf_rs::Geometry::Cylinder { length, .. } => length / 2.0,
                other => panic!("unexpected geometry {other:?}"),
            };
            lo = lo.min(z - half);
            hi = hi.max(z + half);
        }
    }
    let height = hi - lo;
    assert!((1.6..=1.8).contains(&height), "height {height}");
    // Winter (2009) Table 4.1 fractions of body mass.
    let frac = |name: &str| {
        r.links
            .iter()
            .find(|l| l.name == name)
            .unwrap()
            .inertial
            .mass
            .value
            / mass
    };
    let close = |a: f64, b: f64| (a - b).abs() < 1e-4;
    assert!(close(frac("left_thigh"), 0.100));
    assert!(close(frac("right_shank"), 0.0465));
    assert!(close(frac("left_foot"), 0.0145));
    assert!(close(frac("left_arm") + frac("left_shoulder"), 0.050));
    assert!(close(frac("torso"), 0.081 + 0.216 + 0.139 + 0.142));
}

fn box_i(m: f64, s: [f64; 3]) -> [f64; 3] {
    [
        m * (s[1] * s[1] + s[2] * s[2]) / 12.0,
        m * (s[0] * s[0] + s[2] * s[2]) / 12.0,
        m * (s[0] * s[0] + s[1] * s[1]) / 12.0,
    ]
}

#[test]
fn inertias_match_the_collision_primitives() {
    let r = robot();
    let mass: f64 = r.links.iter().map(|l| l.inertial.mass.value).sum();
    for l in &r.links {
        let i = &l.inertial.inertia;
        let m = l.inertial.mass.value;
        let c = l.inertial.origin.xyz.0;
        let (com, diag): ([f64; 3], [f64; 3]) = match (l.name.as_str(), l.collision.as_slice()) {
            (_, [one]) => {
                let centre = one.origin.xyz.0;
                let d = match &one.geometry {
                    urdf_rs::Geometry::Box { size } => box_i(m, size.0),
                    urdf_rs::Geometry::Cylinder { radius, length } => {
                        let a = m * (3.0 * radius * radius + length * length) / 12.0;
                        [a, a, m * radius * radius / 2.0]
                    }
                    urdf_rs::Geometry::Sphere { radius } => [0.4 * m * radius * radius; 3],
                    other => panic!("unexpected geometry {other:?}"),
                };
                (centre, d)
            }
            ("torso", [pelvis, trunk, head]) => {
                // Winter: pelvis 0.142, thorax + abdomen 0.355, head + neck 0.081 of body mass.
                let parts = [
                    (0.142 * mass, pelvis),
                    (0.355 * mass, trunk),
                    (0.081 * mass, head),
                ];
                let total: f64 = parts.iter().map(|p| p.0).sum();
                assert!((total - m).abs() < 1e-3, "torso mass {m} vs {total}");
                let mut com = [0.0; 3];
                for (pm, p) in &parts {
                    for k in 0..3 {
                        com[k] += pm * p.origin.xyz.0[k] / total;
                    }
                }
                let mut d = [0.0; 3];
                for (pm, p) in &parts {
                    let own = match &p.geometry {
                        urdf_rs::Geometry::Box { size } => box_i(*pm, size.0),
                        urdf_rs::Geometry::Sphere { radius } => [0.4 * pm * radius * radius; 3],
                        other => panic!("unexpected torso geometry {other:?}"),
                    };
                    let o = p.origin.xyz.0;
                    let r = [o[0] - com[0], o[1] - com[1], o[2] - com[2]];
                    d[0] += own[0] + pm * (r[1] * r[1] + r[2] * r[2]);
                    d[1] += own[1] + pm * (r[0] * r[0] + r[2] * r[2]);
                    d[2] += own[2] + pm * (r[0] * r[0] + r[1] * r[1]);
                }
                (com, d)
            }
            (name, []) => {
                assert!(
                    name.ends_with("_shoulder") && m <= 0.2,
                    "{name} has no geometry"
                );
                continue;
            }
            (name, shapes) => panic!("{name}: unexpected {} shapes", shapes.len()),
        };
        let rel = |a: f64, b: f64| (a - b).abs() <= 1e-4 * b.abs().max(1e-6) + 1e-9;
        for k in 0..3 {
            assert!(
                (c[k] - com[k]).abs() < 1e-5,
                "{}: COM axis {k}: {} vs {}",
                l.name,
                c[k],
                com[k]
            );
        }
        assert!(
            rel(i.ixx, diag[0]) && rel(i.iyy, diag[1]) && rel(i.izz, diag[2]),
            "{}: {i:?} vs {diag:?}",
            l.name
        );
        assert!(
            i.ixy == 0.0 && i.ixz == 0.0 && i.iyz == 0.0,
            "{}: products of inertia",
            l.name
        );
    }
}
