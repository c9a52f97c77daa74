//! Elementwise ops. Binary ops take equal shapes, or a `(1, 1)` operand on either side that is
//! broadcast (its gradient is the sum over the broadcast).

use crate::graph::{BackCtx, Backward, Graph, Op, Var};
use crate::kern;
use crate::tensor::Tensor;

/// Elementwise unary functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Unary {
    Relu,
    Tanh,
    Sigmoid,
    Softplus,
    Exp,
    Log,
    Neg,
    Square,
}

/// Elementwise binary functions (with (1, 1) broadcasting on either side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Binary {
    Add,
    Sub,
    Mul,
    Div,
    Min,
    Max,
}

struct UnaryNode {
    x: Var,
    f: Unary,
}

struct BinaryNode {
    a: Var,
    b: Var,
    f: Binary,
}

/// `s·x` (and `x + c`, whose gradient is that of `s = 1`).
struct ScaleNode {
    x: Var,
    s: f32,
}

struct ClampNode {
    x: Var,
    lo: f32,
    hi: f32,
}

impl Backward for UnaryNode {
    fn backward(&self, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        unary_backward(self.x, self.f, y, dy, ctx);
    }
}

impl Backward for BinaryNode {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        binary_backward(self.a, self.b, self.f, dy, ctx);
    }
}

impl Backward for ScaleNode {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        scale_backward(self.x, self.s, dy, ctx);
    }
}

impl Backward for ClampNode {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        clamp_backward(self.x, self.lo, self.hi, dy, ctx);
    }
}

impl Graph<'_> {
    fn unary(&mut self, x: Var, f: Unary) -> Var {
        let xv = self.value(x);
        let mut out = Tensor::uninit(xv.rows(), xv.cols());
        unary_forward(f, xv.data(), out.data_mut());
        let rg = self.rg(x);
        self.push(out, Op::of(UnaryNode { x, f }), rg)
    }

    /// `max(x, 0)`. Derivative: 1 where the output is positive, else 0.
    pub fn relu(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Relu)
    }

    /// `tanh(x)`. Derivative: 1 − tanh²(x), read from the output.
    pub fn tanh(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Tanh)
    }

    /// `σ(x) = 1 / (1 + e^(−x))`. Derivative: σ(x)(1 − σ(x)), read from the output.
    pub fn sigmoid(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Sigmoid)
    }

    /// `softplus(x) = log(1 + e^x)`. Derivative: σ(x).
    pub fn softplus(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Softplus)
    }

    /// `e^x`. Derivative: e^x, read from the output.
    pub fn exp(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Exp)
    }

    /// Natural log. Derivative: 1 / x.
    pub fn log(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Log)
    }

    /// `−x`. Derivative: −1.
    pub fn neg(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Neg)
    }

    /// `x²`. Derivative: 2x.
    pub fn square(&mut self, x: Var) -> Var {
        self.unary(x, Unary::Square)
    }

    /// `s·x` for a constant `s`. Derivative: s.
    pub fn scale(&mut self, x: Var, s: f32) -> Var {
        let xv = self.value(x);
        let out = Tensor::from_vec(
            xv.rows(),
            xv.cols(),
            xv.data().iter().map(|v| v * s).collect(),
        );
        let rg = self.rg(x);
        self.push(out, Op::of(ScaleNode { x, s }), rg)
    }

    /// `min(max(x, lo), hi)` (TD3's target smoothing, action bounds). Derivative: 1 where
    /// lo < x < hi, else 0.
    pub fn clamp(&mut self, x: Var, lo: f32, hi: f32) -> Var {
        let xv = self.value(x);
        let out = Tensor::from_vec(
            xv.rows(),
            xv.cols(),
            xv.data().iter().map(|v| v.clamp(lo, hi)).collect(),
        );
        let rg = self.rg(x);
        self.push(out, Op::of(ClampNode { x, lo, hi }), rg)
    }

    /// `x + s` for a constant `s`. Derivative: 1.
    pub fn add_scalar(&mut self, x: Var, s: f32) -> Var {
        let xv = self.value(x);
        let out = Tensor::from_vec(
            xv.rows(),
            xv.cols(),
            xv.data().iter().map(|v| v + s).collect(),
        );
        let rg = self.rg(x);
        self.push(out, Op::of(ScaleNode { x, s: 1.0 }), rg)
    }

    fn binary(&mut self, a: Var, b: Var, f: Binary) -> Var {
        let (av, bv) = (self.value(a), self.value(b));
        let shape = broadcast_shape(av, bv, f);
        let mut out = Tensor::uninit(shape.0, shape.1);
        let op = |x: f32, y: f32| match f {
            Binary::Add => x + y,
            Binary::Sub => x - y,
            Binary::Mul => x * y,
            Binary::Div => x / y,
            Binary::Min => x.min(y),
            Binary::Max => x.max(y),
        };
        let n = out.len();
        let (sa, sb) = (av.len() == n, bv.len() == n);
        for (i, o) in out.data_mut().iter_mut().enumerate() {
            let x = if sa { av.data()[i] } else { av.data()[0] };
            let y = if sb { bv.data()[i] } else { bv.data()[0] };
            *o = op(x, y);
        }
        let rg = self.rg(a) || self.rg(b);
        self.push(out, Op::of(BinaryNode { a, b, f }), rg)
    }

    /// `a + b`. Derivatives: 1, 1.
    pub fn add(&mut self, a: Var, b: Var) -> Var {
        self.binary(a, b, Binary::Add)
    }

    /// `a − b`. Derivatives: 1, −1.
    pub fn sub(&mut self, a: Var, b: Var) -> Var {
        self.binary(a, b, Binary::Sub)
    }

    /// `a ⊙ b`. Derivatives: b, a.
    pub fn mul(&mut self, a: Var, b: Var) -> Var {
        self.binary(a, b, Binary::Mul)
    }

    /// `a / b`. Derivatives: 1/b, −a/b².
    pub fn div(&mut self, a: Var, b: Var) -> Var {
        self.binary(a, b, Binary::Div)
    }

    /// Elementwise `min(a, b)` (twin-critic minimum). Derivative: 1 for the smaller operand
    /// (ties go to `a`), 0 for the other.
    pub fn minimum(&mut self, a: Var, b: Var) -> Var {
        self.binary(a, b, Binary::Min)
    }

    /// Elementwise `max(a, b)`. Derivative: 1 for the larger operand (ties go to `a`).
    pub fn maximum(&mut self, a: Var, b: Var) -> Var {
        self.binary(a, b, Binary::Max)
    }
}

