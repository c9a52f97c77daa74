//! Contract: on the walking environment, a constant limit-pressing action
//! `[1, −1, a, 1, −1, a]` (hips driven into their +30° stop, knees into their 5° stop, a
//! constant ankle torque) never classifies as `walk`, whether the robot topples or stays up
//! and creeps; a stance that stays up the whole episode (20 s, to keep the test short) is
//! `stand`, `shuffle` or `hop` (hard limits at the default physics step chatter, and the
//! stance bounces on them) with its knees on their stop. The stances are those of `esrl-sim`'s
//! rigid-stance test, at the default actuator armature and the `quick` preset's 0.5, plus two
//! with the ankles pushing forward; under the default (fading) joint limits they topple, so
//! the hard limits, under which such stances stay up and creep, are tried as well.

use esrl::eval::walk_episode;
use esrl_metrics::GaitClass;
use esrl_sim::{LimitModel, WalkConfig, WalkEnv};

#[test]
fn a_limit_pressed_stance_is_no_walk() {
    let mut upright = 0;
    let armatures = [WalkConfig::default().physics.actuator_armature, 0.5];
    let limits = [WalkConfig::default().physics.joint_limits, LimitModel::Hard];
    for (armature, limit) in armatures
        .iter()
        .flat_map(|&a| limits.iter().map(move |&l| (a, l)))
    {
        let mut config = WalkConfig {
            episode_seconds: 20.0,
            ..WalkConfig::default()
        };
        config.physics.actuator_armature = armature;
        config.physics.joint_limits = limit;
        let mut env = WalkEnv::new(config).unwrap();
        let stances = [
            (1, -1.0f32),
            (1, -0.6),
            (2, -1.0),
            (2, -0.6),
            (3, -0.3),
            (4, 0.0),
            (5, 0.5),
        ];
        for (seed, ankle) in stances {
            let action = [1.0, -1.0, ankle, 1.0, -1.0, ankle];
            let ep = walk_episode(
                &mut env,
                seed,
                |_, a| a.copy_from_slice(&action),
                |_, _, _| Ok(()),
            )
            .unwrap();
            let g = ep.metrics(50.0).unwrap().expect("finite samples");
            let c = g.cycle.expect("two feet give a gait cycle");
            let what = format!(
                "{limit:?} limits, armature {armature}, seed {seed}, ankle {ankle}: fell {} \
                 after {} s, {}",
                g.fell, g.duration, c.gait_class
            );
            eprintln!("{what}");
            assert_ne!(c.gait_class, GaitClass::Walk, "{what}: {c:?}");
            if !g.fell {
                upright += 1;
                assert!(
                    matches!(
                        c.gait_class,
                        GaitClass::Stand | GaitClass::Shuffle | GaitClass::Hop
                    ),
                    "{what}: {c:?}"
                );
                for knee in g.joints.iter().filter(|j| j.name.contains("knee")) {
                    assert!(knee.at_lower.unwrap() > 0.9, "{what}: {knee:?}");
                }
            }
        }
    }
    // The upright checks mean nothing if every stance fell (under hard limits some stay up).
    assert!(upright >= 1, "every stance fell");
}
