//! Scalar math written so that LLVM vectorises it, and a SIMD dispatch helper.
//!
//! `std`'s `exp` is a library call that stops auto-vectorisation; the LSTM gates need millions
//! of sigmoids and tanhs per update, so [`exp`] here is a Cephes-style polynomial made only of
//! multiplies, adds and bit casts (no FMA, so the result is the same on every code path).
//! [`simd`] runs a closure inside `pulp`'s runtime dispatch so its loops are compiled for the
//! best instruction set the CPU has (AVX2+FMA on x86-64) without `unsafe` here.

use faer::traits::pulp::Arch;
use std::sync::OnceLock;

/// The SIMD level detected at runtime (once).
#[inline]
pub(crate) fn arch() -> Arch {
    static ARCH: OnceLock<Arch> = OnceLock::new();
    *ARCH.get_or_init(Arch::new)
}

/// Runs `f` under the runtime SIMD dispatch. Only code LLVM inlines into the dispatched
/// function gets the wider instruction set; for hot loops use [`simd_fn!`] instead, which
/// guarantees it.
#[inline(always)]
pub(crate) fn simd<R>(f: impl FnOnce() -> R) -> R {
    arch().dispatch(f)
}

/// Defines a function whose body is compiled once per SIMD level and dispatched at runtime.
///
/// A closure passed to `pulp::Arch::dispatch` is one function shared by every branch of the
/// dispatch, so LLVM does not inline it and its loops stay SSE2. Here the body sits in an
/// `#[inline(always)]` generic `with_simd`, instantiated (and inlined) per level, so plain
/// loops are vectorised with AVX2+FMA where available. All reference arguments use `'a`.
macro_rules! simd_fn {
    ($(#[$m:meta])* $vis:vis fn $name:ident<'a>($($arg:ident : $ty:ty),* $(,)?) $body:block) => {
        $(#[$m])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name<'a>($($arg: $ty),*) {
            struct Kernel<'a> {
                $($arg: $ty,)*
                _l: std::marker::PhantomData<&'a ()>,
            }
            impl<'a> faer::traits::pulp::WithSimd for Kernel<'a> {
                type Output = ();
                #[inline(always)]
                fn with_simd<S: faer::traits::pulp::Simd>(self, _simd: S) {
                    let Kernel { $($arg,)* _l } = self;
                    $body
                }
            }
            $crate::kern::arch().dispatch(Kernel { $($arg,)* _l: std::marker::PhantomData })
        }
    };
}
pub(crate) use simd_fn;

const LOG2E: f32 = std::f32::consts::LOG2_E;
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;
/// 1.5·2²³: adding it rounds an f32 of magnitude < 2²² to the nearest integer.
const ROUND_MAGIC: f32 = 12_582_912.0;

/// e^x with relative error ≈ 2e-7 on [-87, 88]; clamps outside (never NaN for finite x,
/// NaN propagates as NaN).
#[inline(always)]
pub(crate) fn exp(x: f32) -> f32 {
    let x = x.clamp(-87.0, 88.0);
    let t = x * LOG2E + ROUND_MAGIC;
    let n = t - ROUND_MAGIC;
    let ni = (t.to_bits() as i32).wrapping_sub(ROUND_MAGIC.to_bits() as i32);
    let r = x - n * LN2_HI - n * LN2_LO;
    let r2 = r * r;
    let p = ((((1.987_569_1e-4 * r + 1.398_2e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 1.666_666_5e-1)
        * r
        + 0.5;
    let p = p * r2 + r + 1.0;
    p * f32::from_bits(((ni + 127) << 23) as u32)
}

/// σ(x) = 1 / (1 + e^(−x)).
#[inline(always)]
pub(crate) fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp(-x))
}

/// tanh(x) = 1 − 2 / (e^(2x) + 1) (absolute error ≈ 1e-7).
#[inline(always)]
pub(crate) fn tanh(x: f32) -> f32 {
    1.0 - 2.0 / (exp(2.0 * x) + 1.0)
}

/// softplus(x) = log(1 + e^x), stable for large |x|.
#[inline]
pub(crate) fn softplus(x: f32) -> f32 {
    x.max(0.0) + (-x.abs()).exp().ln_1p()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_std() {
        let mut worst = 0.0f64;
        let mut x = -80.0f32;
        while x < 80.0 {
            let rel = ((exp(x) as f64 - (x as f64).exp()) / (x as f64).exp()).abs();
            worst = worst.max(rel);
            x += 0.0137;
        }
        assert!(worst < 5e-7, "worst relative error {worst}");
        assert_eq!(exp(-1000.0).min(1e-30), exp(-1000.0));
        assert!(exp(1000.0).is_finite());
    }

    #[test]
    fn sigmoid_tanh_match_std() {
        let mut x = -30.0f32;
        while x < 30.0 {
            assert!(
                (sigmoid(x) as f64 - 1.0 / (1.0 + (-(x as f64)).exp())).abs() < 3e-7,
                "sigmoid {x}"
            );
            assert!(
                (tanh(x) as f64 - (x as f64).tanh()).abs() < 5e-7,
                "tanh {x}"
            );
            x += 0.011;
        }
    }
}