fn broadcast_shape(a: &Tensor, b: &Tensor, f: Binary) -> (usize, usize) {
    if a.shape() == b.shape() || b.shape() == (1, 1) {
        a.shape()
    } else if a.shape() == (1, 1) {
        b.shape()
    } else {
        panic!(
            "{f:?}: shapes {:?} and {:?} do not match (only (1, 1) broadcasts)",
            a.shape(),
            b.shape()
        )
    }
}

kern::simd_fn! {
    /// out = f(x) elementwise (the forwards listed on [`Graph::relu`] … [`Graph::square`]).
    fn unary_forward<'a>(f: Unary, x: &'a [f32], out: &'a mut [f32]) {
        let it = out.iter_mut().zip(x);
        match f {
            Unary::Relu => it.for_each(|(o, &v)| *o = v.max(0.0)),
            Unary::Tanh => it.for_each(|(o, &v)| *o = kern::tanh(v)),
            Unary::Sigmoid => it.for_each(|(o, &v)| *o = kern::sigmoid(v)),
            Unary::Softplus => it.for_each(|(o, &v)| *o = kern::softplus(v)),
            Unary::Exp => it.for_each(|(o, &v)| *o = v.exp()),
            Unary::Log => it.for_each(|(o, &v)| *o = v.ln()),
            Unary::Neg => it.for_each(|(o, &v)| *o = -v),
            Unary::Square => it.for_each(|(o, &v)| *o = v * v),
        }
    }
}

/// dx += dy · f'(x), with f' from [`Graph::relu`] … [`Graph::square`].
pub(crate) fn unary_backward(x: Var, f: Unary, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let x_in = ctx.val(x).data();
    let Some(dx) = ctx.grad(x) else { return };
    unary_grad(f, x_in, y.data(), dy.data(), dx.data_mut());
}

