//! Contract: `Adam` matches hand-computed steps (bias correction, ε, L2 on weights only),
//! global-norm clipping scales the gradient to the threshold before L2 is added, and a
//! non-finite gradient is refused without touching anything.

use esrl_nn::*;

/// θ = [w0, w1 | b0]: a 2-element weight (decayed) and a 1-element bias (not decayed).
fn params() -> Params {
    let mut p = Params::new();
    let mut w = [1.0f32, -2.0].into_iter();
    p.add("w", &[2], true, move || w.next().unwrap());
    p.add("b", &[1], false, || 0.5);
    p
}

#[test]
fn two_steps_match_hand_computation() {
    let cfg = AdamConfig {
        lr: 0.1,
        beta1: 0.9,
        beta2: 0.999,
        eps: 1e-8,
        l2: 0.01,
        grad_clip: None,
    };
    let mut p = params();
    let mut opt = Adam::new(cfg, &p).unwrap();

    // Step 1: g = [0.1, −0.2, 0.3]; with L2, g' = [0.1 + 0.01·1, −0.2 + 0.01·(−2), 0.3]
    // = [0.11, −0.22, 0.3]. m̂ = g', v̂ = g'², so θ −= 0.1 · g'/(|g'| + 1e-8) ≈ 0.1·sign(g').
    opt.step(&mut p, &[0.1, -0.2, 0.3]).unwrap();
    let want1 = [
        1.0 - 0.1 * 0.11 / (0.11 + 1e-8),
        -2.0 + 0.1 * 0.22 / (0.22 + 1e-8),
        0.5 - 0.1 * 0.3 / (0.3 + 1e-8),
    ];
    for (a, b) in p.as_slice().iter().zip(want1) {
        assert!((*a as f64 - b).abs() < 1e-6, "step 1: {a} vs {b}");
    }
    assert_eq!(
        p.as_slice()
            .iter()
            .map(|v| (v * 1e4).round() / 1e4)
            .collect::<Vec<_>>(),
        vec![0.9, -1.9, 0.4]
    );

    // Step 2: g = [−0.05, 0.1, 0.0], by hand in f64 from the definitions.
    let theta1: Vec<f64> = want1.to_vec();
    let g1 = [0.11, -0.22, 0.3];
    let g2 = [-0.05 + 0.01 * theta1[0], 0.1 + 0.01 * theta1[1], 0.0];
    let mut want2 = [0.0f64; 3];
    for i in 0..3 {
        let m = 0.9 * (0.1 * g1[i]) + 0.1 * g2[i];
        let v = 0.999 * (0.001 * g1[i] * g1[i]) + 0.001 * g2[i] * g2[i];
        let mh = m / (1.0 - 0.9f64.powi(2));
        let vh = v / (1.0 - 0.999f64.powi(2));
        want2[i] = theta1[i] - 0.1 * mh / (vh.sqrt() + 1e-8);
    }
    opt.step(&mut p, &[-0.05, 0.1, 0.0]).unwrap();
    for (a, b) in p.as_slice().iter().zip(want2) {
        assert!((*a as f64 - b).abs() < 2e-6, "step 2: {a} vs {b}");
    }
    assert_eq!(opt.state().t, 2);
}

#[test]
fn clip_grad_norm_scales_to_threshold() {
    let mut a = [3.0f32, 0.0];
    let mut b = [4.0f32];
    let norm = clip_grad_norm(&mut [&mut a, &mut b], 1.0);
    assert_eq!(norm, 5.0);
    assert!((a[0] - 0.6).abs() < 1e-7 && a[1] == 0.0 && (b[0] - 0.8).abs() < 1e-7);
    // Below the threshold nothing changes.
    let mut c = [0.3f32, 0.4];
    assert!((clip_grad_norm(&mut [&mut c], 1.0) - 0.5).abs() < 1e-7);
    assert_eq!(c, [0.3, 0.4]);
}

#[test]
fn clipping_happens_before_l2() {
    let cfg = AdamConfig {
        lr: 0.1,
        l2: 0.5,
        grad_clip: Some(1.0),
        ..AdamConfig::default()
    };
    let mut p = params();
    let mut opt = Adam::new(cfg, &p).unwrap();
    // g = [3, 0, −4], ‖g‖ = 5 → clipped [0.6, 0, −0.8]; then L2 on weights:
    // g' = [0.6 + 0.5·1, 0 + 0.5·(−2), −0.8] = [1.1, −1.0, −0.8]; m = (1 − β₁)g'.
    let norm = opt.step(&mut p, &[3.0, 0.0, -4.0]).unwrap();
    assert_eq!(norm, 5.0);
    let want = [0.11f32, -0.1, -0.08];
    for (a, b) in opt.state().m.iter().zip(want) {
        assert!((a - b).abs() < 1e-7, "m: {a} vs {b}");
    }
    let v_want = [0.001f32 * 1.21, 0.001, 0.001 * 0.64];
    for (a, b) in opt.state().v.iter().zip(v_want) {
        assert!((a - b).abs() < 1e-4 * b, "v: {a} vs {b}");
    }
}

