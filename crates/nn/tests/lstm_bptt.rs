//! Contract: the LSTM sequence op (B sequences × T ≥ 5 steps, non-zero initial (h, c))
//! computes the same hidden sequence and final state as an independent f64 implementation of
//! PyTorch's LSTM equations, and its BPTT gradients with respect to the inputs, the initial
//! state and every weight match f64 central differences of that implementation.

mod common;
use common::*;
use esrl_nn::*;
use rand::SeedableRng;

const B: usize = 3;
const T: usize = 6;
const I: usize = 4;
const H: usize = 5;

/// f64 LSTM: x (T·B, I) time-major, θ = [W_ih (4H, I), W_hh (4H, H), b (4H)], gates [i f g o].
/// Returns the hidden sequence (T·B, H) followed by the final c (B, H).
fn lstm_ref(x: &[f64], h0: &[f64], c0: &[f64], theta: &[f64]) -> Vec<f64> {
    let (wih, rest) = theta.split_at(4 * H * I);
    let (whh, b) = rest.split_at(4 * H * H);
    let mut h = h0.to_vec();
    let mut c = c0.to_vec();
    let mut out = Vec::new();
    for t in 0..T {
        let mut hn = vec![0.0; B * H];
        for r in 0..B {
            let xr = &x[(t * B + r) * I..(t * B + r + 1) * I];
            let z = |k: usize| {
                b[k] + (0..I).map(|j| wih[k * I + j] * xr[j]).sum::<f64>()
                    + (0..H).map(|j| whh[k * H + j] * h[r * H + j]).sum::<f64>()
            };
            for u in 0..H {
                let (i, f, g, o) = (
                    sigmoid(z(u)),
                    sigmoid(z(H + u)),
                    z(2 * H + u).tanh(),
                    sigmoid(z(3 * H + u)),
                );
                c[r * H + u] = f * c[r * H + u] + i * g;
                hn[r * H + u] = o * c[r * H + u].tanh();
            }
        }
        h = hn;
        out.extend_from_slice(&h);
    }
    out.extend_from_slice(&c);
    out
}

#[test]
fn lstm_forward_and_bptt_match_f64_reference() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut params = Params::new();
    let lstm = Lstm::new(&mut params, "lstm", I, H, &mut rng);
    // Larger weights than the default init so the gates leave their linear region.
    let theta: Vec<f32> = uniform(params.len(), -0.9, 0.9, 11);
    params.set_flat(&theta).unwrap();
    let x = uniform(T * B * I, -1.5, 1.5, 12);
    let h0 = uniform(B * H, -0.8, 0.8, 13);
    let c0 = uniform(B * H, -1.2, 1.2, 14);
    let wy = uniform(T * B * H, -1.0, 1.0, 15);
    let wc = uniform(B * H, -1.0, 1.0, 16);

    // Loss = Σ wy ⊙ h_seq + Σ wc ⊙ h_T (the final h, read from the sequence, so the gradient
    // through the last step is exercised twice).
    let mut g = Graph::new();
    let xv = g.leaf(Tensor::from_slice(T * B, I, &x));
    let h0v = g.leaf(Tensor::from_slice(B, H, &h0));
    let c0v = g.leaf(Tensor::from_slice(B, H, &c0));
    let out = lstm.forward_vars(&mut g, &params, xv, B, h0v, c0v);
    let h_seq = g.value(out.h).data().to_vec();
    let wyv = g.constant(Tensor::from_slice(T * B, H, &wy));
    let a = g.mul(out.h, wyv);
    let la = g.sum(a);
    let last = g.slice_cols(out.h, 0, H);
    let lw: Vec<f32> = (0..T * B * H)
        .map(|k| {
            if k >= (T - 1) * B * H {
                wc[k - (T - 1) * B * H]
            } else {
                0.0
            }
        })
        .collect();
    let lwv = g.constant(Tensor::from_slice(T * B, H, &lw));
    let b2 = g.mul(last, lwv);
    let lb = g.sum(b2);
    let loss = g.add(la, lb);
    let grads = g.backward(loss);

    let r = lstm_ref(&f64s(&x), &f64s(&h0), &f64s(&c0), &f64s(&theta));
    assert_close("h sequence", &h_seq, &r[..T * B * H], 1e-5, 2e-6);
    assert_close(
        "final h",
        out.state.h.data(),
        &r[(T - 1) * B * H..T * B * H],
        1e-5,
        2e-6,
    );
    assert_close("final c", out.state.c.data(), &r[T * B * H..], 1e-5, 2e-6);

    let (wy64, wc64) = (f64s(&wy), f64s(&wc));
    let f = |v: &[Vec<f64>]| {
        let r = lstm_ref(&v[0], &v[1], &v[2], &v[3]);
        let s1: f64 = r[..T * B * H].iter().zip(&wy64).map(|(a, b)| a * b).sum();
        let s2: f64 = r[(T - 1) * B * H..T * B * H]
            .iter()
            .zip(&wc64)
            .map(|(a, b)| a * b)
            .sum();
        s1 + s2
    };
    let fd = central_differences(&[f64s(&x), f64s(&h0), f64s(&c0), f64s(&theta)], &f);
    assert_close("dx", grads.var(xv).unwrap().data(), &fd[0], 1e-3, 1e-4);
    assert_close("dh0", grads.var(h0v).unwrap().data(), &fd[1], 1e-3, 1e-4);
    assert_close("dc0", grads.var(c0v).unwrap().data(), &fd[2], 1e-3, 1e-4);
    assert_close("dθ", grads.of(&params).unwrap(), &fd[3], 1e-3, 1e-4);
    assert!(
        fd[1].iter().any(|v| v.abs() > 1e-3),
        "initial state must matter for this test to mean anything"
    );
}

#[test]
fn carried_state_equals_one_long_run() {
    // Running T steps, then continuing from the returned state, equals one 2T run.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
    let mut params = Params::new();
    let lstm = Lstm::new(&mut params, "lstm", I, H, &mut rng);
    let x = uniform(2 * T * B * I, -1.0, 1.0, 21);
    let mut g = Graph::no_grad();
    let xa = g.constant(Tensor::from_slice(2 * T * B, I, &x));
    let full = lstm.forward(&mut g, &params, xa, B, None);
    let x1 = g.constant(Tensor::from_slice(T * B, I, &x[..T * B * I]));
    let x2 = g.constant(Tensor::from_slice(T * B, I, &x[T * B * I..]));
    let first = lstm.forward(&mut g, &params, x1, B, None);
    let second = lstm.forward(&mut g, &params, x2, B, Some(&first.state));
    assert_eq!(
        g.value(second.h).data(),
        &g.value(full.h).data()[T * B * H..]
    );
    assert_eq!(second.state, full.state);
}
