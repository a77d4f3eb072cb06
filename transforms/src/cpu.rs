//! The vector instructions the kernels may use, detected once per process (as `vesicle::cpu`
//! does for the rest of the program).

use std::sync::OnceLock;

/// The instructions the kernels have builds for: AVX (the packing and twiddle loops), AVX2 and
/// FMA (the column FFT, the real rows' split, the element-wise loops of [`crate::wide`]).
#[derive(Clone, Copy)]
struct Features {
    avx: bool,
    avx2_fma: bool,
}

/// The CPU's [`Features`], detected on the first call.
fn features() -> Features {
    static FEATURES: OnceLock<Features> = OnceLock::new();
    *FEATURES.get_or_init(detect)
}

#[cfg(target_arch = "x86_64")]
fn detect() -> Features {
    Features {
        avx: is_x86_feature_detected!("avx"),
        avx2_fma: is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn detect() -> Features {
    Features {
        avx: false,
        avx2_fma: false,
    }
}

/// Whether the CPU has AVX.
#[inline]
pub(crate) fn has_avx() -> bool {
    features().avx
}

/// Whether the CPU has AVX2 and FMA.
#[inline]
pub fn has_avx2_fma() -> bool {
    features().avx2_fma
}

#[cfg(test)]
mod tests {
    use super::*;

    /// AVX2 and FMA imply AVX on every x86-64 CPU; the features read twice agree.
    #[test]
    fn features_are_consistent() {
        assert!(!has_avx2_fma() || has_avx(), "AVX2 implies AVX");
        assert_eq!(has_avx(), features().avx);
    }
}
