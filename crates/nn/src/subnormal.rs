//! Subnormal floats flushed to zero on the threads that train and roll out.
//!
//! A float below `f32::MIN_POSITIVE` (≈ 1.2e-38) is *subnormal*, and x86 cores compute with
//! subnormal operands or results one to two orders of magnitude slower than with normal ones.
//! Training makes them: squared gradients of units that barely learn in Adam's second moment,
//! products of small weights and gradients in the backward pass. Measured on the walking
//! recipe (2-core Intel Xeon, one thread, `esrl train es-sac --steps 30000 --seed 11`): the
//! gradient updates took 25.9 s with subnormals and 12.9 s with them flushed, the whole run
//! 55.2 s and 34.6 s, while `esrl bench update` on random data, which makes none, was 1.9 ms
//! an update either way.
//!
//! So every thread that trains or rolls out runs with the CPU's flush-to-zero and
//! denormals-are-zero modes on (MXCSR FTZ and DAZ on x86 and x86-64, FPCR FZ on AArch64; other
//! processors keep IEEE subnormals): a subnormal result becomes 0 and a subnormal operand is
//! read as 0. TensorFlow and XLA run their CPU kernels this way by default, PyTorch offers it
//! as `torch.set_flush_denormal(True)`. Results stay deterministic (the same seed gives the
//! same bits at any thread count, on one kind of processor) because every thread of every
//! pool esrl builds runs in the mode ([`thread_pool`], [`init_global_pool`]), and the two
//! entry points that may run on a caller's thread (`Agent::update` and `rollout` in
//! `esrl-agents`) switch it on for their own duration with [`flushing`], restoring the
//! caller's mode after. Evaluation episodes run on the pools.

/// Runs `f` with subnormals flushed to zero on this thread, then restores the thread's mode.
pub fn flushing<T>(f: impl FnOnce() -> T) -> T {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64", target_arch = "aarch64"))]
    {
        // SAFETY: only the handling of subnormal floats changes, on this thread, for the
        // duration of `f` (restored after it, also on unwinding). Rust's compiler assumes the
        // default floating-point environment, so a subnormal value folded at compile time may
        // differ from the same expression computed at run time; no computation of esrl
        // depends on subnormal values.
        #[allow(unsafe_code)]
        unsafe {
            no_denormals::no_denormals(f)
        }
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64", target_arch = "aarch64")))]
    {
        f()
    }
}

/// A rayon pool of `threads` threads (0: rayon's default) whose threads all run with
/// subnormals flushed to zero.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .spawn_handler(spawn_flushing)
        .build()
}

/// Makes rayon's global pool (used by parallel work outside any pool of [`thread_pool`]) a
/// pool whose threads flush subnormals. Call it before anything uses the global pool; once it
/// exists (built by an earlier call or by other code) it is left as it is, and `false` is
/// returned.
pub fn init_global_pool() -> bool {
    rayon::ThreadPoolBuilder::new()
        .spawn_handler(spawn_flushing)
        .build_global()
        .is_ok()
}

fn spawn_flushing(thread: rayon::ThreadBuilder) -> std::io::Result<()> {
    let mut b = std::thread::Builder::new();
    if let Some(name) = thread.name() {
        b = b.name(name.to_owned());
    }
    if let Some(size) = thread.stack_size() {
        b = b.stack_size(size);
    }
    b.spawn(|| flushing(|| thread.run()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hint::black_box;

    /// Half the smallest normal f32: subnormal in IEEE arithmetic, 0 when flushed.
    fn half_min() -> f32 {
        black_box(f32::MIN_POSITIVE) * black_box(0.5)
    }

    #[test]
    fn flushing_turns_subnormal_results_to_zero_and_restores_the_mode() {
        assert!(half_min().is_subnormal(), "IEEE mode outside");
        #[cfg(any(target_arch = "x86", target_arch = "x86_64", target_arch = "aarch64"))]
        assert_eq!(flushing(half_min), 0.0);
        assert!(half_min().is_subnormal(), "the caller's mode is restored");
    }

    #[test]
    fn pool_threads_flush() {
        let pool = thread_pool(2).unwrap();
        let seen: Vec<f32> = pool.install(|| {
            use rayon::prelude::*;
            (0..64).into_par_iter().map(|_| half_min()).collect()
        });
        #[cfg(any(target_arch = "x86", target_arch = "x86_64", target_arch = "aarch64"))]
        assert!(seen.iter().all(|&x| x == 0.0));
        assert_eq!(seen.len(), 64);
    }
}
