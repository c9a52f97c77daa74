//! Layers: descriptors of where a layer's tensors sit in a network's [`Params`], with a
//! forward that records the layer as one op in a [`Graph`].
//!
//! Initialisation follows PyTorch's defaults (weights and biases uniform in ±1/√fan_in for
//! `Linear`, ±1/√H for the LSTM) with the LSTM forget-gate bias set to 1 (MATLAB's
//! `unit-forget-gate` default, which the paper's networks used).

use crate::graph::{Graph, Var};
use crate::ops::linear::Layout;
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

    /// Records the layer with its input blocks and output stored as `layout` says
    /// (feature-major values: `ops::linear`'s docs).
    pub(crate) fn forward_in<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        xs: &[Var],
        act: Act,
        layout: Layout,
    ) -> Var {
        let dims = (self.in_dim, self.out_dim);
        g.linear_op_in(params, self.w, self.b, dims, xs, act, layout)
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

    /// Like [`Mlp::forward_multi`], with the output, and every value between the layers,
    /// stored feature-major: (out, N). For a stack whose output only a [`Linear`] reads
    /// (with [`Layout::x_t`]): the same numbers with less copying in the products. `None`
    /// when there is no layer.
    pub(crate) fn forward_multi_feature_major<'a>(
        &self,
        g: &mut Graph<'a>,
        params: &'a Params,
        xs: &[Var],
    ) -> Option<Var> {
        let (first, rest) = self.layers.split_first()?;
        let into = Layout {
            x_t: false,
            y_t: true,
        };
        let within = Layout {
            x_t: true,
            y_t: true,
        };
        let h = first.forward_in(g, params, xs, self.act, into);
        Some(
            rest.iter()
                .fold(h, |h, l| l.forward_in(g, params, &[h], self.act, within)),
        )
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn values(n: usize, seed: u64) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| rng.random_range(-1.0f32..1.0)).collect()
    }

    /// The bits of y (N, out), its input gradients and the parameter gradient of `Σ y ⊙ c`
    /// through `[x₁ | x₂ | …]` → `mlp` → `out`, with the stack's values feature-major or not.
    fn run(
        params: &Params,
        mlp: &Mlp,
        out: &Linear,
        xs: &[Tensor],
        c: &Tensor,
        feature_major: bool,
    ) -> (Vec<u32>, Vec<Vec<u32>>, Vec<u32>) {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut g = Graph::new();
        let vs: Vec<Var> = xs.iter().map(|x| g.leaf(x.clone())).collect();
        let y = if feature_major {
            let h = mlp
                .forward_multi_feature_major(&mut g, params, &vs)
                .unwrap();
            let layout = Layout {
                x_t: true,
                y_t: false,
            };
            out.forward_in(&mut g, params, &[h], Act::None, layout)
        } else {
            let h = mlp.forward_multi(&mut g, params, &vs);
            out.forward(&mut g, params, h, Act::None)
        };
        let cv = g.constant(c.clone());
        let yc = g.mul(y, cv);
        let loss = g.sum(yc);
        let yv = bits(g.value(y).data());
        let grads = g.backward(loss);
        let dxs = vs
            .iter()
            .map(|&v| bits(grads.var(v).unwrap().data()))
            .collect();
        (yv, dxs, bits(grads.of(params).unwrap()))
    }

    #[test]
    fn feature_major_stacks_give_the_same_bits_as_row_major_ones() {
        // The recipe's critic (31 + 6 → 256 → 256 → 1) and actor (31 → 256 → 256 → 12)
        // at batch 64, their other pairings, tanh stacks, and odd sizes (a single output
        // after 9 features: the row-major copy's tail).
        type Case = (&'static [usize], &'static [usize], usize, usize, Act);
        let cases: [Case; 7] = [
            (&[31], &[256, 256], 1, 64, Act::Relu),
            (&[31, 6], &[256, 256], 12, 64, Act::Relu),
            (&[31, 6], &[256, 256], 1, 64, Act::Relu),
            (&[31], &[256, 256], 12, 64, Act::Relu),
            (&[5, 3], &[17, 9, 13], 4, 7, Act::Tanh),
            (&[5, 3], &[17, 9], 1, 7, Act::Tanh),
            (&[3], &[8], 2, 1, Act::None),
        ];
        for (case, &(ins, hidden, outs, n, act)) in cases.iter().enumerate() {
            let mut rng = ChaCha8Rng::seed_from_u64(case as u64);
            let mut params = Params::new();
            let width = ins.iter().sum();
            let mlp = Mlp::new(&mut params, "fc", width, hidden, act, &mut rng);
            let out = Linear::new(&mut params, "out", mlp.out_dim(), outs, &mut rng);
            let xs: Vec<Tensor> = ins
                .iter()
                .enumerate()
                .map(|(k, &i)| Tensor::from_vec(n, i, values(n * i, 10 + k as u64)))
                .collect();
            let c = Tensor::from_vec(n, outs, values(n * outs, 20));
            let row_major = run(&params, &mlp, &out, &xs, &c, false);
            let feature_major = run(&params, &mlp, &out, &xs, &c, true);
            assert!(
                row_major.0 == feature_major.0,
                "case {case}: outputs differ"
            );
            assert!(
                row_major.1 == feature_major.1,
                "case {case}: input gradients differ"
            );
            assert!(
                row_major.2 == feature_major.2,
                "case {case}: parameter gradients differ"
            );
        }
    }
}
