//! Column concatenation and slicing.

use crate::graph::{BackCtx, Backward, Graph, Op, Var};
use crate::tensor::Tensor;

impl Graph<'_> {
    /// `[a | b]`: `(N, p)` and `(N, q)` → `(N, p + q)`. Derivative: the identity on each block.
    pub fn concat_cols(&mut self, a: Var, b: Var) -> Var {
        let (av, bv) = (self.value(a), self.value(b));
        assert_eq!(
            av.rows(),
            bv.rows(),
            "concat_cols: {} vs {} rows",
            av.rows(),
            bv.rows()
        );
        let (n, p, q) = (av.rows(), av.cols(), bv.cols());
        let mut out = Tensor::uninit(n, p + q);
        for r in 0..n {
            let o = &mut out.data_mut()[r * (p + q)..(r + 1) * (p + q)];
            o[..p].copy_from_slice(av.row(r));
            o[p..].copy_from_slice(bv.row(r));
        }
        let rg = self.rg(a) || self.rg(b);
        self.push(out, Op::of(ConcatCols { a, b }), rg)
    }

    /// Columns `start..start + len` of `x`. Derivative: dy scattered back into those columns.
    pub fn slice_cols(&mut self, x: Var, start: usize, len: usize) -> Var {
        let xv = self.value(x);
        assert!(
            start + len <= xv.cols(),
            "slice_cols: {start}+{len} > {} cols",
            xv.cols()
        );
        let n = xv.rows();
        let mut out = Tensor::uninit(n, len);
        for r in 0..n {
            out.data_mut()[r * len..(r + 1) * len].copy_from_slice(&xv.row(r)[start..start + len]);
        }
        let rg = self.rg(x);
        self.push(out, Op::of(SliceCols { x, start }), rg)
    }
}

/// da = dy[:, :p], db = dy[:, p:].
pub(crate) fn concat_backward(a: Var, b: Var, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let (p, w) = (ctx.val(a).cols(), dy.cols());
    if let Some(da) = ctx.grad(a) {
        for r in 0..dy.rows() {
            for (g, d) in da.data_mut()[r * p..(r + 1) * p]
                .iter_mut()
                .zip(&dy.row(r)[..p])
            {
                *g += d;
            }
        }
    }
    if let Some(db) = ctx.grad(b) {
        let q = w - p;
        for r in 0..dy.rows() {
            for (g, d) in db.data_mut()[r * q..(r + 1) * q]
                .iter_mut()
                .zip(&dy.row(r)[p..])
            {
                *g += d;
            }
        }
    }
}

/// dx[:, start..start+len] += dy.
pub(crate) fn slice_backward(x: Var, start: usize, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let len = dy.cols();
    if let Some(dx) = ctx.grad(x) {
        let c = dx.cols();
        for r in 0..dy.rows() {
            for (g, d) in dx.data_mut()[r * c + start..r * c + start + len]
                .iter_mut()
                .zip(dy.row(r))
            {
                *g += d;
            }
        }
    }
}

struct ConcatCols {
    a: Var,
    b: Var,
}

struct SliceCols {
    x: Var,
    start: usize,
}

impl Backward for ConcatCols {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        concat_backward(self.a, self.b, dy, ctx);
    }
}

impl Backward for SliceCols {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        slice_backward(self.x, self.start, dy, ctx);
    }
}
