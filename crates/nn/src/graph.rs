//! The tape: a graph of coarse ops recorded during the forward pass and walked backwards.
//!
//! Each op is a node holding its output value and whatever its backward needs. Ops are coarse
//! (a whole `Linear`, a whole LSTM sequence, the Gaussian-tanh sample) so the tape stays short
//! and almost all time goes into matrix products. The forward of each op and its backward live
//! side by side in `crate::ops::*`, which implement [`Backward`]; this file only records nodes
//! and walks them back, and imports no op.
//!
//! Parameters are never copied into the graph: an op that uses a network's weights borrows
//! the network's [`Params`] for the graph's lifetime `'a` and refers to them by a *binding*
//! index. [`Graph::backward`] returns the parameter gradients in a [`Gradients`] value keyed by
//! the parameter set, so the graph (and its borrows) can be dropped before the optimiser
//! mutates the weights.

use std::ops::Range;

use crate::params::Params;
use crate::tensor::Tensor;

/// Handle to a value recorded in a [`Graph`]. Cheap to copy; only valid for its graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Var(pub(crate) usize);

/// A recorded op: a leaf, a parameter tensor, or an op with the inputs and caches its backward
/// needs, as its module (`crate::ops::*`) defines it.
pub(crate) enum Op {
    /// A constant or a gradient leaf; nothing to propagate.
    Leaf,
    /// A whole parameter tensor exposed as a value.
    Param { set: usize, offset: usize },
    /// Any other op.
    Computed(Box<dyn Backward>),
}

impl Op {
    /// The node of an op whose backward is `b`.
    pub(crate) fn of(b: impl Backward + 'static) -> Self {
        Op::Computed(Box::new(b))
    }
}

/// The backward of a recorded op: the graph walks the tape and calls it; each op implements
/// it beside its forward, so the graph knows no op.
pub(crate) trait Backward: Send + Sync {
    /// Accumulates the input gradients of the node whose forward value is `y` and whose
    /// output gradient is `dy`.
    fn backward(&self, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>);
}

pub(crate) struct Node {
    pub(crate) value: Tensor,
    pub(crate) op: Op,
    pub(crate) requires_grad: bool,
}

/// A parameter set used by the graph.
pub(crate) struct Binding<'a> {
    pub(crate) params: &'a Params,
    pub(crate) trainable: bool,
}

/// The tape. `'a` is the lifetime of the networks whose parameters it reads.
///
/// ```
/// use esrl_nn::{Graph, Tensor};
/// let mut g = Graph::new();
/// let x = g.leaf(Tensor::from_vec(1, 2, vec![0.5, -1.0]));
/// let y = g.tanh(x);
/// let loss = g.sum(y);
/// let grads = g.backward(loss);
/// let dx = grads.var(x).unwrap();
/// assert!((dx.get(0, 0) - (1.0 - 0.5f32.tanh().powi(2))).abs() < 1e-6);
/// ```
pub struct Graph<'a> {
    pub(crate) nodes: Vec<Node>,
    pub(crate) bindings: Vec<Binding<'a>>,
    frozen: Vec<u64>,
    grad_enabled: bool,
}

impl Default for Graph<'_> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a> Graph<'a> {
    /// A graph that records what backward needs.
    pub fn new() -> Self {
        Self {
            nodes: Vec::with_capacity(64),
            bindings: Vec::new(),
            frozen: Vec::new(),
            grad_enabled: true,
        }
    }

    /// A graph for inference only (`torch.no_grad()`): no op keeps caches and nothing requires
    /// a gradient, so [`Graph::backward`] returns empty gradients.
    pub fn no_grad() -> Self {
        Self {
            grad_enabled: false,
            ..Self::new()
        }
    }

    /// Whether this graph records for backward.
    pub fn grad_enabled(&self) -> bool {
        self.grad_enabled
    }

    /// Freezes a parameter set in this graph (`requires_grad = False` in PyTorch): ops using
    /// it still propagate gradients to their inputs, but no gradient is computed for these
    /// parameters. Call before the forward pass that uses them.
    pub fn freeze(&mut self, params: &Params) {
        debug_assert!(
            !self.bindings.iter().any(|b| b.params.id() == params.id()),
            "Graph::freeze called after the parameters were used"
        );
        self.frozen.push(params.id());
    }

    /// Registers `params` (once per set) and returns its binding index and whether the graph
    /// computes gradients for it.
    pub(crate) fn bind(&mut self, params: &'a Params) -> (usize, bool) {
        if let Some(i) = self
            .bindings
            .iter()
            .position(|b| b.params.id() == params.id())
        {
            return (i, self.bindings[i].trainable);
        }
        let trainable = self.grad_enabled && !self.frozen.contains(&params.id());
        self.bindings.push(Binding { params, trainable });
        (self.bindings.len() - 1, trainable)
    }

