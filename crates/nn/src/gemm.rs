//! The only place that touches faer's matrix product (its API changes between versions).
//!
//! Everything is row-major f32. A large product is split into blocks of whole output rows
//! (or, for wide short results, whole output columns), one per thread of the rayon pool it
//! runs in, and each block is faer's single-threaded product (`Par::Seq`). The split is only
//! ever over output elements, never over the summed dimension `k`: every output element is
//! the same sequence of multiply-adds whatever the number of blocks, so results do not depend
//! on the thread count (tested bit for bit against the unsplit product in this module and on
//! whole updates in `esrl-agents`).
//!
//! **Where faer packs.** faer 0.24 hands an f32 product of more than a few thousand
//! multiply-adds to `private-gemm-x86`, which first turns the product around so that the
//! result is column-major (for a row-major `dst = op(a)·op(b)` it computes `dstᵀ =
//! op(b)ᵀ·op(a)ᵀ`) and then copies ("packs") its left operand into the kernel's layout
//! whenever the result has more than 12 columns (`n > 3·nr`, `nr = 4`; `private-gemm-x86`
//! 0.1.22, `gemm`). Here every result is row-major, so the left operand is `op(b)ᵀ`: in a
//! layer's forward product and its input gradient, the weight matrix (64 K floats for a
//! 256×256 layer), packed again for every product: about 9 % of a batch-64 SAC update
//! (`results/speed`). No weight layout avoids it (the 12-column rule packs any layout).
//! A feed-forward stack therefore keeps its values feature-major (`ops::linear`'s docs):
//! `yᵀ = W·xᵀ` is a row-major result whose column-major frame is `y = x·Wᵀ`, so the packed
//! operand is the batch's activations, 4× smaller at batch 64. Each output element is the
//! same multiply-adds in the same order either way (tested bit for bit in `layers`).

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

/// Products of fewer multiply-adds than this run on the calling thread: below it, waking
/// another thread costs more than it saves. 2²³ keeps the walking recipe's batch-64 products
/// of the 256-wide layers (64·256·256 = 2²²) whole: on the 2-core Intel machine its ES
/// generation took 0.310–0.327 s at 2 threads against 0.333–0.336 s with 2²² (`esrl bench es
/// --preset walking`, alternated); batch 128 and larger still split.
const PAR_MIN_WORK: usize = 1 << 23;
/// A block keeps at least this many rows (or columns) so faer's kernels stay efficient.
const MIN_BLOCK: usize = 8;

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
    let (a, b) = (view(a, m, k, lda, ta), view(b, k, n, ldb, tb));
    let blocks = if m * n * k < PAR_MIN_WORK {
        1
    } else {
        rayon::current_num_threads()
            .min(m.max(n) / MIN_BLOCK)
            .max(1)
    };
    product(d, beta, a, b, blocks);
}

/// `d = [d +] a·b` in `blocks` blocks of whole rows of `d` (whole columns when `d` is wider
/// than tall), halved recursively onto the rayon pool.
fn product(d: MatMut<'_, f32>, beta: Accum, a: MatRef<'_, f32>, b: MatRef<'_, f32>, blocks: usize) {
    if blocks <= 1 {
        matmul(d, beta, a, b, 1.0f32, Par::Seq);
        return;
    }
    let left = blocks / 2;
    if d.nrows() >= d.ncols() {
        let at = d.nrows() * left / blocks;
        let (d0, d1) = d.split_at_row_mut(at);
        let (a0, a1) = a.split_at_row(at);
        rayon::join(
            || product(d0, beta, a0, b, left),
            || product(d1, beta, a1, b, blocks - left),
        );
    } else {
        let at = d.ncols() * left / blocks;
        let (d0, d1) = d.split_at_col_mut(at);
        let (b0, b1) = b.split_at_col(at);
        rayon::join(
            || product(d0, beta, a, b0, left),
            || product(d1, beta, a, b1, blocks - left),
        );
    }
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

    /// A product on `threads` pool threads.
    fn on_threads(threads: usize, f: impl FnOnce() + Send) {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(f);
    }

    #[test]
    fn split_products_equal_the_single_thread_one_bit_for_bit() {
        // The shapes of the paper's and quick's updates (batch 256, LSTM 2048 = 256 × 8
        // steps, hidden 256, gates 1024 / 512, inputs 31 + 6) and degenerate ones.
        let shapes = [
            (256, 256, 256),
            (64, 256, 256),
            (256, 64, 256),
            (256, 256, 37),
            (37, 256, 256),
            (256, 1, 256),
            (1, 256, 256),
            (2048, 512, 128),
            (128, 512, 2048),
            (2048, 1024, 37),
            (37, 1024, 2048),
            (256, 1024, 256),
            (31, 256, 2048),
            (24, 2048, 24),
        ];
        for &(m, n, k) in &shapes {
            for (ta, tb) in [
                (Tr::N, Tr::N),
                (Tr::N, Tr::T),
                (Tr::T, Tr::N),
                (Tr::T, Tr::T),
            ] {
                let a: Vec<f32> = (0..m * k)
                    .map(|i| ((i * 7919) % 1013) as f32 * 0.0013 - 0.6)
                    .collect();
                let b: Vec<f32> = (0..k * n)
                    .map(|i| ((i * 104729) % 1011) as f32 * 0.0011 - 0.5)
                    .collect();
                let mut one = vec![0.25f32; m * n];
                on_threads(1, || gemm(&mut one, m, n, k, &a, ta, &b, tb, true));
                for threads in [2, 3, 4, 7] {
                    let mut many = vec![0.25f32; m * n];
                    on_threads(threads, || gemm(&mut many, m, n, k, &a, ta, &b, tb, true));
                    assert!(
                        one.iter()
                            .zip(&many)
                            .all(|(x, y)| x.to_bits() == y.to_bits()),
                        "{m}x{n}x{k} {ta:?}{tb:?} on {threads} threads differs from one"
                    );
                }
            }
        }
    }
}