#[test]
fn non_finite_gradient_is_refused() {
    let mut p = params();
    let before = p.to_flat();
    let mut opt = Adam::new(AdamConfig::default(), &p).unwrap();
    let err = opt.step(&mut p, &[f32::NAN, 0.0, 0.0]).unwrap_err();
    assert!(matches!(err, NnError::NonFiniteGradient { .. }), "{err}");
    assert_eq!(p.to_flat(), before);
    assert_eq!(opt.state().t, 0);
    let err = opt.step(&mut p, &[0.0, 0.0]).unwrap_err();
    assert!(matches!(err, NnError::LengthMismatch { .. }), "{err}");
}

#[test]
fn invalid_config_names_the_field() {
    let p = params();
    for (cfg, field) in [
        (
            AdamConfig {
                lr: -1.0,
                ..AdamConfig::default()
            },
            "adam.lr",
        ),
        (
            AdamConfig {
                beta1: 1.0,
                ..AdamConfig::default()
            },
            "adam.beta1",
        ),
        (
            AdamConfig {
                l2: f32::NAN,
                ..AdamConfig::default()
            },
            "adam.l2",
        ),
        (
            AdamConfig {
                grad_clip: Some(0.0),
                ..AdamConfig::default()
            },
            "adam.grad_clip",
        ),
    ] {
        let err = Adam::new(cfg, &p).unwrap_err();
        assert!(err.to_string().contains(field), "{err}");
    }
}

/// The two-pass definition: clip the gradient in place, then the elementwise update with L2
/// on the weights (`mask` 1) only, all in f32 as the module doc writes it.
fn two_pass_reference(
    cfg: &AdamConfig,
    theta: &mut [f32],
    grad: &mut [f32],
    mask: &[f32],
    m: &mut [f32],
    v: &mut [f32],
    t: i32,
) {
    if let Some(c) = cfg.grad_clip {
        clip_grad_norm(&mut [grad], c);
    }
    let step = (cfg.lr as f64 / (1.0 - (cfg.beta1 as f64).powi(t))) as f32;
    let inv_sqrt_bc2 = (1.0 / (1.0 - (cfg.beta2 as f64).powi(t)).sqrt()) as f32;
    for i in 0..theta.len() {
        let g = grad[i] + cfg.l2 * mask[i] * theta[i];
        m[i] = cfg.beta1 * m[i] + (1.0 - cfg.beta1) * g;
        v[i] = cfg.beta2 * v[i] + (1.0 - cfg.beta2) * g * g;
        theta[i] -= step * m[i] / (v[i].sqrt() * inv_sqrt_bc2 + cfg.eps);
    }
}

#[test]
fn the_fused_step_equals_clipping_then_updating_bit_for_bit() {
    // Weights and biases interleaved, sizes that leave SIMD remainders.
    let mut p = Params::new();
    let mut x = 0.37f32;
    let mut next = move || {
        x = (x * 7.31 + 0.13).fract();
        x - 0.5
    };
    for (i, len) in [67usize, 5, 130, 1, 33].into_iter().enumerate() {
        p.add(&format!("t{i}"), &[len], i % 2 == 0, &mut next);
    }
    let mask: Vec<f32> = p
        .specs()
        .iter()
        .flat_map(|s| std::iter::repeat_n(if s.decay { 1.0 } else { 0.0 }, s.len()))
        .collect();
    for clip in [None, Some(0.5), Some(1e6)] {
        let cfg = AdamConfig {
            lr: 3e-3,
            l2: 0.05,
            grad_clip: clip,
            ..AdamConfig::default()
        };
        let mut fused = p.clone();
        let mut opt = Adam::new(cfg.clone(), &fused).unwrap();
        let mut theta = p.to_flat();
        let (mut m, mut v) = (vec![0.0f32; theta.len()], vec![0.0f32; theta.len()]);
        for t in 1..=4 {
            let g: Vec<f32> = (0..theta.len())
                .map(|i| (i as f32 * 0.71 + t as f32).sin())
                .collect();
            opt.step(&mut fused, &g).unwrap();
            two_pass_reference(&cfg, &mut theta, &mut g.clone(), &mask, &mut m, &mut v, t);
        }
        let bits = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fused.to_flat()), bits(&theta), "θ, clip {clip:?}");
        assert_eq!(bits(&opt.state().m), bits(&m), "m, clip {clip:?}");
        assert_eq!(bits(&opt.state().v), bits(&v), "v, clip {clip:?}");
    }
}
