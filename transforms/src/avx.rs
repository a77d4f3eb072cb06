//! AVX versions of the packing and twiddle loops: the same operations as the scalar code, so the same values.
//!
//! Every function here but [`transpose_pairs`] is safe: it checks the lengths of its slices, and
//! needs only AVX, which its `#[target_feature]` makes its callers promise (a call from code
//! built without AVX is `unsafe`, after [`crate::cpu::has_avx`]).

use num_complex::Complex64;
use std::arch::x86_64::*;

/// [`super::rows::unpack_to_packed_rows`] on one lane of n values whose rows `a`, `b` both exist:
/// `a[p] = (u.re, v.re)`, `b[p] = (u.im, v.im)` for `(u, v)` = lane values 2p, 2p + 1, two
/// values of p at a time while 2p + 4 ≤ n; returns the first p not done.
///
/// # Panics
/// If `a` or `b` holds fewer than n/2 values.
#[target_feature(enable = "avx")]
pub fn unpack_pairs(lane: &[Complex64], a: &mut [Complex64], b: &mut [Complex64]) -> usize {
    let n = lane.len();
    assert!(a.len() >= n / 2 && b.len() >= n / 2);
    let (lp, ap, bp) = (
        lane.as_ptr().cast::<f64>(),
        a.as_mut_ptr().cast::<f64>(),
        b.as_mut_ptr().cast::<f64>(),
    );
    let mut p = 0;
    while 2 * p + 4 <= n {
        // SAFETY: lane values 2p … 2p + 3 and row values p, p + 1 are in their slices.
        unsafe {
            let (l0, l1) = (
                _mm256_loadu_pd(lp.add(4 * p)),
                _mm256_loadu_pd(lp.add(4 * p + 4)),
            );
            let (us, vs) = (
                _mm256_permute2f128_pd(l0, l1, 0x20),
                _mm256_permute2f128_pd(l0, l1, 0x31),
            );
            _mm256_storeu_pd(ap.add(2 * p), _mm256_unpacklo_pd(us, vs));
            _mm256_storeu_pd(bp.add(2 * p), _mm256_unpackhi_pd(us, vs));
        }
        p += 2;
    }
    p
}

/// Makhoul's packing of the real rows `a`, `b` (n values each) into `lane`: data values
/// 2p … 2p + 3 of both rows at a time, `lane[p], lane[p+1] = (a + ib)_{2p}, (a + ib)_{2p+2}`
/// and `lane[n−1−p], lane[n−2−p] = (a + ib)_{2p+1}, (a + ib)_{2p+3}`, while 2p + 4 ≤ n;
/// returns the first data index not done.
///
/// # Panics
/// If `b` or `lane` does not hold n values.
#[target_feature(enable = "avx")]
pub fn makhoul_pack(a: &[f64], b: &[f64], lane: &mut [Complex64]) -> usize {
    let n = a.len();
    assert!(b.len() == n && lane.len() == n);
    let (ap, bp, lp) = (a.as_ptr(), b.as_ptr(), lane.as_mut_ptr().cast::<f64>());
    let mut p = 0;
    while 2 * p + 4 <= n {
        // SAFETY: 2p + 3 < n, and lane positions p + 1 < n − 2 − p < n.
        unsafe {
            let (x, y) = (
                _mm256_loadu_pd(ap.add(2 * p)),
                _mm256_loadu_pd(bp.add(2 * p)),
            );
            _mm256_storeu_pd(lp.add(2 * p), _mm256_unpacklo_pd(x, y));
            let odd = _mm256_unpackhi_pd(x, y);
            let odd = _mm256_permute2f128_pd(odd, odd, 1);
            _mm256_storeu_pd(lp.add(2 * (n - 2 - p)), odd);
        }
        p += 2;
    }
    2 * p
}

/// The inverse of [`makhoul_pack`] times `scale`: data values 2p … 2p + 3 of `a` (real
/// parts) and `b` (imaginary parts) from lane positions p, n − 1 − p, p + 1, n − 2 − p,
/// while 2p + 4 ≤ n; returns the first data index not done.
///
/// # Panics
/// If `b` or `lane` does not hold n values.
#[target_feature(enable = "avx")]
pub fn makhoul_unpack(lane: &[Complex64], a: &mut [f64], b: &mut [f64], scale: f64) -> usize {
    let n = a.len();
    assert!(b.len() == n && lane.len() == n);
    let (lp, ap, bp) = (lane.as_ptr().cast::<f64>(), a.as_mut_ptr(), b.as_mut_ptr());
    let s = _mm256_set1_pd(scale);
    let mut p = 0;
    while 2 * p + 4 <= n {
        // SAFETY: as in `makhoul_pack`.
        unsafe {
            let low = _mm256_loadu_pd(lp.add(2 * p));
            let high = _mm256_loadu_pd(lp.add(2 * (n - 2 - p)));
            let high = _mm256_permute2f128_pd(high, high, 1);
            _mm256_storeu_pd(
                ap.add(2 * p),
                _mm256_mul_pd(s, _mm256_unpacklo_pd(low, high)),
            );
            _mm256_storeu_pd(
                bp.add(2 * p),
                _mm256_mul_pd(s, _mm256_unpackhi_pd(low, high)),
            );
        }
        p += 2;
    }
    2 * p
}

