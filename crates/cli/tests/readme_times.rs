//! Contract: the times the start banner states come from one place
//! (`TrainConfig::typical_time`), and the README's quick start states the same ones.

use esrl_run::config::{
    TIME_PENDULUM, TIME_QUICK, TIME_WALKER, TIME_WALKER_EVEN, TIME_WALKER_FAST, TIME_WALKER_MIRROR,
    TIME_WALKER_ROBUST, TIME_WALKING, TIME_WALKING_TORQUE,
};
use esrl_run::{AgentKind, EnvKind, Preset, TrainConfig};

#[test]
fn the_readme_states_the_banner_times() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    for t in [
        TIME_WALKER_EVEN,
        TIME_WALKER_MIRROR,
        TIME_WALKER_ROBUST,
        TIME_WALKER,
        TIME_WALKER_FAST,
        TIME_WALKING_TORQUE,
        TIME_WALKING,
        TIME_QUICK,
        TIME_PENDULUM,
    ] {
        assert!(readme.contains(t), "the README lacks {t:?}");
    }
    let default = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::default());
    assert_eq!(default.typical_time(), Some(TIME_WALKER_EVEN));
    let robust = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::WalkerRobust);
    assert_eq!(robust.typical_time(), Some(TIME_WALKER_ROBUST));
    let mirror = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::WalkerMirror);
    assert_eq!(mirror.typical_time(), Some(TIME_WALKER_MIRROR));
    let walker = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::Walker);
    assert_eq!(walker.typical_time(), Some(TIME_WALKER));
    let fast = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::WalkerFast);
    assert_eq!(fast.typical_time(), Some(TIME_WALKER_FAST));
    let torque = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::WalkingTorque);
    assert_eq!(torque.typical_time(), Some(TIME_WALKING_TORQUE));
    let walking = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::Walking);
    assert_eq!(walking.typical_time(), Some(TIME_WALKING));
    let pendulum = TrainConfig::preset(AgentKind::Sac, EnvKind::Pendulum, Preset::default());
    assert_eq!(pendulum.typical_time(), Some(TIME_PENDULUM));
    let quick = TrainConfig::preset(AgentKind::EsSac, EnvKind::Walk, Preset::Quick);
    assert_eq!(quick.typical_time(), Some(TIME_QUICK));
}
