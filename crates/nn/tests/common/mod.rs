//! Shared helpers for the gradient tests: seeded data, f64 central differences, comparison.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `n` values uniform in [lo, hi) from `seed`.
pub fn uniform(n: usize, lo: f32, hi: f32, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(lo..hi)).collect()
}

/// Widens to f64.
pub fn f64s(v: &[f32]) -> Vec<f64> {
    v.iter().map(|&x| x as f64).collect()
}

/// Central differences of `f` at `inputs` with respect to every element of every input:
/// (f(x + h) − f(x − h)) / 2h in f64 (truncation error O(h²) ≈ 1e-10 for h = 1e-5).
pub fn central_differences(inputs: &[Vec<f64>], f: &dyn Fn(&[Vec<f64>]) -> f64) -> Vec<Vec<f64>> {
    let h = 1e-5;
    let mut x: Vec<Vec<f64>> = inputs.to_vec();
    let mut out = Vec::new();
    for k in 0..x.len() {
        let mut g = Vec::with_capacity(x[k].len());
        for i in 0..x[k].len() {
            let v = x[k][i];
            x[k][i] = v + h;
            let fp = f(&x);
            x[k][i] = v - h;
            let fm = f(&x);
            x[k][i] = v;
            g.push((fp - fm) / (2.0 * h));
        }
        out.push(g);
    }
    out
}

/// Asserts |a − r| ≤ atol + rtol·|r| elementwise, naming the first offender.
pub fn assert_close(what: &str, analytic: &[f32], reference: &[f64], rtol: f64, atol: f64) {
    assert_eq!(analytic.len(), reference.len(), "{what}: length");
    for (i, (&a, &r)) in analytic.iter().zip(reference).enumerate() {
        let err = (a as f64 - r).abs();
        assert!(
            err <= atol + rtol * r.abs(),
            "{what}[{i}]: analytic {a} vs reference {r} (error {err:e})"
        );
    }
}

/// f64 helpers for reference forwards.
pub fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// log(1 + e^x), stable.
pub fn softplus(x: f64) -> f64 {
    x.max(0.0) + (-x.abs()).exp().ln_1p()
}
