//! Adam with global gradient-norm clipping and L2 regularisation.
//!
//! Per step, for gradient g of the loss and parameters θ (t counts steps from 1):
//!
//! ```text
//! g ← g · min(1, clip / ‖g‖₂)            global norm over the whole set (if clip is set)
//! g ← g + λ·θ                            L2, on weights only (biases excluded, as MATLAB)
//! m ← β₁m + (1 − β₁)g     v ← β₂v + (1 − β₂)g²
//! θ ← θ − lr · (m / (1 − β₁ᵗ)) / (√(v / (1 − β₂ᵗ)) + ε)
//! ```
//!
//! Clipping comes before L2 (as `clip_grad_norm_` followed by `Adam(weight_decay=λ)` in
//! PyTorch), so the regulariser is never clipped away.

use crate::error::NnError;
use crate::params::Params;
use serde::{Deserialize, Serialize};

/// Adam hyperparameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdamConfig {
    /// Learning rate. Default 1e-3 (Kingma & Ba); agents set their own.
    pub lr: f32,
    /// First-moment decay β₁. Default 0.9 (MATLAB `GradientDecayFactor`).
    pub beta1: f32,
    /// Second-moment decay β₂. Default 0.999 (MATLAB `SquaredGradientDecayFactor`).
    pub beta2: f32,
    /// ε in the denominator. Default 1e-8 (MATLAB `Epsilon`).
    pub eps: f32,
    /// L2 factor λ on weights. Default 1e-4 (MATLAB `L2RegularizationFactor`).
    pub l2: f32,
    /// Global L2-norm gradient threshold; `None` = no clipping. Default `None` (MATLAB
    /// `GradientThreshold = Inf`).
    pub grad_clip: Option<f32>,
}

impl Default for AdamConfig {
    fn default() -> Self {
        Self {
            lr: 1e-3,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
            l2: 1e-4,
            grad_clip: None,
        }
    }
}

impl AdamConfig {
    /// Checks every field; errors name the field.
    pub fn validate(&self) -> Result<(), NnError> {
        let bad = |field: &str, v: f32, reason: &str| {
            Err(NnError::Config {
                field: format!("adam.{field}"),
                value: v.to_string(),
                reason: reason.into(),
            })
        };
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return bad("lr", self.lr, "must be finite and > 0");
        }
        if !(0.0..1.0).contains(&self.beta1) {
            return bad("beta1", self.beta1, "must be in [0, 1)");
        }
        if !(0.0..1.0).contains(&self.beta2) {
            return bad("beta2", self.beta2, "must be in [0, 1)");
        }
        if !(self.eps.is_finite() && self.eps > 0.0) {
            return bad("eps", self.eps, "must be finite and > 0");
        }
        if !(self.l2.is_finite() && self.l2 >= 0.0) {
            return bad("l2", self.l2, "must be finite and ≥ 0");
        }
        if let Some(c) = self.grad_clip {
            if c.is_nan() || c <= 0.0 {
                return bad("grad_clip", c, "must be > 0 (or absent for no clipping)");
            }
        }
        Ok(())
    }
}

/// Adam's moment estimates, exportable for checkpoints.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct AdamState {
    /// Steps taken.
    pub t: u64,
    /// First moments (flat, parameter layout).
    pub m: Vec<f32>,
    /// Second moments.
    pub v: Vec<f32>,
}

/// Adam over one [`Params`] set.
#[derive(Clone, Debug)]
pub struct Adam {
    config: AdamConfig,
    /// The flat buffer as consecutive runs, each with its L2 mask: 1 where L2 applies
    /// (weights), 0 elsewhere (biases, and any gap between tensors).
    runs: Vec<(std::ops::Range<usize>, f32)>,
    /// Number of parameters.
    len: usize,
    state: AdamState,
}

