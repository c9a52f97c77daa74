//! The fully connected op `y = act(x·Wᵀ + b)` (PyTorch's `nn.Linear` layout: W is (out, in)).

use crate::gemm::{gemm, Tr};
use crate::graph::{BackCtx, Graph, Op, Var};
use crate::kern;
use crate::ops::Act;
use crate::params::Params;
use crate::tensor::Tensor;

impl<'a> Graph<'a> {
    /// `y = act(x·Wᵀ + b)` with x (N, in), W (out, in) at `w` and b (out) at `b` inside
    /// `params`. Derivatives, with dz = dy ⊙ act'(·) (1[y > 0] for ReLU, 1 − y² for tanh):
    /// dx = dz·W, dW = dzᵀ·x, db = Σ_rows dz.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn linear_op(
        &mut self,
        params: &'a Params,
        w: usize,
        b: usize,
        in_dim: usize,
        out_dim: usize,
        x: Var,
        act: Act,
    ) -> Var {
        let (set, trainable) = self.bind(params);
        let p = self.pvals(set);
        let xv = self.value(x);
        assert_eq!(
            xv.cols(),
            in_dim,
            "linear: input has {} columns, layer expects {in_dim}",
            xv.cols()
        );
        let n = xv.rows();
        let mut out = Tensor::uninit(n, out_dim);
        linear_forward(
            out.data_mut(),
            xv.data(),
            &p[w..w + out_dim * in_dim],
            &p[b..b + out_dim],
            n,
            in_dim,
            out_dim,
            act,
        );
        let rg = self.rg(x) || trainable;
        self.push(out, Op::Linear { x, set, w, b, act }, rg)
    }
}

/// out (n, o) = act(x (n, i) · wᵀ + b).
#[allow(clippy::too_many_arguments)]
pub(crate) fn linear_forward(
    out: &mut [f32],
    x: &[f32],
    w: &[f32],
    b: &[f32],
    n: usize,
    i: usize,
    o: usize,
    act: Act,
) {
    for r in 0..n {
        out[r * o..(r + 1) * o].copy_from_slice(b);
    }
    gemm(out, n, o, i, x, Tr::N, w, Tr::T, true);
    apply_act(out, act);
}

/// In-place activation.
pub(crate) fn apply_act(v: &mut [f32], act: Act) {
    match act {
        Act::None => {}
        Act::Relu => relu_inplace(v),
        Act::Tanh => tanh_inplace(v),
    }
}

kern::simd_fn! {
    /// v ← max(v, 0).
    fn relu_inplace<'a>(v: &'a mut [f32]) {
        for x in v.iter_mut() {
            *x = x.max(0.0);
        }
    }
}

kern::simd_fn! {
    /// v ← tanh(v).
    fn tanh_inplace<'a>(v: &'a mut [f32]) {
        for x in v.iter_mut() {
            *x = kern::tanh(*x);
        }
    }
}

kern::simd_fn! {
    /// d ← d ⊙ 1[y > 0].
    fn relu_mask<'a>(d: &'a mut [f32], y: &'a [f32]) {
        for (d, &y) in d.iter_mut().zip(y) {
            *d = if y > 0.0 { *d } else { 0.0 };
        }
    }
}

kern::simd_fn! {
    /// d ← d ⊙ (1 − y²).
    fn tanh_grad<'a>(d: &'a mut [f32], y: &'a [f32]) {
        for (d, &y) in d.iter_mut().zip(y) {
            *d *= 1.0 - y * y;
        }
    }
}

/// Backward of [`Graph::linear_op`]; see its doc for the derivatives.
#[allow(clippy::too_many_arguments)]
pub(crate) fn linear_backward(
    x: Var,
    set: usize,
    w: usize,
    b: usize,
    act: Act,
    y: &Tensor,
    dy: &Tensor,
    ctx: &mut BackCtx<'_, '_>,
) {
    let (n, o) = dy.shape();
    let xv = ctx.val(x);
    let i = xv.cols();
    let mut owned = Vec::new();
    if act != Act::None {
        owned = crate::pool::copy(dy.data());
        match act {
            Act::Relu => relu_mask(&mut owned, y.data()),
            Act::Tanh => tanh_grad(&mut owned, y.data()),
            Act::None => {}
        }
    }
    let dz: &[f32] = if act == Act::None { dy.data() } else { &owned };
    let p = ctx.pvals(set);
    if let Some(pg) = ctx.pgrad(set) {
        gemm(
            &mut pg[w..w + o * i],
            o,
            i,
            n,
            dz,
            Tr::T,
            xv.data(),
            Tr::N,
            true,
        );
        col_sum_into(&mut pg[b..b + o], dz, n, o);
    }
    if let Some(dx) = ctx.grad(x) {
        gemm(
            dx.data_mut(),
            n,
            i,
            o,
            dz,
            Tr::N,
            &p[w..w + o * i],
            Tr::N,
            true,
        );
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
