//! Reductions and the fused mean-squared error. Sums accumulate in f64 so a loss over B·T
//! samples does not lose digits.

use crate::graph::{BackCtx, Backward, Graph, Op, Var};
use crate::tensor::Tensor;

impl Graph<'_> {
    /// Sum of all elements → `(1, 1)`. Derivative: 1 for every element.
    pub fn sum(&mut self, x: Var) -> Var {
        let s: f64 = self.value(x).data().iter().map(|&v| v as f64).sum();
        let rg = self.rg(x);
        self.push(Tensor::scalar(s as f32), Op::of(Sum { x }), rg)
    }

    /// Mean of all elements → `(1, 1)`. Derivative: 1/n for every element.
    pub fn mean(&mut self, x: Var) -> Var {
        let xv = self.value(x);
        let s: f64 = xv.data().iter().map(|&v| v as f64).sum();
        let m = s / xv.len().max(1) as f64;
        let rg = self.rg(x);
        self.push(Tensor::scalar(m as f32), Op::of(Mean { x }), rg)
    }

    /// Row sums: `(N, C)` → `(N, 1)`. Derivative: dy of the row for each element.
    pub fn sum_cols(&mut self, x: Var) -> Var {
        let xv = self.value(x);
        let out: Vec<f32> = (0..xv.rows()).map(|r| xv.row(r).iter().sum()).collect();
        let rg = self.rg(x);
        self.push(
            Tensor::from_vec(xv.rows(), 1, out),
            Op::of(SumCols { x }),
            rg,
        )
    }

    /// Row means: `(N, C)` → `(N, 1)`. Derivative: dy/C for each element.
    pub fn mean_cols(&mut self, x: Var) -> Var {
        let xv = self.value(x);
        let c = xv.cols().max(1) as f32;
        let out: Vec<f32> = (0..xv.rows())
            .map(|r| xv.row(r).iter().sum::<f32>() / c)
            .collect();
        let rg = self.rg(x);
        self.push(
            Tensor::from_vec(xv.rows(), 1, out),
            Op::of(MeanCols { x }),
            rg,
        )
    }

    /// Mean squared error `mean((a − b)²)` → `(1, 1)`.
    /// Derivatives: 2(a − b)/n and −2(a − b)/n.
    pub fn mse(&mut self, a: Var, b: Var) -> Var {
        let (av, bv) = (self.value(a), self.value(b));
        assert_eq!(
            av.shape(),
            bv.shape(),
            "mse: shapes {:?} vs {:?}",
            av.shape(),
            bv.shape()
        );
        let s: f64 = av
            .data()
            .iter()
            .zip(bv.data())
            .map(|(&x, &y)| ((x - y) as f64).powi(2))
            .sum();
        let m = s / av.len().max(1) as f64;
        let rg = self.rg(a) || self.rg(b);
        self.push(Tensor::scalar(m as f32), Op::of(Mse { a, b }), rg)
    }
}

/// dx += k · dy (dy is (1, 1)).
pub(crate) fn sum_backward(x: Var, k: f32, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let d = k * dy.data()[0];
    if let Some(dx) = ctx.grad(x) {
        dx.data_mut().iter_mut().for_each(|g| *g += d);
    }
}

/// dx[r, :] += k · dy[r].
pub(crate) fn sum_cols_backward(x: Var, k: f32, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    if let Some(dx) = ctx.grad(x) {
        let c = dx.cols();
        for (r, &d) in dy.data().iter().enumerate() {
            dx.data_mut()[r * c..(r + 1) * c]
                .iter_mut()
                .for_each(|g| *g += k * d);
        }
    }
}

/// da += 2(a − b)/n · dy, db −= 2(a − b)/n · dy.
pub(crate) fn mse_backward(a: Var, b: Var, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    let (av, bv) = (ctx.val(a), ctx.val(b));
    let k = 2.0 * dy.data()[0] / av.len().max(1) as f32;
    if let Some(da) = ctx.grad(a) {
        for ((g, &x), &y) in da.data_mut().iter_mut().zip(av.data()).zip(bv.data()) {
            *g += k * (x - y);
        }
    }
    if let Some(db) = ctx.grad(b) {
        for ((g, &x), &y) in db.data_mut().iter_mut().zip(av.data()).zip(bv.data()) {
            *g -= k * (x - y);
        }
    }
}

struct Sum {
    x: Var,
}

struct Mean {
    x: Var,
}

struct SumCols {
    x: Var,
}

struct MeanCols {
    x: Var,
}

struct Mse {
    a: Var,
    b: Var,
}

impl Backward for Sum {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        sum_backward(self.x, 1.0, dy, ctx);
    }
}

impl Backward for Mean {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        let n = ctx.val(self.x).len().max(1) as f32;
        sum_backward(self.x, 1.0 / n, dy, ctx);
    }
}

impl Backward for SumCols {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        sum_cols_backward(self.x, 1.0, dy, ctx);
    }
}

impl Backward for MeanCols {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        let n = ctx.val(self.x).cols().max(1) as f32;
        sum_cols_backward(self.x, 1.0 / n, dy, ctx);
    }
}

impl Backward for Mse {
    fn backward(&self, _: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        mse_backward(self.a, self.b, dy, ctx);
    }
}
