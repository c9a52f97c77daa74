//! Scalar math written so that LLVM vectorises it, and a SIMD dispatch helper.
//!
//! `std`'s `exp` and `tanh` are library calls that stop auto-vectorisation; the LSTM gates need
//! millions of sigmoids and tanhs per update, so [`tanh`] here is a rational function and
//! [`exp`], [`ln`] Cephes-style polynomials, made only of multiplies, adds, divisions and bit
//! casts (no FMA, so the result is the same on every code path).
//! [`simd_fn!`] compiles a function body inside `pulp`'s runtime dispatch so its loops use the
//! best instruction set the CPU has (AVX2+FMA on x86-64) without `unsafe` here.

use faer::traits::pulp::Arch;
use std::sync::OnceLock;

/// The SIMD level detected at runtime (once).
#[inline]
pub(crate) fn arch() -> Arch {
    static ARCH: OnceLock<Arch> = OnceLock::new();
    *ARCH.get_or_init(Arch::new)
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

/// σ(x) = (1 + tanh(x/2)) / 2.
#[inline(always)]
pub(crate) fn sigmoid(x: f32) -> f32 {
    0.5 + 0.5 * tanh(0.5 * x)
}

/// tanh(x) as a rational function x·P(x²)/Q(x²) on [−7.9, 7.9] (Eigen's float tanh,
/// error ≈ 1 ulp; saturates to ±1 beyond).
#[inline(always)]
pub(crate) fn tanh(x: f32) -> f32 {
    let x = x.clamp(-7.905_311, 7.905_311);
    let x2 = x * x;
    let mut p = -2.760_768_5e-16f32;
    for c in [
        2.000_188e-13,
        -8.604_672e-11,
        5.122_297e-8,
        1.485_722_4e-5,
        6.372_619_3e-4,
        4.893_524_6e-3,
    ] {
        p = p * x2 + c;
    }
    let p = p * x;
    let q = ((1.198_258_4e-6 * x2 + 1.185_347e-4) * x2 + 2.268_434_6e-3) * x2 + 4.893_525e-3;
    p / q
}

/// Natural log for finite x > 0 (Cephes `logf`: x = m·2ᵉ, m ∈ [√½, √2), a degree-8
/// polynomial in m − 1; error ≈ 1 ulp). x ≤ 0, infinities and NaN are passed to `f32::ln`'s
/// conventions by the caller's domain, not handled here.
#[inline(always)]
pub(crate) fn ln(x: f32) -> f32 {
    let bits = x.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 127;
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    // Move m from [1, 2) to [√½, √2).
    let big = m > std::f32::consts::SQRT_2;
    m = if big { m * 0.5 } else { m };
    e += big as i32;
    let f = m - 1.0;
    let z = f * f;
    let mut p = 7.037_683_6e-2f32;
    for c in [
        -1.151_461e-1,
        1.167_699_9e-1,
        -1.242_014_1e-1,
        1.424_932_3e-1,
        -1.666_805_8e-1,
        2.000_071_4e-1,
        -2.499_999_4e-1,
        3.333_333e-1,
    ] {
        p = p * f + c;
    }
    let e = e as f32;
    let y = f * z * p + e * -2.121_944_4e-4 - 0.5 * z;
    f + y + e * 0.693_359_4
}

/// log(1 + e) for e ≥ 0, accurate for tiny e (Goldberg: log(u)·e/(u − 1) with u = 1 + e
/// rounded, which cancels the rounding of u).
#[inline(always)]
pub(crate) fn ln_1p(e: f32) -> f32 {
    let u = 1.0 + e;
    let d = u - 1.0;
    if d == 0.0 {
        e
    } else {
        ln(u) * (e / d)
    }
}

/// softplus(x) = log(1 + e^x) = max(x, 0) + log(1 + e^(−|x|)), stable for large |x|.
#[inline(always)]
pub(crate) fn softplus(x: f32) -> f32 {
    x.max(0.0) + ln_1p(exp(-x.abs()))
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
    fn ln_and_softplus_match_std() {
        let mut x = 1e-30f32;
        while x < 1e30 {
            let want = (x as f64).ln();
            assert!(
                (ln(x) as f64 - want).abs() <= 2e-7 * want.abs().max(1.0),
                "ln {x}: {} vs {want}",
                ln(x)
            );
            x *= 1.37;
        }
        let mut x = -40.0f32;
        while x < 40.0 {
            let want = (x as f64).max(0.0) + (-(x as f64).abs()).exp().ln_1p();
            assert!(
                (softplus(x) as f64 - want).abs() <= 3e-7 * want.max(1e-3),
                "softplus {x}"
            );
            x += 0.013;
        }
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
