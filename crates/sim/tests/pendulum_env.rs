//! Contract: `Pendulum` is Gymnasium's `Pendulum-v1`. Expected values below were computed by
//! hand from the formulas in `gymnasium/envs/classic_control/pendulum.py` (θ̇' = θ̇ + (3g/(2l)
//! sin θ + 3u/(m l²)) dt, clipped to ±8; θ' = θ + θ̇' dt; reward −(norm(θ)² + 0.1 θ̇² +
//! 0.001 u²); g = 10, m = l = 1, dt = 0.05, |u| ≤ 2; truncation at 200 steps).

use esrl_sim::pendulum::angle_normalize;
use esrl_sim::{Env, Pendulum};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn one_step_matches_the_formulas() {
    let mut env = Pendulum::new();
    env.set_state(1.0, 0.5);
    // Action 0.25 → u = 0.5 N·m.
    let s = env.step(&[0.25]);
    let (th, thd) = env.state();
    assert!(close(thd, 1.2061032386059223, 1e-12), "θ̇ {thd}");
    assert!(close(th, 1.0603051619302961, 1e-12), "θ {th}");
    assert!(
        close(s.reward as f64, -1.02525, 1e-6),
        "reward {}",
        s.reward
    );
    assert!(close(s.obs[0] as f64, 0.4886058494189488, 1e-6));
    assert!(close(s.obs[1] as f64, 0.8725046268723092, 1e-6));
    assert!(close(s.obs[2] as f64, 1.2061032386059223, 1e-6));
    let sum: f32 = s.info.reward_terms.iter().map(|t| t.1).sum();
    assert!(close(sum as f64, s.reward as f64, 1e-6));
    assert!(!s.terminated && !s.truncated);
}

#[test]
fn speed_is_clipped_and_actions_saturate() {
    let mut env = Pendulum::new();
    env.set_state(1.0, 7.9);
    // Action 5 is clipped to 1 → u = 2; θ̇ would reach 8.83 and is clipped to 8.
    let s = env.step(&[5.0]);
    let (th, thd) = env.state();
    assert_eq!(thd, 8.0);
    assert!(close(th, 1.4, 1e-12), "θ {th}");
    assert!(close(s.reward as f64, -7.245, 1e-5), "reward {}", s.reward);
}

#[test]
fn angles_are_normalized_in_the_cost() {
    assert!(close(angle_normalize(4.0), -2.2831853071795862, 1e-12));
    assert!(close(angle_normalize(-4.0), 2.2831853071795862, 1e-12));
    assert!(close(angle_normalize(0.3), 0.3, 1e-12));
    let mut env = Pendulum::new();
    env.set_state(4.0, 0.0);
    let s = env.step(&[0.0]);
    assert!(
        close(s.reward as f64, -5.212935146920741, 1e-5),
        "reward {}",
        s.reward
    );
}

#[test]
fn episodes_truncate_at_200_steps_and_never_terminate() {
    let mut env = Pendulum::new();
    env.reset(0);
    for i in 1..=200 {
        let s = env.step(&[1.0]);
        assert!(!s.terminated);
        assert_eq!(s.truncated, i == 200, "step {i}");
    }
    assert_eq!(env.max_episode_steps(), 200);
    assert_eq!(env.control_period(), 0.05);
    assert_eq!((env.obs_dim(), env.act_dim()), (3, 1));
}

#[test]
fn reset_draws_from_the_gymnasium_ranges() {
    let mut env = Pendulum::new();
    let (mut th_lo, mut th_hi, mut v_lo, mut v_hi) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for seed in 0..2000 {
        let obs = env.reset(seed);
        let (th, thd) = env.state();
        assert!((-std::f64::consts::PI..=std::f64::consts::PI).contains(&th));
        assert!((-1.0..=1.0).contains(&thd));
        assert!(close(obs[0] as f64, th.cos(), 1e-6) && close(obs[1] as f64, th.sin(), 1e-6));
        th_lo = th_lo.min(th);
        th_hi = th_hi.max(th);
        v_lo = v_lo.min(thd);
        v_hi = v_hi.max(thd);
    }
    // Uniform draws over 2000 seeds cover the ranges.
    assert!(th_lo < -3.0 && th_hi > 3.0 && v_lo < -0.95 && v_hi > 0.95);
}
