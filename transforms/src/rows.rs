//! The transform along the last (contiguous) axis, row by row, and the packing of rows into lanes.

use std::sync::Arc;

use num_complex::Complex64;
use vesicle_fft_plans::{ComplexToReal, RealToComplex};

use super::{has_avx, makhoul_position, Direction, LaneKernel, Work};
use crate::real_rows::RealRows;
use crate::wide_fn;

/// The transform along the last (contiguous) axis.
pub(super) enum LastAxis {
    /// Real-to-complex FFT of even rows through a half-length complex FFT (periodic axis).
    Halved(RealRows),
    /// Real-to-complex FFT by `realfft` (periodic axis of odd length, or no AVX2).
    Real {
        r2c: Arc<dyn RealToComplex<f64>>,
        c2r: Arc<dyn ComplexToReal<f64>>,
    },
    /// DCT-II (mirror axis), two real rows per complex lane; their spectra written `packed`
    /// (see the module documentation) or as complex values with zero imaginary parts.
    Mirror { kernel: LaneKernel, packed: bool },
}

impl LastAxis {
    /// Forward transform of the contiguous rows of length `n` in `x` into rows of `y` (`x` used
    /// as scratch).
    pub(super) fn forward_rows(
        &self,
        x: &mut [f64],
        y: &mut [Complex64],
        n: usize,
        work: &mut Work,
    ) {
        match self {
            LastAxis::Halved(rows) => rows.forward(x, y, &mut work.scratch),
            LastAxis::Real { r2c, .. } => {
                let scratch = &mut work.scratch[..r2c.get_scratch_len()];
                for (xr, yr) in x.chunks_exact_mut(n).zip(y.chunks_exact_mut(n / 2 + 1)) {
                    r2c.process_with_scratch(xr, yr, scratch)
                        .expect("lengths fixed by the plan");
                }
            }
            LastAxis::Mirror { kernel, packed } => {
                let rows = 2 * kernel.batch;
                let s = if *packed { n.div_ceil(2) } else { n };
                for (xg, yg) in x.chunks(rows * n).zip(y.chunks_mut(rows * s)) {
                    let lanes = &mut work.lanes[..(xg.len() / n).div_ceil(2) * n];
                    pack_real_rows(xg, lanes, n);
                    kernel.apply(Direction::Forward, lanes, &mut work.scratch);
                    if *packed {
                        unpack_to_packed_rows(lanes, yg, n);
                    } else {
                        unpack_to_complex_rows(lanes, yg, n);
                    }
                }
            }
        }
    }

    /// Inverse of [`LastAxis::forward_rows`] scaled by `scale`; `y` is used as scratch.
    pub(super) fn inverse_rows(
        &self,
        y: &mut [Complex64],
        x: &mut [f64],
        n: usize,
        scale: f64,
        work: &mut Work,
    ) {
        match self {
            LastAxis::Halved(rows) => rows.inverse(y, x, scale, &mut work.scratch),
            LastAxis::Real { c2r, .. } => {
                let scratch = &mut work.scratch[..c2r.get_scratch_len()];
                for (yr, xr) in y.chunks_exact_mut(n / 2 + 1).zip(x.chunks_exact_mut(n)) {
                    yr[0].im = 0.0;
                    if n.is_multiple_of(2) {
                        yr[n / 2].im = 0.0;
                    }
                    c2r.process_with_scratch(yr, xr, scratch)
                        .expect("lengths fixed by the plan, self-conjugate entries made real");
                    xr.iter_mut().for_each(|v| *v *= scale);
                }
            }
            LastAxis::Mirror { kernel, packed } => {
                let rows = 2 * kernel.batch;
                let s = if *packed { n.div_ceil(2) } else { n };
                for (yg, xg) in y.chunks(rows * s).zip(x.chunks_mut(rows * n)) {
                    let lanes = &mut work.lanes[..(xg.len() / n).div_ceil(2) * n];
                    if *packed {
                        pack_packed_rows(yg, lanes, n);
                    } else {
                        pack_complex_rows(yg, lanes, n);
                    }
                    kernel.apply(Direction::Inverse, lanes, &mut work.scratch);
                    unpack_to_real_rows(lanes, xg, n, scale);
                }
            }
        }
    }
}

/// Pack real rows `2l`, `2l+1` of `x` (rows of `n` values) into lane `l` as `x_{2l} + i x_{2l+1}`,
/// in Makhoul's order ([`makhoul_positions`]). With AVX, four data values of each row at a time
/// ([`avx::makhoul_pack`]: the same values, moved).
fn pack_real_rows(x: &[f64], lanes: &mut [Complex64], n: usize) {
    let wide = has_avx();
    for (lane, pair) in lanes.chunks_exact_mut(n).zip(x.chunks(2 * n)) {
        let (a, b) = pair.split_at(n);
        if b.is_empty() {
            for (i, &u) in a.iter().enumerate() {
                lane[makhoul_position(i, n)] = Complex64::new(u, 0.0);
            }
            continue;
        }
        let from = match wide {
            // SAFETY: the CPU has AVX; `a`, `b`, `lane` hold n values.
            #[cfg(target_arch = "x86_64")]
            true => unsafe { super::avx::makhoul_pack(a, b, lane) },
            _ => 0,
        };
        for i in from..n {
            lane[makhoul_position(i, n)] = Complex64::new(a[i], b[i]);
        }
    }
}

