//! Contract: `bench::bench_walk` (behind `esrl bench env`) runs the requested number of control
//! steps with random actions, resets after every episode, and reports the physics settings it
//! ran with.

use esrl_sim::bench::bench_walk;
use esrl_sim::{ActionMode, LimitModel, WalkConfig};

#[test]
fn bench_reports_what_it_ran() {
    let mut config = WalkConfig::default();
    config.physics.substeps = 2;
    config.physics.solver_iterations = 3;
    config.physics.joint_limits = LimitModel::Hard;
    config.action = ActionMode::Target;
    let r = bench_walk(&config, 300, 11).unwrap();
    assert_eq!(r.steps, 300);
    assert!(r.steps_per_s > 0.0 && r.wall_s > 0.0);
    assert!((r.steps_per_s * r.wall_s - 300.0).abs() < 1e-6 * 300.0);
    // Random torques topple the robot within seconds: several episodes, all but the last
    // ended by a fall.
    assert!(r.episodes > 2, "{r:?}");
    assert_eq!(r.falls, r.episodes - 1);
    assert_eq!((r.substeps, r.solver_iterations), (2, 3));
    assert_eq!(
        (r.joint_limits, r.action),
        (LimitModel::Hard, ActionMode::Target)
    );
    assert_eq!(r.control_period, 0.025);
    assert_eq!(r.dt, 0.0125);
    assert_eq!((r.obs_dim, r.act_dim), (43, 6));
    let bad = WalkConfig {
        control_period: -1.0,
        ..WalkConfig::default()
    };
    assert!(bench_walk(&bad, 10, 0).is_err());
}
