//! Contract: `check.confirm_starts` runs more starts only for a policy at the bar on its first
//! ones, and judges the bar again on all of them. The committed flagship walk is at the bar
//! from its first 2 starts and is confirmed on 2 more; the standing pose (a zero actor) is
//! below the bar and runs its 2 starts alone.

use esrl_run::check::{CheckConfig, Checker};
use esrl_run::{build, checkpoint, TrainConfig};
use std::path::PathBuf;

fn flagship() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../results/walking/flagship")
}

#[test]
fn only_a_policy_at_the_bar_is_run_from_the_confirmation_starts() {
    let dir = flagship();
    let cfg = TrainConfig::load(&dir.join("config.toml")).unwrap();
    let envs = build::envs(cfg.env, &cfg.walk).unwrap();
    let mut walker = build::agent(&cfg, &envs).unwrap();
    checkpoint::load_agent(&dir, &mut walker).unwrap();
    let mut stander = walker.clone();
    stander
        .set_genome(&vec![0.0; stander.genome_len()])
        .unwrap();
    let config = CheckConfig {
        starts: 2,
        confirm_starts: 2,
        ..CheckConfig::default()
    };
    let checker = Checker::new(
        config.clone(),
        build::load_model(&cfg.walk).unwrap(),
        cfg.walk.clone(),
        cfg.seed,
    );

    let walk = checker.check(&walker).unwrap();
    assert_eq!(
        (walk.starts, walk.confirm_starts),
        (4, 2),
        "{}",
        walk.describe()
    );
    assert!(walk.at_bar, "{}", walk.describe());
    // The first two starts alone give the unconfirmed check's figures.
    let unconfirmed = Checker::new(
        CheckConfig {
            confirm_starts: 0,
            ..config
        },
        build::load_model(&cfg.walk).unwrap(),
        cfg.walk.clone(),
        cfg.seed,
    )
    .check(&walker)
    .unwrap();
    assert_eq!((unconfirmed.starts, unconfirmed.confirm_starts), (2, 0));
    assert!(unconfirmed.at_bar);
    assert!(walk.check_steps > unconfirmed.check_steps);

    let stand = checker.check(&stander).unwrap();
    assert_eq!(
        (stand.starts, stand.confirm_starts),
        (2, 0),
        "{}",
        stand.describe()
    );
    assert!(!stand.at_bar && stand.finished == 0);
}
