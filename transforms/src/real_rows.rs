//! The real FFT of contiguous rows of even length `n` through one complex FFT of length
//! `m = n/2` a row, with the split into the real spectrum vectorised (AVX2/FMA): the periodic
//! last axis's transform.
//!
//! Forward, a row `x` read as `z_j = x_{2j} + i x_{2j+1}` (no copy) has the DFT `Z = F_m z`, and
//! with `E_k = (Z_k + Z*_{m−k})/2`, `O_k = −i (Z_k − Z*_{m−k})/2` (the DFTs of the even and odd
//! samples, `Z_m ≡ Z_0`) and `w = e^{−2πi/n}`,
//!
//! ```text
//! X_k = E_k + w^k O_k,   X_{m−k} = (E_k − w^k O_k)*      (1 ≤ k < m/2),
//! X_0 = Re Z_0 + Im Z_0,   X_m = Re Z_0 − Im Z_0,   X_{m/2} = Z*_{m/2} (m even).
//! ```
//!
//! Inverse, scaled by `s`, the same relations backwards with the factors 1/2 dropped (so that
//! inverse ∘ forward = `n s`, as `realfft`'s unnormalised inverse times `s`):
//! `E_k = s (X_k + X*_{m−k})`, `O_k = s w^{−k} (X_k − X*_{m−k})`, `Z_k = E_k + i O_k`,
//! `Z_{m−k} = (E_k − i O_k)*`, then `z = F_m^{−1} Z`. The imaginary parts of `X_0` and `X_m`
//! are ignored (they are those of a real field's spectrum only up to round-off).
//!
//! Against `realfft` (the same algorithm with the split in scalar complex arithmetic), the
//! split takes two bins a register and the row's mirror bins from the same loads.

use std::f64::consts::PI;
use std::sync::Arc;

use num_complex::Complex64;
use vesicle_fft_plans::{Fft, Planner};

/// Rows transformed by one call of the complex FFT (16 rows of 64 reals and their spectra take
/// 16 KiB, so the split reads what the FFT left in L1).
const GROUP: usize = 16;

/// A planned real FFT of rows of even length `n`.
pub struct RealRows {
    m: usize,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    /// `w^k = e^{−2πik/n}`, `k < m`.
    twiddles: Vec<Complex64>,
}

impl RealRows {
    /// The plan for rows of length `n`, if `n ≥ 2` is even and the CPU has AVX2 and FMA.
    pub fn new(planner: &mut Planner, n: usize) -> Option<Self> {
        if n < 2 || !n.is_multiple_of(2) || !crate::cpu::has_avx2_fma() {
            return None;
        }
        let m = n / 2;
        let twiddles = (0..m)
            .map(|k| Complex64::from_polar(1.0, -2.0 * PI * k as f64 / n as f64))
            .collect();
        Some(RealRows {
            m,
            forward: planner.forward(m),
            inverse: planner.inverse(m),
            twiddles,
        })
    }

    /// Scratch values [`Self::forward`] and [`Self::inverse`] need.
    pub fn scratch_len(&self) -> usize {
        self.forward
            .get_inplace_scratch_len()
            .max(self.inverse.get_inplace_scratch_len())
    }

    /// The spectra `X_0..=X_m` of the rows of `x` into the rows of `y` (m + 1 values each);
    /// `x` is overwritten.
    ///
    /// # Panics
    /// If `x` is not whole rows, `y` does not hold as many rows or `scratch` is short.
    pub fn forward(&self, x: &mut [f64], y: &mut [Complex64], scratch: &mut [Complex64]) {
        let m = self.m;
        let z = as_complex(x);
        assert_eq!(z.len() / m, y.len() / (m + 1), "rows of x and y");
        let scratch = &mut scratch[..self.forward.get_inplace_scratch_len()];
        for (zg, yg) in z.chunks_mut(GROUP * m).zip(y.chunks_mut(GROUP * (m + 1))) {
            self.forward.process_with_scratch(zg, scratch);
            for (zr, yr) in zg.chunks_exact(m).zip(yg.chunks_exact_mut(m + 1)) {
                split(zr, yr, &self.twiddles);
            }
        }
    }

    /// The rows of `x` from the spectra in the rows of `y`, times `n scale` (see the module
    /// documentation); `y` is left as it was.
    ///
    /// # Panics
    /// As for [`Self::forward`].
    pub fn inverse(&self, y: &[Complex64], x: &mut [f64], scale: f64, scratch: &mut [Complex64]) {
        let m = self.m;
        let z = as_complex(x);
        assert_eq!(z.len() / m, y.len() / (m + 1), "rows of x and y");
        let scratch = &mut scratch[..self.inverse.get_inplace_scratch_len()];
        for (zg, yg) in z.chunks_mut(GROUP * m).zip(y.chunks(GROUP * (m + 1))) {
            for (zr, yr) in zg.chunks_exact_mut(m).zip(yg.chunks_exact(m + 1)) {
                merge(yr, zr, &self.twiddles, scale);
            }
            self.inverse.process_with_scratch(zg, scratch);
        }
    }
}

