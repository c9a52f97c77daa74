//! The ops: each file holds forwards (as `Graph` methods) and, beside each, its backward.

pub(crate) mod elementwise;
pub(crate) mod linear;
pub(crate) mod lstm;
pub(crate) mod policy;
pub(crate) mod reduce;
pub(crate) mod shape;

use crate::graph::{BackCtx, Op};
use crate::tensor::Tensor;

/// Activation fused into a [`crate::Linear`] op.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Act {
    /// Identity.
    #[default]
    None,
    /// max(x, 0).
    Relu,
    /// tanh(x).
    Tanh,
}

/// Dispatches the backward of one node. `y` is the node's forward value, `dy` its gradient.
pub(crate) fn backward(op: &Op, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
    match op {
        Op::Leaf => {}
        Op::Param { set, offset } => {
            if let Some(pg) = ctx.pgrad(*set) {
                for (g, d) in pg[*offset..*offset + dy.len()].iter_mut().zip(dy.data()) {
                    *g += d;
                }
            }
        }
        Op::Linear(node) => linear::linear_backward(node, y, dy, ctx),
        Op::Lstm(node) => lstm::lstm_backward(node, y, dy, ctx),
        Op::Unary { x, f } => elementwise::unary_backward(*x, *f, y, dy, ctx),
        Op::Binary { a, b, f } => elementwise::binary_backward(*a, *b, *f, dy, ctx),
        Op::Scale { x, s } => elementwise::scale_backward(*x, *s, dy, ctx),
        Op::Clamp { x, lo, hi } => elementwise::clamp_backward(*x, *lo, *hi, dy, ctx),
        Op::AddScalar { x } => elementwise::scale_backward(*x, 1.0, dy, ctx),
        Op::ConcatCols { a, b } => shape::concat_backward(*a, *b, dy, ctx),
        Op::SliceCols { x, start } => shape::slice_backward(*x, *start, dy, ctx),
        Op::Sum { x } => reduce::sum_backward(*x, 1.0, dy, ctx),
        Op::Mean { x } => {
            let n = ctx.val(*x).len().max(1) as f32;
            reduce::sum_backward(*x, 1.0 / n, dy, ctx)
        }
        Op::SumCols { x } => reduce::sum_cols_backward(*x, 1.0, dy, ctx),
        Op::MeanCols { x } => {
            let n = ctx.val(*x).cols().max(1) as f32;
            reduce::sum_cols_backward(*x, 1.0 / n, dy, ctx)
        }
        Op::Mse { a, b } => reduce::mse_backward(*a, *b, dy, ctx),
        Op::GaussianTanh { mean, std, eps } => {
            policy::gaussian_tanh_backward(*mean, *std, eps, y, dy, ctx)
        }
    }
}
