//! Contract: every graph op's forward matches an independent f64 implementation, and its
//! backward matches f64 central differences of that implementation (|error| ≤ 1e-4 +
//! 1e-3·|reference|). Each loss is Σ w ⊙ op(inputs) with random weights w, so every output
//! element's gradient is exercised with a different factor. Literal values for a few
//! derivatives are checked too.

mod common;
use common::*;
use esrl_nn::*;

type Build = dyn Fn(&mut Graph<'_>, &[Var]) -> Var;
type Reference = dyn Fn(&[Vec<f64>]) -> Vec<f64>;

/// Checks one op: `shapes` of the inputs and their value range, `build` records the op on
/// leaves, `reference` computes the op's output in f64 (row-major).
fn check(name: &str, shapes: &[(usize, usize, f32, f32)], build: &Build, reference: &Reference) {
    let inputs: Vec<Vec<f32>> = shapes
        .iter()
        .enumerate()
        .map(|(k, &(r, c, lo, hi))| uniform(r * c, lo, hi, 100 + k as u64))
        .collect();
    let mut g = Graph::new();
    let vars: Vec<Var> = inputs
        .iter()
        .zip(shapes)
        .map(|(v, &(r, c, _, _))| g.leaf(Tensor::from_slice(r, c, v)))
        .collect();
    let y = build(&mut g, &vars);
    let (yr, yc) = g.shape(y);
    let w = uniform(yr * yc, -1.0, 1.0, 7);
    let wv = g.constant(Tensor::from_slice(yr, yc, &w));
    let yw = g.mul(y, wv);
    let loss = g.sum(yw);
    let y_val = g.value(y).data().to_vec();
    let grads = g.backward(loss);

    let x64: Vec<Vec<f64>> = inputs.iter().map(|v| f64s(v)).collect();
    let y_ref = reference(&x64);
    assert_close(&format!("{name} forward"), &y_val, &y_ref, 1e-5, 1e-6);
    let w64 = f64s(&w);
    let f = |x: &[Vec<f64>]| {
        reference(x)
            .iter()
            .zip(&w64)
            .map(|(a, b)| a * b)
            .sum::<f64>()
    };
    let fd = central_differences(&x64, &f);
    for (k, v) in vars.iter().enumerate() {
        let (r, c, _, _) = shapes[k];
        let zero = Tensor::zeros(r, c);
        let an = grads.var(*v).unwrap_or(&zero);
        assert_close(
            &format!("{name} d/dinput{k}"),
            an.data(),
            &fd[k],
            1e-3,
            1e-4,
        );
    }
}

fn unary(name: &str, lo: f32, hi: f32, op: fn(&mut Graph<'_>, Var) -> Var, f: fn(f64) -> f64) {
    check(
        name,
        &[(3, 4, lo, hi)],
        &move |g, v| op(g, v[0]),
        &move |x| x[0].iter().map(|&v| f(v)).collect(),
    );
}

#[test]
fn unary_ops() {
    unary("relu", -1.0, 1.0, |g, x| g.relu(x), |v| v.max(0.0));
    unary("tanh", -3.0, 3.0, |g, x| g.tanh(x), f64::tanh);
    unary("sigmoid", -6.0, 6.0, |g, x| g.sigmoid(x), sigmoid);
    unary("softplus", -8.0, 8.0, |g, x| g.softplus(x), softplus);
    unary("exp", -3.0, 3.0, |g, x| g.exp(x), f64::exp);
    unary("log", 0.2, 4.0, |g, x| g.log(x), f64::ln);
    unary("neg", -2.0, 2.0, |g, x| g.neg(x), |v| -v);
    unary("square", -2.0, 2.0, |g, x| g.square(x), |v| v * v);
    unary("scale", -2.0, 2.0, |g, x| g.scale(x, -1.7), |v| -1.7 * v);
    unary(
        "add_scalar",
        -2.0,
        2.0,
        |g, x| g.add_scalar(x, 0.3),
        |v| v + 0.3,
    );
}

fn binary(
    name: &str,
    shapes: [(usize, usize); 2],
    op: fn(&mut Graph<'_>, Var, Var) -> Var,
    f: fn(f64, f64) -> f64,
) {
    let (lo_b, hi_b) = if name.starts_with("div") {
        (0.5, 2.0)
    } else {
        (-2.0, 2.0)
    };
    check(
        name,
        &[
            (shapes[0].0, shapes[0].1, -2.0, 2.0),
            (shapes[1].0, shapes[1].1, lo_b, hi_b),
        ],
        &move |g, v| op(g, v[0], v[1]),
        &move |x| {
            let n = x[0].len().max(x[1].len());
            (0..n)
                .map(|i| {
                    f(
                        x[0][if x[0].len() == 1 { 0 } else { i }],
                        x[1][if x[1].len() == 1 { 0 } else { i }],
                    )
                })
                .collect()
        },
    );
}

#[test]
fn binary_ops_with_broadcast() {
    for (tag, shapes) in [
        ("", [(3, 4), (3, 4)]),
        (" scalar right", [(3, 4), (1, 1)]),
        (" scalar left", [(1, 1), (3, 4)]),
    ] {
        binary(
            &format!("add{tag}"),
            shapes,
            |g, a, b| g.add(a, b),
            |a, b| a + b,
        );
        binary(
            &format!("sub{tag}"),
            shapes,
            |g, a, b| g.sub(a, b),
            |a, b| a - b,
        );
        binary(
            &format!("mul{tag}"),
            shapes,
            |g, a, b| g.mul(a, b),
            |a, b| a * b,
        );
        binary(
            &format!("div{tag}"),
            shapes,
            |g, a, b| g.div(a, b),
            |a, b| a / b,
        );
    }
    binary(
        "minimum",
        [(4, 3), (4, 3)],
        |g, a, b| g.minimum(a, b),
        f64::min,
    );
    binary(
        "maximum",
        [(4, 3), (4, 3)],
        |g, a, b| g.maximum(a, b),
        f64::max,
    );
}

#[test]
fn shape_ops_and_reductions() {
    check(
        "concat_cols",
        &[(3, 2, -1.0, 1.0), (3, 4, -1.0, 1.0)],
        &|g, v| g.concat_cols(v[0], v[1]),
        &|x| {
            (0..3)
                .flat_map(|r| {
                    x[0][r * 2..r * 2 + 2]
                        .iter()
                        .chain(&x[1][r * 4..r * 4 + 4])
                        .copied()
                        .collect::<Vec<_>>()
                })
                .collect()
        },
    );
    check(
        "slice_cols",
        &[(3, 5, -1.0, 1.0)],
        &|g, v| g.slice_cols(v[0], 1, 3),
        &|x| {
            (0..3)
                .flat_map(|r| x[0][r * 5 + 1..r * 5 + 4].to_vec())
                .collect()
        },
    );
    check("sum", &[(3, 5, -1.0, 1.0)], &|g, v| g.sum(v[0]), &|x| {
        vec![x[0].iter().sum()]
    });
    check("mean", &[(3, 5, -1.0, 1.0)], &|g, v| g.mean(v[0]), &|x| {
        vec![x[0].iter().sum::<f64>() / 15.0]
    });
    check(
        "sum_cols",
        &[(3, 5, -1.0, 1.0)],
        &|g, v| g.sum_cols(v[0]),
        &|x| x[0].chunks(5).map(|r| r.iter().sum()).collect(),
    );
    check(
        "mean_cols",
        &[(3, 5, -1.0, 1.0)],
        &|g, v| g.mean_cols(v[0]),
        &|x| {
            x[0].chunks(5)
                .map(|r| r.iter().sum::<f64>() / 5.0)
                .collect()
        },
    );
    check(
        "mse",
        &[(4, 3, -1.0, 1.0), (4, 3, -1.0, 1.0)],
        &|g, v| g.mse(v[0], v[1]),
        &|x| {
            vec![
                x[0].iter()
                    .zip(&x[1])
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    / 12.0,
            ]
        },
    );
}

/// f64 reference of act(x·Wᵀ + b).
fn linear_ref(x: &[f64], w: &[f64], b: &[f64], n: usize, i: usize, o: usize, act: Act) -> Vec<f64> {
    let mut y = vec![0.0; n * o];
    for r in 0..n {
        for k in 0..o {
            let z = b[k] + (0..i).map(|j| x[r * i + j] * w[k * i + j]).sum::<f64>();
            y[r * o + k] = match act {
                Act::None => z,
                Act::Relu => z.max(0.0),
                Act::Tanh => z.tanh(),
            };
        }
    }
    y
}

#[test]
fn linear_op_input_and_parameter_gradients() {
    let (n, i, o) = (5, 4, 3);
    for act in [Act::None, Act::Relu, Act::Tanh] {
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(3);
        let mut params = Params::new();
        let lin = Linear::new(&mut params, "l", i, o, &mut rng);
        let theta0 = params.to_flat();
        let x = uniform(n * i, -1.0, 1.0, 9);
        let w = uniform(n * o, -1.0, 1.0, 10);
        let (dx, dtheta, y) = {
            let mut g = Graph::new();
            let xv = g.leaf(Tensor::from_slice(n, i, &x));
            let y = lin.forward(&mut g, &params, xv, act);
            let wv = g.constant(Tensor::from_slice(n, o, &w));
            let yw = g.mul(y, wv);
            let loss = g.sum(yw);
            let yv = g.value(y).data().to_vec();
            let grads = g.backward(loss);
            (
                grads.var(xv).unwrap().data().to_vec(),
                grads.of(&params).unwrap().to_vec(),
                yv,
            )
        };
        // Parameter layout: weight (o, i) then bias (o).
        let split = |t: &[f64]| (t[..o * i].to_vec(), t[o * i..].to_vec());
        let (w0, b0) = split(&f64s(&theta0));
        assert_close(
            &format!("linear {act:?} forward"),
            &y,
            &linear_ref(&f64s(&x), &w0, &b0, n, i, o, act),
            1e-5,
            1e-6,
        );
        let w64 = f64s(&w);
        let f = |v: &[Vec<f64>]| {
            let (wt, bt) = split(&v[1]);
            linear_ref(&v[0], &wt, &bt, n, i, o, act)
                .iter()
                .zip(&w64)
                .map(|(a, b)| a * b)
                .sum::<f64>()
        };
        let fd = central_differences(&[f64s(&x), f64s(&theta0)], &f);
        assert_close(&format!("linear {act:?} dx"), &dx, &fd[0], 1e-3, 1e-4);
        assert_close(&format!("linear {act:?} dθ"), &dtheta, &fd[1], 1e-3, 1e-4);
    }
}

#[test]
fn param_op_accumulates_into_its_set() {
    let mut p = Params::new();
    p.add("log_alpha", &[1], false, || 0.3);
    let mut g = Graph::new();
    let la = g.param(&p, "log_alpha");
    let x = g.constant(Tensor::from_vec(4, 1, vec![1.0, -2.0, 0.5, 3.0]));
    // L = −mean(log α · (x + H̄)), H̄ = −1: dL/dlog α = −mean(x − 1) = −(2.5/4 − 1) = 0.375.
    let xh = g.add_scalar(x, -1.0);
    let prod = g.mul(la, xh);
    let m = g.mean(prod);
    let loss = g.neg(m);
    let grads = g.backward(loss);
    let d = grads.of(&p).unwrap()[0];
    assert!((d - 0.375).abs() < 1e-6, "{d}");
}

#[test]
fn literal_derivatives() {
    let mut g = Graph::new();
    let x = g.leaf(Tensor::from_vec(1, 3, vec![0.0, 1.0, -2.0]));
    let s = g.sigmoid(x);
    let loss = g.sum(s);
    let d = g.backward(loss).var(x).unwrap().data().to_vec();
    // σ'(0) = 1/4, σ'(1) = e⁻¹/(1 + e⁻¹)² = 0.19661193, σ'(−2) = 0.10499359.
    for (a, b) in d.iter().zip([0.25, 0.196_611_93, 0.104_993_59]) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
    let mut g = Graph::new();
    let x = g.leaf(Tensor::from_vec(1, 2, vec![0.0, 2.0]));
    let s = g.softplus(x);
    let loss = g.sum(s);
    assert!((g.value(s).get(0, 0) - std::f32::consts::LN_2).abs() < 1e-7);
    let d = g.backward(loss).var(x).unwrap().data().to_vec();
    assert!(
        (d[0] - 0.5).abs() < 1e-7 && (d[1] - 0.880_797_1).abs() < 1e-6,
        "{d:?}"
    );
}

#[test]
fn no_grad_graph_and_frozen_sets_compute_nothing() {
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(1);
    let mut params = Params::new();
    let lin = Linear::new(&mut params, "l", 3, 2, &mut rng);
    let x = Tensor::from_vec(2, 3, vec![0.1, 0.2, 0.3, -0.4, 0.5, -0.6]);
    let mut g = Graph::no_grad();
    let xv = g.leaf(x.clone());
    let y = lin.forward(&mut g, &params, xv, Act::Relu);
    let loss = g.sum(y);
    let grads = g.backward(loss);
    assert!(grads.of(&params).is_none() && grads.var(xv).is_none());

    let mut g = Graph::new();
    g.freeze(&params);
    let xv = g.leaf(x);
    let y = lin.forward(&mut g, &params, xv, Act::None);
    let loss = g.sum(y);
    let grads = g.backward(loss);
    assert!(grads.of(&params).is_none(), "frozen set got a gradient");
    // dx = 1·W summed over outputs: column sums of W (2, 3).
    let w = params.tensor("l.weight").unwrap();
    let want: Vec<f64> = (0..3).map(|j| (w[j] + w[3 + j]) as f64).collect();
    assert_close(
        "frozen dx",
        &grads.var(xv).unwrap().data()[..3],
        &want,
        1e-6,
        1e-7,
    );
}

#[test]
fn linear_on_column_blocks_equals_linear_on_their_concatenation() {
    // [x₁ | x₂]·Wᵀ without a concatenation: values and all gradients equal the concatenated
    // version's, and a constant block gets no gradient.
    let (n, i1, i2, o) = (4, 3, 2, 5);
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(8);
    let mut params = Params::new();
    let lin = Linear::new(&mut params, "l", i1 + i2, o, &mut rng);
    let x1 = Tensor::from_vec(n, i1, uniform(n * i1, -1.0, 1.0, 30));
    let x2 = Tensor::from_vec(n, i2, uniform(n * i2, -1.0, 1.0, 31));
    let w = Tensor::from_vec(n, o, uniform(n * o, -1.0, 1.0, 32));
    let run = |blocks: bool| {
        let mut g = Graph::new();
        let a = g.leaf(x1.clone());
        let b = g.constant(x2.clone());
        let y = if blocks {
            lin.forward_multi(&mut g, &params, &[a, b], Act::Tanh)
        } else {
            let x = g.concat_cols(a, b);
            lin.forward(&mut g, &params, x, Act::Tanh)
        };
        let wv = g.constant(w.clone());
        let yw = g.mul(y, wv);
        let loss = g.sum(yw);
        let yv = g.value(y).clone();
        let grads = g.backward(loss);
        assert!(grads.var(b).is_none());
        (
            yv,
            grads.var(a).unwrap().clone(),
            grads.of(&params).unwrap().to_vec(),
        )
    };
    let (y1, da1, dp1) = run(true);
    let (y2, da2, dp2) = run(false);
    assert_close("blocks forward", y1.data(), &f64s(y2.data()), 1e-6, 1e-7);
    assert_close("blocks dx₁", da1.data(), &f64s(da2.data()), 1e-6, 1e-7);
    assert_close("blocks dθ", &dp1, &f64s(&dp2), 1e-6, 1e-7);
}
