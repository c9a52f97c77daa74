//! Contract: the LSTM, trained end to end with BPTT and Adam, learns a task that needs
//! memory: from a sine sequence with random phase and frequency, predict the value three
//! steps ahead (the current value alone does not say whether the wave rises or falls, nor how
//! fast). The MSE must fall below 2e-3, far under the ≈0.35 of the best guess from the current value alone.

use esrl_nn::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn lstm_learns_to_predict_a_sine_three_steps_ahead() {
    let (b, t, h, ahead) = (16, 24, 24, 3);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut params = Params::new();
    let lstm = Lstm::new(&mut params, "lstm", 1, h, &mut rng);
    let head = Linear::new(&mut params, "head", h, 1, &mut rng);
    let mut opt = Adam::new(
        AdamConfig {
            lr: 1e-2,
            l2: 0.0,
            ..AdamConfig::default()
        },
        &params,
    )
    .unwrap();
    let mut data_rng = ChaCha8Rng::seed_from_u64(2);
    let batch = |rng: &mut ChaCha8Rng| {
        let (mut x, mut y) = (vec![0.0f32; t * b], vec![0.0f32; t * b]);
        for s in 0..b {
            let phase = rng.random_range(0.0..std::f32::consts::TAU);
            let w = rng.random_range(0.25f32..0.45);
            for k in 0..t {
                x[k * b + s] = (w * k as f32 + phase).sin();
                y[k * b + s] = (w * (k + ahead) as f32 + phase).sin();
            }
        }
        (Tensor::from_vec(t * b, 1, x), Tensor::from_vec(t * b, 1, y))
    };
    // Score only steps ≥ 4, once the LSTM has seen enough of the wave.
    let mask: Vec<f32> = (0..t * b)
        .map(|r| if r / b >= 4 { 1.0 } else { 0.0 })
        .collect();
    let scored = mask.iter().sum::<f32>();
    let mut last = f32::INFINITY;
    for it in 0..1000 {
        let (x, y) = batch(&mut data_rng);
        let mut g = Graph::new();
        let xv = g.constant(x);
        let yv = g.constant(y);
        let hs = lstm.forward(&mut g, &params, xv, b, None).h;
        let pred = head.forward(&mut g, &params, hs, Act::None);
        let err = g.sub(pred, yv);
        let sq = g.square(err);
        let m = g.constant(Tensor::from_slice(t * b, 1, &mask));
        let sq = g.mul(sq, m);
        let s = g.sum(sq);
        let loss = g.scale(s, 1.0 / scored);
        let v = g.value(loss).item();
        let mut grads = g.backward(loss);
        drop(g);
        opt.apply(&mut params, &mut grads).unwrap();
        if it >= 980 {
            last = last.min(v);
        }
    }
    println!("final MSE {last}");
    assert!(last < 2e-3, "LSTM failed to fit: MSE {last}");
}
