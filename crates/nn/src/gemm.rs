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
/// with row stride `ld` as `(rows, cols)` for [`Tr::N`] or `(cols, rows)` for [`Tr::T`].
#[inline]
fn view(a: &[f32], rows: usize, cols: usize, ld: usize, t: Tr) -> MatRef<'_, f32> {
    let (r, c) = match t {
        Tr::N => (rows, cols),
        Tr::T => (cols, rows),
    };
    let need = if r == 0 || c == 0 {
        0
    } else {
        (r - 1) * ld + c
    };
    let m = MatRef::from_row_major_slice_with_stride(&a[..need], r, c, ld);
    match t {
        Tr::N => m,
        Tr::T => m.transpose(),
    }
}

/// `dst (m, n) = [dst +] op(a) (m, k) · op(b) (k, n)`, all row-major with row strides
/// `ldd`, `lda`, `ldb` (so operands and results can be column blocks of wider matrices).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn gemm_ex(
    dst: &mut [f32],
    ldd: usize,
    m: usize,
    n: usize,
    k: usize,
    a: &[f32],
    lda: usize,
    ta: Tr,
    b: &[f32],
    ldb: usize,
    tb: Tr,
    accumulate: bool,
) {
    if m == 0 || n == 0 {
        return;
    }
    if k == 0 {
        if !accumulate {
            for r in 0..m {
                dst[r * ldd..r * ldd + n].fill(0.0);
            }
        }
        return;
    }
    let beta = if accumulate {
        Accum::Add
    } else {
        Accum::Replace
    };
    let need = (m - 1) * ldd + n;
    // faer 0.24.4's `MatMut::from_row_major_slice_with_stride_mut` builds column-major
    // strides (and then writes out of bounds); the transposed column-major view is correct.
    let d = MatMut::from_column_major_slice_with_stride_mut(&mut dst[..need], n, m, ldd)
        .transpose_mut();
    matmul(
        d,
        beta,
        view(a, m, k, lda, ta),
        view(b, k, n, ldb, tb),
        1.0f32,
        Par::Seq,
    );
}

/// `dst (m, n) = [dst +] op(a) (m, k) · op(b) (k, n)`, all contiguous.
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
    let lda = if ta == Tr::N { k } else { m };
    let ldb = if tb == Tr::N { n } else { k };
    gemm_ex(dst, n, m, n, k, a, lda, ta, b, ldb, tb, accumulate);
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
    fn strided_blocks_match_naive() {
        // C[:, 1..4] += A[:, 2..5] · B[1..4, :]ᵀ-stored, inside wider matrices.
        let (m, n, k) = (5, 3, 3);
        let a: Vec<f32> = (0..m * 7).map(|i| (i % 9) as f32 * 0.3 - 1.0).collect();
        let b: Vec<f32> = (0..6 * 8).map(|i| (i % 5) as f32 * 0.2 - 0.4).collect();
        let mut c = vec![0.5f32; m * 6];
        gemm_ex(
            &mut c[1..],
            6,
            m,
            n,
            k,
            &a[2..],
            7,
            Tr::N,
            &b[8 + 1..],
            8,
            Tr::T,
            true,
        );
        for i in 0..m {
            for j in 0..6 {
                let want = if (1..4).contains(&j) {
                    0.5 + (0..k)
                        .map(|l| a[i * 7 + 2 + l] * b[(1 + j - 1) * 8 + 1 + l])
                        .sum::<f32>()
                } else {
                    0.5
                };
                assert!(
                    (c[i * 6 + j] - want).abs() < 1e-5,
                    "({i},{j}) {} vs {want}",
                    c[i * 6 + j]
                );
            }
        }
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