    /// The values of a bound parameter set.
    #[inline]
    pub(crate) fn pvals(&self, set: usize) -> &'a [f32] {
        self.bindings[set].params.as_slice()
    }

    pub(crate) fn push(&mut self, value: Tensor, op: Op, requires_grad: bool) -> Var {
        self.nodes.push(Node {
            value,
            op,
            requires_grad: requires_grad && self.grad_enabled,
        });
        Var(self.nodes.len() - 1)
    }

    /// Whether `v` needs a gradient.
    #[inline]
    pub(crate) fn rg(&self, v: Var) -> bool {
        self.nodes[v.0].requires_grad
    }

    /// A constant input (no gradient).
    pub fn constant(&mut self, t: Tensor) -> Var {
        self.push(t, Op::Leaf, false)
    }

    /// An input whose gradient [`Graph::backward`] reports (via [`Gradients::var`]).
    pub fn leaf(&mut self, t: Tensor) -> Var {
        self.push(t, Op::Leaf, true)
    }

    /// The value of `v`.
    pub fn value(&self, v: Var) -> &Tensor {
        &self.nodes[v.0].value
    }

    /// Moves the value of `v` out of the graph (leaving an empty tensor), e.g. to keep a
    /// no-grad result after the graph is dropped without copying.
    pub fn take_value(&mut self, v: Var) -> Tensor {
        std::mem::take(&mut self.nodes[v.0].value)
    }

    /// `(rows, cols)` of `v`.
    pub fn shape(&self, v: Var) -> (usize, usize) {
        self.nodes[v.0].value.shape()
    }

    /// Exposes the parameter tensor `name` of `params` as a value, e.g. a learnable
    /// `log α`. A 1-D tensor of length n becomes `(1, n)`; an (r, c) tensor stays (r, c).
    ///
    /// # Panics
    /// If `params` has no tensor called `name` (a programming error).
    pub fn param(&mut self, params: &'a Params, name: &str) -> Var {
        let spec = params
            .specs()
            .iter()
            .find(|s| s.name == name)
            .unwrap_or_else(|| panic!("Graph::param: no tensor `{name}`"));
        let (rows, cols) = match spec.shape.as_slice() {
            [n] => (1, *n),
            [r, c] => (*r, *c),
            s => (1, s.iter().product()),
        };
        let offset = spec.offset;
        let (set, trainable) = self.bind(params);
        let value =
            Tensor::from_slice(rows, cols, &params.as_slice()[offset..offset + rows * cols]);
        self.push(value, Op::Param { set, offset }, trainable)
    }

    /// Reverse pass from a `(1, 1)` loss: d loss / d loss = 1.
    ///
    /// # Panics
    /// If `loss` is not `(1, 1)`.
    pub fn backward(&mut self, loss: Var) -> Gradients {
        assert_eq!(
            self.shape(loss),
            (1, 1),
            "Graph::backward needs a (1, 1) loss"
        );
        self.backward_with(loss, Tensor::scalar(1.0))
    }

    /// Reverse pass seeded with `seed` = d loss / d `out` (same shape as `out`).
    pub fn backward_with(&mut self, out: Var, seed: Tensor) -> Gradients {
        self.backward_seeded(vec![(out, seed)])
    }

    /// Reverse pass seeded at several values: each `(v, d loss / d v)`, as if the rest of
    /// the loss were computed elsewhere (e.g. on another graph, on another thread). Each seed
    /// is that value's whole gradient, as the reverse pass would have accumulated it.
    ///
    /// # Panics
    /// If a seed's shape differs from its value's, or a value is seeded twice.
    pub fn backward_seeded(&mut self, seeds: Vec<(Var, Tensor)>) -> Gradients {
        let mut grads: Vec<Option<Tensor>> = (0..self.nodes.len()).map(|_| None).collect();
        let mut last = 0;
        for (v, seed) in seeds {
            assert_eq!(self.shape(v), seed.shape(), "Graph::backward: seed shape");
            assert!(grads[v.0].is_none(), "Graph::backward: {v:?} seeded twice");
            if self.nodes[v.0].requires_grad {
                grads[v.0] = Some(seed);
            }
            last = last.max(v.0);
        }
        let mut pgrads: Vec<Option<ParamGrad>> = self
            .bindings
            .iter()
            .map(|b| b.trainable.then(|| ParamGrad::new(b.params.len())))
            .collect();
        for i in (0..=last).rev() {
            let Some(dy) = grads[i].take() else { continue };
            let node = &self.nodes[i];
            if !node.requires_grad {
                continue;
            }
            if let Op::Leaf = node.op {
                grads[i] = Some(dy);
                continue;
            }
            let mut ctx = BackCtx {
                nodes: &self.nodes,
                grads: &mut grads,
                pgrads: &mut pgrads,
                bindings: &self.bindings,
            };
            match &node.op {
                Op::Leaf => {}
                Op::Param { set, offset } => {
                    let r = *offset..*offset + dy.len();
                    if let Some((pg, fresh)) = ctx.pgrad_fresh(*set, r.clone()) {
                        if fresh {
                            pg[r].copy_from_slice(dy.data());
                        } else {
                            for (g, d) in pg[r].iter_mut().zip(dy.data()) {
                                *g += d;
                            }
                        }
                    }
                }
                Op::Computed(op) => op.backward(&node.value, &dy, &mut ctx),
            }
        }
        let params = self
            .bindings
            .iter()
            .zip(pgrads)
            .filter_map(|(b, g)| g.map(|g| (b.params.id(), g.finish())))
            .collect();
        Gradients {
            params,
            vars: grads,
        }
    }
}

