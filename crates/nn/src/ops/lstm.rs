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
//! Inputs are time-major `(T·B, I)`; the input projection of all T steps is one product.

use crate::gemm::{gemm, Tr};
use crate::graph::{BackCtx, Graph, Op, Var};
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
    x: Var,
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
    /// Runs the LSTM in `params` at `s` over `x` (T·B, I) time-major from the state
    /// `h0`, `c0` (B, H). Returns the hidden sequence (T·B, H) and the final cell state
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
        x: Var,
        h0: Var,
        c0: Var,
        batch: usize,
    ) -> (Var, Tensor) {
        let (set, trainable) = self.bind(params);
        let p = self.pvals(set);
        let (xv, h0v, c0v) = (self.value(x), self.value(h0), self.value(c0));
        let (rows, i_dim) = xv.shape();
        let h = s.hidden;
        assert_eq!(
            i_dim, s.input,
            "lstm: input has {i_dim} columns, layer expects {}",
            s.input
        );
        assert!(
            batch > 0 && rows % batch == 0,
            "lstm: {rows} rows is not a multiple of batch {batch}"
        );
        assert_eq!(h0v.shape(), (batch, h), "lstm: h0 shape");
        assert_eq!(c0v.shape(), (batch, h), "lstm: c0 shape");
        let mut out = Tensor::uninit(rows, h);
        let mut gates = crate::pool::dirty(rows * 4 * h);
        let mut c = crate::pool::dirty(rows * h);
        let mut tc = crate::pool::dirty(rows * h);
        lstm_forward(
            p,
            s,
            xv.data(),
            h0v.data(),
            c0v.data(),
            batch,
            out.data_mut(),
            &mut gates,
            &mut c,
            &mut tc,
        );
        let t = rows / batch;
        let c_last = Tensor::from_slice(batch, h, &c[(t - 1) * batch * h..]);
        let rg = trainable || self.rg(x) || self.rg(h0) || self.rg(c0);
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
            x,
            h0,
            c0,
            set,
            s,
            batch,
            gates,
            c,
            tc,
        };
        (self.push(out, Op::Lstm(Box::new(node)), rg), c_last)
    }
}

/// Forward over all steps; fills `out` (T·B, H), `gates` (T·B, 4H), `c` and `tc` (T·B, H).
#[allow(clippy::too_many_arguments)]
pub(crate) fn lstm_forward(
    p: &[f32],
    s: LstmSlots,
    x: &[f32],
    h0: &[f32],
    c0: &[f32],
    batch: usize,
    out: &mut [f32],
    gates: &mut [f32],
    c: &mut [f32],
    tc: &mut [f32],
) {
    let (h, i_dim) = (s.hidden, s.input);
    let g4 = 4 * h;
    let rows = x.len() / i_dim;
    let steps = rows / batch;
    let w_ih = &p[s.w_ih..s.w_ih + g4 * i_dim];
    let w_hh = &p[s.w_hh..s.w_hh + g4 * h];
    let bias = &p[s.b..s.b + g4];
    for r in 0..rows {
        gates[r * g4..(r + 1) * g4].copy_from_slice(bias);
    }
    gemm(gates, rows, g4, i_dim, x, Tr::N, w_ih, Tr::T, true);
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
    /// Gate nonlinearities and the state update for one step of B rows; activates `z` in
    /// place.
    pub(crate) fn cell_forward<'a>(z: &'a mut [f32], c_prev: &'a [f32], c: &'a mut [f32], tc: &'a mut [f32], hout: &'a mut [f32], batch: usize, h: usize) {
        for r in 0..batch {
            let zr = &mut z[r * 4 * h..(r + 1) * 4 * h];
            let (zi, rest) = zr.split_at_mut(h);
            let (zf, rest) = rest.split_at_mut(h);
            let (zg, zo) = rest.split_at_mut(h);
            let rr = r * h..(r + 1) * h;
            cell_forward_row(zi, zf, zg, zo, &c_prev[rr.clone()], &mut c[rr.clone()], &mut tc[rr.clone()], &mut hout[rr]);
        }
    }
}

/// One row of [`cell_forward`]. Separate slice arguments carry `noalias`, so the loop
/// vectorises without runtime overlap checks.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn cell_forward_row(
    zi: &mut [f32],
    zf: &mut [f32],
    zg: &mut [f32],
    zo: &mut [f32],
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
    for j in 0..n {
        let i = kern::sigmoid(zi[j]);
        let f = kern::sigmoid(zf[j]);
        let g = kern::tanh(zg[j]);
        let o = kern::sigmoid(zo[j]);
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
    let (h, i_dim, batch) = (s.hidden, s.input, n.batch);
    let g4 = 4 * h;
    let rows = dy.rows();
    let steps = rows / batch;
    let bh = batch * h;
    let p = ctx.pvals(n.set);
    let w_ih = &p[s.w_ih..s.w_ih + g4 * i_dim];
    let w_hh = &p[s.w_hh..s.w_hh + g4 * h];
    let (xv, h0v, c0v) = (ctx.val(n.x), ctx.val(n.h0), ctx.val(n.c0));
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
        cell_backward(
            &n.gates[t * batch * g4..(t + 1) * batch * g4],
            &n.tc[t * bh..(t + 1) * bh],
            c_prev,
            &dy.data()[t * bh..(t + 1) * bh],
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
    if let Some(pg) = ctx.pgrad(n.set) {
        gemm(
            &mut pg[s.w_ih..s.w_ih + g4 * i_dim],
            g4,
            i_dim,
            rows,
            &dz,
            Tr::T,
            xv.data(),
            Tr::N,
            true,
        );
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
    if let Some(dx) = ctx.grad(n.x) {
        gemm(
            dx.data_mut(),
            rows,
            i_dim,
            g4,
            &dz,
            Tr::N,
            w_ih,
            Tr::N,
            true,
        );
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
                [&gr[..h], &gr[h..2 * h], &gr[2 * h..3 * h], &gr[3 * h..]],
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

/// One row of [`cell_backward`] (separate slices so the loop vectorises).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn cell_backward_row(
    [gi, gf, gg, go]: [&[f32]; 4],
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