wide_fn! {
/// Unpack lanes of length `n` into complex rows of `y`: lane `l` gives row `2l` its real part
/// and row `2l+1` its imaginary part (stored as real values, imaginary parts zero).
fn unpack_to_complex_rows(lanes: &[Complex64], y: &mut [Complex64], n: usize) {
    for (lane, pair) in lanes.chunks_exact(n).zip(y.chunks_mut(2 * n)) {
        let (a, b) = pair.split_at_mut(n);
        a.iter_mut()
            .zip(lane)
            .for_each(|(u, z)| *u = Complex64::new(z.re, 0.0));
        b.iter_mut()
            .zip(lane)
            .for_each(|(v, z)| *v = Complex64::new(z.im, 0.0));
    }
}
}

wide_fn! {
/// Unpack lanes of length `n` into packed rows of `y` (`⌈n/2⌉` values each): lane `l` gives row
/// `2l` its real parts and row `2l+1` its imaginary parts, two consecutive values to a complex
/// value (the last imaginary part 0 for odd `n`). With AVX, two values of each row at a time
/// ([`avx::unpack_pairs`], the same values moved; the compiler's own loop took twice the
/// instructions, while its loop for [`pack_packed_rows`] was already as short as a written one).
pub(super) fn unpack_to_packed_rows(lanes: &[Complex64], y: &mut [Complex64], n: usize) {
    let s = n.div_ceil(2);
    let wide = has_avx();
    for (lane, rows) in lanes.chunks_exact(n).zip(y.chunks_mut(2 * s)) {
        let (a, b) = rows.split_at_mut(s);
        let (pairs, last) = lane.as_chunks::<2>();
        if b.is_empty() {
            for (a, [u, v]) in a.iter_mut().zip(pairs) {
                *a = Complex64::new(u.re, v.re);
            }
        } else {
            let from = match wide {
                // SAFETY: the CPU has AVX; `lane` holds n values, `a` and `b` ⌈n/2⌉.
                #[cfg(target_arch = "x86_64")]
                true => unsafe { super::avx::unpack_pairs(lane, a, b) },
                _ => 0,
            };
            let rows = a[from..].iter_mut().zip(b[from..].iter_mut());
            for ((a, b), [u, v]) in rows.zip(&pairs[from..]) {
                (*a, *b) = (Complex64::new(u.re, v.re), Complex64::new(u.im, v.im));
            }
        }
        if let [u] = last {
            a[s - 1] = Complex64::new(u.re, 0.0);
            if let Some(b) = b.last_mut() {
                *b = Complex64::new(u.im, 0.0);
            }
        }
    }
}
}

wide_fn! {
/// Inverse of [`unpack_to_packed_rows`]: packed rows `2l`, `2l+1` of `y` into lane `l` of
/// length `n` (the first row's reals as its real parts, the second's as its imaginary parts).
fn pack_packed_rows(y: &[Complex64], lanes: &mut [Complex64], n: usize) {
    let s = n.div_ceil(2);
    for (lane, rows) in lanes.chunks_exact_mut(n).zip(y.chunks(2 * s)) {
        let (a, b) = rows.split_at(s);
        let (pairs, last) = lane.as_chunks_mut::<2>();
        if b.is_empty() {
            for ([u, v], a) in pairs.iter_mut().zip(a) {
                (*u, *v) = (Complex64::new(a.re, 0.0), Complex64::new(a.im, 0.0));
            }
        } else {
            for ([u, v], (a, b)) in pairs.iter_mut().zip(a.iter().zip(b)) {
                (*u, *v) = (Complex64::new(a.re, b.re), Complex64::new(a.im, b.im));
            }
        }
        if let [u] = last {
            let q = b.last().map_or(0.0, |b| b.re);
            *u = Complex64::new(a[s - 1].re, q);
        }
    }
}
}

wide_fn! {
/// Pack the real parts of complex rows `2l`, `2l+1` of `y` (length `n`) into lane `l`.
fn pack_complex_rows(y: &[Complex64], lanes: &mut [Complex64], n: usize) {
    for (lane, pair) in lanes.chunks_exact_mut(n).zip(y.chunks(2 * n)) {
        let (a, b) = pair.split_at(n);
        if b.is_empty() {
            lane.iter_mut()
                .zip(a)
                .for_each(|(z, u)| *z = Complex64::new(u.re, 0.0));
        } else {
            for ((z, u), v) in lane.iter_mut().zip(a).zip(b) {
                *z = Complex64::new(u.re, v.re);
            }
        }
    }
}
}

/// Unpack lane `l` (Makhoul's order, [`makhoul_positions`]) into real rows `2l` (real part) and
/// `2l+1` (imaginary part) of `x` (rows of `n` values), times `scale`. With AVX, four data
/// values of each row at a time ([`avx::makhoul_unpack`]: the same products).
fn unpack_to_real_rows(lanes: &[Complex64], x: &mut [f64], n: usize, scale: f64) {
    let wide = has_avx();
    for (lane, pair) in lanes.chunks_exact(n).zip(x.chunks_mut(2 * n)) {
        let (a, b) = pair.split_at_mut(n);
        let from = match wide && !b.is_empty() {
            // SAFETY: the CPU has AVX; `a`, `b`, `lane` hold n values.
            #[cfg(target_arch = "x86_64")]
            true => unsafe { super::avx::makhoul_unpack(lane, a, b, scale) },
            _ => 0,
        };
        for i in from..n {
            let v = lane[makhoul_position(i, n)];
            a[i] = scale * v.re;
            if let Some(b) = b.get_mut(i) {
                *b = scale * v.im;
            }
        }
    }
}
