//! Contract: a whole SAC-style update (burn-in without grad, no-grad target, twin-critic MSE
//! loss, actor loss through frozen critics, entropy coefficient, Polyak) can be written with
//! the public API, and the gradients it produces match central finite differences of the same
//! losses: the critic-loss gradient for both critics, the actor-loss gradient for the actor
//! (through the critics' action input), and no gradient for the frozen critics.

use esrl_nn::*;

const OBS: usize = 4;
const ACT: usize = 2;
const B: usize = 3;
const T: usize = 5;
const BURN: usize = 2;

fn data(rows: usize, cols: usize, k: f32) -> Tensor {
    Tensor::from_vec(
        rows,
        cols,
        (0..rows * cols)
            .map(|i| ((i as f32 * 0.731 + k) * 1.37).sin())
            .collect(),
    )
}

struct Nets {
    actor: Actor,
    q1: Critic,
    q2: Critic,
}

fn nets() -> Nets {
    let acfg = ActorConfig {
        fc: vec![6],
        lstm_hidden: 5,
        ..ActorConfig::default()
    };
    let ccfg = CriticConfig {
        obs_fc: vec![5],
        act_fc: vec![4],
        lstm_hidden: 6,
        ..CriticConfig::default()
    };
    Nets {
        actor: Actor::new(OBS, ACT, &acfg, 11).unwrap(),
        q1: Critic::new(OBS, ACT, &ccfg, 12).unwrap(),
        q2: Critic::new(OBS, ACT, &ccfg, 13).unwrap(),
    }
}

struct Batch {
    obs_burn: Tensor,
    act_burn: Tensor,
    obs: Tensor,
    act: Tensor,
    y: Tensor,
    eps: Tensor,
}

fn batch() -> Batch {
    Batch {
        obs_burn: data(BURN * B, OBS, 0.1),
        act_burn: data(BURN * B, ACT, 0.2),
        obs: data(T * B, OBS, 0.3),
        act: data(T * B, ACT, 0.4),
        y: data(T * B, 1, 0.5),
        eps: data(T * B, ACT, 0.6),
    }
}

type States = (Option<LstmState>, Option<LstmState>, Option<LstmState>);

fn burn_in(n: &Nets, bt: &Batch) -> States {
    let mut g = Graph::no_grad();
    let (o, a) = (
        g.constant(bt.obs_burn.clone()),
        g.constant(bt.act_burn.clone()),
    );
    let sa = n.actor.forward(&mut g, o, B, None).state;
    let s1 = n.q1.forward(&mut g, o, a, B, None).state;
    let s2 = n.q2.forward(&mut g, o, a, B, None).state;
    (sa, s1, s2)
}

fn critic_loss(n: &Nets, bt: &Batch, st: &States) -> (f32, Gradients) {
    let mut g = Graph::new();
    let (o, a, y) = (
        g.constant(bt.obs.clone()),
        g.constant(bt.act.clone()),
        g.constant(bt.y.clone()),
    );
    let qa = n.q1.forward(&mut g, o, a, B, st.1.as_ref()).q;
    let qb = n.q2.forward(&mut g, o, a, B, st.2.as_ref()).q;
    let la = g.mse(qa, y);
    let lb = g.mse(qb, y);
    let loss = g.add(la, lb);
    let v = g.value(loss).item();
    (v, g.backward(loss))
}

fn actor_loss(n: &Nets, bt: &Batch, st: &States, alpha: f32) -> (f32, Gradients, Tensor) {
    let mut g = Graph::new();
    g.freeze(n.q1.params());
    g.freeze(n.q2.params());
    let o = g.constant(bt.obs.clone());
    let out = n.actor.forward(&mut g, o, B, st.0.as_ref());
    let s = n.actor.sample_with_noise(&mut g, &out, bt.eps.clone());
    let qa = n.q1.forward(&mut g, o, s.action, B, st.1.as_ref()).q;
    let qb = n.q2.forward(&mut g, o, s.action, B, st.2.as_ref()).q;
    let qmin = g.minimum(qa, qb);
    let lp = g.scale(s.log_prob, alpha);
    let d = g.sub(lp, qmin);
    let loss = g.mean(d);
    let v = g.value(loss).item();
    let lp = g.value(s.log_prob).clone();
    (v, g.backward(loss), lp)
}

/// Checks `grad` against central differences of `f` on `count` evenly spread coordinates and
/// on one random direction; returns the number of coordinates checked.
fn check(
    what: &str,
    params: &mut Params,
    grad: &[f32],
    mut f: impl FnMut(&Params) -> f32,
) -> usize {
    let h = 2e-3f32;
    let n = params.len();
    let base = params.to_flat();
    let mut checked = 0;
    let stride = (n / 40).max(1);
    for i in (0..n).step_by(stride) {
        let mut p = base.clone();
        p[i] = base[i] + h;
        params.set_flat(&p).unwrap();
        let fp = f(params);
        p[i] = base[i] - h;
        params.set_flat(&p).unwrap();
        let fm = f(params);
        let fd = (fp - fm) / (2.0 * h);
        let tol = 2e-3 + 2e-2 * fd.abs().max(grad[i].abs());
        assert!(
            (fd - grad[i]).abs() < tol,
            "{what}[{i}] ({}): analytic {} vs finite difference {fd}",
            spec_of(params, i),
            grad[i]
        );
        checked += 1;
    }
    // Directional derivative along a fixed pseudo-random direction.
    let dir: Vec<f32> = (0..n)
        .map(|i| ((i as f32 * 12.9898).sin() * 43758.547).fract() - 0.5)
        .collect();
    let along: f64 = grad
        .iter()
        .zip(&dir)
        .map(|(&g, &d)| g as f64 * d as f64)
        .sum();
    let shifted = |s: f32| {
        base.iter()
            .zip(&dir)
            .map(|(&b, &d)| b + s * d)
            .collect::<Vec<_>>()
    };
    params.set_flat(&shifted(h)).unwrap();
    let fp = f(params);
    params.set_flat(&shifted(-h)).unwrap();
    let fm = f(params);
    params.set_flat(&base).unwrap();
    let fd = ((fp - fm) / (2.0 * h)) as f64;
    assert!(
        (fd - along).abs() < 5e-3 + 1e-2 * fd.abs(),
        "{what}: directional analytic {along} vs finite difference {fd}"
    );
    checked
}

