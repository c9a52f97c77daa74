//! The only place that touches faer's matrix product (its API changes between versions).
//!
//! Everything is row-major f32 and single-threaded (`Par::Seq`): parallelism in esrl lives one
//! level up (rollouts, population members), and a single-threaded product keeps results
//! independent of the thread count.

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

/// Whether an operand is used as stored or transposed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Tr {
    /// Use the matrix as stored.
    N,
    /// Use its transpose.
    T,
}

/// Row-major view of `op(a)` with logical shape `(rows, cols)` where `a` is stored row-major
/// as `(rows, cols)` for [`Tr::N`] or `(cols, rows)` for [`Tr::T`].
#[inline]
fn view(a: &[f32], rows: usize, cols: usize, t: Tr) -> MatRef<'_, f32> {
    match t {
        Tr::N => MatRef::from_row_major_slice(&a[..rows * cols], rows, cols),
        Tr::T => MatRef::from_row_major_slice(&a[..rows * cols], cols, rows).transpose(),
    }
}

/// `dst (m, n) = [dst +] op(a) (m, k) · op(b) (k, n)`, everything row-major.
///
/// `dst` is a row-major `(m, n)` block with row stride `ldd` (≥ n), so a product can write
/// into a column block of a wider matrix.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn gemm_strided(
    dst: &mut [f32],
    ldd: usize,
    m: usize,
    n: usize,
    k: usize,
    a: &[f32],
    ta: Tr,
    b: &[f32],
    tb: Tr,
    accumulate: bool,
) {
    if m == 0 || n == 0 {
        return;
    }
    let beta = if accumulate {
        Accum::Add
    } else {
        Accum::Replace
    };
    if k == 0 {
        if !accumulate {
            for r in 0..m {
                dst[r * ldd..r * ldd + n].fill(0.0);
            }
        }
        return;
    }
    let need = (m - 1) * ldd + n;
    // faer 0.24.4's `MatMut::from_row_major_slice_with_stride_mut` builds column-major
    // strides (and then writes out of bounds); the transposed column-major view is correct.
    let d = MatMut::from_column_major_slice_with_stride_mut(&mut dst[..need], n, m, ldd)
        .transpose_mut();
    matmul(
        d,
        beta,
        view(a, m, k, ta),
        view(b, k, n, tb),
        1.0f32,
        Par::Seq,
    );
}

/// `dst (m, n) = [dst +] op(a) (m, k) · op(b) (k, n)` with a contiguous `dst`.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn gemm(
    dst: &mut [f32],
    m: usize,
    n: usize,
    k: usize,
    a: &[f32],
    ta: Tr,
    b: &[f32],
    tb: Tr,
    accumulate: bool,
) {
    gemm_strided(dst, n, m, n, k, a, ta, b, tb, accumulate);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive(m: usize, n: usize, k: usize, a: &[f32], ta: Tr, b: &[f32], tb: Tr) -> Vec<f32> {
        let mut out = vec![0.0f32; m * n];
        for i in 0..m {
            for j in 0..n {
                let mut s = 0.0f64;
                for l in 0..k {
                    let x = if ta == Tr::N {
                        a[i * k + l]
                    } else {
                        a[l * m + i]
                    };
                    let y = if tb == Tr::N {
                        b[l * n + j]
                    } else {
                        b[j * k + l]
                    };
                    s += x as f64 * y as f64;
                }
                out[i * n + j] = s as f32;
            }
        }
        out
    }

    #[test]
    fn gemm_matches_naive() {
        let shapes = [
            (1, 1, 1),
            (3, 5, 7),
            (17, 33, 9),
            (64, 400, 256),
            (256, 400, 100),
            (400, 100, 256),
            (2, 448, 112),
            (1, 6, 100),
        ];
        for &(m, n, k) in &shapes {
            for ta in [Tr::N, Tr::T] {
                for tb in [Tr::N, Tr::T] {
                    let a: Vec<f32> = (0..m * k)
                        .map(|i| ((i * 7919) % 13) as f32 * 0.1 - 0.6)
                        .collect();
                    let b: Vec<f32> = (0..k * n)
                        .map(|i| ((i * 104729) % 11) as f32 * 0.1 - 0.5)
                        .collect();
                    let want = naive(m, n, k, &a, ta, &b, tb);
                    let mut got = vec![1.0f32; m * n];
                    gemm(&mut got, m, n, k, &a, ta, &b, tb, true);
                    for (g, w) in got.iter().zip(&want) {
                        assert!(
                            (g - 1.0 - w).abs() < 1e-3 * (1.0 + w.abs()),
                            "{m}x{n}x{k} {ta:?}{tb:?}: {g} vs {w}"
                        );
                    }
                }
            }
        }
    }
}
