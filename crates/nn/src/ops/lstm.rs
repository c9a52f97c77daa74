//! A whole LSTM sequence as one op, with backpropagation through time inside.
//!
//! Gates follow PyTorch's order and layout: the rows of `W_ih` (4H, I) and `W_hh` (4H, H) are
//! the blocks [i; f; g; o]; one bias b (4H) (PyTorch keeps two, `bias_ih + bias_hh`):
//!
//! ```text
//! z_t = x_t·W_ihᵀ + h_{t−1}·W_hhᵀ + b            (B, 4H)
//! i = σ(z_i)  f = σ(z_f)  g = tanh(z_g)  o = σ(z_o)
//! c_t = f ⊙ c_{t−1} + i ⊙ g
//! h_t = o ⊙ tanh(c_t)
//! ```
//!
//! Inputs are time-major `(T·B, I)`; the input projection of all T steps is one product per
//! input block (the input may be given as column blocks `[x₁ | x₂ | …]`, never concatenated;
//! blocks that need no gradient cost no backward product).

use crate::gemm::{gemm, gemm_ex, Tr};
use crate::graph::{BackCtx, Backward, Graph, Op, Var};
use crate::kern;
use crate::ops::linear::col_sum_into;
use crate::params::Params;
use crate::tensor::Tensor;

/// Where an LSTM's tensors sit in its [`Params`] and its sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct LstmSlots {
    pub(crate) w_ih: usize,
    pub(crate) w_hh: usize,
    pub(crate) b: usize,
    pub(crate) input: usize,
    pub(crate) hidden: usize,
}

/// The recorded op: inputs, slots and the caches BPTT needs.
pub(crate) struct LstmNode {
    xs: Vec<Var>,
    h0: Var,
    c0: Var,
    set: usize,
    s: LstmSlots,
    batch: usize,
    /// Activated gates [i f g o] per row, (T·B, 4H).
    gates: Vec<f32>,
    /// Cell states c_t, (T·B, H).
    c: Vec<f32>,
    /// tanh(c_t), (T·B, H).
    tc: Vec<f32>,
}

impl Drop for LstmNode {
    fn drop(&mut self) {
        crate::pool::recycle(std::mem::take(&mut self.gates));
        crate::pool::recycle(std::mem::take(&mut self.c));
        crate::pool::recycle(std::mem::take(&mut self.tc));
    }
}

