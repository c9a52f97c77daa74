//! Contract: `--preset walking` is exactly `quick` with the overlay documented in
//! `results/walking/overlay.toml` (the configuration of the runs in `results/walking`), and
//! plain agents under it learn at the same update-to-data ratio within the same step budget.

mod common;

use common::{options, without_preset_name};
use esrl_agents::LearnEvery;
use esrl_run::{AgentKind, EnvKind, Overrides, Preset, TrainConfig};
use std::path::PathBuf;

/// `preset` resolved for `agent` on the pendulum, without its name.
fn on_pendulum(agent: AgentKind, preset: Preset) -> String {
    let o = Overrides {
        preset,
        env: Some(EnvKind::Pendulum),
        ..Overrides::default()
    };
    without_preset_name(&TrainConfig::resolve(agent, &o, Some(0)).unwrap())
}

#[test]
fn walking_is_quick_with_the_documented_overlay() {
    let overlay =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../results/walking/overlay.toml");
    for agent in [AgentKind::EsSac, AgentKind::EsTd3, AgentKind::EsDdpg] {
        let documented = TrainConfig::resolve(
            agent,
            &options(Preset::Quick, Some(overlay.clone()), None),
            Some(0),
        )
        .unwrap();
        let walking =
            TrainConfig::resolve(agent, &options(Preset::Walking, None, None), Some(0)).unwrap();
        assert_eq!(walking.preset, Preset::Walking);
        assert_eq!(walking.env, EnvKind::Walk);
        assert_eq!(
            without_preset_name(&walking),
            without_preset_name(&documented)
        );
        assert_eq!(walking.updates_per_step, Some(0.25));
        assert_eq!(walking.max_env_steps, Some(4_000_000));
        assert_eq!(walking.best_every_steps, Some(1_000_000));
        assert_eq!(
            walking.walk.gait_clock.as_ref().map(|c| c.chatter),
            Some(1.0)
        );
        assert_eq!(walking.walk.target.range, Some(0.3));
        assert!(!walking.walk.end_at_finish);
        assert_eq!(walking.walk.reward.forward_cap, Some(1.1));
        assert!(walking.rl.clip_targets);
    }
}

#[test]
fn plain_agents_learn_at_the_same_ratio_within_the_same_steps() {
    let hybrid = TrainConfig::resolve(
        AgentKind::EsSac,
        &options(Preset::Walking, None, None),
        Some(0),
    )
    .unwrap();
    for agent in [AgentKind::Sac, AgentKind::Td3, AgentKind::Ddpg] {
        let plain =
            TrainConfig::resolve(agent, &options(Preset::Walking, None, None), Some(0)).unwrap();
        assert_eq!(plain.max_env_steps, hybrid.max_env_steps);
        assert_eq!(plain.rl.learn_every, LearnEvery::Steps(4));
        assert_eq!(plain.rl.updates_per_learn, 1);
        // The step budget ends training, not the episode count.
        assert!(plain.episodes as u64 * 2400 > plain.max_env_steps.unwrap());
        assert_eq!(plain.walk, hybrid.walk);
        assert!(plain.rl.clip_targets);
        assert_eq!(plain.network, hybrid.network);
    }
    // `quick` itself is untouched.
    let quick = TrainConfig::resolve(
        AgentKind::EsSac,
        &options(Preset::Quick, None, None),
        Some(0),
    )
    .unwrap();
    assert_eq!(quick.updates_per_step, None);
    assert!(quick.walk.gait_clock.is_none());
    assert!(quick.walk.end_at_finish && quick.walk.reward.forward_cap.is_none());
    assert!(!quick.rl.clip_targets);
}

/// `walking-torque` is `walking` on torque actions that stops at the first walk, with the
/// generation cap lifted: those keys and nothing else, for every agent on the walking env,
/// and the pendulum's settings are `walking`'s.
#[test]
fn walking_torque_is_walking_on_torques_until_the_first_walk() {
    for agent in AgentKind::ALL {
        let walking =
            TrainConfig::resolve(agent, &options(Preset::Walking, None, None), Some(0)).unwrap();
        let torque =
            TrainConfig::resolve(agent, &options(Preset::WalkingTorque, None, None), Some(0))
                .unwrap();
        let differ = esrl_run::config::config_differences(&walking, &torque).unwrap();
        assert_eq!(
            differ,
            [
                "generations: 3000 vs 20000",
                "preset: \"walking\" vs \"walking-torque\"",
                "stop_at_walk: none vs true",
                "walk.action: \"target\" vs \"torque\"",
            ],
            "{agent:?}"
        );
    }
}

