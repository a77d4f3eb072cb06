//! The machine: its cores and the vector instructions the kernels may use, each detected once
//! per process, and a worker pool of a given size, in which a command runs.

use std::sync::OnceLock;

/// Vector instructions the kernels have builds for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// AVX (the transforms' twiddle passes).
    pub avx: bool,
    /// AVX2 (the FD sweeps).
    pub avx2: bool,
    /// FMA (with AVX2: the spectral kernels).
    pub fma: bool,
}

/// The CPU's [`Features`], detected on the first call.
pub fn features() -> Features {
    static FEATURES: OnceLock<Features> = OnceLock::new();
    *FEATURES.get_or_init(detect)
}

#[cfg(target_arch = "x86_64")]
fn detect() -> Features {
    Features {
        avx: is_x86_feature_detected!("avx"),
        avx2: is_x86_feature_detected!("avx2"),
        fma: is_x86_feature_detected!("fma"),
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn detect() -> Features {
    Features {
        avx: false,
        avx2: false,
        fma: false,
    }
}

/// Whether the CPU has AVX.
#[inline]
pub fn has_avx() -> bool {
    features().avx
}

/// Whether the CPU has AVX2.
#[inline]
pub fn has_avx2() -> bool {
    features().avx2
}

/// Whether the CPU has AVX2 and FMA.
#[inline]
pub fn has_avx2_fma() -> bool {
    let f = features();
    f.avx2 && f.fma
}

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

    /// AVX2 and FMA imply AVX on every x86-64 CPU; the features read twice agree.
    #[test]
    fn features_are_consistent() {
        let f = features();
        assert!(f.avx || !f.avx2, "{f:?}");
        assert_eq!(features(), f);
        assert_eq!(has_avx2_fma(), f.avx2 && f.fma);
    }
}
