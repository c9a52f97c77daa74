//! Contract: an evaluation episode's return split by reward term is each term of every step
//! summed over the episode (checked against a loop over the environment's own steps), and the
//! terms add up to the return.

use esrl_eval::rollout;
use esrl_sim::{Env, WalkConfig, WalkEnv};

/// A fixed, non-trivial action: the legs bend a little, so several terms are non-zero.
fn act(_: &[f32], action: &mut [f32]) {
    for (i, a) in action.iter_mut().enumerate() {
        *a = 0.3 * ((i as f32) * 0.7).sin();
    }
}

#[test]
fn return_terms_are_the_steps_terms_summed() {
    let config = WalkConfig {
        episode_seconds: 3.0,
        ..WalkConfig::default()
    };
    let seed = 5;
    let mut env = WalkEnv::new(config.clone()).unwrap();
    let r = rollout(&mut env, seed, act, |_, _, _| Ok(())).unwrap();

    // The same episode stepped by hand.
    let mut env = WalkEnv::new(config).unwrap();
    let mut obs = env.reset(seed);
    let mut action = vec![0.0; env.act_dim()];
    let mut sums: Vec<(&'static str, f64)> = Vec::new();
    let mut steps = 0;
    loop {
        act(&obs, &mut action);
        let step = env.step(&action);
        steps += 1;
        for &(name, value) in &step.info.reward_terms {
            match sums.iter_mut().find(|(n, _)| *n == name) {
                Some((_, s)) => *s += f64::from(value),
                None => sums.push((name, f64::from(value))),
            }
        }
        if step.terminated || step.truncated || steps == env.max_episode_steps() {
            break;
        }
        obs = step.obs;
    }
    assert_eq!(r.length, steps);
    assert_eq!(r.return_terms, sums);
    assert!(
        sums.iter().filter(|(_, s)| *s != 0.0).count() >= 3,
        "several terms pay: {sums:?}"
    );
    // The terms of a step sum to its single-precision reward; over the episode their sums
    // differ from the return only by that rounding.
    let total: f64 = sums.iter().map(|(_, s)| s).sum();
    assert!(
        (total - r.ret).abs() <= 1e-5 * steps as f64,
        "terms sum to {total}, return {}",
        r.ret
    );
}
