//! The vector instructions the kernels may use, detected once per process: the transforms'
//! and, re-exported by `vesicle::cpu`, the rest of the program's.

use std::sync::OnceLock;

/// Vector instructions the kernels have builds for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// AVX (the transforms' packing and twiddle loops).
    pub avx: bool,
    /// AVX2 (the FD sweeps).
    pub avx2: bool,
    /// FMA (with AVX2: the column FFT, the real rows' split, the element-wise loops of
    /// [`crate::wide_fn`]).
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

#[cfg(test)]
mod tests {
    use super::*;

    /// AVX2 and FMA imply AVX on every x86-64 CPU; the features read twice agree.
    #[test]
    fn features_are_consistent() {
        let f = features();
        assert!(!f.avx2 || f.avx, "AVX2 implies AVX: {f:?}");
        assert_eq!(features(), f);
        assert_eq!(has_avx2_fma(), f.avx2 && f.fma);
    }
}
