//! Contract: a constant action that presses both hips into their +30° limit and both knees
//! into their 5° limit, with any constant ankle action, held for 60 s, either falls or moves
//! the torso less than 3 m from t = 1 s on (0.05 m/s, 5 % of the paper's ES-SAC walking speed
//! of 1.05 m/s), at the default physics settings, from several reset seeds, with the default
//! actuator armature and with the `quick` preset's 0.5. Such a stance is a rigid object on
//! flat ground: it must not travel. With `hard` limits at the same integrator step the
//! limit-pressed joints chatter and the feet ratchet the body across the floor (about 9 m in a
//! minute), which learned policies exploited; the last test shows that this contract catches it.

use esrl_sim::bench::rigid_stance_travel;
use esrl_sim::{LimitModel, WalkConfig, WalkEnv};

/// Travel of a rigid stance that lasts 60 s may be at most this, m.
const LIMIT: f32 = 0.05 * 59.0;

#[test]
fn a_limit_pressing_stance_falls_or_stays_put() {
    for armature in [WalkConfig::default().physics.actuator_armature, 0.5] {
        let mut config = WalkConfig::default();
        config.physics.actuator_armature = armature;
        let mut env = WalkEnv::new(config).unwrap();
        for seed in [1, 2, 3] {
            for ankle in [-1.0, -0.6, -0.3, 0.0, 0.5] {
                if let Some(d) = rigid_stance_travel(&mut env, seed, ankle) {
                    assert!(
                        d < LIMIT,
                        "armature {armature}, seed {seed}, ankle {ankle}: travelled {d:.2} m in 59 s"
                    );
                }
            }
        }
    }
}

#[test]
fn with_hard_limits_the_same_stance_creeps() {
    let mut config = WalkConfig::default();
    config.physics.joint_limits = LimitModel::Hard;
    config.physics.actuator_armature = 0.5;
    let mut env = WalkEnv::new(config).unwrap();
    let d = rigid_stance_travel(&mut env, 2, -1.0);
    assert!(
        d.is_some_and(|d| d > LIMIT),
        "hard limits at the default step: {d:?} (expected a stance that stays up and creeps)"
    );
}
