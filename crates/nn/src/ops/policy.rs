//! The tanh-squashed Gaussian policy sample with its log-probability (SAC, paper eq. 1).

use crate::graph::{BackCtx, Backward, Graph, Op, Var};
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
        let mut act = crate::pool::dirty(n * a_dim);
        let mut term = crate::pool::dirty(n * a_dim);
        sample_terms(mv.data(), sv.data(), eps.data(), &mut act, &mut term);
        let mut out = Tensor::uninit(n, w);
        for r in 0..n {
            let o = &mut out.data_mut()[r * w..(r + 1) * w];
            o[..a_dim].copy_from_slice(&act[r * a_dim..(r + 1) * a_dim]);
            o[a_dim] = term[r * a_dim..(r + 1) * a_dim].iter().sum();
        }
        crate::pool::recycle(act);
        crate::pool::recycle(term);
        let rg = self.rg(mean) || self.rg(std);
        let both = self.push(out, Op::of(GaussianTanh { mean, std, eps }), rg);
        (
            self.slice_cols(both, 0, a_dim),
            self.slice_cols(both, a_dim, 1),
        )
    }
}

kern::simd_fn! {
    /// Per element: a = tanh(u), u = μ + σε, and the log-density term
    /// −ε²/2 − log σ − log(2π)/2 − 2(log 2 − u − softplus(−2u)) (NaN for σ ≤ 0).
    fn sample_terms<'a>(mean: &'a [f32], std: &'a [f32], eps: &'a [f32], act: &'a mut [f32], term: &'a mut [f32]) {
        let n = act.len();
        let (mean, std, eps, term) = (&mean[..n], &std[..n], &eps[..n], &mut term[..n]);
        for k in 0..n {
            let (m, s, e) = (mean[k], std[k], eps[k]);
            let u = m + s * e;
            act[k] = kern::tanh(u);
            let log_s = if s > 0.0 { kern::ln(s) } else { f32::NAN };
            term[k] = -0.5 * e * e - log_s - HALF_LN_2PI - 2.0 * (LN2 - u - kern::softplus(-2.0 * u));
        }
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

/// Tanh-squashed Gaussian sample with its log-probability; output `[a | log π]`.
struct GaussianTanh {
    mean: Var,
    std: Var,
    eps: Tensor,
}

impl Backward for GaussianTanh {
    fn backward(&self, y: &Tensor, dy: &Tensor, ctx: &mut BackCtx<'_, '_>) {
        gaussian_tanh_backward(self.mean, self.std, &self.eps, y, dy, ctx);
    }
}
