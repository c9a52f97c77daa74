//! Layers: descriptors of where a layer's tensors sit in a network's [`Params`], with a
//! forward that records the layer as one op in a [`Graph`].
//!
//! Initialisation follows PyTorch's defaults (weights and biases uniform in ±1/√fan_in for
//! `Linear`, ±1/√H for the LSTM) with the LSTM forget-gate bias set to 1 (MATLAB's
//! `unit-forget-gate` default, which the paper's networks used).

use crate::graph::{Graph, Var};
use crate::ops::lstm::LstmSlots;
use crate::ops::Act;
use crate::params::Params;
use crate::tensor::Tensor;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

fn uniform(rng: &mut ChaCha8Rng, bound: f32) -> impl FnMut() -> f32 + '_ {
    move || rng.random_range(-bound..=bound)
}

/// A fully connected layer `y = act(x·Wᵀ + b)`; tensors `{name}.weight` (out, in) and
/// `{name}.bias` (out).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Linear {
    pub(crate) w: usize,
    pub(crate) b: usize,
    in_dim: usize,
    out_dim: usize,
}

impl Linear {
    /// Adds the layer's tensors to `params`.
    pub fn new(
        params: &mut Params,
        name: &str,
        in_dim: usize,
        out_dim: usize,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let bound = 1.0 / (in_dim.max(1) as f32).sqrt();
        let w = params.add(
            &format!("{name}.weight"),
            &[out_dim, in_dim],
            true,
            uniform(rng, bound),
        );
        let b = params.add(
            &format!("{name}.bias"),
            &[out_dim],
            false,
            uniform(rng, bound),
        );
        Self {
            w,
            b,
            in_dim,
            out_dim,
        }
    }

    /// Several layers with the same input and output widths, stored so that they act as one
    /// layer of `names.len() · out_dim` outputs: first every `{name}.weight` (out, in), then
    /// every `{name}.bias` (out). The actor's mean and std heads are built this way.
    pub fn stacked<const K: usize>(
        params: &mut Params,
        names: [&str; K],
        in_dim: usize,
        out_dim: usize,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let bound = 1.0 / (in_dim.max(1) as f32).sqrt();
        let w = names
            .iter()
            .map(|n| {
                params.add(
                    &format!("{n}.weight"),
                    &[out_dim, in_dim],
                    true,
                    uniform(rng, bound),
                )
            })
            .min()
            .unwrap_or(0);
        let b = names
            .iter()
            .map(|n| params.add(&format!("{n}.bias"), &[out_dim], false, uniform(rng, bound)))
            .min()
            .unwrap_or(0);
        Self {
            w,
            b,
            in_dim,
            out_dim: K * out_dim,
        }
    }

    /// Input width.
    pub fn in_dim(&self) -> usize {
        self.in_dim
    }

    /// Output width.
    pub fn out_dim(&self) -> usize {
        self.out_dim
    }

    /// Records `act(x·Wᵀ + b)` for x (N, in) → (N, out).
    pub fn forward<'a>(&self, g: &mut Graph<'a>, params: &'a Params, x: Var, act: Act) -> Var {
        g.linear_op(params, self.w, self.b, self.in_dim, self.out_dim, &[x], act)
    }

    /// Records `act([x₁ | x₂ | …]·Wᵀ + b)` without concatenating: each block multiplies its
    /// column block of W, and only blocks that need a gradient get one.
    pub fn forward_multi<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        xs: &[Var],
        act: Act,
    ) -> Var {
        g.linear_op(params, self.w, self.b, self.in_dim, self.out_dim, xs, act)
    }

    /// Inference on one row without a graph: `out = act(x·Wᵀ + b)`.
    pub(crate) fn apply_row(&self, p: &[f32], x: &[f32], out: &mut [f32], act: Act) {
        let (i, o) = (self.in_dim, self.out_dim);
        let w = &p[self.w..self.w + i * o];
        gemv(&mut out[..o], w, &x[..i], false);
        crate::ops::linear::bias_act(&mut out[..o], &p[self.b..self.b + o], act);
    }
}