/// `walker` is `walking-torque` with the stricter stop (all 10 check starts at the line,
/// then 19 of 20; checks stopped once out of reach) and `[restart]` at its defaults: those
/// keys and nothing else on the walking env; on the pendulum (no check, so no restart) every
/// preset of the recipe resolves alike.
#[test]
fn walker_is_walking_torque_with_a_stricter_stop_and_restarts() {
    for agent in AgentKind::ALL {
        let torque =
            TrainConfig::resolve(agent, &options(Preset::WalkingTorque, None, None), Some(0))
                .unwrap();
        let walker =
            TrainConfig::resolve(agent, &options(Preset::Walker, None, None), Some(0)).unwrap();
        assert_eq!(walker.preset, Preset::Walker);
        let differ = esrl_run::config::config_differences(&torque, &walker).unwrap();
        assert_eq!(
            differ,
            [
                "check.confirm_starts: 0 vs 10",
                "check.finish_share: 0.8 vs 0.95",
                // `stop_early = false` is left out of config.toml: "none".
                "check.stop_early: none vs true",
                "preset: \"walking-torque\" vs \"walker\"",
                "restart: none vs { at_steps = 1000000, max = 2, min_distance = 15.0, whole_budget = false }",
            ],
            "{agent:?}"
        );
        let on = |preset| on_pendulum(agent, preset);
        assert_eq!(on(Preset::Walker), on(Preset::Walking), "{agent:?}");
        assert_eq!(on(Preset::WalkingTorque), on(Preset::Walking), "{agent:?}");
    }
}

/// Contract: `results/clock-fast/fast40.toml`, the file the screen's runs are written as, is
/// `walker` (the default until 2026-12-07) with its 0.8 s gait clock, speed paid up to
/// 1.4 m/s and a stop at the line within 40 s, and changes nothing else; the preset
/// `walker-fast` is the same with a budget of 5 M env steps instead of 4 on the walk, and
/// `walker` on the pendulum, for every agent.
#[test]
fn the_fast40_file_is_walker_with_a_faster_clock_a_higher_cap_and_a_stop_at_40_s() {
    let file =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../results/clock-fast/fast40.toml");
    let agent = AgentKind::EsSac;
    let fast = TrainConfig::resolve(
        agent,
        &options(Preset::Walker, Some(file.clone()), None),
        Some(0),
    )
    .unwrap();
    let mut walker =
        TrainConfig::resolve(agent, &options(Preset::Walker, None, None), Some(0)).unwrap();
    assert_ne!(fast, walker);
    if let Some(clock) = &mut walker.walk.gait_clock {
        clock.period = 0.8;
    }
    walker.walk.reward.forward_cap = Some(1.4);
    if let Some(check) = &mut walker.check {
        check.max_track_time = Some(40.0);
    }
    assert_eq!(fast, walker);
    for agent in AgentKind::ALL {
        let on = |preset, file: Option<&PathBuf>| {
            let o = options(preset, file.cloned(), None);
            TrainConfig::resolve(agent, &o, Some(0)).unwrap()
        };
        let mut fast_file = on(Preset::Walker, Some(&file));
        assert_eq!(fast_file.max_env_steps, Some(4_000_000), "{agent:?}");
        fast_file.max_env_steps = Some(5_000_000);
        assert_eq!(
            without_preset_name(&on(Preset::WalkerFast, None)),
            without_preset_name(&fast_file),
            "{agent:?}"
        );
        let pendulum =
            |preset| without_preset_name(&TrainConfig::preset(agent, EnvKind::Pendulum, preset));
        assert_eq!(
            pendulum(Preset::WalkerFast),
            pendulum(Preset::Walker),
            "{agent:?}"
        );
    }
}