kern::simd_fn! {
    /// dx += dy · f'(x) (reading f' from the output y where that is cheaper).
    fn unary_grad<'a>(f: Unary, x: &'a [f32], y: &'a [f32], dy: &'a [f32], dx: &'a mut [f32]) {
        match f {
            Unary::Relu => dx.iter_mut().zip(y.iter().zip(dy)).for_each(|(g, (&y, &d))| *g += if y > 0.0 { d } else { 0.0 }),
            Unary::Tanh => dx.iter_mut().zip(y.iter().zip(dy)).for_each(|(g, (&y, &d))| *g += d * (1.0 - y * y)),
            Unary::Sigmoid => dx.iter_mut().zip(y.iter().zip(dy)).for_each(|(g, (&y, &d))| *g += d * y * (1.0 - y)),
            Unary::Exp => dx.iter_mut().zip(y.iter().zip(dy)).for_each(|(g, (&y, &d))| *g += d * y),
            Unary::Neg => dx.iter_mut().zip(dy).for_each(|(g, &d)| *g -= d),
            Unary::Softplus => dx.iter_mut().zip(x.iter().zip(dy)).for_each(|(g, (&x, &d))| *g += d * kern::sigmoid(x)),
            Unary::Log => dx.iter_mut().zip(x.iter().zip(dy)).for_each(|(g, (&x, &d))| *g += d / x),
            Unary::Square => dx.iter_mut().zip(x.iter().zip(dy)).for_each(|(g, (&x, &d))| *g += 2.0 * x * d),
        }
    }
}

/// Accumulates `val(i)` into `g`, summing when `g` is a broadcast `(1, 1)` operand.
fn acc(g: &mut Tensor, n: usize, val: impl Fn(usize) -> f32) {
    if g.len() == n {
        for (i, gi) in g.data_mut().iter_mut().enumerate() {
            *gi += val(i);
        }
    } else {
        let s: f32 = (0..n).map(val).sum();
        g.data_mut()[0] += s;
    }
}

/// Derivatives listed on each binary forward, with broadcast operands summed.
pub(crate) fn binary_backward(a: Var, b: Var, f: Binary, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let n = dy.len();
    let av = ctx.val(a);
    let bv = ctx.val(b);
    let at = |i: usize| {
        if av.len() == n {
            av.data()[i]
        } else {
            av.data()[0]
        }
    };
    let bt = |i: usize| {
        if bv.len() == n {
            bv.data()[i]
        } else {
            bv.data()[0]
        }
    };
    let d = dy.data();
    if let Some(ga) = ctx.grad(a) {
        match f {
            Binary::Add | Binary::Sub => acc(ga, n, |i| d[i]),
            Binary::Mul => acc(ga, n, |i| d[i] * bt(i)),
            Binary::Div => acc(ga, n, |i| d[i] / bt(i)),
            Binary::Min => acc(ga, n, |i| if at(i) <= bt(i) { d[i] } else { 0.0 }),
            Binary::Max => acc(ga, n, |i| if at(i) >= bt(i) { d[i] } else { 0.0 }),
        }
    }
    if let Some(gb) = ctx.grad(b) {
        match f {
            Binary::Add => acc(gb, n, |i| d[i]),
            Binary::Sub => acc(gb, n, |i| -d[i]),
            Binary::Mul => acc(gb, n, |i| d[i] * at(i)),
            Binary::Div => acc(gb, n, |i| -d[i] * at(i) / (bt(i) * bt(i))),
            Binary::Min => acc(gb, n, |i| if at(i) <= bt(i) { 0.0 } else { d[i] }),
            Binary::Max => acc(gb, n, |i| if at(i) >= bt(i) { 0.0 } else { d[i] }),
        }
    }
}

/// dx = s · dy.
pub(crate) fn scale_backward(x: Var, s: f32, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    if let Some(dx) = ctx.grad(x) {
        for (g, d) in dx.data_mut().iter_mut().zip(dy.data()) {
            *g += s * d;
        }
    }
}

/// dx += dy where lo < x < hi.
pub(crate) fn clamp_backward(x: Var, lo: f32, hi: f32, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let xv = ctx.val(x);
    if let Some(dx) = ctx.grad(x) {
        for ((g, &d), &v) in dx.data_mut().iter_mut().zip(dy.data()).zip(xv.data()) {
            if v > lo && v < hi {
                *g += d;
            }
        }
    }
}
