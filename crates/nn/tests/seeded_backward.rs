//! Contract: a reverse pass seeded at intermediate values with their gradients
//! (`Graph::backward_seeded`) gives the same gradients, bit for bit, as the reverse pass of
//! the whole loss, when the seeds are what that pass accumulates there: a graph may be cut
//! and its parts differentiated on their own (as the actor update does across threads).

use esrl_nn::{Graph, Tensor};

const X: [f32; 6] = [0.3, -1.2, 0.7, 0.05, -0.4, 1.9];
const W: [f32; 6] = [0.9, -0.2, 0.4, 1.1, -0.7, 0.3];
const C: [f32; 6] = [0.5, 2.0, -1.5, 0.25, 1.0, -0.75];

#[test]
fn seeding_two_cut_values_equals_the_whole_reverse_pass() {
    let (x, w, c) = (
        Tensor::from_vec(3, 2, X.to_vec()),
        Tensor::from_vec(3, 2, W.to_vec()),
        Tensor::from_vec(3, 2, C.to_vec()),
    );

    // Whole: loss = Σ c ⊙ tanh(x ⊙ w) + Σ (x ⊙ w)².
    let mut whole = Graph::new();
    let (xv, wv, cv) = (
        whole.leaf(x.clone()),
        whole.constant(w.clone()),
        whole.constant(c.clone()),
    );
    let y = whole.mul(xv, wv);
    let t = whole.tanh(y);
    let ct = whole.mul(t, cv);
    let a = whole.sum(ct);
    let y2 = whole.square(y);
    let b = whole.sum(y2);
    let loss = whole.add(a, b);
    let full = whole.backward(loss);
    let dx_whole = full.var(xv).unwrap().clone();

    // Cut at t and y2: seed them with what the whole pass gives there, ∂L/∂t = c, ∂L/∂y² = 1.
    let mut cut = Graph::new();
    let (xv, wv) = (cut.leaf(x), cut.constant(w));
    let y = cut.mul(xv, wv);
    let t = cut.tanh(y);
    let y2 = cut.square(y);
    let grads = cut.backward_seeded(vec![(t, c), (y2, Tensor::from_vec(3, 2, vec![1.0; 6]))]);
    let dx_cut = grads.var(xv).unwrap();

    let bits = |t: &Tensor| t.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(dx_cut), bits(&dx_whole));
    // And the gradient is the analytic one: c·(1 − tanh²(xw))·w + 2·(xw)·w.
    for i in 0..6 {
        let (xi, wi, ci) = (f64::from(X[i]), f64::from(W[i]), f64::from(C[i]));
        let want = ci * (1.0 - (xi * wi).tanh().powi(2)) * wi + 2.0 * xi * wi * wi;
        assert!((f64::from(dx_cut.data()[i]) - want).abs() < 1e-6);
    }
}