/// What an op's backward may read and write.
pub(crate) struct BackCtx<'g, 'a> {
    pub(crate) nodes: &'g [Node],
    pub(crate) grads: &'g mut [Option<Tensor>],
    pub(crate) pgrads: &'g mut [Option<ParamGrad>],
    pub(crate) bindings: &'g [Binding<'a>],
}

/// The gradient of one trainable binding during a reverse pass. Its buffer is not zeroed up
/// front: the first op to write a parameter range overwrites it, later ones add to it, and
/// [`ParamGrad::finish`] zeroes what no op wrote. This spares a memset of every trainable
/// set and the products' read of it, with the same numbers: `0 + x` is `x`.
pub(crate) struct ParamGrad {
    buf: Vec<f32>,
    /// Ranges written so far; any two are equal or disjoint.
    written: Vec<Range<usize>>,
}

impl ParamGrad {
    fn new(len: usize) -> Self {
        Self {
            buf: crate::pool::dirty(len),
            written: Vec::new(),
        }
    }

    /// Marks `r` written and says whether this is its first write.
    ///
    /// # Panics
    /// If `r` overlaps a range written before without being equal to it (ops claim whole
    /// parameter tensors, so this is a programming error).
    fn claim(&mut self, r: Range<usize>) -> bool {
        if self.written.contains(&r) {
            return false;
        }
        assert!(
            self.written
                .iter()
                .all(|w| w.end <= r.start || r.end <= w.start),
            "parameter gradient range {r:?} overlaps one written before"
        );
        self.written.push(r);
        true
    }

    /// The gradient, zero where no op wrote.
    fn finish(mut self) -> Vec<f32> {
        self.written.sort_by_key(|r| r.start);
        let mut at = 0;
        for r in &self.written {
            self.buf[at..r.start].fill(0.0);
            at = r.end;
        }
        self.buf[at..].fill(0.0);
        self.buf
    }
}

impl<'g, 'a> BackCtx<'g, 'a> {
    /// The forward value of `v` (borrowed from the tape, not from `self`).
    #[inline]
    pub(crate) fn val(&self, v: Var) -> &'g Tensor {
        &self.nodes[v.0].value
    }

    /// Whether `v` needs a gradient.
    #[inline]
    pub(crate) fn rg(&self, v: Var) -> bool {
        self.nodes[v.0].requires_grad
    }

    /// The gradient accumulator of `v` (zero-initialised on first use), or `None` when `v`
    /// needs no gradient.
    #[inline]
    pub(crate) fn grad(&mut self, v: Var) -> Option<&mut Tensor> {
        if !self.nodes[v.0].requires_grad {
            return None;
        }
        let (r, c) = self.nodes[v.0].value.shape();
        Some(self.grads[v.0].get_or_insert_with(|| Tensor::zeros(r, c)))
    }

    /// Like [`BackCtx::grad`], but a first use returns an *unwritten* buffer and `true`: the
    /// caller must then overwrite every element instead of accumulating (saves a memset and
    /// a read pass for large input gradients).
    #[inline]
    pub(crate) fn grad_fresh(&mut self, v: Var) -> Option<(&mut Tensor, bool)> {
        if !self.nodes[v.0].requires_grad {
            return None;
        }
        let fresh = self.grads[v.0].is_none();
        let (r, c) = self.nodes[v.0].value.shape();
        Some((
            self.grads[v.0].get_or_insert_with(|| Tensor::uninit(r, c)),
            fresh,
        ))
    }

    /// The gradient buffer of a binding (`None` when frozen) and whether the parameter range
    /// `r` is written for the first time: then the caller must overwrite every element of
    /// `r` instead of accumulating, and must not touch the buffer outside `r`. `r` is a
    /// whole parameter tensor (ranges claimed in one pass are equal or disjoint).
    #[inline]
    pub(crate) fn pgrad_fresh(
        &mut self,
        set: usize,
        r: Range<usize>,
    ) -> Option<(&mut [f32], bool)> {
        let g = self.pgrads[set].as_mut()?;
        let fresh = g.claim(r);
        Some((&mut g.buf, fresh))
    }

    /// The gradient buffer of a binding (`None` when frozen) for an op that accumulates into
    /// the parameter ranges `rs` (whole tensors): each is zeroed on its first write.
    pub(crate) fn pgrad_zeroed(&mut self, set: usize, rs: &[Range<usize>]) -> Option<&mut [f32]> {
        let g = self.pgrads[set].as_mut()?;
        for r in rs {
            if g.claim(r.clone()) {
                g.buf[r.clone()].fill(0.0);
            }
        }
        Some(&mut g.buf)
    }

    /// Parameter values of a binding.
    #[inline]
    pub(crate) fn pvals(&self, set: usize) -> &'a [f32] {
        self.bindings[set].params.as_slice()
    }
}