fn spec_of(p: &Params, i: usize) -> String {
    p.specs()
        .iter()
        .find(|s| s.range().contains(&i))
        .map(|s| s.name.clone())
        .unwrap_or_default()
}

#[test]
fn critic_loss_gradient_matches_finite_differences() {
    let n = nets();
    let bt = batch();
    let st = burn_in(&n, &bt);
    let (_, grads) = critic_loss(&n, &bt, &st);
    let g1 = grads.of(n.q1.params()).expect("critic 1 gradient").to_vec();
    let g2 = grads.of(n.q2.params()).expect("critic 2 gradient").to_vec();
    assert!(
        grads.of(n.actor.params()).is_none(),
        "the actor took no part in the critic loss"
    );
    let mut p = n.q1.params().clone();
    let c = check("critic1", &mut p, &g1, |p| {
        let mut m = nets();
        m.q1.params_mut().set_flat(p.as_slice()).unwrap();
        critic_loss(&m, &bt, &st).0
    });
    assert!(c >= 40);
    let mut p = n.q2.params().clone();
    check("critic2", &mut p, &g2, |p| {
        let mut m = nets();
        m.q2.params_mut().set_flat(p.as_slice()).unwrap();
        critic_loss(&m, &bt, &st).0
    });
}

#[test]
fn actor_loss_gradient_flows_through_frozen_critics() {
    let n = nets();
    let bt = batch();
    let st = burn_in(&n, &bt);
    let alpha = 0.3;
    let (_, grads, _) = actor_loss(&n, &bt, &st, alpha);
    assert!(
        grads.of(n.q1.params()).is_none() && grads.of(n.q2.params()).is_none(),
        "frozen critics got gradients"
    );
    let ga = grads.of(n.actor.params()).expect("actor gradient").to_vec();
    assert!(ga.iter().any(|&v| v != 0.0));
    let mut p = n.actor.params().clone();
    check("actor", &mut p, &ga, |p| {
        let mut m = nets();
        m.actor.params_mut().set_flat(p.as_slice()).unwrap();
        actor_loss(&m, &bt, &st, alpha).0
    });
}

#[test]
fn full_sac_update_changes_what_it_should() {
    let mut n = nets();
    let bt = batch();
    let (mut q1_t, q2_t) = (n.q1.clone(), n.q2.clone());
    let mut opt_q1 = Adam::new(AdamConfig::default(), n.q1.params()).unwrap();
    let mut opt_q2 = Adam::new(AdamConfig::default(), n.q2.params()).unwrap();
    let mut opt_pi = Adam::new(AdamConfig::default(), n.actor.params()).unwrap();
    let st = burn_in(&n, &bt);

    // Target with no gradient at all.
    let y = {
        let mut g = Graph::no_grad();
        let o2 = g.constant(bt.obs.clone());
        let out = n.actor.forward(&mut g, o2, B, st.0.as_ref());
        let s = n.actor.sample_with_noise(&mut g, &out, bt.eps.clone());
        let qa = q1_t.forward(&mut g, o2, s.action, B, None).q;
        let qb = q2_t.forward(&mut g, o2, s.action, B, None).q;
        let m = g.minimum(qa, qb);
        let r = g.constant(bt.y.clone());
        let y = g.add(r, m);
        let loss = g.mean(y);
        let grads = g.backward(loss);
        assert!(
            grads.of(n.actor.params()).is_none(),
            "no-grad graph produced gradients"
        );
        g.take_value(y)
    };
    assert_eq!(y.shape(), (T * B, 1));

    let (before_q, mut grads) = critic_loss(
        &n,
        &Batch {
            y: y.clone(),
            ..batch()
        },
        &st,
    );
    let q1_before = n.q1.params().to_flat();
    let a_before = n.actor.params().to_flat();
    opt_q1.apply(n.q1.params_mut(), &mut grads).unwrap();
    opt_q2.apply(n.q2.params_mut(), &mut grads).unwrap();
    assert_ne!(q1_before, n.q1.params().to_flat());
    assert_eq!(a_before, n.actor.params().to_flat());
    let (after_q, _) = critic_loss(&n, &Batch { y, ..batch() }, &st);
    assert!(
        after_q < before_q,
        "one Adam step should lower the critic loss: {before_q} → {after_q}"
    );

    let q1_now = n.q1.params().to_flat();
    let (_, mut grads, lp) = actor_loss(&n, &bt, &st, 0.2);
    opt_pi.apply(n.actor.params_mut(), &mut grads).unwrap();
    assert_ne!(a_before, n.actor.params().to_flat());
    assert_eq!(
        q1_now,
        n.q1.params().to_flat(),
        "actor step must not touch the critics"
    );
    assert_eq!(lp.shape(), (T * B, 1));

    let t_before = q1_t.params().to_flat();
    q1_t.params_mut()
        .polyak_update(n.q1.params(), 0.005)
        .unwrap();
    for ((t, b), s) in q1_t
        .params()
        .as_slice()
        .iter()
        .zip(&t_before)
        .zip(n.q1.params().as_slice())
    {
        assert!((t - (0.995 * b + 0.005 * s)).abs() < 1e-6);
    }
}