/// The DCT twiddle ([`super::dct::dct_post_pair`] when `POST`, else [`super::dct::dct_pre_pair`]) on
/// the pairs (k, m − k) of one lane of m values, two values of k at a time for k = 1, 2, …
/// while k + 1 ≤ (m − 1)/2; returns the first k not done. Each value is computed by the
/// scalar formula's operations in its order (no fused multiply-add), so the results are the
/// same bit for bit.
///
/// # Panics
/// If `w` has fewer than m values.
#[target_feature(enable = "avx")]
pub fn twiddle_pairs<const POST: bool>(lane: &mut [Complex64], w: &[Complex64]) -> usize {
    let m = lane.len();
    let pairs = m.saturating_sub(1) / 2;
    assert!(w.len() >= m);
    let (x, w) = (lane.as_mut_ptr() as *mut f64, w.as_ptr() as *const f64);
    // i z of two values: (re, im) → (−im, re).
    let sign = _mm256_setr_pd(-0.0, 0.0, -0.0, 0.0);
    let times_i = |z: __m256d| _mm256_xor_pd(_mm256_permute_pd(z, 0b0101), sign);
    let half = _mm256_set1_pd(0.5);
    let mut k = 1;
    while k < pairs {
        // SAFETY: 1 ≤ k < k + 1 < pairs ≤ (m − 1)/2, so the values k, k + 1 of `w` (m values or
        // more, asserted) and of the lane, and m − k − 1, m − k < m of the lane, are in their
        // slices.
        unsafe {
            // w_k, w_{k+1} = (c, −s): c = (c_k, c_k, c_{k+1}, c_{k+1}), s likewise.
            let wk = _mm256_loadu_pd(w.add(2 * k));
            let c = _mm256_movedup_pd(wk);
            let s = _mm256_xor_pd(_mm256_permute_pd(wk, 0b1111), _mm256_set1_pd(-0.0));
            let a = _mm256_loadu_pd(x.add(2 * k));
            // b_{k+1}, b_k at m − k − 1, m − k: swapped to b_k, b_{k+1}.
            let high = x.add(2 * (m - k - 1));
            let b = _mm256_permute2f128_pd(_mm256_loadu_pd(high), _mm256_loadu_pd(high), 0x01);
            let (low, up) = if POST {
                let (sum, diff) = (_mm256_add_pd(a, b), _mm256_sub_pd(a, b));
                let low = _mm256_sub_pd(_mm256_mul_pd(c, sum), times_i(_mm256_mul_pd(s, diff)));
                let up = _mm256_add_pd(_mm256_mul_pd(s, sum), times_i(_mm256_mul_pd(c, diff)));
                (_mm256_mul_pd(half, low), _mm256_mul_pd(half, up))
            } else {
                let p = _mm256_add_pd(_mm256_mul_pd(c, a), _mm256_mul_pd(s, b));
                let q = times_i(_mm256_sub_pd(_mm256_mul_pd(s, a), _mm256_mul_pd(c, b)));
                (_mm256_add_pd(p, q), _mm256_sub_pd(p, q))
            };
            _mm256_storeu_pd(x.add(2 * k), low);
            _mm256_storeu_pd(high, _mm256_permute2f128_pd(up, up, 0x01));
        }
        k += 2;
    }
    k
}

/// `dst[j · dst_stride + i] = src[i · src_stride + j]` for `i < n`, `j < m` (`(n, m)` =
/// `shape`): complex values transposed two rows and two columns at a time. With
/// `DST_ROWS_OUTER` the loops walk the destination's rows (its stores contiguous, the loads
/// strided), else the source's rows (loads contiguous, stores strided): a strided side should
/// be the small lane buffer, which stays in L1, not the spectrum, whose rows a stride apart
/// share a few cache sets.
///
/// # Safety
/// The CPU has AVX; `src` holds `n` rows of `m` values `src_stride` apart and `dst` `m` rows
/// of `n` values `dst_stride` apart; the two do not overlap.
#[target_feature(enable = "avx")]
pub unsafe fn transpose_pairs<const DST_ROWS_OUTER: bool>(
    src: *const Complex64,
    src_stride: usize,
    dst: *mut Complex64,
    dst_stride: usize,
    (n, m): (usize, usize),
) {
    let (src, dst) = (src as *const f64, dst as *mut f64);
    let at = |i: usize, j: usize, stride: usize| 2 * (i * stride + j);
    let (n2, m2) = (n - n % 2, m - m % 2);
    // Rows i, i + 1 and columns j, j + 1 of `src`.
    // SAFETY: `block` is called with i + 1 < n, j + 1 < m (and `one` below with i < n, j < m):
    // values inside `src` and `dst` by the caller's conditions.
    let block = |i: usize, j: usize| unsafe {
        let a = _mm256_loadu_pd(src.add(at(i, j, src_stride)));
        let b = _mm256_loadu_pd(src.add(at(i + 1, j, src_stride)));
        let (lo, hi) = (
            _mm256_permute2f128_pd(a, b, 0x20),
            _mm256_permute2f128_pd(a, b, 0x31),
        );
        _mm256_storeu_pd(dst.add(at(j, i, dst_stride)), lo);
        _mm256_storeu_pd(dst.add(at(j + 1, i, dst_stride)), hi);
    };
    if DST_ROWS_OUTER {
        for j in (0..m2).step_by(2) {
            for i in (0..n2).step_by(2) {
                block(i, j);
            }
        }
    } else {
        for i in (0..n2).step_by(2) {
            for j in (0..m2).step_by(2) {
                block(i, j);
            }
        }
    }
    // SAFETY: as for `block` above.
    let one = |i: usize, j: usize| unsafe {
        _mm_storeu_pd(
            dst.add(at(j, i, dst_stride)),
            _mm_loadu_pd(src.add(at(i, j, src_stride))),
        );
    };
    if m2 < m {
        (0..n2).for_each(|i| one(i, m2));
    }
    if n2 < n {
        (0..m).for_each(|j| one(n2, j));
    }
}