impl<'a> Graph<'a> {
    /// Runs the LSTM in `params` at `s` over `x = [x₁ | x₂ | …]` (T·B, I) time-major from the
    /// state `h0`, `c0` (B, H). Returns the hidden sequence (T·B, H) and the final cell state
    /// (the final hidden state is the last B rows of the sequence).
    ///
    /// Derivatives (BPTT), per step from t = T−1 down, with dh = dy_t + dh_{t+1→t}:
    /// do = dh ⊙ tanh c_t; dc = dc_{t+1→t} + dh ⊙ o ⊙ (1 − tanh² c_t);
    /// di = dc ⊙ g; dg = dc ⊙ i; df = dc ⊙ c_{t−1}; dc_{t→t−1} = dc ⊙ f;
    /// dz = [di·i(1−i), df·f(1−f), dg·(1−g²), do·o(1−o)]; dh_{t→t−1} = dz·W_hh.
    /// Then dW_ih = Σ dzᵀx, dW_hh = Σ dz_tᵀh_{t−1}, db = Σ dz, dx = dz·W_ih.
    pub(crate) fn lstm_op(
        &mut self,
        params: &'a Params,
        s: LstmSlots,
        xs: &[Var],
        h0: Var,
        c0: Var,
        batch: usize,
    ) -> (Var, Tensor) {
        let (set, trainable) = self.bind(params);
        let p = self.pvals(set);
        let h = s.hidden;
        let g4 = 4 * h;
        assert!(!xs.is_empty(), "lstm: no input");
        let rows = self.value(xs[0]).rows();
        let width: usize = xs.iter().map(|&x| self.value(x).cols()).sum();
        assert_eq!(
            width, s.input,
            "lstm: inputs have {width} columns in all, layer expects {}",
            s.input
        );
        assert!(
            batch > 0 && rows.is_multiple_of(batch) && rows > 0,
            "lstm: {rows} rows is not a positive multiple of batch {batch}"
        );
        let (h0v, c0v) = (self.value(h0), self.value(c0));
        assert_eq!(h0v.shape(), (batch, h), "lstm: h0 shape");
        assert_eq!(c0v.shape(), (batch, h), "lstm: c0 shape");
        let mut out = Tensor::uninit(rows, h);
        let mut gates = crate::pool::dirty(rows * g4);
        let mut c = crate::pool::dirty(rows * h);
        let mut tc = crate::pool::dirty(rows * h);
        // Input projection of all steps: one product per input block, no bias yet.
        let mut off = 0;
        for (k, &x) in xs.iter().enumerate() {
            let xv = self.value(x);
            assert_eq!(
                xv.rows(),
                rows,
                "lstm: input blocks have {} and {rows} rows",
                xv.rows()
            );
            let wk = xv.cols();
            gemm_ex(
                &mut gates,
                g4,
                rows,
                g4,
                wk,
                xv.data(),
                wk,
                Tr::N,
                &p[s.w_ih + off..],
                s.input,
                Tr::T,
                k > 0,
            );
            off += wk;
        }
        recurrence(
            p,
            s,
            h0v.data(),
            c0v.data(),
            batch,
            out.data_mut(),
            &mut gates,
            &mut c,
            &mut tc,
        );
        let steps = rows / batch;
        let c_last = Tensor::from_slice(batch, h, &c[(steps - 1) * batch * h..]);
        let rg = trainable || xs.iter().any(|&x| self.rg(x)) || self.rg(h0) || self.rg(c0);
        let keep = rg && self.grad_enabled();
        let (gates, c, tc) = if keep {
            (gates, c, tc)
        } else {
            crate::pool::recycle(gates);
            crate::pool::recycle(c);
            crate::pool::recycle(tc);
            (Vec::new(), Vec::new(), Vec::new())
        };
        let node = LstmNode {
            xs: xs.to_vec(),
            h0,
            c0,
            set,
            s,
            batch,
            gates,
            c,
            tc,
        };
        (self.push(out, Op::of(node), rg), c_last)
    }
}

/// The recurrent part of the forward, given the input projections (without bias) in
/// `gates` (T·B, 4H): fills `out` (T·B, H), activates `gates`, fills `c` and `tc`.
#[allow(clippy::too_many_arguments)]
fn recurrence(
    p: &[f32],
    s: LstmSlots,
    h0: &[f32],
    c0: &[f32],
    batch: usize,
    out: &mut [f32],
    gates: &mut [f32],
    c: &mut [f32],
    tc: &mut [f32],
) {
    let h = s.hidden;
    let g4 = 4 * h;
    let steps = out.len() / (batch * h);
    let w_hh = &p[s.w_hh..s.w_hh + g4 * h];
    let bias = &p[s.b..s.b + g4];
    let bh = batch * h;
    for t in 0..steps {
        let z = &mut gates[t * batch * g4..(t + 1) * batch * g4];
        let (done, cur) = out.split_at_mut(t * bh);
        let h_prev: &[f32] = if t == 0 { h0 } else { &done[(t - 1) * bh..] };
        gemm(z, batch, g4, h, h_prev, Tr::N, w_hh, Tr::T, true);
        let (c_done, c_cur) = c.split_at_mut(t * bh);
        let c_prev: &[f32] = if t == 0 { c0 } else { &c_done[(t - 1) * bh..] };
        cell_forward(
            z,
            bias,
            c_prev,
            &mut c_cur[..bh],
            &mut tc[t * bh..(t + 1) * bh],
            &mut cur[..bh],
            batch,
            h,
        );
    }
}

kern::simd_fn! {
    /// Adds the bias, applies the gate nonlinearities and updates the state for one step of
    /// B rows; `z` (B, 4H) is activated in place.
    pub(crate) fn cell_forward<'a>(z: &'a mut [f32], bias: &'a [f32], c_prev: &'a [f32], c: &'a mut [f32], tc: &'a mut [f32], hout: &'a mut [f32], batch: usize, h: usize) {
        let (bi, rest) = bias.split_at(h);
        let (bf, rest) = rest.split_at(h);
        let (bg, bo) = rest.split_at(h);
        for r in 0..batch {
            let zr = &mut z[r * 4 * h..(r + 1) * 4 * h];
            let (zi, rest) = zr.split_at_mut(h);
            let (zf, rest) = rest.split_at_mut(h);
            let (zg, zo) = rest.split_at_mut(h);
            let rr = r * h..(r + 1) * h;
            cell_forward_row(zi, zf, zg, zo, bi, bf, bg, bo, &c_prev[rr.clone()], &mut c[rr.clone()], &mut tc[rr.clone()], &mut hout[rr]);
        }
    }
}

