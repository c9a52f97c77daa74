//! The tanh-squashed Gaussian policy sample with its log-probability (SAC, paper eq. 1).

use crate::graph::{BackCtx, Graph, Op, Var};
use crate::kern;
use crate::tensor::Tensor;

const HALF_LN_2PI: f32 = 0.918_938_5;
const LN2: f32 = std::f32::consts::LN_2;

impl Graph<'_> {
    /// Reparameterised sample `a = tanh(u)`, `u = μ + σ ⊙ ε`, and its log-density
    /// `log π(a) = Σ_j [−ε_j²/2 − log σ_j − log(2π)/2 − log(1 − tanh² u_j)]`, with the
    /// correction in the stable form `log(1 − tanh² u) = 2(log 2 − u − softplus(−2u))`.
    ///
    /// `mean` and `std` are (N, A) (std > 0); `eps` is a constant (N, A) standard normal draw.
    /// Returns `(action (N, A), log_prob (N, 1))`.
    ///
    /// Derivatives (ε fixed): ∂a/∂μ = 1 − a², ∂a/∂σ = (1 − a²)ε,
    /// ∂log π/∂μ = 2a (since d/du[−log(1 − tanh² u)] = 2 tanh u), ∂log π/∂σ = −1/σ + 2aε.
    pub fn gaussian_tanh(&mut self, mean: Var, std: Var, eps: Tensor) -> (Var, Var) {
        let (mv, sv) = (self.value(mean), self.value(std));
        assert_eq!(
            mv.shape(),
            sv.shape(),
            "gaussian_tanh: mean {:?} vs std {:?}",
            mv.shape(),
            sv.shape()
        );
        assert_eq!(
            mv.shape(),
            eps.shape(),
            "gaussian_tanh: mean {:?} vs eps {:?}",
            mv.shape(),
            eps.shape()
        );
        let (n, a_dim) = mv.shape();
        let w = a_dim + 1;
        let mut out = Tensor::uninit(n, w);
        for r in 0..n {
            let (m, s, e) = (mv.row(r), sv.row(r), eps.row(r));
            let o = &mut out.data_mut()[r * w..(r + 1) * w];
            let mut lp = 0.0f32;
            for j in 0..a_dim {
                let u = m[j] + s[j] * e[j];
                o[j] = kern::tanh(u);
                lp += -0.5 * e[j] * e[j]
                    - s[j].ln()
                    - HALF_LN_2PI
                    - 2.0 * (LN2 - u - kern::softplus(-2.0 * u));
            }
            o[a_dim] = lp;
        }
        let rg = self.rg(mean) || self.rg(std);
        let both = self.push(out, Op::GaussianTanh { mean, std, eps }, rg);
        (
            self.slice_cols(both, 0, a_dim),
            self.slice_cols(both, a_dim, 1),
        )
    }
}

/// Backward of [`Graph::gaussian_tanh`]; see its doc for the derivatives.
pub(crate) fn gaussian_tanh_backward(
    mean: Var,
    std: Var,
    eps: &Tensor,
    y: &Tensor,
    dy: &Tensor,
    ctx: &mut BackCtx<'_, '_>,
) {
    let (n, a_dim) = eps.shape();
    let sv = ctx.val(std);
    if let Some(dm) = ctx.grad(mean) {
        for r in 0..n {
            let (yr, dr) = (y.row(r), dy.row(r));
            for j in 0..a_dim {
                let a = yr[j];
                dm.data_mut()[r * a_dim + j] += dr[j] * (1.0 - a * a) + dr[a_dim] * 2.0 * a;
            }
        }
    }
    if let Some(ds) = ctx.grad(std) {
        for r in 0..n {
            let (yr, dr, e, s) = (y.row(r), dy.row(r), eps.row(r), sv.row(r));
            for j in 0..a_dim {
                let a = yr[j];
                ds.data_mut()[r * a_dim + j] +=
                    dr[j] * (1.0 - a * a) * e[j] + dr[a_dim] * (2.0 * a * e[j] - 1.0 / s[j]);
            }
        }
    }
}
