//! The fully connected op `y = act(x·Wᵀ + b)` (PyTorch's `nn.Linear` layout: W is (out, in)).
//!
//! The input may be given as column blocks `x = [x₁ | x₂ | …]` that are never concatenated:
//! each block multiplies its own column block of W (a strided view). The critic's state and
//! action paths feed their join this way, and in the actor loss only the action block, which
//! needs a gradient, pays for one.
//!
//! **Feature-major values.** Inside a stack of layers the op can keep its input and output
//! *feature-major*: stored transposed, as an (in, N) or (out, N) row-major tensor. Then the
//! product `yᵀ = W·xᵀ` has a column-major result in the frame of faer's kernels, which pack
//! the batch's activations (N × in) instead of the weight matrix (out × in): a quarter of the
//! copying at batch 64 and width 256 (`gemm`'s module docs). Every output element is the
//! same sequence of multiply-adds in either layout, and the bias gradient sums its rows in
//! the same order, so the numbers are the same bit for bit. The one exception is a layer
//! with a single output (the critic's Q): faer computes a matrix-vector product as dot
//! products along contiguous rows, in an order that depends on the layout, so that layer
//! reads a row-major copy of its feature-major input (about 4 % of a batch-64 update, less
//! than the packing it spares upstream).

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
    layout: Layout,
    /// Row-major copies of feature-major input blocks, made for a single-output layer.
    row_major: Vec<Tensor>,
}

/// Which of a linear op's values are stored feature-major (transposed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Layout {
    /// Every input block is stored (in_k, N) instead of (N, in_k).
    pub(crate) x_t: bool,
    /// The output is stored (out, N) instead of (N, out).
    pub(crate) y_t: bool,
}

/// `(rows, features)` of a value stored feature-major when `t`.
fn logical((r, c): (usize, usize), t: bool) -> (usize, usize) {
    if t {
        (c, r)
    } else {
        (r, c)
    }
}

/// Row stride and operand flag of a logical (N, features) matrix stored feature-major when
/// `t`.
fn operand(rows: usize, features: usize, t: bool) -> (usize, Tr) {
    if t {
        (rows, Tr::T)
    } else {
        (features, Tr::N)
    }
}