/// Gradients produced by [`Graph::backward`]: per parameter set, and per leaf value.
#[derive(Debug, Default)]
pub struct Gradients {
    params: Vec<(u64, Vec<f32>)>,
    vars: Vec<Option<Tensor>>,
}

impl Drop for Gradients {
    fn drop(&mut self) {
        for (_, g) in self.params.drain(..) {
            crate::pool::recycle(g);
        }
    }
}

impl Gradients {
    /// Gradient with respect to `params` in its flat layout, or `None` when the set was not
    /// used, was frozen, or the graph was no-grad.
    pub fn of(&self, params: &Params) -> Option<&[f32]> {
        self.params
            .iter()
            .find(|(id, _)| *id == params.id())
            .map(|(_, g)| g.as_slice())
    }

    /// Like [`Gradients::of`] but moves the buffer out.
    pub fn take(&mut self, params: &Params) -> Option<Vec<f32>> {
        let i = self.params.iter().position(|(id, _)| *id == params.id())?;
        Some(self.params.swap_remove(i).1)
    }

    /// Gradient with respect to a [`Graph::leaf`] (or `None` if no path reached it).
    pub fn var(&self, v: Var) -> Option<&Tensor> {
        self.vars.get(v.0).and_then(|g| g.as_ref())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tensors large enough (≥ 4,096 floats) that their buffers are pooled.
    const N: usize = 4096;

    fn ramp(n: usize, scale: f32) -> Vec<f32> {
        (0..n).map(|i| ((i % 97) as f32 - 48.0) * scale).collect()
    }

    #[test]
    fn parameter_gradients_are_the_sum_of_their_uses_and_zero_where_unused() {
        let mut p = Params::new();
        p.add("a", &[N], false, || 0.5);
        p.add("unused", &[N + 3], false, || 0.25);
        p.add("b", &[N], false, || -1.0);
        let (c1, c2, c3) = (ramp(N, 0.01), ramp(N, -0.03), ramp(N, 0.7));

        // loss = Σ a ⊙ c1 + Σ a ⊙ c2 + Σ b ⊙ c3, `a` read through two parameter nodes.
        let mut g = Graph::new();
        let k1 = g.constant(Tensor::from_vec(1, N, c1.clone()));
        let k2 = g.constant(Tensor::from_vec(1, N, c2.clone()));
        let k3 = g.constant(Tensor::from_vec(1, N, c3.clone()));
        let (a1, a2, b) = (g.param(&p, "a"), g.param(&p, "a"), g.param(&p, "b"));
        let (t1, t2, t3) = (g.mul(a1, k1), g.mul(a2, k2), g.mul(b, k3));
        let (s1, s2, s3) = (g.sum(t1), g.sum(t2), g.sum(t3));
        let s12 = g.add(s1, s2);
        let loss = g.add(s12, s3);
        // The gradient buffer the pass takes from the pool is full of NaN: every element it
        // returns must have been written or zeroed.
        crate::pool::recycle(vec![f32::NAN; p.len()]);
        let grads = g.backward(loss);
        let d = grads.of(&p).unwrap();

        let (da, rest) = d.split_at(N);
        let (dunused, db) = rest.split_at(N + 3);
        for i in 0..N {
            assert_eq!(da[i], c1[i] + c2[i], "a[{i}]");
            assert_eq!(db[i], c3[i], "b[{i}]");
        }
        assert!(
            dunused.iter().all(|&x| x.to_bits() == 0),
            "the unused tensor's gradient is not exactly +0"
        );
    }

    #[test]
    #[should_panic(expected = "overlaps")]
    fn a_range_overlapping_one_written_before_is_refused() {
        let mut g = ParamGrad::new(10);
        assert!(g.claim(0..4));
        assert!(!g.claim(0..4));
        g.claim(2..6);
    }
}
