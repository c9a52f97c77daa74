//! Contract: the graph-free single-step path `Actor::step` used in rollouts produces the same
//! μ and σ as the batched graph forward over the same sequence, for the recurrent and the
//! feed-forward actor, carries (h, c) across calls and resets cleanly.

use esrl_nn::*;

fn check(cfg: &ActorConfig) {
    let (od, ad, t) = (7, 3, 9);
    let actor = Actor::new(od, ad, cfg, 4).unwrap();
    let obs: Vec<f32> = (0..t * od)
        .map(|i| ((i as f32) * 0.61).sin() * 1.5)
        .collect();
    let mut g = Graph::no_grad();
    let o = g.constant(Tensor::from_slice(t, od, &obs));
    let out = actor.forward(&mut g, o, 1, None);
    let (mean, std) = (g.value(out.mean).clone(), g.value(out.std).clone());
    let mut st = actor.step_state();
    for round in 0..2 {
        for k in 0..t {
            actor.step(&obs[k * od..(k + 1) * od], &mut st);
            for j in 0..ad {
                assert!(
                    (st.mean()[j] - mean.get(k, j)).abs() < 1e-5,
                    "round {round} step {k} mean"
                );
                assert!(
                    (st.std()[j] - std.get(k, j)).abs() < 1e-5,
                    "round {round} step {k} std"
                );
            }
        }
        if let Some(s) = &out.state {
            for (a, b) in st.h().iter().zip(s.h.data()) {
                assert!((a - b).abs() < 1e-5);
            }
        }
        st.reset();
    }
    let mut a = vec![0.0; ad];
    st.deterministic_action(&mut a);
    assert!(a.iter().all(|v| v.abs() < 1.0));
}

#[test]
fn recurrent_step_matches_graph() {
    check(&ActorConfig {
        fc: vec![12],
        lstm_hidden: 10,
        ..ActorConfig::default()
    });
}

#[test]
fn feed_forward_step_matches_graph() {
    check(&ActorConfig {
        fc: vec![16, 8],
        recurrent: false,
        ..ActorConfig::default()
    });
}