/// `mask` (one entry per parameter) as maximal runs of equal values.
fn runs_of(mask: &[f32]) -> Vec<(std::ops::Range<usize>, f32)> {
    let mut runs: Vec<(std::ops::Range<usize>, f32)> = Vec::new();
    for (i, &d) in mask.iter().enumerate() {
        match runs.last_mut() {
            Some((r, v)) if *v == d => r.end = i + 1,
            _ => runs.push((i..i + 1, d)),
        }
    }
    runs
}

/// Scales `grads` (several buffers seen as one vector) so that their global L2 norm is at most
/// `max_norm`; returns the norm before scaling. Non-finite norms are returned unscaled.
pub fn clip_grad_norm(grads: &mut [&mut [f32]], max_norm: f32) -> f32 {
    let norm = grads.iter().map(|g| sum_sq(g)).sum::<f64>().sqrt() as f32;
    if let Some(k) = clip_factor(norm, max_norm) {
        grads
            .iter_mut()
            .for_each(|g| g.iter_mut().for_each(|x| *x *= k));
    }
    norm
}

/// The factor that brings a gradient of norm `norm` down to `max_norm`, if it is above it
/// (none for a non-finite norm).
fn clip_factor(norm: f32, max_norm: f32) -> Option<f32> {
    (norm.is_finite() && norm > max_norm).then(|| max_norm / norm)
}

impl Adam {
    /// An optimiser for `params` (only its layout is read).
    pub fn new(config: AdamConfig, params: &Params) -> Result<Self, NnError> {
        config.validate()?;
        let mut decay = vec![0.0f32; params.len()];
        for s in params.specs() {
            decay[s.range()].fill(if s.decay { 1.0 } else { 0.0 });
        }
        let n = params.len();
        Ok(Self {
            config,
            runs: runs_of(&decay),
            len: n,
            state: AdamState {
                t: 0,
                m: vec![0.0; n],
                v: vec![0.0; n],
            },
        })
    }

    /// The hyperparameters.
    pub fn config(&self) -> &AdamConfig {
        &self.config
    }

    /// Changes the learning rate (schedules).
    pub fn set_lr(&mut self, lr: f32) {
        self.config.lr = lr;
    }

    /// The moments, for checkpoints.
    pub fn state(&self) -> &AdamState {
        &self.state
    }

    /// Restores moments saved by [`Adam::state`].
    pub fn set_state(&mut self, state: AdamState) -> Result<(), NnError> {
        for (what, v) in [("Adam m", &state.m), ("Adam v", &state.v)] {
            if v.len() != self.len {
                return Err(NnError::LengthMismatch {
                    what: what.into(),
                    expected: self.len,
                    found: v.len(),
                });
            }
        }
        self.state = state;
        Ok(())
    }

    /// One step on `params` with its gradient taken out of `grads` (the usual call after
    /// [`crate::Graph::backward`]). Returns the gradient norm before clipping.
    pub fn apply(
        &mut self,
        params: &mut Params,
        grads: &mut crate::Gradients,
    ) -> Result<f32, NnError> {
        let g = grads
            .take(params)
            .ok_or(NnError::NoGradient { len: params.len() })?;
        let r = self.step(params, &g);
        crate::pool::recycle(g);
        r
    }

