//! Contract: malformed or hostile URDF input is refused with the error variant naming what is
//! wrong (and the link or joint at fault), never with a panic. Randomly damaged copies of the
//! humanoid either load or fail cleanly, and those that load simulate without panicking.

use esrl_sim::{Env, RobotModel, SimError, UrdfError, WalkConfig, WalkEnv};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const INERTIAL: &str = r#"<inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>"#;

fn link(name: &str) -> String {
    format!(r#"<link name="{name}">{INERTIAL}</link>"#)
}

fn joint(name: &str, kind: &str, parent: &str, child: &str) -> String {
    format!(
        r#"<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="5"/></joint>"#
    )
}

/// Whether an error is the expected one.
type Check = fn(&UrdfError) -> bool;

fn robot(body: &str) -> String {
    format!(r#"<robot name="r">{body}</robot>"#)
}

fn err(text: &str) -> UrdfError {
    match RobotModel::from_urdf_str(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

#[test]
fn a_valid_two_link_robot_loads() {
    let ok = robot(&format!(
        "{}{}{}",
        link("a"),
        link("b"),
        joint("j", "revolute", "a", "b")
    ));
    let m = RobotModel::from_urdf_str(&ok).unwrap();
    assert_eq!(m.links().len(), 2);
}

#[test]
fn each_defect_gets_its_error() {
    let two = |j: &str| robot(&format!("{}{}{}", link("a"), link("b"), j));
    let with_link = |inner: &str| {
        robot(&format!(
            r#"{}<link name="b">{inner}</link>{}"#,
            link("a"),
            joint("j", "revolute", "a", "b")
        ))
    };
    let inertial = |mass: &str, ixx: &str, izz: &str| {
        format!(
            r#"<inertial><mass value="{mass}"/><inertia ixx="{ixx}" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="{izz}"/></inertial>"#
        )
    };

    let cases: Vec<(&str, String, Check)> = vec![
        ("not xml", "this is not a robot".into(), |e| {
            matches!(e, UrdfError::Parse(_))
        }),
        ("truncated", robot(&link("a"))[..40].to_owned(), |e| {
            matches!(e, UrdfError::Parse(_))
        }),
        ("no links", robot(""), |e| matches!(e, UrdfError::NoLinks)),
        (
            "duplicate link",
            robot(&format!("{}{}", link("a"), link("a"))),
            |e| matches!(e, UrdfError::DuplicateLink(n) if n == "a"),
        ),
        (
            "duplicate joint",
            robot(&format!(
                "{}{}{}{}{}",
                link("a"),
                link("b"),
                link("c"),
                joint("j", "revolute", "a", "b"),
                joint("j", "revolute", "b", "c")
            )),
            |e| matches!(e, UrdfError::DuplicateJoint(n) if n == "j"),
        ),
        (
            "unknown parent",
            two(&joint("j", "revolute", "ghost", "b")),
            |e| matches!(e, UrdfError::UnknownParent { joint, link } if joint == "j" && link == "ghost"),
        ),
        (
            "unknown child",
            two(&joint("j", "revolute", "a", "ghost")),
            |e| matches!(e, UrdfError::UnknownChild { joint, link } if joint == "j" && link == "ghost"),
        ),
        (
            "self joint",
            two(&joint("j", "revolute", "a", "a")),
            |e| matches!(e, UrdfError::SelfJoint { joint, .. } if joint == "j"),
        ),
        (
            "cycle",
            robot(&format!(
                "{}{}{}{}{}",
                link("a"),
                link("b"),
                link("c"),
                joint("j1", "revolute", "b", "c"),
                joint("j2", "revolute", "c", "b")
            )),
            |e| matches!(e, UrdfError::Cycle { link } if link == "b" || link == "c"),
        ),
        (
            "closed loop, no root",
            robot(&format!(
                "{}{}{}{}",
                link("a"),
                link("b"),
                joint("j1", "revolute", "a", "b"),
                joint("j2", "revolute", "b", "a")
            )),
            |e| matches!(e, UrdfError::Cycle { .. }),
        ),
        (
            "two parents",
            robot(&format!(
                "{}{}{}{}{}",
                link("a"),
                link("b"),
                link("c"),
                joint("j1", "revolute", "a", "c"),
                joint("j2", "revolute", "b", "c")
            )),
            |e| matches!(e, UrdfError::SeveralParents { link, .. } if link == "c"),
        ),
        (
            "several roots",
            robot(&format!("{}{}", link("a"), link("b"))),
            |e| matches!(e, UrdfError::SeveralRoots { roots } if roots.len() == 2),
        ),
        (
            "negative mass",
            with_link(&inertial("-1", "0.1", "0.1")),
            |e| matches!(e, UrdfError::NonPhysicalInertial { link, .. } if link == "b"),
        ),
        (
            "missing inertial",
            with_link(""),
            |e| matches!(e, UrdfError::NonPhysicalInertial { link, .. } if link == "b"),
        ),
        (
            "indefinite inertia",
            with_link(&inertial("1", "-0.1", "0.1")),
            |e| matches!(e, UrdfError::NonPhysicalInertial { link, .. } if link == "b"),
        ),
        (
            "triangle inequality",
            with_link(&inertial("1", "0.1", "5")),
            |e| matches!(e, UrdfError::NonPhysicalInertial { link, .. } if link == "b"),
        ),
        (
            "NaN mass",
            with_link(&inertial("NaN", "0.1", "0.1")),
            |e| matches!(e, UrdfError::NonFinite { name, field, .. } if name == "b" && field == "inertial/mass"),
        ),
        (
            "infinite joint origin",
            two(
                r#"<joint name="j" type="revolute"><origin xyz="0 inf 0"/><parent link="a"/><child link="b"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#,
            ),
            |e| matches!(e, UrdfError::NonFinite { element: "joint", name, .. } if name == "j"),
        ),
        (
            "mesh",
            with_link(&format!(
                r#"{INERTIAL}<collision><geometry><mesh filename="package://x/leg.stl"/></geometry></collision>"#
            )),
            |e| matches!(e, UrdfError::MeshGeometry { link, filename } if link == "b" && filename.contains("leg.stl")),
        ),
        (
            "capsule",
            with_link(&format!(
                r#"{INERTIAL}<collision><geometry><capsule radius="0.1" length="0.3"/></geometry></collision>"#
            )),
            |e| matches!(e, UrdfError::UnsupportedGeometry { link, kind: "capsule" } if link == "b"),
        ),
        (
            "zero box",
            with_link(&format!(
                r#"{INERTIAL}<collision><geometry><box size="0.1 0 0.1"/></geometry></collision>"#
            )),
            |e| matches!(e, UrdfError::InvalidGeometry { link, .. } if link == "b"),
        ),
        (
            "prismatic",
            two(&joint("slide", "prismatic", "a", "b")),
            |e| matches!(e, UrdfError::UnsupportedJoint { joint, kind } if joint == "slide" && kind == "prismatic"),
        ),
        (
            "floating",
            two(&joint("free", "floating", "a", "b")),
            |e| matches!(e, UrdfError::UnsupportedJoint { joint, .. } if joint == "free"),
        ),
        (
            "inverted limits",
            two(
                r#"<joint name="j" type="revolute"><parent link="a"/><child link="b"/><limit lower="1" upper="-1" effort="1" velocity="1"/></joint>"#,
            ),
            |e| matches!(e, UrdfError::InvalidLimits { joint, .. } if joint == "j"),
        ),
        (
            "revolute without limit",
            two(r#"<joint name="j" type="revolute"><parent link="a"/><child link="b"/></joint>"#),
            |e| matches!(e, UrdfError::InvalidLimits { joint, .. } if joint == "j"),
        ),
        (
            "zero axis",
            two(
                r#"<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint>"#,
            ),
            |e| matches!(e, UrdfError::ZeroAxis { joint } if joint == "j"),
        ),
        (
            "negative damping",
            two(
                r#"<joint name="j" type="continuous"><parent link="a"/><child link="b"/><dynamics damping="-2"/></joint>"#,
            ),
            |e| matches!(e, UrdfError::Negative { joint, field: "dynamics damping", .. } if joint == "j"),
        ),
    ];
    assert!(cases.len() >= 10);
    for (what, text, check) in &cases {
        let e = err(text);
        assert!(check(&e), "{what}: wrong error {e:?}");
        assert!(!e.to_string().is_empty());
    }
}

#[test]
fn missing_file_names_the_path() {
    let e = RobotModel::from_urdf_path("/definitely/not/here.urdf").unwrap_err();
    assert!(
        matches!(&e, UrdfError::Io { path, .. } if path.ends_with("here.urdf")),
        "{e:?}"
    );
    assert!(e.to_string().contains("/definitely/not/here.urdf"));
}

#[test]
fn a_massless_root_is_refused_as_a_floating_base() {
    let text = robot(&format!(
        r#"<link name="world"/>{}{}"#,
        link("b"),
        joint("j", "revolute", "world", "b")
    ));
    let model = std::sync::Arc::new(RobotModel::from_urdf_str(&text).unwrap());
    let config = WalkConfig {
        actuated_joints: vec!["j".into()],
        foot_links: ["b".into(), "b".into()],
        standing_pose: Default::default(),
        ..WalkConfig::default()
    };
    match WalkEnv::from_model(model, config) {
        Err(SimError::Urdf(UrdfError::MasslessFloatingRoot { link })) => assert_eq!(link, "world"),
        Err(e) => panic!("wrong error {e:?}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn a_config_naming_missing_joints_is_refused() {
    let config = WalkConfig {
        actuated_joints: vec!["left_hip".into(), "left_elbow".into()],
        ..WalkConfig::default()
    };
    match WalkEnv::new(config) {
        Err(SimError::Model { field, reason }) => {
            assert_eq!(field, "actuated_joints");
            assert!(reason.contains("left_elbow"), "{reason}");
        }
        Err(e) => panic!("wrong error {e:?}"),
        Ok(_) => panic!("accepted"),
    }
}

/// Damages the humanoid at random (byte deletions, insertions, number corruption) and checks
/// that loading never panics, and that whatever loads also builds and steps without panicking.
#[test]
fn damaged_humanoids_never_panic() {
    let original = esrl_sim::HUMANOID_URDF.as_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let junk: &[&str] = &[
        "nan", "inf", "-1", "0", "1e30", "<", ">", "\"", "</link>", "<joint", "&", "\u{0}", "é",
    ];
    let (mut loaded, mut stepped) = (0, 0);
    for _ in 0..400 {
        let mut text = original.to_vec();
        for _ in 0..rng.random_range(1..4) {
            let at = rng.random_range(0..text.len());
            match rng.random_range(0..4) {
                0 => {
                    let n = rng.random_range(1..20).min(text.len() - at);
                    text.drain(at..at + n);
                }
                1 => {
                    let s = junk[rng.random_range(0..junk.len())];
                    text.splice(at..at, s.bytes());
                }
                2 => {
                    // Replace the next number with a hostile one.
                    if let Some(p) = text[at..].iter().position(|b| b.is_ascii_digit()) {
                        let s = junk[rng.random_range(0..6)];
                        text.splice(at + p..at + p + 1, s.bytes());
                    }
                }
                _ => text.truncate(at.max(1)),
            }
        }
        let text = String::from_utf8_lossy(&text).into_owned();
        let result = std::panic::catch_unwind(|| {
            let Ok(model) = RobotModel::from_urdf_str(&text) else {
                return (false, false);
            };
            let Ok(mut env) =
                WalkEnv::from_model(std::sync::Arc::new(model), WalkConfig::default())
            else {
                return (true, false);
            };
            env.reset(0);
            for _ in 0..5 {
                let s = env.step(&[1.0, -1.0, 1.0, -1.0, 1.0, -1.0]);
                assert!(s.obs.len() == env.obs_dim());
            }
            (true, true)
        });
        match result {
            Ok((l, s)) => {
                loaded += l as usize;
                stepped += s as usize;
            }
            Err(_) => panic!("panicked on damaged URDF:\n{text}"),
        }
    }
    // The damage is light enough that some copies still load and run.
    eprintln!("damaged copies: {loaded} loaded, {stepped} stepped");
    assert!(
        loaded > 0 && stepped > 0,
        "loaded {loaded}, stepped {stepped}"
    );
}

/// Valid but absurd numbers (huge efforts, feather-light links) must not crash the physics:
/// the episode ends (a non-finite state counts as a fall) instead.
#[test]
fn absurd_but_valid_values_do_not_panic() {
    let variants = [
        esrl_sim::HUMANOID_URDF.replace(r#"effort="150""#, r#"effort="1e30""#),
        esrl_sim::HUMANOID_URDF.replace(r#"<mass value="1.015"/>"#, r#"<mass value="1e-9"/>"#),
        esrl_sim::HUMANOID_URDF.replace(r#"<mass value="7"/>"#, r#"<mass value="1e9"/>"#),
    ];
    for text in variants {
        let model = std::sync::Arc::new(RobotModel::from_urdf_str(&text).unwrap());
        let mut env = WalkEnv::from_model(model, WalkConfig::default()).unwrap();
        env.reset(0);
        for _ in 0..200 {
            let s = env.step(&[1.0, -1.0, 1.0, -1.0, 1.0, -1.0]);
            assert!(s.reward.is_finite());
            if s.terminated {
                break;
            }
        }
    }
}