/// Row stride and operand flag of the *transpose* (features, N) of a logical (N, features)
/// matrix stored feature-major when `t`.
fn operand_t(rows: usize, features: usize, t: bool) -> (usize, Tr) {
    if t {
        (rows, Tr::N)
    } else {
        (features, Tr::T)
    }
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
        self.linear_op_in(params, w, b, (in_dim, out_dim), xs, act, Layout::default())
    }

    /// [`Graph::linear_op`] with its input blocks and output stored as `layout` says.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn linear_op_in(
        &mut self,
        params: &'a Params,
        w: usize,
        b: usize,
        (in_dim, out_dim): (usize, usize),
        xs: &[Var],
        act: Act,
        layout: Layout,
    ) -> Var {
        let (set, trainable) = self.bind(params);
        let p = self.pvals(set);
        assert!(!xs.is_empty(), "linear: no input");
        let shape = |g: &Self, x: Var| logical(g.value(x).shape(), layout.x_t);
        let n = shape(self, xs[0]).0;
        let width: usize = xs.iter().map(|&x| shape(self, x).1).sum();
        assert_eq!(
            width, in_dim,
            "linear: inputs have {width} columns in all, layer expects {in_dim}"
        );
        let mut out = if layout.y_t {
            Tensor::uninit(out_dim, n)
        } else {
            Tensor::uninit(n, out_dim)
        };
        // faer sums a matrix-vector product (one output) in an order that depends on the
        // matrix's layout: such a layer reads row-major copies of feature-major blocks, so
        // its output and weight gradient keep the bits of a row-major stack.
        let row_major: Vec<Tensor> = if layout.x_t && out_dim == 1 {
            xs.iter().map(|&x| transposed(self.value(x))).collect()
        } else {
            Vec::new()
        };
        let x_t = layout.x_t && row_major.is_empty();
        let mut off = 0;
        for (k, &x) in xs.iter().enumerate() {
            let (rows, wk) = shape(self, x);
            assert_eq!(rows, n, "linear: input blocks have {rows} and {n} rows");
            let xv = row_major.get(k).unwrap_or_else(|| self.value(x)).data();
            let wv = &p[w + off..];
            if layout.y_t {
                // yᵀ (out, N) = W_k (out, wk) · x_kᵀ (wk, N)
                let (ldx, tx) = operand_t(n, wk, x_t);
                gemm_ex(
                    out.data_mut(),
                    n,
                    out_dim,
                    n,
                    wk,
                    wv,
                    in_dim,
                    Tr::N,
                    xv,
                    ldx,
                    tx,
                    k > 0,
                );
            } else {
                // y (N, out) = x_k (N, wk) · W_kᵀ (wk, out)
                let (ldx, tx) = operand(n, wk, x_t);
                gemm_ex(
                    out.data_mut(),
                    out_dim,
                    n,
                    out_dim,
                    wk,
                    xv,
                    ldx,
                    tx,
                    wv,
                    in_dim,
                    Tr::T,
                    k > 0,
                );
            }
            off += wk;
        }
        let bias = &p[b..b + out_dim];
        if layout.y_t {
            bias_act_t(out.data_mut(), bias, act);
        } else {
            bias_act(out.data_mut(), bias, act);
        }
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
                layout,
                row_major,
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

/// In-place `v[j, :] ← act(v[j, :] + b[j])` for a feature-major `(b.len(), N)` value.
fn bias_act_t(v: &mut [f32], b: &[f32], act: Act) {
    match act {
        Act::None => bias_none_t(v, b),
        Act::Relu => bias_relu_t(v, b),
        Act::Tanh => bias_tanh_t(v, b),
    }
}

kern::simd_fn! {
    /// v[j, :] ← v[j, :] + b[j].
    fn bias_none_t<'a>(v: &'a mut [f32], b: &'a [f32]) {
        for (row, &c) in v.chunks_exact_mut(v.len() / b.len()).zip(b) {
            for x in row {
                *x += c;
            }
        }
    }
}

kern::simd_fn! {
    /// v[j, :] ← max(v[j, :] + b[j], 0).
    fn bias_relu_t<'a>(v: &'a mut [f32], b: &'a [f32]) {
        for (row, &c) in v.chunks_exact_mut(v.len() / b.len()).zip(b) {
            for x in row {
                *x = (*x + c).max(0.0);
            }
        }
    }
}

