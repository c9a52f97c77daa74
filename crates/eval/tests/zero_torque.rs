//! Contract: a scripted zero-torque policy, driven through the evaluation library on the
//! default walking environment, collapses: the episode terminates early with a fall, the gait
//! metrics report `fell` and no track time, and no torque was applied.

use esrl_eval::walk_episode;
use esrl_sim::{Env, WalkConfig, WalkEnv};

#[test]
fn zero_torque_falls_and_never_finishes() {
    let config = WalkConfig {
        episode_seconds: 10.0,
        ..WalkConfig::default()
    };
    let mut env = WalkEnv::new(config).unwrap();
    let max = env.max_episode_steps();
    let mut steps = 0;
    let ep = walk_episode(
        &mut env,
        7,
        |_, action| action.fill(0.0),
        |_, _, _| {
            steps += 1;
            Ok(())
        },
    )
    .unwrap();
    assert!(ep.rollout.terminated, "a limp robot must fall");
    assert!(!ep.rollout.truncated);
    assert!(ep.rollout.length < max, "fell before the time limit");
    assert_eq!(ep.rollout.length, steps, "on_step sees every step");
    let g = ep
        .metrics(50.0)
        .unwrap()
        .expect("finite samples were logged");
    assert!(g.fell);
    assert_eq!(g.track_time, None);
    assert_eq!(g.steps, ep.rollout.length);
    assert!(
        g.distance.abs() < 1.0,
        "a fall does not walk: {} m",
        g.distance
    );
    assert_eq!(
        g.mean_abs_torque_overall, 0.0,
        "zero actions apply no torque"
    );
    assert_eq!(g.mean_abs_power_overall, 0.0);
    assert_eq!(
        g.knee_torque_asymmetry, 0.0,
        "both knees at 0 are symmetric"
    );
    assert!(
        g.mean_vertical < 0.0,
        "the torso ends below its standing height"
    );
}