/// One row of [`cell_forward`]. Every slice is its own argument so it carries `noalias`
/// and the loop vectorises without runtime overlap checks (slices packed in an array or
/// split inside the function lose that and fall back to scalar code).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn cell_forward_row(
    zi: &mut [f32],
    zf: &mut [f32],
    zg: &mut [f32],
    zo: &mut [f32],
    bi: &[f32],
    bf: &[f32],
    bg: &[f32],
    bo: &[f32],
    cp: &[f32],
    c: &mut [f32],
    tc: &mut [f32],
    h: &mut [f32],
) {
    let n = zi.len();
    let (zf, zg, zo, cp, c, tc, h) = (
        &mut zf[..n],
        &mut zg[..n],
        &mut zo[..n],
        &cp[..n],
        &mut c[..n],
        &mut tc[..n],
        &mut h[..n],
    );
    let (bi, bf, bg, bo) = (&bi[..n], &bf[..n], &bg[..n], &bo[..n]);
    for j in 0..n {
        let i = kern::sigmoid(zi[j] + bi[j]);
        let f = kern::sigmoid(zf[j] + bf[j]);
        let g = kern::tanh(zg[j] + bg[j]);
        let o = kern::sigmoid(zo[j] + bo[j]);
        let cn = f * cp[j] + i * g;
        let t = kern::tanh(cn);
        zi[j] = i;
        zf[j] = f;
        zg[j] = g;
        zo[j] = o;
        c[j] = cn;
        tc[j] = t;
        h[j] = o * t;
    }
}

/// BPTT; see [`Graph::lstm_op`] for the derivatives.
pub(crate) fn lstm_backward(n: &LstmNode, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let s = n.s;
    let (h, batch) = (s.hidden, n.batch);
    let g4 = 4 * h;
    let rows = dy.rows();
    let steps = rows / batch;
    let bh = batch * h;
    let p = ctx.pvals(n.set);
    let w_hh = &p[s.w_hh..s.w_hh + g4 * h];
    let (h0v, c0v) = (ctx.val(n.h0), ctx.val(n.c0));
    let need_h0 = ctx.rg(n.h0);
    let mut dz = crate::pool::dirty(rows * g4);
    let mut dh_next = crate::pool::zeros(bh);
    let mut dc_next = crate::pool::zeros(bh);
    for t in (0..steps).rev() {
        let c_prev: &[f32] = if t == 0 {
            c0v.data()
        } else {
            &n.c[(t - 1) * bh..t * bh]
        };
        let zt = &mut dz[t * batch * g4..(t + 1) * batch * g4];
        let rt = t * bh..(t + 1) * bh;
        cell_backward(
            &n.gates[t * batch * g4..(t + 1) * batch * g4],
            &n.tc[rt.clone()],
            c_prev,
            &dy.data()[rt],
            &dh_next,
            &mut dc_next,
            zt,
            batch,
            h,
        );
        if t > 0 || need_h0 {
            gemm(&mut dh_next, batch, h, g4, zt, Tr::N, w_hh, Tr::N, false);
        }
    }
    if let Some(g) = ctx.grad(n.h0) {
        g.data_mut()
            .iter_mut()
            .zip(&dh_next)
            .for_each(|(a, b)| *a += b);
    }
    if let Some(g) = ctx.grad(n.c0) {
        g.data_mut()
            .iter_mut()
            .zip(&dc_next)
            .for_each(|(a, b)| *a += b);
    }
    let xvals: Vec<&Tensor> = n.xs.iter().map(|&x| ctx.val(x)).collect();
    let ranges = [
        s.w_ih..s.w_ih + g4 * s.input,
        s.w_hh..s.w_hh + g4 * h,
        s.b..s.b + g4,
    ];
    if let Some(pg) = ctx.pgrad_zeroed(n.set, &ranges) {
        let mut off = 0;
        for xv in &xvals {
            let wk = xv.cols();
            gemm_ex(
                &mut pg[s.w_ih + off..],
                s.input,
                g4,
                wk,
                rows,
                &dz,
                g4,
                Tr::T,
                xv.data(),
                wk,
                Tr::N,
                true,
            );
            off += wk;
        }
        let dwhh = &mut pg[s.w_hh..s.w_hh + g4 * h];
        gemm(
            dwhh,
            g4,
            h,
            batch,
            &dz[..batch * g4],
            Tr::T,
            h0v.data(),
            Tr::N,
            true,
        );
        if steps > 1 {
            gemm(
                dwhh,
                g4,
                h,
                rows - batch,
                &dz[batch * g4..],
                Tr::T,
                &y.data()[..(rows - batch) * h],
                Tr::N,
                true,
            );
        }
        col_sum_into(&mut pg[s.b..s.b + g4], &dz, rows, g4);
    }
    let mut off = 0;
    for (&x, xv) in n.xs.iter().zip(&xvals) {
        let wk = xv.cols();
        if let Some((dx, fresh)) = ctx.grad_fresh(x) {
            gemm_ex(
                dx.data_mut(),
                wk,
                rows,
                wk,
                g4,
                &dz,
                g4,
                Tr::N,
                &p[s.w_ih + off..],
                s.input,
                Tr::N,
                !fresh,
            );
        }
        off += wk;
    }
    crate::pool::recycle(dz);
    crate::pool::recycle(dh_next);
    crate::pool::recycle(dc_next);
}

