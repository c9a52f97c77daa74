//! The fully connected op `y = act(x·Wᵀ + b)` (PyTorch's `nn.Linear` layout: W is (out, in)).
//!
//! The input may be given as column blocks `x = [x₁ | x₂ | …]` that are never concatenated:
//! each block multiplies its own column block of W (a strided view). The critic's state and
//! action paths feed their join this way, and in the actor loss only the action block, which
//! needs a gradient, pays for one.

use crate::gemm::{gemm_ex, Tr};
use crate::graph::{BackCtx, Backward, Graph, Op, Var};
use crate::kern;
use crate::ops::Act;
use crate::params::Params;
use crate::tensor::Tensor;

/// The recorded op.
pub(crate) struct LinearNode {
    xs: Vec<Var>,
    set: usize,
    w: usize,
    b: usize,
    in_dim: usize,
    act: Act,
}

impl<'a> Graph<'a> {
    /// `y = act([x₁ | x₂ | …]·Wᵀ + b)` with the x_k (N, i_k), Σ i_k = in, W (out, in) at `w`
    /// and b (out) at `b` inside `params`. Derivatives, with dz = dy ⊙ act'(·) (1[y > 0] for
    /// ReLU, 1 − y² for tanh): dx_k = dz·W[:, block k], dW[:, block k] = dzᵀ·x_k,
    /// db = Σ_rows dz.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn linear_op(
        &mut self,
        params: &'a Params,
        w: usize,
        b: usize,
        in_dim: usize,
        out_dim: usize,
        xs: &[Var],
        act: Act,
    ) -> Var {
        let (set, trainable) = self.bind(params);
        let p = self.pvals(set);
        assert!(!xs.is_empty(), "linear: no input");
        let n = self.value(xs[0]).rows();
        let width: usize = xs.iter().map(|&x| self.value(x).cols()).sum();
        assert_eq!(
            width, in_dim,
            "linear: inputs have {width} columns in all, layer expects {in_dim}"
        );
        let mut out = Tensor::uninit(n, out_dim);
        let mut off = 0;
        for (k, &x) in xs.iter().enumerate() {
            let xv = self.value(x);
            assert_eq!(
                xv.rows(),
                n,
                "linear: input blocks have {} and {n} rows",
                xv.rows()
            );
            let wk = xv.cols();
            gemm_ex(
                out.data_mut(),
                out_dim,
                n,
                out_dim,
                wk,
                xv.data(),
                wk,
                Tr::N,
                &p[w + off..],
                in_dim,
                Tr::T,
                k > 0,
            );
            off += wk;
        }
        bias_act(out.data_mut(), &p[b..b + out_dim], act);
        let rg = trainable || xs.iter().any(|&x| self.rg(x));
        self.push(
            out,
            Op::of(LinearNode {
                xs: xs.to_vec(),
                set,
                w,
                b,
                in_dim,
                act,
            }),
            rg,
        )
    }
}

/// In-place `v[r, :] ← act(v[r, :] + b)` for every row.
pub(crate) fn bias_act(v: &mut [f32], b: &[f32], act: Act) {
    match act {
        Act::None => bias_none(v, b),
        Act::Relu => bias_relu(v, b),
        Act::Tanh => bias_tanh(v, b),
    }
}

kern::simd_fn! {
    /// v ← v + b (row-broadcast).
    fn bias_none<'a>(v: &'a mut [f32], b: &'a [f32]) {
        for row in v.chunks_exact_mut(b.len()) {
            for (x, &c) in row.iter_mut().zip(b) {
                *x += c;
            }
        }
    }
}

kern::simd_fn! {
    /// v ← max(v + b, 0).
    fn bias_relu<'a>(v: &'a mut [f32], b: &'a [f32]) {
        for row in v.chunks_exact_mut(b.len()) {
            for (x, &c) in row.iter_mut().zip(b) {
                *x = (*x + c).max(0.0);
            }
        }
    }
}

