//! The machine: its cores and the vector instructions the kernels may use, each detected once
//! per process, and a worker pool of a given size, in which a command runs.

use std::sync::OnceLock;

/// The vector instructions, detected once (by the transforms' crate, whose kernels use them
/// too).
pub use vesicle_transforms::cpu::{features, has_avx, has_avx2, has_avx2_fma, Features};

/// Cores this process may use (1 if the system cannot tell), read on the first call.
pub fn cores() -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// Run `f` in a new pool of `threads` workers (at least one): every parallel region inside it
/// runs on those workers.
///
/// # Panics
/// If the operating system refuses to start the threads.
pub fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .expect("thread pool")
        .install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pool of k workers reports k (and a request for 0 gets one).
    #[test]
    fn pools_have_the_size_asked_for() {
        for k in [0, 1, 3] {
            assert_eq!(in_pool(k, rayon::current_num_threads), k.max(1));
        }
        assert!(cores() >= 1);
    }
}
