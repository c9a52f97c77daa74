//! Writes a tiny actor and critic with formula weights, their inputs, outputs and gradients to
//! one safetensors file, for `scripts/torch_parity.py` to recompute in PyTorch:
//! `cargo run --release -p esrl-nn --example torch_parity_export -- out.safetensors`.
//! `tests/torch_parity.rs` builds the same networks and holds the values PyTorch printed.

use esrl_nn::*;

/// Shapes and formulas shared with `tests/torch_parity.rs`.
const T: usize = 4;
const B: usize = 2;
const OBS: usize = 5;
const ACT: usize = 3;

fn formula(n: usize, a: f32, b: f32, scale: f32) -> Vec<f32> {
    (0..n).map(|i| scale * (a * i as f32 + b).sin()).collect()
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "torch_parity.safetensors".into());
    let acfg = ActorConfig {
        fc: vec![7],
        lstm_hidden: 4,
        ..ActorConfig::default()
    };
    let ccfg = CriticConfig {
        obs_fc: vec![6],
        act_fc: vec![5],
        lstm_hidden: 4,
        ..CriticConfig::default()
    };
    let mut actor = Actor::new(OBS, ACT, &acfg, 0).unwrap();
    let mut critic = Critic::new(OBS, ACT, &ccfg, 0).unwrap();
    let na = actor.num_params();
    let nc = critic.num_params();
    actor
        .params_mut()
        .set_flat(&formula(na, 1.3, 0.2, 0.5))
        .unwrap();
    critic
        .params_mut()
        .set_flat(&formula(nc, 0.7, 1.1, 0.5))
        .unwrap();
    let obs = Tensor::from_vec(T * B, OBS, formula(T * B * OBS, 0.9, 0.3, 1.0));
    let act = Tensor::from_vec(T * B, ACT, formula(T * B * ACT, 1.7, 0.5, 0.9));
    let eps = Tensor::from_vec(T * B, ACT, formula(T * B * ACT, 2.3, 0.1, 1.2));
    let y = Tensor::from_vec(T * B, 1, formula(T * B, 0.6, 0.4, 1.0));

    let mut g = Graph::new();
    let o = g.constant(obs.clone());
    let out = actor.forward(&mut g, o, B, None);
    let s = actor.sample_with_noise(&mut g, &out, eps.clone());
    let asum = g.sum_cols(s.action);
    let d = g.sub(s.log_prob, asum);
    let loss = g.mean(d);
    let (mean, std) = (g.value(out.mean).clone(), g.value(out.std).clone());
    let (action, logp) = (g.value(s.action).clone(), g.value(s.log_prob).clone());
    let ga = g.backward(loss).of(actor.params()).unwrap().to_vec();

    let mut g = Graph::new();
    let (o, a, yv) = (
        g.constant(obs.clone()),
        g.constant(act.clone()),
        g.constant(y.clone()),
    );
    let q = critic.forward(&mut g, o, a, B, None).q;
    let loss = g.mse(q, yv);
    let qv = g.value(q).clone();
    let gc = g.backward(loss).of(critic.params()).unwrap().to_vec();

    let mut tensors = Vec::new();
    let mut push = |name: String, shape: Vec<usize>, data: Vec<f32>| {
        tensors.push(NamedTensor { name, shape, data })
    };
    for (prefix, p, grad) in [
        ("actor.", actor.params(), &ga),
        ("critic.", critic.params(), &gc),
    ] {
        for s in p.specs() {
            push(
                format!("{prefix}{}", s.name),
                s.shape.clone(),
                p.as_slice()[s.range()].to_vec(),
            );
            push(
                format!("grad.{prefix}{}", s.name),
                s.shape.clone(),
                grad[s.range()].to_vec(),
            );
        }
    }
    for (name, t) in [
        ("in.obs", &obs),
        ("in.act", &act),
        ("in.eps", &eps),
        ("in.y", &y),
        ("out.mean", &mean),
        ("out.std", &std),
        ("out.action", &action),
        ("out.logp", &logp),
        ("out.q", &qv),
    ] {
        push(name.into(), vec![t.rows(), t.cols()], t.data().to_vec());
    }
    save_tensors(std::path::Path::new(&path), &tensors, None).unwrap();
    println!("wrote {path}");
}