kern::simd_fn! {
    /// v ← tanh(v + b).
    fn bias_tanh<'a>(v: &'a mut [f32], b: &'a [f32]) {
        for row in v.chunks_exact_mut(b.len()) {
            for (x, &c) in row.iter_mut().zip(b) {
                *x = kern::tanh(*x + c);
            }
        }
    }
}

kern::simd_fn! {
    /// dz ← dy ⊙ 1[y > 0].
    fn relu_mask<'a>(dz: &'a mut [f32], dy: &'a [f32], y: &'a [f32]) {
        // A multiply rather than `if y > 0 { dy } else { 0 }` (or a bit mask), which LLVM
        // turns into masked stores, microcoded and slow on AMD cores. (A NaN in dy stays NaN.)
        for ((z, &d), &y) in dz.iter_mut().zip(dy).zip(y) {
            *z = d * if y > 0.0 { 1.0 } else { 0.0 };
        }
    }
}

kern::simd_fn! {
    /// dz ← dy ⊙ (1 − y²).
    fn tanh_grad<'a>(dz: &'a mut [f32], dy: &'a [f32], y: &'a [f32]) {
        for ((z, &d), &y) in dz.iter_mut().zip(dy).zip(y) {
            *z = d * (1.0 - y * y);
        }
    }
}

/// Backward of [`Graph::linear_op`]; see its doc for the derivatives.
pub(crate) fn linear_backward(
    node: &LinearNode,
    y: &Tensor,
    dy: &Tensor,
    ctx: &mut BackCtx<'_, '_>,
) {
    let LinearNode {
        xs,
        set,
        w,
        b,
        in_dim,
        act,
    } = node;
    let (set, w, b, in_dim, act) = (*set, *w, *b, *in_dim, *act);
    let (n, o) = dy.shape();
    let mut owned = Vec::new();
    if act != Act::None {
        owned = crate::pool::dirty(dy.len());
        match act {
            Act::Relu => relu_mask(&mut owned, dy.data(), y.data()),
            Act::Tanh => tanh_grad(&mut owned, dy.data(), y.data()),
            Act::None => {}
        }
    }
    let dz: &[f32] = if act == Act::None { dy.data() } else { &owned };
    let p = ctx.pvals(set);
    let xvals: Vec<&Tensor> = xs.iter().map(|&x| ctx.val(x)).collect();
    if let Some((pg, fresh)) = ctx.pgrad_fresh(set, w..w + o * in_dim) {
        // The input blocks write disjoint column blocks of dW that cover it.
        let mut off = 0;
        for xv in &xvals {
            let wk = xv.cols();
            gemm_ex(
                &mut pg[w + off..],
                in_dim,
                o,
                wk,
                n,
                dz,
                o,
                Tr::T,
                xv.data(),
                wk,
                Tr::N,
                !fresh,
            );
            off += wk;
        }
    }
    let bias = b..b + o;
    if let Some(pg) = ctx.pgrad_zeroed(set, std::slice::from_ref(&bias)) {
        col_sum_into(&mut pg[bias], dz, n, o);
    }
    let mut off = 0;
    for (&x, xv) in xs.iter().zip(&xvals) {
        let wk = xv.cols();
        if let Some((dx, fresh)) = ctx.grad_fresh(x) {
            gemm_ex(
                dx.data_mut(),
                wk,
                n,
                wk,
                o,
                dz,
                o,
                Tr::N,
                &p[w + off..],
                in_dim,
                Tr::N,
                !fresh,
            );
        }
        off += wk;
    }
    crate::pool::recycle(owned);
}

kern::simd_fn! {
    /// acc[j] += Σ_r m[r, j] for a row-major (n, c) matrix.
    pub(crate) fn col_sum_into<'a>(acc: &'a mut [f32], m: &'a [f32], n: usize, c: usize) {
        for r in 0..n {
            for (a, &v) in acc.iter_mut().zip(&m[r * c..(r + 1) * c]) {
                *a += v;
            }
        }
    }
}

impl Backward for LinearNode {
    fn backward(&self, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        linear_backward(self, y, dy, ctx);
    }
}
