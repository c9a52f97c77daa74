//! Contract: the tanh-squashed Gaussian sample and its log-probability
//! (`Graph::gaussian_tanh`) equal the change-of-variables density
//! log N(u; μ, σ) − log(1 − tanh² u) computed in f64, stay finite for saturated u where the
//! naive form is −∞, integrate to 1 over the action interval, and have gradients with respect
//! to μ and σ that match f64 central differences.

mod common;
use common::*;
use esrl_nn::*;

const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// f64 reference: actions (N, A) then log-probs (N).
fn reference(mean: &[f64], std: &[f64], eps: &[f64], n: usize, a: usize) -> Vec<f64> {
    let mut acts = Vec::new();
    let mut lps = Vec::new();
    for r in 0..n {
        let mut lp = 0.0;
        for j in 0..a {
            let k = r * a + j;
            let u = mean[k] + std[k] * eps[k];
            acts.push(u.tanh());
            let gauss = -0.5 * ((u - mean[k]) / std[k]).powi(2) - std[k].ln() - 0.5 * LN_2PI;
            // log(1 − tanh² u) = 2(log 2 − u − softplus(−2u)), exact identity, stable in f64.
            let log_jac = 2.0 * (std::f64::consts::LN_2 - u - softplus(-2.0 * u));
            lp += gauss - log_jac;
        }
        lps.push(lp);
    }
    acts.extend(lps);
    acts
}

fn run(
    mean: &[f32],
    std: &[f32],
    eps: &[f32],
    n: usize,
    a: usize,
) -> (Vec<f32>, Vec<f32>, Graph<'static>, Var, Var, Var, Var) {
    let mut g = Graph::new();
    let m = g.leaf(Tensor::from_slice(n, a, mean));
    let s = g.leaf(Tensor::from_slice(n, a, std));
    let (act, lp) = g.gaussian_tanh(m, s, Tensor::from_slice(n, a, eps));
    (
        g.value(act).data().to_vec(),
        g.value(lp).data().to_vec(),
        g,
        m,
        s,
        act,
        lp,
    )
}

#[test]
fn values_match_change_of_variables_density() {
    let (n, a) = (5, 3);
    let mean = uniform(n * a, -1.5, 1.5, 1);
    let std = uniform(n * a, 0.1, 1.2, 2);
    let eps = uniform(n * a, -2.0, 2.0, 3);
    let (act, lp, ..) = run(&mean, &std, &eps, n, a);
    let r = reference(&f64s(&mean), &f64s(&std), &f64s(&eps), n, a);
    assert_close("action", &act, &r[..n * a], 1e-6, 1e-6);
    assert_close("log_prob", &lp, &r[n * a..], 1e-5, 1e-5);
    // Naive form agrees where it is well conditioned.
    for (k, &lp_k) in lp.iter().enumerate() {
        let naive: f64 = (0..a)
            .map(|j| {
                let i = k * a + j;
                let u = mean[i] as f64 + std[i] as f64 * eps[i] as f64;
                -0.5 * (eps[i] as f64).powi(2)
                    - (std[i] as f64).ln()
                    - 0.5 * LN_2PI
                    - (1.0 - u.tanh().powi(2)).ln()
            })
            .sum();
        assert!(
            (lp_k as f64 - naive).abs() < 1e-4,
            "{lp_k} vs naive {naive}"
        );
    }
}

#[test]
fn saturated_samples_stay_finite() {
    let mean = [25.0f32, -25.0, 9.0, -40.0];
    let std = [1.0f32; 4];
    let eps = [0.5f32, -0.5, 0.0, 1.0];
    let (act, lp, mut g, m, s, _, lpv) = run(&mean, &std, &eps, 4, 1);
    let r = reference(&f64s(&mean), &f64s(&std), &f64s(&eps), 4, 1);
    assert_close("saturated log_prob", &lp, &r[4..], 1e-6, 1e-4);
    assert!(act.iter().all(|a| a.abs() <= 1.0));
    // The naive f32 form would be log(1 − 1) = −∞ here.
    assert!((1.0f32 - (25.5f32).tanh().powi(2)).ln().is_infinite());
    let loss = g.sum(lpv);
    let grads = g.backward(loss);
    assert!(grads.var(m).unwrap().all_finite() && grads.var(s).unwrap().all_finite());
}

#[test]
fn density_integrates_to_one() {
    // For one action dimension, ∫ π(a) da over (−1, 1) = ∫ exp(log π(a(ε))) · |da/dε| dε with
    // da/dε = σ(1 − a²); a midpoint rule over ε ∈ [−8, 8] is exact to ~1e-6.
    for (mu, sigma) in [(0.0f32, 1.0f32), (1.3, 0.4), (-0.7, 2.0)] {
        let k = 4000;
        let de = 16.0 / k as f32;
        let eps: Vec<f32> = (0..k).map(|i| -8.0 + (i as f32 + 0.5) * de).collect();
        let (act, lp, ..) = run(&vec![mu; k], &vec![sigma; k], &eps, k, 1);
        let total: f64 = act
            .iter()
            .zip(&lp)
            .map(|(&a, &l)| {
                (l as f64).exp() * sigma as f64 * (1.0 - (a as f64).powi(2)) * de as f64
            })
            .sum();
        assert!((total - 1.0).abs() < 2e-3, "μ={mu} σ={sigma}: ∫π = {total}");
    }
}

#[test]
fn gradients_match_central_differences() {
    let (n, a) = (4, 3);
    let mean = uniform(n * a, -1.5, 1.5, 4);
    let std = uniform(n * a, 0.2, 1.5, 5);
    let eps = uniform(n * a, -2.0, 2.0, 6);
    let wa = uniform(n * a, -1.0, 1.0, 7);
    let wl = uniform(n, -1.0, 1.0, 8);
    let (_, _, mut g, m, s, act, lp) = run(&mean, &std, &eps, n, a);
    let wav = g.constant(Tensor::from_slice(n, a, &wa));
    let wlv = g.constant(Tensor::from_slice(n, 1, &wl));
    let x = g.mul(act, wav);
    let y = g.mul(lp, wlv);
    let sx = g.sum(x);
    let sy = g.sum(y);
    let loss = g.add(sx, sy);
    let grads = g.backward(loss);
    let (eps64, wa64, wl64) = (f64s(&eps), f64s(&wa), f64s(&wl));
    let f = |v: &[Vec<f64>]| {
        let r = reference(&v[0], &v[1], &eps64, n, a);
        r[..n * a]
            .iter()
            .zip(&wa64)
            .map(|(p, q)| p * q)
            .sum::<f64>()
            + r[n * a..]
                .iter()
                .zip(&wl64)
                .map(|(p, q)| p * q)
                .sum::<f64>()
    };
    let fd = central_differences(&[f64s(&mean), f64s(&std)], &f);
    assert_close("d/dmean", grads.var(m).unwrap().data(), &fd[0], 1e-3, 1e-4);
    assert_close("d/dstd", grads.var(s).unwrap().data(), &fd[1], 1e-3, 1e-4);
}