/// Dot product with 8 independent accumulators so it vectorises.
#[inline(always)]
pub(crate) fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let n = a.len().min(b.len());
    let (a8, ar) = a[..n].split_at(n / 8 * 8);
    let (b8, br) = b[..n].split_at(n / 8 * 8);
    for (ca, cb) in a8.chunks_exact(8).zip(b8.chunks_exact(8)) {
        for k in 0..8 {
            acc[k] += ca[k] * cb[k];
        }
    }
    let mut s = ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
    for (x, y) in ar.iter().zip(br) {
        s += x * y;
    }
    s
}

/// A stack of [`Linear`] layers with the same activation after each (FC+ReLU blocks).
/// Tensors `{name}.{k}.weight`, `{name}.{k}.bias` for k = 0, 1, ….
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mlp {
    layers: Vec<Linear>,
    act: Act,
    in_dim: usize,
}

impl Mlp {
    /// Adds layers of widths `hidden` after an input of `in_dim`.
    pub fn new(
        params: &mut Params,
        name: &str,
        in_dim: usize,
        hidden: &[usize],
        act: Act,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let mut layers = Vec::with_capacity(hidden.len());
        let mut d = in_dim;
        for (k, &h) in hidden.iter().enumerate() {
            layers.push(Linear::new(params, &format!("{name}.{k}"), d, h, rng));
            d = h;
        }
        Self {
            layers,
            act,
            in_dim,
        }
    }

    /// Output width (the input width when there is no layer).
    pub fn out_dim(&self) -> usize {
        self.layers.last().map_or(self.in_dim, |l| l.out_dim())
    }

    /// The layers.
    pub fn layers(&self) -> &[Linear] {
        &self.layers
    }

    /// Records all layers; returns `x` itself when there is none.
    pub fn forward<'a>(&self, g: &mut Graph<'a>, params: &'a Params, x: Var) -> Var {
        self.forward_multi(g, params, &[x])
    }

    /// Records all layers on the column blocks `[x₁ | x₂ | …]` (the first layer reads them
    /// without concatenating); with no layer, returns the concatenation.
    pub fn forward_multi<'a>(&self, g: &mut Graph<'a>, params: &'a Params, xs: &[Var]) -> Var {
        let Some((first, rest)) = self.layers.split_first() else {
            return xs[1..].iter().fold(xs[0], |acc, &x| g.concat_cols(acc, x));
        };
        let h = first.forward_multi(g, params, xs, self.act);
        rest.iter()
            .fold(h, |h, l| l.forward(g, params, h, self.act))
    }
}

/// The (h, c) state of an LSTM for B sequences: both (B, H).
#[derive(Clone, Debug, PartialEq)]
pub struct LstmState {
    /// Hidden state h, (B, H).
    pub h: Tensor,
    /// Cell state c, (B, H).
    pub c: Tensor,
}

impl LstmState {
    /// The zero state for `batch` sequences of an LSTM with `hidden` units.
    pub fn zeros(batch: usize, hidden: usize) -> Self {
        Self {
            h: Tensor::zeros(batch, hidden),
            c: Tensor::zeros(batch, hidden),
        }
    }

    /// Number of sequences B.
    pub fn batch(&self) -> usize {
        self.h.rows()
    }
}

/// Output of [`Lstm::forward`].
#[derive(Debug)]
pub struct LstmOutput {
    /// Hidden sequence (T·B, H), time-major.
    pub h: Var,
    /// State after the last step (values only; carries no gradient).
    pub state: LstmState,
}

/// A single-layer LSTM; tensors `{name}.weight_ih` (4H, I), `{name}.weight_hh` (4H, H),
/// `{name}.bias` (4H), gate blocks in PyTorch's order [i; f; g; o].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lstm {
    pub(crate) s: LstmSlots,
}

impl Lstm {
    /// Adds the layer's tensors to `params`.
    pub fn new(
        params: &mut Params,
        name: &str,
        input: usize,
        hidden: usize,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let bound = 1.0 / (hidden.max(1) as f32).sqrt();
        let w_ih = params.add(
            &format!("{name}.weight_ih"),
            &[4 * hidden, input],
            true,
            uniform(rng, bound),
        );
        let w_hh = params.add(
            &format!("{name}.weight_hh"),
            &[4 * hidden, hidden],
            true,
            uniform(rng, bound),
        );
        let mut k = 0usize;
        let mut u = uniform(rng, bound);
        let b = params.add(&format!("{name}.bias"), &[4 * hidden], false, || {
            let v = if (hidden..2 * hidden).contains(&k) {
                1.0
            } else {
                u()
            };
            k += 1;
            v
        });
        Self {
            s: LstmSlots {
                w_ih,
                w_hh,
                b,
                input,
                hidden,
            },
        }
    }

