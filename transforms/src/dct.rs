//! The DCT-II through a complex FFT (Makhoul): the even/odd reordering and the twiddles.

use std::f64::consts::PI;

use num_complex::Complex64;

use crate::cpu::has_avx;

/// Makhoul's reordering for the DCT through an FFT: data index `i` goes to lane position
/// `i/2` when even and `m − 1 − (i−1)/2` when odd.
pub(crate) fn makhoul_positions(m: usize) -> Vec<usize> {
    (0..m).map(|i| makhoul_position(i, m)).collect()
}

/// Lane position of data index `i` in a lane of `m` values ([`makhoul_positions`]).
#[inline(always)]
pub(super) fn makhoul_position(i: usize, m: usize) -> usize {
    if i.is_multiple_of(2) {
        i / 2
    } else {
        m - 1 - i / 2
    }
}

/// The DCT twiddles `w_k = e^{−iπk/(2m)}`, k = 0..m, of a lane of m values.
pub(crate) fn dct_twiddle_table(m: usize) -> Vec<Complex64> {
    (0..m)
        .map(|k| Complex64::from_polar(1.0, -PI * k as f64 / (2 * m) as f64))
        .collect()
}

/// From `V = FFT(v)` of the reordered lane to the DCT-II: with `w_k = e^{−iπk/(2m)} =
/// c_k − i s_k` (so `w_{m−k} = −i w̄_k`), `a = V_k`, `b = V_{m−k}`,
///
/// ```text
/// X_k     = (w_k a + w̄_k b)/2         = (c_k (a + b) − i s_k (a − b))/2,
/// X_{m−k} = (w_{m−k} b + w̄_{m−k} a)/2 = (s_k (a + b) + i c_k (a − b))/2,
/// ```
///
/// and `X_0 = V_0`. The map is C-linear, so it holds for complex lanes (the DCT of the real and
/// imaginary parts).
#[inline(always)]
pub(super) fn dct_post_pair(w: Complex64, a: Complex64, b: Complex64) -> (Complex64, Complex64) {
    let (c, s) = (w.re, -w.im);
    let (sum, diff) = (a + b, a - b);
    (
        0.5 * (c * sum - times_i(s * diff)),
        0.5 * (s * sum + times_i(c * diff)),
    )
}

/// Inverse of [`dct_post_pair`] up to the FFT normalisation: with `a = X_k`, `b = X_{m−k}`,
///
/// ```text
/// V_k     = w̄_k (a − i b)         = P + iQ,
/// V_{m−k} = w̄_{m−k} (b − i a)     = P − iQ,     P = c_k a + s_k b,  Q = s_k a − c_k b,
/// ```
///
/// and `V_0 = X_0`.
#[inline(always)]
pub(super) fn dct_pre_pair(w: Complex64, a: Complex64, b: Complex64) -> (Complex64, Complex64) {
    let (c, s) = (w.re, -w.im);
    let (p, q) = (c * a + s * b, s * a - c * b);
    (p + times_i(q), p - times_i(q))
}

/// A DCT twiddle in place on one lane of m values: `pair` on (k, m − k) for k = `from`..=(m−1)/2,
/// then, for even m, on the middle value k = m/2 paired with itself (its second output: the
/// value at m − k, written last).
#[inline(always)]
pub(super) fn twiddle_lane(
    lane: &mut [Complex64],
    w: &[Complex64],
    from: usize,
    pair: impl Fn(Complex64, Complex64, Complex64) -> (Complex64, Complex64),
) {
    let m = lane.len();
    for k in from..=m.saturating_sub(1) / 2 {
        (lane[k], lane[m - k]) = pair(w[k], lane[k], lane[m - k]);
    }
    if m > 0 && m.is_multiple_of(2) {
        let v = lane[m / 2];
        lane[m / 2] = pair(w[m / 2], v, v).1;
    }
}

/// The DCT twiddle on every lane of `lanes` (`len` values each, `stride` apart): [`dct_post_pair`]
/// after the forward FFT (`POST`), [`dct_pre_pair`] before the inverse. With AVX the pairs go
/// two at a time ([`avx::twiddle_pairs`]: the same operations, so the same values).
pub(super) fn dct_twiddles<const POST: bool>(
    lanes: &mut [Complex64],
    stride: usize,
    len: usize,
    w: &[Complex64],
) {
    let pair = if POST { dct_post_pair } else { dct_pre_pair };
    let wide = has_avx();
    for lane in lanes.chunks_exact_mut(stride) {
        let lane = &mut lane[..len];
        let from = match wide {
            // SAFETY: the CPU has AVX; `w` holds a twiddle for every position of the lane.
            #[cfg(target_arch = "x86_64")]
            true => unsafe { super::avx::twiddle_pairs::<POST>(lane, w) },
            _ => 1,
        };
        twiddle_lane(lane, w, from, pair);
    }
}

/// i z.
#[inline(always)]
pub(super) fn times_i(z: Complex64) -> Complex64 {
    Complex64::new(-z.im, z.re)
}
