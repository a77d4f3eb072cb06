//! [`wide_fn`]: element-wise loops compiled for AVX2/FMA as well as for the baseline (the
//! transforms' rows, and vesicle's spectral sweeps).

/// Defines a function whose body is compiled twice, for AVX2/FMA and as it is, and runs the
/// first when the CPU has those instructions: the body's element-wise loops are then vectorised
/// four values wide. Plain `a * b + c` is never fused into an FMA by the compiler, so both
/// builds give the same values. The arguments are plain names; `const` generics may be given.
#[macro_export]
macro_rules! wide_fn {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident $(<$(const $c:ident: $ct:ty),*>)?
        ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block
    ) => {
        $(#[$meta])*
        #[inline(always)]
        $vis fn $name $(<$(const $c: $ct),*>)? ($($arg: $ty),*) $(-> $ret)? {
            #[inline(always)]
            fn body $(<$(const $c: $ct),*>)? ($($arg: $ty),*) $(-> $ret)? $body
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,fma")]
            fn avx2 $(<$(const $c: $ct),*>)? ($($arg: $ty),*) $(-> $ret)? {
                body $(::<$($c),*>)? ($($arg),*)
            }
            #[cfg(target_arch = "x86_64")]
            if $crate::cpu::has_avx2_fma() {
                // SAFETY: the CPU has AVX2 and FMA (checked just now).
                return unsafe { avx2 $(::<$($c),*>)? ($($arg),*) };
            }
            body $(::<$($c),*>)? ($($arg),*)
        }
    };
}
