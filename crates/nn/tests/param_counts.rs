//! Contract: the default (paper) actor and critic for the walking env (obs 43, act 6) have
//! 155,276 and 171,953 parameters — within 5% of the paper's 153.7k and 169.6k — and the
//! counts follow the layer formulas for any size.

use esrl_nn::*;

fn linear(i: usize, o: usize) -> usize {
    i * o + o
}

fn lstm(i: usize, h: usize) -> usize {
    4 * h * (i + h) + 4 * h
}

#[test]
fn paper_sizes() {
    let a = Actor::new(43, 6, &ActorConfig::paper(), 0).unwrap();
    let c = Critic::new(43, 6, &CriticConfig::paper(), 0).unwrap();
    println!(
        "actor parameters: {} (paper 153.7k), critic parameters: {} (paper 169.6k)",
        a.num_params(),
        c.num_params()
    );
    assert_eq!(
        a.num_params(),
        linear(43, 256) + lstm(256, 100) + 2 * linear(100, 6)
    );
    assert_eq!(a.num_params(), 155_276);
    assert_eq!(
        c.num_params(),
        linear(43, 128) + linear(6, 128) + lstm(256, 112) + linear(112, 1)
    );
    assert_eq!(c.num_params(), 171_953);
    assert!((a.num_params() as f64 / 153_700.0 - 1.0).abs() < 0.05);
    assert!((c.num_params() as f64 / 169_600.0 - 1.0).abs() < 0.05);
}

#[test]
fn feed_forward_variants() {
    let a = Actor::new(43, 6, &ActorConfig::feed_forward(), 0).unwrap();
    let c = Critic::new(43, 6, &CriticConfig::feed_forward(), 0).unwrap();
    assert_eq!(
        a.num_params(),
        linear(43, 256) + linear(256, 256) + 2 * linear(256, 6)
    );
    assert_eq!(
        c.num_params(),
        linear(49, 256) + linear(256, 256) + linear(256, 1)
    );
    assert!(a.lstm_hidden().is_none() && c.zero_state(4).is_none());
}

#[test]
fn invalid_sizes_name_the_field() {
    let err = Actor::new(0, 6, &ActorConfig::paper(), 0).unwrap_err();
    assert!(err.to_string().contains("actor.obs_dim"), "{err}");
    let err = Actor::new(
        43,
        6,
        &ActorConfig {
            fc: vec![256, 0],
            ..ActorConfig::paper()
        },
        0,
    )
    .unwrap_err();
    assert!(err.to_string().contains("actor.fc[1]"), "{err}");
    let err = Critic::new(
        43,
        6,
        &CriticConfig {
            lstm_hidden: 0,
            ..CriticConfig::paper()
        },
        0,
    )
    .unwrap_err();
    assert!(err.to_string().contains("critic.lstm_hidden"), "{err}");
    let err = Actor::new(
        43,
        6,
        &ActorConfig {
            min_std: f32::NAN,
            ..ActorConfig::paper()
        },
        0,
    )
    .unwrap_err();
    assert!(err.to_string().contains("actor.min_std"), "{err}");
}