    /// Hidden size H.
    pub fn hidden(&self) -> usize {
        self.s.hidden
    }

    /// Input size I.
    pub fn input(&self) -> usize {
        self.s.input
    }

    /// Runs B = `batch` sequences: `x` is (T·B, I) time-major, `state` the initial (h, c)
    /// (zeros when `None`), taken as a constant.
    pub fn forward<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        x: Var,
        batch: usize,
        state: Option<&LstmState>,
    ) -> LstmOutput {
        self.forward_multi(g, params, &[x], batch, state)
    }

    /// Like [`Lstm::forward`] with the input given as column blocks `[x₁ | x₂ | …]` that are
    /// never concatenated (only blocks that need a gradient get one).
    pub fn forward_multi<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        xs: &[Var],
        batch: usize,
        state: Option<&LstmState>,
    ) -> LstmOutput {
        let (h0, c0) = match state {
            Some(s) => {
                assert_eq!(
                    s.batch(),
                    batch,
                    "Lstm::forward: state batch {} vs batch {batch}",
                    s.batch()
                );
                (g.constant(s.h.clone()), g.constant(s.c.clone()))
            }
            None => (
                g.constant(Tensor::zeros(batch, self.s.hidden)),
                g.constant(Tensor::zeros(batch, self.s.hidden)),
            ),
        };
        self.run(g, params, xs, batch, h0, c0)
    }

    /// Like [`Lstm::forward`] with the initial state as graph values (so gradients reach
    /// them when they are leaves).
    pub fn forward_vars<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        x: Var,
        batch: usize,
        h0: Var,
        c0: Var,
    ) -> LstmOutput {
        self.run(g, params, &[x], batch, h0, c0)
    }

    fn run<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        xs: &[Var],
        batch: usize,
        h0: Var,
        c0: Var,
    ) -> LstmOutput {
        let (h, c_last) = g.lstm_op(params, self.s, xs, h0, c0, batch);
        let rows = g.shape(h).0;
        let h_last = g.value(h).rows_range(rows - batch, batch);
        LstmOutput {
            h,
            state: LstmState {
                h: h_last,
                c: c_last,
            },
        }
    }

    /// One step for one sequence without a graph: updates `h`, `c` (H each) in place from
    /// input `x` (I); `scratch` holds at least 6H values.
    pub(crate) fn step_row(
        &self,
        p: &[f32],
        x: &[f32],
        h: &mut [f32],
        c: &mut [f32],
        scratch: &mut [f32],
    ) {
        let s = self.s;
        let (hd, i) = (s.hidden, s.input);
        let w_ih = &p[s.w_ih..s.w_ih + 4 * hd * i];
        let w_hh = &p[s.w_hh..s.w_hh + 4 * hd * hd];
        let (z, rest) = scratch[..6 * hd].split_at_mut(4 * hd);
        let (c_prev, tc) = rest.split_at_mut(hd);
        gemv(z, w_ih, x, false);
        gemv(z, w_hh, h, true);
        c_prev.copy_from_slice(c);
        crate::ops::lstm::cell_forward(z, &p[s.b..s.b + 4 * hd], c_prev, c, tc, h, 1, hd);
    }
}

crate::kern::simd_fn! {
    /// out[k] (+)= Σ_j w[k, j]·x[j] for a row-major (out.len(), x.len()) matrix w.
    pub(crate) fn gemv<'a>(out: &'a mut [f32], w: &'a [f32], x: &'a [f32], accumulate: bool) {
        let i = x.len();
        for (k, o) in out.iter_mut().enumerate() {
            let d = dot(&w[k * i..(k + 1) * i], x);
            *o = if accumulate { *o + d } else { d };
        }
    }
}