kern::simd_fn! {
    /// v[j, :] ← tanh(v[j, :] + b[j]).
    fn bias_tanh_t<'a>(v: &'a mut [f32], b: &'a [f32]) {
        for (row, &c) in v.chunks_exact_mut(v.len() / b.len()).zip(b) {
            for x in row {
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
        layout,
        row_major,
    } = node;
    let (set, w, b, in_dim, act, layout) = (*set, *w, *b, *in_dim, *act, *layout);
    let (n, o) = logical(dy.shape(), layout.y_t);
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
    let width = |xv: &Tensor| logical(xv.shape(), layout.x_t).1;
    if let Some((pg, fresh)) = ctx.pgrad_fresh(set, w..w + o * in_dim) {
        // The input blocks write disjoint column blocks of dW that cover it.
        // dW_k (out, wk) = dzᵀ (out, N) · x_k (N, wk)
        let (ldz, tz) = operand_t(n, o, layout.y_t);
        let x_t = layout.x_t && row_major.is_empty();
        let mut off = 0;
        for (k, xv) in xvals.iter().enumerate() {
            let wk = width(xv);
            let xv = row_major.get(k).unwrap_or(xv);
            let (ldx, tx) = operand(n, wk, x_t);
            gemm_ex(
                &mut pg[w + off..],
                in_dim,
                o,
                wk,
                n,
                dz,
                ldz,
                tz,
                xv.data(),
                ldx,
                tx,
                !fresh,
            );
            off += wk;
        }
    }
    let bias = b..b + o;
    if let Some(pg) = ctx.pgrad_zeroed(set, std::slice::from_ref(&bias)) {
        if layout.y_t {
            row_sum_into(&mut pg[bias], dz, n);
        } else {
            col_sum_into(&mut pg[bias], dz, n, o);
        }
    }
    let mut off = 0;
    for (&x, xv) in xs.iter().zip(&xvals) {
        let wk = width(xv);
        if let Some((dx, fresh)) = ctx.grad_fresh(x) {
            let wv = &p[w + off..];
            if layout.x_t {
                // dx_kᵀ (wk, N) = W_kᵀ (wk, out) · dzᵀ (out, N)
                let (ldz, tz) = operand_t(n, o, layout.y_t);
                gemm_ex(
                    dx.data_mut(),
                    n,
                    wk,
                    n,
                    o,
                    wv,
                    in_dim,
                    Tr::T,
                    dz,
                    ldz,
                    tz,
                    !fresh,
                );
            } else {
                // dx_k (N, wk) = dz (N, out) · W_k (out, wk)
                let (ldz, tz) = operand(n, o, layout.y_t);
                gemm_ex(
                    dx.data_mut(),
                    wk,
                    n,
                    wk,
                    o,
                    dz,
                    ldz,
                    tz,
                    wv,
                    in_dim,
                    Tr::N,
                    !fresh,
                );
            }
        }
        off += wk;
    }
    crate::pool::recycle(owned);
}

/// The (cols, rows) transpose of a (rows, cols) tensor.
fn transposed(t: &Tensor) -> Tensor {
    let (rows, cols) = t.shape();
    let mut out = Tensor::uninit(cols, rows);
    let src = t.data();
    let dst = out.data_mut();
    // Eight source rows at a time, each output row getting eight contiguous values.
    const R: usize = 8;
    let whole = rows / R * R;
    for (rb, block) in src[..whole * cols].chunks_exact(R * cols).enumerate() {
        let s: [&[f32]; R] = std::array::from_fn(|q| &block[q * cols..(q + 1) * cols]);
        for (c, d) in dst.chunks_exact_mut(rows).enumerate() {
            let d: &mut [f32; R] = (&mut d[rb * R..rb * R + R]).try_into().expect("8 values");
            *d = std::array::from_fn(|q| s[q][c]);
        }
    }
    for r in whole..rows {
        for (c, &v) in src[r * cols..(r + 1) * cols].iter().enumerate() {
            dst[c * rows + r] = v;
        }
    }
    out
}

/// acc[j] += Σ_r m[j, r] for a row-major (acc.len(), n) matrix, each sum taken in the order
/// of r, as [`col_sum_into`] takes it for the transpose (so both give the same bits). Eight
/// rows at a time, read in 8 × 8 tiles, keep eight independent sums in flight.
// The loops index a column across eight rows at once, which no single iterator expresses.
#[allow(clippy::needless_range_loop)]
pub(crate) fn row_sum_into(acc: &mut [f32], m: &[f32], n: usize) {
    const LANES: usize = 8;
    let whole = acc.len() / LANES * LANES;
    let (head, tail) = acc.split_at_mut(whole);
    let cols = n / LANES * LANES;
    for (a, block) in head.chunks_exact_mut(LANES).zip(m.chunks_exact(LANES * n)) {
        let rows: [&[f32]; LANES] = std::array::from_fn(|q| &block[q * n..(q + 1) * n]);
        let mut s: [f32; LANES] = (&*a).try_into().expect("eight sums");
        for c in (0..cols).step_by(LANES) {
            let tile: [[f32; LANES]; LANES] =
                std::array::from_fn(|q| rows[q][c..c + LANES].try_into().expect("eight values"));
            for k in 0..LANES {
                s = std::array::from_fn(|q| s[q] + tile[q][k]);
            }
        }
        for c in cols..n {
            s = std::array::from_fn(|q| s[q] + rows[q][c]);
        }
        a.copy_from_slice(&s);
    }
    for (a, row) in tail.iter_mut().zip(m[whole * n..].chunks_exact(n)) {
        *a = row.iter().fold(*a, |s, &v| s + v);
    }
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