/// `x` as complex values `x_{2j} + i x_{2j+1}` (`Complex64` is `repr(C)`, two `f64`).
fn as_complex(x: &mut [f64]) -> &mut [Complex64] {
    assert!(x.len().is_multiple_of(2), "whole rows of even length");
    bytemuck::cast_slice_mut(x)
}

/// One row's split: `y` (m + 1 values) from `z = F_m z` (m values), `w` the twiddles.
fn split(z: &[Complex64], y: &mut [Complex64], w: &[Complex64]) {
    let m = z.len();
    y[0] = Complex64::new(z[0].re + z[0].im, 0.0);
    y[m] = Complex64::new(z[0].re - z[0].im, 0.0);
    if m.is_multiple_of(2) {
        y[m / 2] = z[m / 2].conj();
    }
    // SAFETY: plans exist only when the CPU has AVX2 and FMA (`RealRows::new`).
    #[cfg(target_arch = "x86_64")]
    let mut k = unsafe { x86::split_pairs(z, y, w) };
    #[cfg(not(target_arch = "x86_64"))]
    let mut k = 1;
    while 2 * k < m {
        let (a, b) = (z[k], z[m - k].conj());
        let (e, d) = ((a + b) * 0.5, (a - b) * 0.5);
        let o = Complex64::new(d.im, -d.re);
        let t = w[k] * o;
        y[k] = e + t;
        y[m - k] = (e - t).conj();
        k += 1;
    }
}

