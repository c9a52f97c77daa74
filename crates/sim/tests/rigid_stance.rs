//! Contract: a stance with both hips and knees pressed into their joint limits at full effort
//! and constant ankle torques is a rigid object on flat ground, so once it has settled (after
//! the first second) it must not travel: with the default physics, every such stance that
//! stays up for 60 s moves less than 0.05 m/s on average (5 % of the paper's ES-SAC walking
//! speed, 1.05 m/s), with the default actuator armature and with the `quick` preset's 0.5.
//! A coarser integrator lets the limit-pressed joints chatter and the feet ratchet the body
//! across the floor (9 m in a minute at 4 solver iterations), which learned policies exploit.

use esrl_sim::bench::rigid_stance_travel;
use esrl_sim::{WalkConfig, WalkEnv};

#[test]
fn a_rigid_stance_does_not_creep() {
    let limit = 0.05 * 59.0;
    let mut upright = 0;
    for armature in [WalkConfig::default().physics.actuator_armature, 0.5] {
        let mut config = WalkConfig::default();
        config.physics.actuator_armature = armature;
        let mut env = WalkEnv::new(config).unwrap();
        for (seed, ankle) in [(1, -1.0), (1, -0.6), (2, -1.0), (2, -0.6), (3, -0.3)] {
            if let Some(d) = rigid_stance_travel(&mut env, seed, ankle) {
                upright += 1;
                assert!(
                    d < limit,
                    "armature {armature}, seed {seed}, ankle {ankle}: travelled {d:.2} m in 59 s"
                );
            }
        }
    }
    // The check means nothing if every stance fell.
    assert!(upright >= 2, "only {upright} of 10 stances stayed up");
}