/// `walker-mirror` is `walker-fast` with mirrored transitions
/// (`rl.mirror`, every agent) and the ES mean's check (`check.mean`, the hybrid agents, which
/// have a mean) on the walking env, and nothing else; on the pendulum, which has no mirror
/// and no check, it resolves as `walker` does. The study it was chosen on ran
/// `walker-fast` with exactly these two keys set
/// (`results/unseen-starts/mirror-mean/study.toml`).
#[test]
fn walker_mirror_is_walker_fast_with_mirrored_transitions_and_the_means_check() {
    for agent in AgentKind::ALL {
        let fast =
            TrainConfig::resolve(agent, &options(Preset::WalkerFast, None, None), Some(0)).unwrap();
        let mirror =
            TrainConfig::resolve(agent, &options(Preset::WalkerMirror, None, None), Some(0))
                .unwrap();
        let differ = esrl_run::config::config_differences(&fast, &mirror).unwrap();
        let mut expected = vec![
            "preset: \"walker-fast\" vs \"walker-mirror\"",
            // `mirror = false` is left out of config.toml: "none".
            "rl.mirror: none vs true",
        ];
        if agent.is_hybrid() {
            // `mean = false` is left out of config.toml: "none".
            expected.insert(0, "check.mean: none vs true");
        }
        assert_eq!(differ, expected, "{agent:?}");
        assert_eq!(
            on_pendulum(agent, Preset::WalkerMirror),
            on_pendulum(agent, Preset::Walker),
            "{agent:?}"
        );
    }
}

/// The default preset is `walker-even`: `walker-mirror` with a margin of symmetry in the
/// walking check (`check.max_knee_asymmetry = 0.1`, every agent, on the walking env) and a
/// whole budget of 4 M env steps, a restart's included, and nothing else; on the pendulum,
/// which has no check, it resolves as `walker` does. Its seed study ran `walker-mirror` with
/// the margin (`results/unseen-starts/mirror-mean-even/study.toml`); every run of it had
/// handed over its policy by 3.94 M env steps, so the budget changes none of them.
#[test]
fn the_default_is_walker_mirror_with_a_margin_of_symmetry_and_a_whole_budget() {
    assert_eq!(Preset::default(), Preset::WalkerEven);
    for agent in AgentKind::ALL {
        let mirror =
            TrainConfig::resolve(agent, &options(Preset::WalkerMirror, None, None), Some(0))
                .unwrap();
        let default = TrainConfig::resolve(agent, &Overrides::default(), Some(0)).unwrap();
        assert_eq!(default.preset, Preset::WalkerEven);
        assert_eq!(
            default.check.as_ref().unwrap().max_knee_asymmetry,
            Some(0.1)
        );
        let differ = esrl_run::config::config_differences(&mirror, &default).unwrap();
        assert_eq!(
            differ,
            [
                // No margin is left out of config.toml: "none".
                "check.max_knee_asymmetry: none vs 0.1",
                "max_env_steps: 5000000 vs 4000000",
                "preset: \"walker-mirror\" vs \"walker-even\"",
                "restart.whole_budget: false vs true",
            ],
            "{agent:?}"
        );
        assert_eq!(
            on_pendulum(agent, Preset::WalkerEven),
            on_pendulum(agent, Preset::Walker),
            "{agent:?}"
        );
    }
}

#[test]
fn walker_robust_is_the_committed_descent_file_over_the_default_from_a_walk() {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../results/robustness/downhill-probes/even-down01-cap11.toml");
    let walk = PathBuf::from("/runs/even-s2/best");
    for agent in AgentKind::ALL {
        // The screens' command: the default, the file, `--steps 1500000 --until budget`.
        let screened = TrainConfig::resolve(
            agent,
            &Overrides {
                config: Some(file.clone()),
                steps: Some(1_500_000),
                stop_at_walk: Some(false),
                init: Some(walk.clone()),
                ..options(Preset::WalkerEven, None, None)
            },
            Some(2),
        )
        .unwrap();
        let robust = TrainConfig::resolve(
            agent,
            &Overrides {
                init: Some(walk.clone()),
                ..options(Preset::WalkerRobust, None, None)
            },
            Some(2),
        )
        .unwrap();
        assert_eq!(robust.preset, Preset::WalkerRobust);
        assert_eq!(
            without_preset_name(&robust),
            without_preset_name(&screened),
            "{agent:?}"
        );
        assert_eq!(robust.walk.reward.forward_cap, Some(1.1));
        assert_eq!(robust.walk.perturb.slope_range, Some([-8.0, 5.0]));
        // The restart rule is judged past the budget: it never fires.
        assert!(robust.restart.as_ref().unwrap().at_steps > robust.max_env_steps.unwrap());
        // Without a walk to start from, the walking task is refused by name.
        let err = TrainConfig::resolve(agent, &options(Preset::WalkerRobust, None, None), Some(2))
            .unwrap_err()
            .to_string();
        assert!(err.contains("--init RUN/best"), "{err}");
        // On the pendulum it is the default's (no robot to disturb, no walk needed).
        assert_eq!(
            on_pendulum(agent, Preset::WalkerRobust),
            on_pendulum(agent, Preset::WalkerEven),
            "{agent:?}"
        );
    }
}