/// One row's merge: `z` (m values, before the inverse FFT) from the spectrum `y`, times `s`.
fn merge(y: &[Complex64], z: &mut [Complex64], w: &[Complex64], s: f64) {
    let m = z.len();
    let (a, b) = (y[0].re, y[m].re);
    z[0] = Complex64::new(s * (a + b), s * (a - b));
    if m.is_multiple_of(2) {
        z[m / 2] = y[m / 2].conj() * (2.0 * s);
    }
    // SAFETY: as in `split`.
    #[cfg(target_arch = "x86_64")]
    let mut k = unsafe { x86::merge_pairs(y, z, w, s) };
    #[cfg(not(target_arch = "x86_64"))]
    let mut k = 1;
    while 2 * k < m {
        let (e, d) = (y[k] + y[m - k].conj(), y[k] - y[m - k].conj());
        let (e, o) = (e * s, w[k].conj() * (d * s));
        let io = Complex64::new(-o.im, o.re);
        z[k] = e + io;
        z[m - k] = (e - io).conj();
        k += 1;
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! [`super::split`] and [`super::merge`] two bins a register: bins k, k + 1 and their
    //! mirrors m − k, m − k − 1 (loaded as one register and its halves swapped). Safe functions
    //! that need AVX2 and FMA (their `#[target_feature]`): a caller built without them calls
    //! them in an `unsafe` block once it knows the CPU has them; the lengths are asserted.

    use num_complex::Complex64;
    use std::arch::x86_64::*;

    /// Conjugate (flip the imaginary signs).
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn conj(v: __m256d) -> __m256d {
        _mm256_xor_pd(v, _mm256_setr_pd(0.0, -0.0, 0.0, -0.0))
    }

    /// The two values of `v` swapped.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn swap(v: __m256d) -> __m256d {
        _mm256_permute2f128_pd(v, v, 1)
    }

    /// `w v` (`conj`: `w* v`), each sum fused.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn times<const CONJ: bool>(w: __m256d, v: __m256d) -> __m256d {
        let (re, im) = (_mm256_movedup_pd(w), _mm256_permute_pd(w, 0b1111));
        let cross = _mm256_mul_pd(_mm256_permute_pd(v, 0b0101), im);
        if CONJ {
            _mm256_fmsubadd_pd(v, re, cross)
        } else {
            _mm256_fmaddsub_pd(v, re, cross)
        }
    }

    /// `i v` (`NEG`: `−i v`).
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn turn<const NEG: bool>(v: __m256d) -> __m256d {
        let swapped = _mm256_permute_pd(v, 0b0101);
        let sign = if NEG {
            _mm256_setr_pd(0.0, -0.0, 0.0, -0.0)
        } else {
            _mm256_setr_pd(-0.0, 0.0, -0.0, 0.0)
        };
        _mm256_xor_pd(swapped, sign)
    }

    /// The bins k = 1, 3, 5, … of [`super::split`] two at a time while k + 1 < m/2; returns the
    /// first bin left.
    ///
    /// # Panics
    /// If `y` holds m values or fewer, or `w` fewer than m.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn split_pairs(z: &[Complex64], y: &mut [Complex64], w: &[Complex64]) -> usize {
        let m = z.len();
        assert!(y.len() > m && w.len() >= m);
        let (zp, yp, wp) = (
            z.as_ptr().cast::<f64>(),
            y.as_mut_ptr().cast::<f64>(),
            w.as_ptr(),
        );
        let half = _mm256_set1_pd(0.5);
        let mut k = 1;
        while 2 * (k + 1) < m {
            // SAFETY: k + 1 < m − k − 1 < m, so every value read or written is in its slice.
            unsafe {
                let a = _mm256_loadu_pd(zp.add(2 * k));
                let b = conj(swap(_mm256_loadu_pd(zp.add(2 * (m - k - 1)))));
                let e = _mm256_mul_pd(_mm256_add_pd(a, b), half);
                let o = turn::<true>(_mm256_mul_pd(_mm256_sub_pd(a, b), half));
                let t = times::<false>(_mm256_loadu_pd(wp.add(k).cast()), o);
                _mm256_storeu_pd(yp.add(2 * k), _mm256_add_pd(e, t));
                _mm256_storeu_pd(yp.add(2 * (m - k - 1)), swap(conj(_mm256_sub_pd(e, t))));
            }
            k += 2;
        }
        k
    }

    /// The bins k = 1, 3, 5, … of [`super::merge`] two at a time while k + 1 < m/2; returns the
    /// first bin left.
    ///
    /// # Panics
    /// If `y` holds m values or fewer, or `w` fewer than m.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn merge_pairs(
        y: &[Complex64],
        z: &mut [Complex64],
        w: &[Complex64],
        s: f64,
    ) -> usize {
        let m = z.len();
        assert!(y.len() > m && w.len() >= m);
        let (yp, zp, wp) = (
            y.as_ptr().cast::<f64>(),
            z.as_mut_ptr().cast::<f64>(),
            w.as_ptr(),
        );
        let s = _mm256_set1_pd(s);
        let mut k = 1;
        while 2 * (k + 1) < m {
            // SAFETY: as in `split_pairs`.
            unsafe {
                let a = _mm256_loadu_pd(yp.add(2 * k));
                let b = conj(swap(_mm256_loadu_pd(yp.add(2 * (m - k - 1)))));
                let e = _mm256_mul_pd(_mm256_add_pd(a, b), s);
                let d = _mm256_mul_pd(_mm256_sub_pd(a, b), s);
                let io = turn::<false>(times::<true>(_mm256_loadu_pd(wp.add(k).cast()), d));
                _mm256_storeu_pd(zp.add(2 * k), _mm256_add_pd(e, io));
                _mm256_storeu_pd(zp.add(2 * (m - k - 1)), swap(conj(_mm256_sub_pd(e, io))));
            }
            k += 2;
        }
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic values in [−1, 1).
    fn values(len: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..len)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// Forward against the naive real DFT `X_k = Σ_j x_j e^{−2πijk/n}`, and inverse ∘ forward
    /// against `n s x`, on every even length to 40 and some longer ones, three rows each; to
    /// 1e-14 of Σ|x| (round-off of sums of n terms). Fails when a sign of the split, a twiddle
    /// or the merge's scale is changed.
    #[test]
    fn rows_match_the_naive_real_dft() {
        let mut planner = Planner::new();
        let lengths = (2..=40).step_by(2).chain([48, 64, 96, 100, 128, 192, 256]);
        for n in lengths {
            let Some(plan) = RealRows::new(&mut planner, n) else {
                return; // no AVX2 here: the transform takes realfft's route
            };
            let (m, rows) = (n / 2, 3);
            let x = values(rows * n, n as u64);
            let mut work = x.clone();
            let mut y = vec![Complex64::default(); rows * (m + 1)];
            let mut scratch = vec![Complex64::default(); plan.scratch_len()];
            plan.forward(&mut work, &mut y, &mut scratch);
            for r in 0..rows {
                let row = &x[r * n..][..n];
                let tol = 1e-14 * row.iter().map(|v| v.abs()).sum::<f64>();
                for k in 0..=m {
                    let naive: Complex64 = row
                        .iter()
                        .enumerate()
                        .map(|(j, &v)| {
                            let e = ((j * k) % n) as f64;
                            Complex64::from_polar(v, -2.0 * PI * e / n as f64)
                        })
                        .sum();
                    let got = y[r * (m + 1) + k];
                    assert!(
                        (got - naive).norm() < tol,
                        "n = {n}, row {r}, bin {k}: {got} against {naive}"
                    );
                }
            }
            let scale = 0.37;
            plan.inverse(&y, &mut work, scale, &mut scratch);
            for (i, (&back, &v)) in work.iter().zip(&x).enumerate() {
                let want = n as f64 * scale * v;
                assert!(
                    (back - want).abs() < 1e-13 * n as f64,
                    "n = {n}, value {i}: {back} against {want}"
                );
            }
        }
    }

    #[test]
    fn odd_lengths_have_no_plan() {
        let mut planner = Planner::new();
        for n in [1, 3, 15, 33] {
            assert!(RealRows::new(&mut planner, n).is_none(), "n = {n}");
        }
    }
}
