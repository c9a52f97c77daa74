//! Contract: the networks agree with PyTorch. A tiny actor and critic with formula weights
//! (built exactly as in `examples/torch_parity_export.rs`) must reproduce the log-probabilities,
//! Q-values and gradients that PyTorch computed in f64 after loading our safetensors file into
//! `nn.Linear`/`nn.LSTM` (`bias_ih = bias`, `bias_hh = 0`); the values below were printed by
//! `scripts/torch_parity.py` (torch 2.15) and pasted here. This pins gate order, weight layout,
//! the Softplus std head and the tanh log-probability correction to PyTorch's conventions.

mod common;
use common::assert_close;
use esrl_nn::*;

const T: usize = 4;
const B: usize = 2;
const OBS: usize = 5;
const ACT: usize = 3;

fn formula(n: usize, a: f32, b: f32, scale: f32) -> Vec<f32> {
    (0..n).map(|i| scale * (a * i as f32 + b).sin()).collect()
}

const TORCH_LOG_PROB: &[f64] = &[
    -1.524173046e+00,
    -1.065994232e+00,
    -7.543987913e-01,
    -9.286858215e-01,
    -9.987868837e-01,
    -1.697516327e+00,
    -2.435574632e+00,
    -2.711234333e+00,
];
const TORCH_Q: &[f64] = &[
    2.802654166e-01,
    3.976571684e-01,
    3.429460233e-01,
    3.180650141e-01,
    4.315702222e-01,
    2.961182992e-01,
    4.077522313e-01,
    2.739986322e-01,
];
const TORCH_GRAD_ACTOR_LSTM_BIAS: &[f64] = &[
    -1.361286271e-02,
    6.352394863e-03,
    9.670547218e-02,
    -2.393366116e-02,
    5.168201181e-03,
    7.099185746e-04,
    3.790045102e-02,
    -1.407379086e-02,
    -2.326713539e-01,
    -6.763733466e-02,
    1.056927912e-01,
    1.863830065e-01,
    8.005018391e-03,
    1.322207749e-02,
    7.349501220e-02,
    -2.276736131e-02,
];
const TORCH_GRAD_CRITIC_LSTM_WEIGHT_HH: &[f64] = &[
    -2.746056607e-03,
    -4.817541385e-04,
    1.241968048e-04,
    -1.138214101e-03,
    1.976364368e-03,
    3.253531884e-04,
    -1.345650917e-04,
    6.584857311e-04,
    -1.512139045e-03,
    -4.270203616e-05,
    3.132885952e-04,
    -4.442337985e-04,
    6.025574039e-04,
    1.330998556e-03,
    7.617357232e-04,
    3.130098348e-04,
    -2.766187022e-03,
    -5.534248985e-04,
    1.457189897e-04,
    -9.611791740e-04,
    3.896414676e-04,
    3.487358191e-04,
    1.702589345e-04,
    1.676753244e-04,
    -9.854477607e-04,
    3.822570932e-04,
    4.332353560e-04,
    -2.972110415e-04,
    3.118149651e-03,
    5.053083519e-04,
    -2.124840128e-04,
    1.139135336e-03,
    -8.595297380e-03,
    -4.703556828e-03,
    -1.756678416e-03,
    -3.520252666e-03,
    5.314858058e-03,
    1.869774414e-03,
    2.594168196e-04,
    1.937603129e-03,
    1.228042092e-02,
    4.652908517e-03,
    1.299804520e-03,
    5.162970490e-03,
    1.632342419e-02,
    5.893736469e-03,
    8.790532117e-04,
    5.817547561e-03,
    -4.578448853e-03,
    -4.039930234e-04,
    4.383220461e-04,
    -1.737122632e-03,
    1.593000667e-03,
    3.513644868e-04,
    6.412155836e-05,
    7.384206893e-04,
    -2.487566473e-03,
    5.433759455e-05,
    6.950236935e-04,
    -4.753523060e-04,
    3.866418744e-03,
    2.509495983e-03,
    9.106432341e-04,
    1.496669183e-03,
];
const TORCH_GRAD_CRITIC_ACT_FC_WEIGHT: &[f64] = &[
    0.000000000e+00,
    0.000000000e+00,
    0.000000000e+00,
    -9.095546337e-03,
    -4.179333279e-04,
    9.203248714e-03,
    1.027582451e-02,
    -1.751850050e-02,
    -5.761500519e-03,
    -7.908406478e-03,
    -2.402399039e-02,
    1.409913766e-02,
    -2.422159347e-03,
    -1.931767930e-02,
    7.400121255e-03,
];

#[test]
fn actor_and_critic_match_pytorch() {
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
    let (na, nc) = (actor.num_params(), critic.num_params());
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
    let s = actor.sample_with_noise(&mut g, &out, eps);
    let asum = g.sum_cols(s.action);
    let d = g.sub(s.log_prob, asum);
    let loss = g.mean(d);
    let logp = g.value(s.log_prob).clone();
    let ga = g.backward(loss).of(actor.params()).unwrap().to_vec();
    assert_close("log π", logp.data(), TORCH_LOG_PROB, 1e-5, 1e-6);
    let bias = actor
        .params()
        .specs()
        .iter()
        .find(|s| s.name == "lstm.bias")
        .unwrap()
        .range();
    assert_close(
        "d/d actor lstm.bias",
        &ga[bias],
        TORCH_GRAD_ACTOR_LSTM_BIAS,
        1e-4,
        1e-7,
    );

    let mut g = Graph::new();
    let (o, a, yv) = (g.constant(obs), g.constant(act), g.constant(y));
    let q = critic.forward(&mut g, o, a, B, None).q;
    let loss = g.mse(q, yv);
    let qv = g.value(q).clone();
    let gc = g.backward(loss).of(critic.params()).unwrap().to_vec();
    assert_close("Q", qv.data(), TORCH_Q, 1e-5, 1e-6);
    let range = |name: &str| {
        critic
            .params()
            .specs()
            .iter()
            .find(|s| s.name == name)
            .unwrap()
            .range()
    };
    assert_close(
        "d/d critic lstm.weight_hh",
        &gc[range("lstm.weight_hh")],
        TORCH_GRAD_CRITIC_LSTM_WEIGHT_HH,
        1e-4,
        1e-7,
    );
    assert_close(
        "d/d critic act_fc.0.weight",
        &gc[range("act_fc.0.weight")],
        TORCH_GRAD_CRITIC_ACT_FC_WEIGHT,
        1e-4,
        1e-7,
    );
}