    /// One step on `params` with the loss gradient `grad`. Returns the gradient norm before
    /// clipping. A non-finite gradient is refused with [`NnError::NonFiniteGradient`] and
    /// nothing changes.
    ///
    /// Two passes over memory: the norm, then one fused pass that clips, adds L2 and moves
    /// the moments and the parameters. It computes what clipping in place and then updating
    /// would, bit for bit (the clip factor is the same f32 product, and 1 where there is no
    /// clipping).
    pub fn step(&mut self, params: &mut Params, grad: &[f32]) -> Result<f32, NnError> {
        let n = self.len;
        if params.len() != n || grad.len() != n {
            return Err(NnError::LengthMismatch {
                what: "Adam::step gradient/parameters".into(),
                expected: n,
                found: grad.len().min(params.len()),
            });
        }
        let norm = sum_sq(grad).sqrt() as f32;
        let clip = self
            .config
            .grad_clip
            .and_then(|c| clip_factor(norm, c))
            .unwrap_or(1.0);
        if !norm.is_finite() {
            return Err(NnError::NonFiniteGradient {
                what: format!("{n} parameters"),
            });
        }
        let c = &self.config;
        self.state.t += 1;
        let t = self.state.t as i32;
        let bc1 = 1.0 - (c.beta1 as f64).powi(t);
        let bc2 = 1.0 - (c.beta2 as f64).powi(t);
        let step = (c.lr as f64 / bc1) as f32;
        let inv_sqrt_bc2 = (1.0 / bc2.sqrt()) as f32;
        let (b1, b2, eps, l2) = (c.beta1, c.beta2, c.eps, c.l2);
        let theta = params.as_mut_slice();
        let (m, v) = (&mut self.state.m, &mut self.state.v);
        for (r, mask) in &self.runs {
            let k = AdamConsts {
                b1,
                b2,
                eps,
                clip,
                l2: l2 * mask,
                step,
                inv_sqrt_bc2,
            };
            let r = r.clone();
            adam_update(
                &mut theta[r.clone()],
                &grad[r.clone()],
                &mut m[r.clone()],
                &mut v[r],
                k,
            );
        }
        Ok(norm)
    }
}

/// Σ x² accumulated in f64 (8 fixed lanes, so the result does not depend on the SIMD level).
fn sum_sq(x: &[f32]) -> f64 {
    let mut acc = [0.0f64; 8];
    sum_sq_lanes(x, &mut acc);
    acc.iter().sum()
}

crate::kern::simd_fn! {
    /// acc[k] += Σ_j x[8j + k]² in f64.
    fn sum_sq_lanes<'a>(x: &'a [f32], acc: &'a mut [f64; 8]) {
        let mut a = *acc;
        let chunks = x.chunks_exact(8);
        let rest = chunks.remainder();
        for c in chunks {
            for k in 0..8 {
                let v = c[k] as f64;
                a[k] += v * v;
            }
        }
        for (k, &v) in rest.iter().enumerate() {
            a[k] += (v as f64) * (v as f64);
        }
        *acc = a;
    }
}

/// Scalars of one Adam step.
#[derive(Clone, Copy)]
struct AdamConsts {
    b1: f32,
    b2: f32,
    eps: f32,
    /// The clip factor (1 for none).
    clip: f32,
    /// λ on this run: λ·1 on weights, λ·0 on biases.
    l2: f32,
    /// lr / (1 − β₁ᵗ).
    step: f32,
    /// 1 / √(1 − β₂ᵗ).
    inv_sqrt_bc2: f32,
}

crate::kern::simd_fn! {
    /// The elementwise Adam update (see the module doc).
    fn adam_update<'a>(theta: &'a mut [f32], grad: &'a [f32], m: &'a mut [f32], v: &'a mut [f32], k: AdamConsts) {
        adam_rows(theta, grad, m, v, k);
    }
}

/// Body of [`adam_update`]; slices as separate arguments so the loop vectorises.
#[inline(always)]
fn adam_rows(theta: &mut [f32], grad: &[f32], m: &mut [f32], v: &mut [f32], k: AdamConsts) {
    let n = theta.len();
    let (grad, m, v) = (&grad[..n], &mut m[..n], &mut v[..n]);
    for i in 0..n {
        // (λ·mask)·θ as the former λ·mask[i]·θ[i]; g·clip as the former in-place clip.
        let g = grad[i] * k.clip + k.l2 * theta[i];
        let mi = k.b1 * m[i] + (1.0 - k.b1) * g;
        let vi = k.b2 * v[i] + (1.0 - k.b2) * g * g;
        m[i] = mi;
        v[i] = vi;
        theta[i] -= k.step * mi / (vi.sqrt() * k.inv_sqrt_bc2 + k.eps);
    }
}