kern::simd_fn! {
    /// One step of the cell's backward for B rows: writes the pre-activation gradient `dz`
    /// (B, 4H) and replaces `dc` (carried c gradient) by its value at t − 1.
    fn cell_backward<'a>(gates: &'a [f32], tc: &'a [f32], c_prev: &'a [f32], dy: &'a [f32], dh_next: &'a [f32], dc: &'a mut [f32], dz: &'a mut [f32], batch: usize, h: usize) {
        for r in 0..batch {
            let gr = &gates[r * 4 * h..(r + 1) * 4 * h];
            let zr = &mut dz[r * 4 * h..(r + 1) * 4 * h];
            let (dzi, rest) = zr.split_at_mut(h);
            let (dzf, rest) = rest.split_at_mut(h);
            let (dzg, dzo) = rest.split_at_mut(h);
            let rr = r * h..(r + 1) * h;
            cell_backward_row(
                &gr[..h],
                &gr[h..2 * h],
                &gr[2 * h..3 * h],
                &gr[3 * h..],
                &tc[rr.clone()],
                &c_prev[rr.clone()],
                &dy[rr.clone()],
                &dh_next[rr.clone()],
                &mut dc[rr],
                dzi,
                dzf,
                dzg,
                dzo,
            );
        }
    }
}

/// One row of [`cell_backward`] (one argument per slice, see [`cell_forward_row`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn cell_backward_row(
    gi: &[f32],
    gf: &[f32],
    gg: &[f32],
    go: &[f32],
    tc: &[f32],
    cp: &[f32],
    dy: &[f32],
    dhn: &[f32],
    dc: &mut [f32],
    dzi: &mut [f32],
    dzf: &mut [f32],
    dzg: &mut [f32],
    dzo: &mut [f32],
) {
    let n = dc.len();
    let (gi, gf, gg, go, tc, cp, dy, dhn) = (
        &gi[..n],
        &gf[..n],
        &gg[..n],
        &go[..n],
        &tc[..n],
        &cp[..n],
        &dy[..n],
        &dhn[..n],
    );
    let (dzi, dzf, dzg, dzo) = (&mut dzi[..n], &mut dzf[..n], &mut dzg[..n], &mut dzo[..n]);
    for j in 0..n {
        let (i, f, g, og) = (gi[j], gf[j], gg[j], go[j]);
        let t = tc[j];
        let dh = dy[j] + dhn[j];
        let d_o = dh * t;
        let dcc = dc[j] + dh * og * (1.0 - t * t);
        dzi[j] = dcc * g * i * (1.0 - i);
        dzf[j] = dcc * cp[j] * f * (1.0 - f);
        dzg[j] = dcc * i * (1.0 - g * g);
        dzo[j] = d_o * og * (1.0 - og);
        dc[j] = dcc * f;
    }
}

impl Backward for LstmNode {
    fn backward(&self, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        lstm_backward(self, y, dy, ctx);
    }
}
