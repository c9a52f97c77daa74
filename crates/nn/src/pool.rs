//! A per-thread pool of large f32 buffers.
//!
//! One update allocates tens of megabytes of activations, caches and gradients and frees them
//! at the end. Fresh large allocations are mmapped by the allocator and every page is faulted
//! in and zeroed by the kernel again (about a sixth of an update's time when measured), so
//! buffers of at least [`POOL_MIN`] floats are recycled here instead. The pool is
//! thread-local (rayon workers each keep their own) and bounded.

use std::cell::RefCell;

/// Smallest buffer (in f32) worth pooling: 16 KiB.
const POOL_MIN: usize = 4096;
/// At most this many buffers are kept per thread.
const POOL_MAX_BUFFERS: usize = 96;
/// At most this many f32 are kept per thread (512 MiB).
const POOL_MAX_FLOATS: usize = 128 << 20;

thread_local! {
    static POOL: RefCell<Vec<Vec<f32>>> = const { RefCell::new(Vec::new()) };
}

/// Takes the smallest pooled buffer with capacity ≥ n, if any.
fn take(n: usize) -> Option<Vec<f32>> {
    if n < POOL_MIN {
        return None;
    }
    POOL.with(|p| {
        let mut p = p.borrow_mut();
        let best = p
            .iter()
            .enumerate()
            .filter(|(_, v)| v.capacity() >= n)
            .min_by_key(|(_, v)| v.capacity())
            .map(|(i, _)| i)?;
        Some(p.swap_remove(best))
    })
}

/// A buffer of `n` zeros.
pub(crate) fn zeros(n: usize) -> Vec<f32> {
    match take(n) {
        Some(mut v) => {
            v.clear();
            v.resize(n, 0.0);
            v
        }
        None => vec![0.0; n],
    }
}

/// A buffer of length `n` with unspecified (finite or not) contents, for outputs that are
/// entirely overwritten.
pub(crate) fn dirty(n: usize) -> Vec<f32> {
    match take(n) {
        Some(mut v) => {
            if v.len() > n {
                v.truncate(n);
            } else {
                v.resize(n, 0.0);
            }
            v
        }
        None => vec![0.0; n],
    }
}

/// A copy of `src` in a pooled buffer.
pub(crate) fn copy(src: &[f32]) -> Vec<f32> {
    let mut v = dirty(src.len());
    v.copy_from_slice(src);
    v
}

/// Returns a buffer to the pool (or frees it when small or the pool is full).
pub(crate) fn recycle(v: Vec<f32>) {
    if v.capacity() < POOL_MIN {
        return;
    }
    // `try_with`: during thread teardown the pool may already be gone; then just free.
    let _ = POOL.try_with(|p| {
        let Ok(mut p) = p.try_borrow_mut() else {
            return;
        };
        let held: usize = p.iter().map(|b| b.capacity()).sum();
        if p.len() < POOL_MAX_BUFFERS && held + v.capacity() <= POOL_MAX_FLOATS {
            p.push(v);
        }
    });
}
