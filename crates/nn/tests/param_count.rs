//! Contract: the parameter counts computed from a config (for memory estimates before
//! anything is allocated) equal those of the networks built from it, and widths past
//! `MAX_WIDTH` are refused by name.

use esrl_nn::{Actor, ActorConfig, Critic, CriticConfig, Module, MAX_WIDTH};

#[test]
fn counts_match_built_networks() {
    let actors = [
        ActorConfig::paper(),
        ActorConfig::feed_forward(),
        ActorConfig {
            fc: vec![7, 5, 3],
            lstm_hidden: 4,
            ..ActorConfig::default()
        },
        ActorConfig {
            fc: vec![],
            ..ActorConfig::default()
        },
    ];
    for (obs, act) in [(43, 6), (3, 1)] {
        for cfg in &actors {
            let built = Actor::new(obs, act, cfg, 0).unwrap();
            assert_eq!(cfg.param_count(obs, act), built.params().len(), "{cfg:?}");
        }
    }
    assert_eq!(ActorConfig::paper().param_count(43, 6), 155_276);
    let critics = [
        CriticConfig::paper(),
        CriticConfig::feed_forward(),
        CriticConfig {
            obs_fc: vec![9],
            act_fc: vec![],
            joint_fc: vec![6, 2],
            recurrent: true,
            lstm_hidden: 3,
        },
    ];
    for (obs, act) in [(43, 6), (3, 1)] {
        for cfg in &critics {
            let built = Critic::new(obs, act, cfg, 0).unwrap();
            assert_eq!(cfg.param_count(obs, act), built.params().len(), "{cfg:?}");
        }
    }
    assert_eq!(CriticConfig::paper().param_count(43, 6), 171_953);
}

#[test]
fn oversized_layers_are_refused_by_name() {
    let cfg = ActorConfig {
        fc: vec![64, MAX_WIDTH + 1],
        ..ActorConfig::default()
    };
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.contains("actor.fc[1]"), "{e}");
    let cfg = CriticConfig {
        lstm_hidden: 100_000,
        ..CriticConfig::default()
    };
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.contains("critic.lstm_hidden"), "{e}");
}
