//! Planned three-dimensional real transforms: FFT on periodic axes, DCT-II on mirror axes.
//!
//! A real field `x` of shape `[n0, n1, n2]` maps to a spectrum `X` indexed by `[j0, j1, j2]`
//! over [`Transform::index_shape`]. Every axis contributes one factor of the separable kernel
//!
//! * periodic axis of length `n`: `e^{−2πi j i / n}` (DFT); on the last axis the real-to-complex
//!   half spectrum `j = 0..=n/2` is kept;
//! * mirror axis of length `m`: `cos(π j (2i+1) / (2m))` (unnormalised DCT-II), which is the DFT
//!   of the half-sample-even extension of the data to `2m` points.
//!
//! The inverse is the exact inverse of the forward map (`1/n` per periodic axis, the DCT-III
//! scaled by `1/m`, i.e. `x_i = (X_0 + 2 Σ_{j≥1} X_j cos(π j (2i+1)/(2m))) / m`, per mirror axis).
//!
//! **Storage.** The spectrum is held as complex values of shape [`Transform::spectral_shape`]:
//! the index layout itself, except when every axis longer than 1 is a mirror axis. Then the
//! spectrum is real, and it is *packed*: two consecutive reals of a row in one complex value,
//! `Y[j0, j1, p] = X[j0, j1, 2p] + i X[j0, j1, 2p+1]` (the last imaginary part 0 when `n2` is
//! odd), so that no sweep moves zeros. Every other operator of the program is a real, even
//! function of k, which acts on a packed spectrum real by real ([`crate::engines::spectral::pieces`]).
//!
//! Implementation: the last (contiguous) axis is transformed row by row, periodic through a
//! complex FFT of half its length ([`super::real_rows`]; `realfft` when the length is odd) or,
//! for a mirror axis, two real lanes at a time packed as one complex lane. The other axes are
//! transformed down the columns in place ([`super::columns`]) when their length is a product of
//! 2s, 3s and 5s, and otherwise gathered a block of columns at a time into contiguous lanes,
//! transformed with one batched `rustfft` call and scattered back. A DCT-II of length `m` is
//! computed with one complex FFT of length `m` (Makhoul's even/odd reordering plus a twiddle); it
//! is C-linear, so a complex lane holding two real lanes (or the real and imaginary parts of one
//! complex lane) costs one FFT: a packed spectrum's columns are such lanes as they stand.
//! All buffers live in the struct: a transform call allocates nothing.

use std::f64::consts::PI;
use std::fmt;
use std::sync::Arc;

use ndarray::{s, Array3, ArrayView2, ArrayView3, ArrayViewMut2, ArrayViewMut3, Axis};
use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

use super::columns::ColumnFft;
use super::kernels::wide_fn;
use super::real_rows::RealRows;
use crate::cpu::has_avx;
use crate::engines::private::Private;
use crate::problem::grid::AxisKind;

/// Complex values in one batch of gathered lanes (32 KiB: stays in L1 with the FFT scratch).
const LANE_BUFFER: usize = 2048;
/// Fewest lanes per batch (four complex values fill one 64-byte cache line of a row).
const MIN_BATCH: usize = 4;
/// Column split between threads is rounded to this many columns (whole cache lines).
const COLUMN_ALIGN: usize = 8;
/// Padding between the gathered lanes of a strided stage (one cache line): lanes of a power of
/// two values would start a multiple of 1 KiB apart, so a gather's stores to 32 lanes would all
/// fall in four of the 64 sets of the L1 cache.
const LANE_PAD: usize = 4;

/// Direction of a transform stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Direction {
    Forward,
    Inverse,
}

/// A batched 1D kernel along one axis: a complex FFT (periodic) or a DCT-II/DCT-III computed with
/// a complex FFT of the same length (mirror). Both act on lanes of `len` contiguous values.
struct LaneKernel {
    len: usize,
    /// Values from one lane's start to the next (`len`, or `len + LANE_PAD` in a strided stage).
    stride: usize,
    /// Lanes per batch.
    batch: usize,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    scratch_len: usize,
    /// Lane position of data index `i`: `i` for the FFT; for the DCT the Makhoul order
    /// `v_p = x_{2p}`, `v_{m−1−p} = x_{2p+1}`.
    pos: Vec<usize>,
    /// Lane position of spectral index `j`: always `j`.
    identity: Vec<usize>,
    /// DCT twiddles `w_k = e^{−iπk/(2m)}`; empty for the FFT.
    twiddle: Vec<Complex64>,
}

impl LaneKernel {
    /// The kernel of an axis of `len` points; `padded` lanes are [`LANE_PAD`] values apart.
    fn new(planner: &mut FftPlanner<f64>, len: usize, kind: AxisKind, padded: bool) -> Self {
        let stride = if padded { len + LANE_PAD } else { len };
        let forward = planner.plan_fft_forward(len);
        let inverse = planner.plan_fft_inverse(len);
        let scratch_len = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        let (pos, twiddle) = match kind {
            AxisKind::Periodic => ((0..len).collect(), Vec::new()),
            AxisKind::Mirror => (makhoul_positions(len), dct_twiddle_table(len)),
        };
        LaneKernel {
            len,
            stride,
            batch: (LANE_BUFFER / stride).max(MIN_BATCH),
            forward,
            inverse,
            scratch_len,
            pos,
            identity: (0..len).collect(),
            twiddle,
        }
    }

    /// Lane positions of the rows to gather and of the rows to scatter for direction `dir`:
    /// data order on the real-space side, identity on the spectral side.
    fn orders(&self, dir: Direction) -> (&[usize], &[usize]) {
        match dir {
            Direction::Forward => (&self.pos, &self.identity),
            Direction::Inverse => (&self.identity, &self.pos),
        }
    }

    /// Transform every lane of `lanes` (a whole number of lanes, `stride` apart) in place.
    fn apply(&self, dir: Direction, lanes: &mut [Complex64], scratch: &mut [Complex64]) {
        let scratch = &mut scratch[..self.scratch_len];
        let fft = match dir {
            Direction::Forward => &self.forward,
            Direction::Inverse => &self.inverse,
        };
        let mirror = !self.twiddle.is_empty();
        if mirror && dir == Direction::Inverse {
            dct_twiddles::<false>(lanes, self.stride, self.len, &self.twiddle);
        }
        if self.stride == self.len {
            fft.process_with_scratch(lanes, scratch);
        } else {
            for lane in lanes.chunks_exact_mut(self.stride) {
                fft.process_with_scratch(&mut lane[..self.len], scratch);
            }
        }
        if mirror && dir == Direction::Forward {
            dct_twiddles::<true>(lanes, self.stride, self.len, &self.twiddle);
        }
    }
}

/// Makhoul's reordering for the DCT through an FFT: data index `i` goes to lane position
/// `i/2` when even and `m − 1 − (i−1)/2` when odd.
pub(super) fn makhoul_positions(m: usize) -> Vec<usize> {
    (0..m).map(|i| makhoul_position(i, m)).collect()
}

/// Lane position of data index `i` in a lane of `m` values ([`makhoul_positions`]).
#[inline(always)]
fn makhoul_position(i: usize, m: usize) -> usize {
    if i.is_multiple_of(2) {
        i / 2
    } else {
        m - 1 - i / 2
    }
}

/// The DCT twiddles `w_k = e^{−iπk/(2m)}`, k = 0..m, of a lane of m values.
pub(super) fn dct_twiddle_table(m: usize) -> Vec<Complex64> {
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
fn dct_post_pair(w: Complex64, a: Complex64, b: Complex64) -> (Complex64, Complex64) {
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
fn dct_pre_pair(w: Complex64, a: Complex64, b: Complex64) -> (Complex64, Complex64) {
    let (c, s) = (w.re, -w.im);
    let (p, q) = (c * a + s * b, s * a - c * b);
    (p + times_i(q), p - times_i(q))
}

/// A DCT twiddle in place on one lane of m values: `pair` on (k, m − k) for k = `from`..=(m−1)/2,
/// then, for even m, on the middle value k = m/2 paired with itself (its second output: the
/// value at m − k, written last).
#[inline(always)]
fn twiddle_lane(
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
fn dct_twiddles<const POST: bool>(
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
            true => unsafe { avx::twiddle_pairs::<POST>(lane, w) },
            _ => 1,
        };
        twiddle_lane(lane, w, from, pair);
    }
}

/// i z.
#[inline(always)]
fn times_i(z: Complex64) -> Complex64 {
    Complex64::new(-z.im, z.re)
}

/// The transform along the last (contiguous) axis.
enum LastAxis {
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

/// How a strided axis (0 or 1) is transformed.
enum Strided {
    /// Down the columns in place: an axis whose length [`ColumnFft::new`] plans (periodic: an
    /// FFT; mirror: a DCT, [`ColumnFft::new_dct`]).
    Columns(ColumnFft),
    /// Gathered into lanes, transformed by a batched kernel and scattered back.
    Lanes(LaneKernel),
}

impl Strided {
    /// The transform of axis `a` of `shape` with walls `kinds`.
    fn new(
        planner: &mut FftPlanner<f64>,
        a: usize,
        shape: [usize; 3],
        kinds: [AxisKind; 3],
    ) -> Self {
        let n = shape[a];
        let columns = match kinds[a] {
            AxisKind::Periodic => ColumnFft::new(n),
            AxisKind::Mirror => ColumnFft::new_dct(n),
        };
        match columns {
            Some(columns) => Strided::Columns(columns),
            None => Strided::Lanes(LaneKernel::new(planner, n, kinds[a], true)),
        }
    }
}

/// Scratch owned by one parallel chunk.
struct Work {
    lanes: Private<Complex64>,
    scratch: Private<Complex64>,
}

/// Everything fixed at planning time (shared read-only by the parallel chunks).
struct Plan {
    shape: [usize; 3],
    kinds: [AxisKind; 3],
    spectral: [usize; 3],
    last: LastAxis,
    /// Kernels of axes 0 and 1; `None` for an axis of length 1 (identity).
    strided: [Option<Strided>; 2],
    /// Whether the spectrum is real and packed (see the module documentation).
    packed: bool,
}

/// A planned 3D real transform (FFT on periodic axes, DCT-II on mirror axes) with all scratch
/// preallocated; see the module documentation for the conventions.
pub struct Transform {
    plan: Plan,
    works: Vec<Work>,
    /// Two real slabs per thread: the fields of [`Transform::round_trip`] that never reach a
    /// full array.
    slab_fields: Vec<Private<f64>>,
}

impl fmt::Debug for Transform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Transform")
            .field("shape", &self.plan.shape)
            .field("kinds", &self.plan.kinds)
            .field("threads", &self.works.len())
            .finish()
    }
}

impl Transform {
    /// Plan the transform of real fields of shape `shape` with boundary kinds `kinds`, with
    /// scratch for `threads` parallel chunks run on rayon's current pool (`threads <= 1`: serial,
    /// no rayon). Planning picks the fastest FFT kernels of this CPU (AVX when present).
    ///
    /// # Panics
    /// If an axis has length 0.
    pub fn new(shape: [usize; 3], kinds: [AxisKind; 3], threads: usize) -> Self {
        assert!(shape.iter().all(|&n| n > 0), "axes must not be empty");
        let mut planner = FftPlanner::new();
        let packed = kinds[2] == AxisKind::Mirror
            && (0..2).all(|a| shape[a] == 1 || kinds[a] == AxisKind::Mirror);
        let last = match kinds[2] {
            AxisKind::Periodic => match RealRows::new(&mut planner, shape[2]) {
                Some(rows) => LastAxis::Halved(rows),
                None => {
                    let mut real = RealFftPlanner::new();
                    LastAxis::Real {
                        r2c: real.plan_fft_forward(shape[2]),
                        c2r: real.plan_fft_inverse(shape[2]),
                    }
                }
            },
            AxisKind::Mirror => LastAxis::Mirror {
                kernel: LaneKernel::new(&mut planner, shape[2], AxisKind::Mirror, false),
                packed,
            },
        };
        let strided =
            [0, 1].map(|a| (shape[a] > 1).then(|| Strided::new(&mut planner, a, shape, kinds)));
        let mut spectral = shape;
        if kinds[2] == AxisKind::Periodic {
            spectral[2] = shape[2] / 2 + 1;
        } else if packed {
            spectral[2] = shape[2].div_ceil(2);
        }
        let plan = Plan {
            shape,
            kinds,
            spectral,
            last,
            strided,
            packed,
        };
        let works = (0..threads.max(1)).map(|_| plan.new_work()).collect();
        let slab = shape[1] * shape[2];
        let slab_fields = (0..threads.max(1))
            .map(|_| Private::new(2 * slab, 0.0))
            .collect();
        Transform {
            plan,
            works,
            slab_fields,
        }
    }

    /// Shape `[s0, s1, s2]` of the spectrum as stored: `s_a = n_a`, except `s2 = n2/2 + 1` when
    /// axis 2 is periodic (real-to-complex half spectrum) and `s2 = ⌈n2/2⌉` when the spectrum is
    /// [packed](Transform::packed).
    pub fn spectral_shape(&self) -> [usize; 3] {
        self.plan.spectral
    }

    /// Shape of the spectral index range `[j0, j1, j2]`: the stored shape, or `[n0, n1, n2]`
    /// for a packed spectrum.
    pub fn index_shape(&self) -> [usize; 3] {
        if self.plan.packed {
            self.plan.shape
        } else {
            self.plan.spectral
        }
    }

    /// Whether the spectrum is real and stored packed, two consecutive reals of a row in one
    /// complex value (every axis longer than 1 a mirror axis; see the module documentation).
    pub fn packed(&self) -> bool {
        self.plan.packed
    }

    /// A stored spectrum in the index layout ([`Transform::index_shape`]; a packed one's reals
    /// as complex values with zero imaginary parts).
    ///
    /// # Panics
    /// If `y` does not have the spectral shape.
    pub fn unpacked(&self, y: ArrayView3<Complex64>) -> Array3<Complex64> {
        assert_eq!(y.shape(), self.plan.spectral, "spectrum shape");
        if !self.plan.packed {
            return y.to_owned();
        }
        Array3::from_shape_fn(self.plan.shape, |(i, j, k)| {
            let v = y[(i, j, k / 2)];
            Complex64::new(if k % 2 == 0 { v.re } else { v.im }, 0.0)
        })
    }

    /// Inverse of [`Transform::unpacked`]: a spectrum in the index layout stored as this
    /// transform stores it (a packed spectrum keeps only the real parts).
    ///
    /// # Panics
    /// If `x` does not have the index shape or is not in standard layout.
    pub fn packed_from(&self, x: ArrayView3<Complex64>) -> Array3<Complex64> {
        assert_eq!(x.shape(), self.index_shape(), "spectrum shape");
        let x = x.as_slice().expect("standard layout");
        let packed = self.packed_reals::<f64>(bytemuck::cast_slice(x));
        let values = bytemuck::cast_slice(&packed).to_vec();
        Array3::from_shape_vec(self.plan.spectral, values).expect("the spectral shape")
    }

    /// [`Transform::packed_from`] on a spectrum given as interleaved (re, im) reals.
    ///
    /// # Panics
    /// If `reals` does not hold a spectrum of the index shape.
    pub fn packed_reals<T: Copy + Default>(&self, reals: &[T]) -> Vec<T> {
        let index = self.index_shape();
        assert_eq!(
            reals.len(),
            2 * index.iter().product::<usize>(),
            "spectrum length"
        );
        if !self.plan.packed {
            return reals.to_vec();
        }
        let (n2, s2) = (index[2], self.plan.spectral[2]);
        let mut out = vec![T::default(); 2 * s2 * index[0] * index[1]];
        for (row, packed) in reals.chunks_exact(2 * n2).zip(out.chunks_exact_mut(2 * s2)) {
            packed
                .iter_mut()
                .zip(row.iter().step_by(2))
                .for_each(|(p, &r)| *p = r);
        }
        out
    }

    /// Real-space shape `[n0, n1, n2]` this transform was planned for.
    pub fn shape(&self) -> [usize; 3] {
        self.plan.shape
    }

    /// Forward transform `X_j = Σ_i x_i Π_a K_a(j_a, i_a)` with `K = e^{−2πi j i/n}` on periodic
    /// axes and `K = cos(π j (2i+1)/(2m))` on mirror axes. When every axis longer than 1 is a
    /// mirror axis the spectrum is real, and written [packed](Transform::packed).
    ///
    /// `input` is used as scratch, as in [`Transform::inverse`]: its contents are garbage
    /// afterwards (the real-to-complex stage transforms each row in place instead of a copy).
    ///
    /// # Panics
    /// If the shapes differ from the plan or an array is not in standard layout.
    pub fn forward(&mut self, input: &mut Array3<f64>, out: &mut Array3<Complex64>) {
        let Transform { plan, works, .. } = self;
        assert_eq!(input.shape(), plan.shape, "input shape");
        assert_eq!(out.shape(), plan.spectral, "spectrum shape");
        let x = input.as_slice_mut().expect("input in standard layout");
        let y = out.as_slice_mut().expect("spectrum in standard layout");
        let [n0, n1, n2] = plan.shape;
        let s2 = plan.spectral[2];
        let threads = works.len();
        if threads == 1 {
            plan.forward_slabs(x, y, &mut works[0]);
        } else if n0 >= threads {
            let slabs = n0.div_ceil(threads);
            x.par_chunks_mut(slabs * n1 * n2)
                .zip(y.par_chunks_mut(slabs * n1 * s2))
                .zip(works.par_iter_mut())
                .for_each(|((x, y), work)| plan.forward_slabs(x, y, work));
        } else {
            let rows = (n0 * n1).div_ceil(threads);
            x.par_chunks_mut(rows * n2)
                .zip(y.par_chunks_mut(rows * s2))
                .zip(works.par_iter_mut())
                .for_each(|((x, y), work)| plan.last.forward_rows(x, y, n2, work));
            plan.strided_pass(1, Direction::Forward, y, works);
        }
        plan.strided_pass(0, Direction::Forward, y, works);
        plan.clear_padding(y);
    }

    /// Inverse transform: the exact inverse of [`Transform::forward`] (normalised by
    /// `1/(n0 n1 n2)`), returning the real part. Before the real-to-complex inverse the
    /// imaginary parts of the self-conjugate columns (`j2 = 0`, and `j2 = n2/2` for even `n2`)
    /// are zeroed; on a mirror last axis only real parts are used (of a packed spectrum, both).
    ///
    /// `input` is used as scratch: its contents are garbage afterwards.
    ///
    /// # Panics
    /// If the shapes differ from the plan or an array is not in standard layout.
    pub fn inverse(&mut self, input: &mut Array3<Complex64>, out: &mut Array3<f64>) {
        let Transform { plan, works, .. } = self;
        assert_eq!(input.shape(), plan.spectral, "spectrum shape");
        assert_eq!(out.shape(), plan.shape, "output shape");
        let y = input.as_slice_mut().expect("spectrum in standard layout");
        let x = out.as_slice_mut().expect("output in standard layout");
        let [n0, n1, n2] = plan.shape;
        let s2 = plan.spectral[2];
        let scale = 1.0 / (n0 * n1 * n2) as f64;
        let threads = works.len();
        plan.strided_pass(0, Direction::Inverse, y, works);
        if threads == 1 {
            plan.inverse_slabs(y, x, scale, &mut works[0]);
        } else if n0 >= threads {
            let slabs = n0.div_ceil(threads);
            y.par_chunks_mut(slabs * n1 * s2)
                .zip(x.par_chunks_mut(slabs * n1 * n2))
                .zip(works.par_iter_mut())
                .for_each(|((y, x), work)| plan.inverse_slabs(y, x, scale, work));
        } else {
            plan.strided_pass(1, Direction::Inverse, y, works);
            let rows = (n0 * n1).div_ceil(threads);
            y.par_chunks_mut(rows * s2)
                .zip(x.par_chunks_mut(rows * n2))
                .zip(works.par_iter_mut())
                .for_each(|((y, x), work)| plan.last.inverse_rows(y, x, n2, scale, work));
        }
    }

    /// A round trip through real space, slab by slab: the inverse transforms of `a` into `real`
    /// and of `b` into a slab of scratch, then per slab of axis 0 `visit(first, x_a, x_b, y)`
    /// (`first` the slab's first index in `real`, `x_a` its slab of `real`, `x_b` and `y` two
    /// slabs of scratch), which leaves in `y` and `x_b` the fields whose forward transforms
    /// replace `a` and `b`. The same as [`Transform::inverse`] twice, `visit` over the box and
    /// [`Transform::forward`] twice, but each slab's fields stay in cache from the inverse
    /// transforms to the forward ones, and the two scratch fields never reach memory. Returns
    /// the slabs' values summed by `add` from `S::default()` (in slab order within a thread,
    /// then over the threads), or `None`, having done nothing, when the box has fewer slabs
    /// than threads.
    ///
    /// # Panics
    /// If the shapes are not those of the plan.
    pub fn round_trip<S: Send + Default>(
        &mut self,
        [a, b]: [&mut Array3<Complex64>; 2],
        real: &mut Array3<f64>,
        visit: impl Fn(usize, &[f64], &mut [f64], &mut [f64]) -> S + Sync,
        add: impl Fn(S, S) -> S + Sync,
    ) -> Option<S> {
        let Transform {
            plan,
            works,
            slab_fields,
        } = self;
        let [n0, n1, n2] = plan.shape;
        let threads = works.len();
        if n0 < threads {
            return None;
        }
        for y in [&*a, &*b] {
            assert_eq!(y.shape(), plan.spectral, "spectrum shape");
        }
        assert_eq!(real.shape(), plan.shape, "real shape");
        let (ya, yb) = (
            a.as_slice_mut().expect("layout"),
            b.as_slice_mut().expect("layout"),
        );
        let x = real.as_slice_mut().expect("real field in standard layout");
        plan.strided_pass(0, Direction::Inverse, ya, works);
        plan.strided_pass(0, Direction::Inverse, yb, works);
        let (slab, spectral_slab) = (n1 * n2, n1 * plan.spectral[2]);
        let scale = 1.0 / (n0 * slab) as f64;
        // The slabs from `first_slab` of one thread: `ya`, `yb`, `x` hold just those slabs.
        let slabs = |first_slab: usize,
                     (ya, yb, x): (&mut [Complex64], &mut [Complex64], &mut [f64]),
                     work: &mut Work,
                     fields: &mut [f64]|
         -> S {
            let (xb, y) = fields.split_at_mut(slab);
            let ya = ya.chunks_exact_mut(spectral_slab);
            let yb = yb.chunks_exact_mut(spectral_slab);
            let mut total = S::default();
            for (i, ((ya, yb), x)) in ya.zip(yb).zip(x.chunks_exact_mut(slab)).enumerate() {
                plan.inverse_slabs(ya, x, scale, work);
                plan.inverse_slabs(yb, xb, scale, work);
                total = add(total, visit((first_slab + i) * slab, x, xb, y));
                plan.forward_slabs(y, ya, work);
                plan.forward_slabs(xb, yb, work);
            }
            total
        };
        let total = if threads == 1 {
            slabs(0, (ya, yb, x), &mut works[0], &mut slab_fields[0])
        } else {
            let per = n0.div_ceil(threads);
            ya.par_chunks_mut(per * spectral_slab)
                .zip(yb.par_chunks_mut(per * spectral_slab))
                .zip(x.par_chunks_mut(per * slab))
                .zip(works.par_iter_mut().zip(slab_fields.par_iter_mut()))
                .enumerate()
                .map(|(t, (((ya, yb), x), (work, fields)))| {
                    slabs(t * per, (ya, yb, x), work, fields)
                })
                .reduce(S::default, &add)
        };
        plan.strided_pass(0, Direction::Forward, ya, works);
        plan.strided_pass(0, Direction::Forward, yb, works);
        plan.clear_padding(ya);
        plan.clear_padding(yb);
        Some(total)
    }

    /// Signed wavenumber of every spectral index ([`Transform::index_shape`]), per axis, for
    /// grid spacing `h`:
    /// periodic `k_j = 2π m_j/(n h)` with `m_j = j` for `j <= n/2` and `j − n` otherwise
    /// (`m_j = j` on a real-to-complex last axis); mirror `k_j = π j/(m h)`.
    pub fn wavenumbers(&self, h: f64) -> [Vec<f64>; 3] {
        let range = self.index_shape();
        [0, 1, 2].map(|a| {
            let n = self.plan.shape[a];
            (0..range[a])
                .map(|j| match self.plan.kinds[a] {
                    AxisKind::Mirror => PI * j as f64 / (n as f64 * h),
                    AxisKind::Periodic => {
                        let m = if j <= n / 2 {
                            j as f64
                        } else {
                            j as f64 - n as f64
                        };
                        2.0 * PI * m / (n as f64 * h)
                    }
                })
                .collect()
        })
    }

    /// Per-axis weights over the spectral indices ([`Transform::index_shape`]) with
    /// `Σ_x u v = Σ_k w0[k0] w1[k1] w2[k2] Re(U_k conj V_k)` for real
    /// fields `u, v` (in particular `Σ_x x² = Σ_k w |X_k|²`): `1/n` on a complex periodic axis;
    /// on a real-to-complex last axis `1/n` for `j = 0` and for `j = n/2` when `n` is even, `2/n`
    /// otherwise; on a mirror axis `1/m` for `j = 0` and `2/m` otherwise.
    pub fn parseval_weights(&self) -> [Vec<f64>; 3] {
        let range = self.index_shape();
        [0, 1, 2].map(|a| {
            let n = self.plan.shape[a];
            let inv = 1.0 / n as f64;
            (0..range[a])
                .map(|j| {
                    let doubled = match self.plan.kinds[a] {
                        AxisKind::Mirror => j > 0,
                        AxisKind::Periodic => a == 2 && j > 0 && 2 * j != n,
                    };
                    if doubled {
                        2.0 * inv
                    } else {
                        inv
                    }
                })
                .collect()
        })
    }

    /// Project a spectrum onto the spectra of real fields, whose coefficients satisfy
    /// `X(−k0, −k1, j2) = conj X(k0, k1, j2)` (`−k` taken mod `n` on periodic axes, `−k = k` on
    /// mirror axes, where the cosine coefficients are real):
    /// `X ← (X + conj X(−k0,−k1)) / 2` on every self-conjugate plane `j2`.
    ///
    /// * Periodic last axis (real-to-complex half spectrum): the planes `j2 = 0` and `j2 = n2/2`
    ///   (even `n2`) are self-conjugate; the other planes hold independent coefficients.
    /// * Mirror last axis: every plane is self-conjugate (the DCT along axis 2 is real).
    /// * A packed spectrum holds reals only: only an odd row's padding (the imaginary part of
    ///   its last value) is set to 0.
    ///
    /// The inverse transform drops the part this removes, so a spectrum carried from step to step
    /// must be projected, or the dropped part grows unseen where the explicit tension term is
    /// anti-diffusive (DESIGN.md §3).
    ///
    /// # Panics
    /// If `a` does not have the spectral shape.
    pub fn hermitian_symmetrize(&self, a: &mut Array3<Complex64>) {
        assert_eq!(a.shape(), self.plan.spectral, "spectrum shape");
        if self.plan.packed {
            self.plan
                .clear_padding(a.as_slice_mut().expect("standard layout"));
            return;
        }
        if self.plan.kinds[2] == AxisKind::Mirror {
            self.symmetrize_lanes(a);
            return;
        }
        let [n0, n1, s2] = self.plan.spectral;
        let n2 = self.plan.shape[2];
        let planes = [Some(0), n2.is_multiple_of(2).then_some(n2 / 2)];
        let planes = planes.iter().flatten();
        let slab = n1 * s2;
        // The mean of value `i1` of slab `lo` and value −i1 of slab `hi` (the slab of −i0) on
        // each self-conjugate plane: `lo`'s takes the mean, `hi`'s its conjugate.
        let pair = |lo: &mut [Complex64], hi: &mut [Complex64]| {
            for i1 in 0..n1 {
                let q1 = self.negated(i1, 1);
                for &j2 in planes.clone() {
                    conjugate_mean(&mut lo[i1 * s2 + j2], &mut hi[q1 * s2 + j2]);
                }
            }
        };
        // A slab that is its own partner (−i0 = i0): pairs within it, each once, and the
        // self-conjugate values made real.
        let own = |s: &mut [Complex64]| {
            for i1 in 0..n1 {
                let q1 = self.negated(i1, 1);
                for &j2 in planes.clone() {
                    let (p, q) = (i1 * s2 + j2, q1 * s2 + j2);
                    if q == p {
                        s[p].im = 0.0;
                    } else if q > p {
                        let (low, high) = s.split_at_mut(q);
                        conjugate_mean(&mut low[p], &mut high[0]);
                    }
                }
            }
        };
        let data = a.as_slice_mut().expect("standard layout");
        if self.plan.kinds[0] == AxisKind::Mirror {
            data.par_chunks_mut(slab).for_each(own);
            return;
        }
        // Slab i0 pairs with n0 − i0: slabs 1..=half with n0 − 1 down to n0 − half, in
        // parallel; slab 0, and n0/2 when n0 is even, with themselves.
        let half = (n0 - 1) / 2;
        let (first, rest) = data.split_at_mut(slab);
        let (lows, rest) = rest.split_at_mut(half * slab);
        let (middle, highs) = rest.split_at_mut(if n0 % 2 == 0 { slab } else { 0 });
        rayon::join(
            || {
                own(first);
                if !middle.is_empty() {
                    own(middle);
                }
            },
            || {
                lows.par_chunks_mut(slab)
                    .zip(highs.par_chunks_mut(slab).rev())
                    .for_each(|(lo, hi)| pair(lo, hi));
            },
        );
    }

    /// Index of `−k` on axis `a` for spectral index `j`.
    fn negated(&self, j: usize, a: usize) -> usize {
        let n = self.plan.shape[a];
        match self.plan.kinds[a] {
            AxisKind::Periodic => (n - j) % n,
            AxisKind::Mirror => j,
        }
    }

    /// Hermitian projection of every plane at once (mirror last axis), a contiguous lane of all
    /// `j2` per pair `(k0, k1)`, `(−k0, −k1)`.
    fn symmetrize_lanes(&self, a: &mut Array3<Complex64>) {
        let [n0, n1, s2] = self.plan.spectral;
        let data = a.as_slice_mut().expect("standard layout");
        for i0 in 0..n0 {
            for i1 in 0..n1 {
                let p = i0 * n1 + i1;
                let q = self.negated(i0, 0) * n1 + self.negated(i1, 1);
                if q < p {
                    continue;
                }
                if q == p {
                    data[p * s2..(p + 1) * s2]
                        .iter_mut()
                        .for_each(|x| x.im = 0.0);
                    continue;
                }
                let (low, high) = data.split_at_mut(q * s2);
                let lane_p = &mut low[p * s2..(p + 1) * s2];
                for (x, y) in lane_p.iter_mut().zip(&mut high[..s2]) {
                    conjugate_mean(x, y);
                }
            }
        }
    }
}

/// X(k) ← (X(k) + conj X(−k))/2 into `x` and its conjugate into `y` = X(−k).
#[inline]
fn conjugate_mean(x: &mut Complex64, y: &mut Complex64) {
    let mean = 0.5 * (*x + y.conj());
    *x = mean;
    *y = mean.conj();
}

impl Plan {
    /// Zero the padding of a packed spectrum with odd rows (the imaginary part of each row's
    /// last value): the strided stages transform it with its column, and leave round-off there
    /// that no sweep should carry.
    fn clear_padding(&self, y: &mut [Complex64]) {
        if self.packed && !self.shape[2].is_multiple_of(2) {
            let s2 = self.spectral[2];
            y.chunks_exact_mut(s2).for_each(|row| row[s2 - 1].im = 0.0);
        }
    }

    /// Scratch for one parallel chunk, sized for every stage.
    fn new_work(&self) -> Work {
        let (mut lanes, mut scratch) = (0, 0);
        for strided in self.strided.iter().flatten() {
            match strided {
                Strided::Columns(c) => lanes = lanes.max(c.scratch_len()),
                Strided::Lanes(k) => {
                    lanes = lanes.max(k.batch * k.stride);
                    scratch = scratch.max(k.scratch_len);
                }
            }
        }
        match &self.last {
            LastAxis::Halved(rows) => scratch = scratch.max(rows.scratch_len()),
            LastAxis::Real { r2c, c2r } => {
                scratch = scratch
                    .max(r2c.get_scratch_len())
                    .max(c2r.get_scratch_len());
            }
            LastAxis::Mirror { kernel: k, .. } => {
                lanes = lanes.max(k.batch * k.len);
                scratch = scratch.max(k.scratch_len);
            }
        }
        Work {
            lanes: Private::new(lanes, Complex64::default()),
            scratch: Private::new(scratch, Complex64::default()),
        }
    }

    /// Forward transform along axes 2 then 1 of whole slabs (`x`, `y` hold whole `i0` slabs),
    /// one slab at a time so that it stays in cache between the two stages.
    fn forward_slabs(&self, x: &mut [f64], y: &mut [Complex64], work: &mut Work) {
        let [_, n1, n2] = self.shape;
        let s2 = self.spectral[2];
        for (xs, ys) in x.chunks_exact_mut(n1 * n2).zip(y.chunks_exact_mut(n1 * s2)) {
            self.last.forward_rows(xs, ys, n2, work);
            if let Some(kernel) = &self.strided[1] {
                let slab = ArrayViewMut3::from_shape([1, n1, s2], ys).expect("slab shape");
                strided_piece(slab, kernel, Direction::Forward, work);
            }
        }
    }

    /// Inverse of [`Plan::forward_slabs`], with the overall normalisation `scale`.
    fn inverse_slabs(&self, y: &mut [Complex64], x: &mut [f64], scale: f64, work: &mut Work) {
        let [_, n1, n2] = self.shape;
        let s2 = self.spectral[2];
        for (ys, xs) in y.chunks_exact_mut(n1 * s2).zip(x.chunks_exact_mut(n1 * n2)) {
            if let Some(kernel) = &self.strided[1] {
                let slab = ArrayViewMut3::from_shape([1, n1, s2], &mut *ys).expect("slab shape");
                strided_piece(slab, kernel, Direction::Inverse, work);
            }
            self.last.inverse_rows(ys, xs, n2, scale, work);
        }
    }

    /// Transform the whole spectrum along axis `a` (0 or 1), split between the chunks of
    /// `works`: by slabs when there are enough, by column ranges otherwise.
    fn strided_pass(&self, a: usize, dir: Direction, y: &mut [Complex64], works: &mut [Work]) {
        let Some(kernel) = &self.strided[a] else {
            return;
        };
        let s = self.spectral;
        let geometry = if a == 0 {
            [1, s[0], s[1] * s[2]]
        } else {
            [s[0], s[1], s[2]]
        };
        let mut view = ArrayViewMut3::from_shape(geometry, y).expect("spectrum shape");
        let threads = works.len();
        if threads == 1 {
            strided_piece(view, kernel, dir, &mut works[0]);
            return;
        }
        let (axis, chunk) = if geometry[0] >= threads {
            (Axis(0), geometry[0].div_ceil(threads))
        } else {
            let cols = geometry[2].div_ceil(threads).div_ceil(COLUMN_ALIGN) * COLUMN_ALIGN;
            (Axis(2), cols)
        };
        view.axis_chunks_iter_mut(axis, chunk)
            .into_par_iter()
            .zip(works.par_iter_mut())
            .for_each(|(piece, work)| strided_piece(piece, kernel, dir, work));
    }
}

impl LastAxis {
    /// Forward transform of the contiguous rows of length `n` in `x` into rows of `y` (`x` used
    /// as scratch).
    fn forward_rows(&self, x: &mut [f64], y: &mut [Complex64], n: usize, work: &mut Work) {
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
    fn inverse_rows(
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
            true => unsafe { avx::makhoul_pack(a, b, lane) },
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
fn unpack_to_packed_rows(lanes: &[Complex64], y: &mut [Complex64], n: usize) {
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
                true => unsafe { avx::unpack_pairs(lane, a, b) },
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
            true => unsafe { avx::makhoul_unpack(lane, a, b, scale) },
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

/// Transform a piece `[outer, len, width]` of the spectrum along its middle axis: down the
/// columns in place, or a block of columns at a time gathered into contiguous lanes,
/// transformed in one batched call and scattered back.
fn strided_piece(
    mut piece: ArrayViewMut3<Complex64>,
    strided: &Strided,
    dir: Direction,
    work: &mut Work,
) {
    let kernel = match strided {
        Strided::Columns(columns) => {
            for slab in piece.outer_iter_mut() {
                columns.process(dir == Direction::Inverse, slab, &mut work.lanes);
            }
            return;
        }
        Strided::Lanes(kernel) => kernel,
    };
    let columns = kernel.batch;
    let (from, to) = kernel.orders(dir);
    for mut slab in piece.outer_iter_mut() {
        let width = slab.ncols();
        for c0 in (0..width).step_by(columns) {
            let mut block = slab.slice_mut(s![.., c0..(c0 + columns).min(width)]);
            let lanes = &mut work.lanes[..block.ncols() * kernel.stride];
            if kernel.twiddle.is_empty() {
                gather_in_order(block.view(), lanes, kernel.stride);
                kernel.apply(dir, lanes, &mut work.scratch);
                scatter_in_order(lanes, kernel.stride, block.view_mut());
            } else {
                gather(block.view(), lanes, kernel.stride, from);
                kernel.apply(dir, lanes, &mut work.scratch);
                scatter(lanes, kernel.stride, block.view_mut(), to);
            }
        }
    }
}

wide_fn! {
/// Copy the columns of `block` into lanes `stride` apart: lane `l`, position `pos[i]` ← row `i`
/// of column `l`.
fn gather(block: ArrayView2<Complex64>, lanes: &mut [Complex64], stride: usize, pos: &[usize]) {
    for (row, &p) in block.rows().into_iter().zip(pos) {
        let row = row.to_slice().expect("rows are contiguous");
        for (lane, &v) in lanes.chunks_exact_mut(stride).zip(row) {
            lane[p] = v;
        }
    }
}
}

wide_fn! {
/// Inverse of [`gather`]: write the lanes back into the columns of `block`.
fn scatter(lanes: &[Complex64], stride: usize, block: ArrayViewMut2<Complex64>, pos: &[usize]) {
    let mut block = block;
    for (row, &p) in block.rows_mut().into_iter().zip(pos) {
        let row = row.into_slice().expect("rows are contiguous");
        for (lane, v) in lanes.chunks_exact(stride).zip(row) {
            *v = lane[p];
        }
    }
}
}

/// [`gather`] of complex columns in their own order (an FFT lane, positions `0..len`): lane `l`,
/// position `i` ← row `i` of column `l`. With AVX, two rows and two columns at a time: each
/// pair of 32-byte loads is a 2×2 transpose of complex values into two 32-byte stores.
fn gather_in_order(block: ArrayView2<Complex64>, lanes: &mut [Complex64], stride: usize) {
    let (rows, cols) = block.dim();
    assert!(stride >= rows && lanes.len() >= stride * cols);
    assert!(cols == 1 || block.strides()[1] == 1);
    #[cfg(target_arch = "x86_64")]
    if has_avx() {
        // SAFETY: the CPU has AVX; rows are contiguous and `lanes` holds every column (asserted).
        unsafe {
            avx::transpose_pairs::<false>(
                block.as_ptr(),
                block.strides()[0] as usize,
                lanes.as_mut_ptr(),
                stride,
                (rows, cols),
            )
        };
        return;
    }
    for (i, row) in block.rows().into_iter().enumerate() {
        for (lane, &v) in lanes.chunks_exact_mut(stride).zip(row) {
            lane[i] = v;
        }
    }
}

/// Inverse of [`gather_in_order`].
fn scatter_in_order(lanes: &[Complex64], stride: usize, mut block: ArrayViewMut2<Complex64>) {
    let (rows, cols) = block.dim();
    assert!(stride >= rows && lanes.len() >= stride * cols);
    assert!(cols == 1 || block.strides()[1] == 1);
    #[cfg(target_arch = "x86_64")]
    if has_avx() {
        let row_stride = block.strides()[0] as usize;
        // SAFETY: the CPU has AVX; rows are contiguous and `lanes` holds every column (asserted).
        unsafe {
            avx::transpose_pairs::<true>(
                lanes.as_ptr(),
                stride,
                block.as_mut_ptr(),
                row_stride,
                (cols, rows),
            )
        };
        return;
    }
    for (i, mut row) in block.rows_mut().into_iter().enumerate() {
        for (lane, v) in lanes.chunks_exact(stride).zip(row.iter_mut()) {
            *v = lane[i];
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use rustfft::num_complex::Complex64;
    use std::arch::x86_64::*;

    /// [`super::unpack_to_packed_rows`] on one lane of n values whose rows `a`, `b` both exist:
    /// `a[p] = (u.re, v.re)`, `b[p] = (u.im, v.im)` for `(u, v)` = lane values 2p, 2p + 1, two
    /// values of p at a time while 2p + 4 ≤ n; returns the first p not done.
    ///
    /// # Safety
    /// The CPU has AVX; `lane` holds n values, `a` and `b` at least n/2.
    #[target_feature(enable = "avx")]
    pub unsafe fn unpack_pairs(
        lane: &[Complex64],
        a: &mut [Complex64],
        b: &mut [Complex64],
    ) -> usize {
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
    /// # Safety
    /// The CPU has AVX; `a`, `b` and `lane` hold n values.
    #[target_feature(enable = "avx")]
    pub unsafe fn makhoul_pack(a: &[f64], b: &[f64], lane: &mut [Complex64]) -> usize {
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
    /// # Safety
    /// As for [`makhoul_pack`].
    #[target_feature(enable = "avx")]
    pub unsafe fn makhoul_unpack(
        lane: &[Complex64],
        a: &mut [f64],
        b: &mut [f64],
        scale: f64,
    ) -> usize {
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

    /// The DCT twiddle ([`super::dct_post_pair`] when `POST`, else [`super::dct_pre_pair`]) on
    /// the pairs (k, m − k) of one lane of m values, two values of k at a time for k = 1, 2, …
    /// while k + 1 ≤ (m − 1)/2; returns the first k not done. Each value is computed by the
    /// scalar formula's operations in its order (no fused multiply-add), so the results are the
    /// same bit for bit.
    ///
    /// # Safety
    /// The CPU has AVX; `w` has at least m values.
    #[target_feature(enable = "avx")]
    pub unsafe fn twiddle_pairs<const POST: bool>(
        lane: &mut [Complex64],
        w: &[Complex64],
    ) -> usize {
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
        let block = |i: usize, j: usize| {
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
        let one = |i: usize, j: usize| {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    /// The DCT twiddles of a batch of lanes (two pairs at a time with AVX where the CPU has it)
    /// equal the scalar formulas applied pair by pair, bit for bit, for every lane length from 0
    /// to 70 (odd and even, with and without a pair left over) and padded lanes.
    #[test]
    fn batched_dct_twiddles_equal_the_scalar_formulas() {
        for m in 0..=70 {
            let stride = m + LANE_PAD;
            let lanes: Vec<Complex64> = (0..3 * stride)
                .map(|i| Complex64::new((i as f64 * 0.37).sin(), (i as f64 * 0.91).cos() * 3.0))
                .collect();
            let w = dct_twiddle_table(m);
            for post in [true, false] {
                let (mut batched, mut scalar) = (lanes.clone(), lanes.clone());
                if post {
                    dct_twiddles::<true>(&mut batched, stride, m, &w);
                } else {
                    dct_twiddles::<false>(&mut batched, stride, m, &w);
                }
                for lane in scalar.chunks_exact_mut(stride) {
                    let pair = if post { dct_post_pair } else { dct_pre_pair };
                    twiddle_lane(&mut lane[..m], &w, 1, pair);
                }
                let bits = |v: &[Complex64]| -> Vec<(u64, u64)> {
                    v.iter().map(|z| (z.re.to_bits(), z.im.to_bits())).collect()
                };
                assert_eq!(bits(&batched), bits(&scalar), "m = {m}, post = {post}");
            }
        }
    }

    /// The in-order gather and scatter move each value to its place (odd and even row and column
    /// counts, a block that is a column range of wider rows), and scatter undoes gather.
    #[test]
    fn in_order_gather_and_scatter_transpose() {
        for (rows, cols, width) in [(8, 6, 6), (7, 5, 9), (6, 3, 4), (1, 1, 1), (5, 8, 11)] {
            let value = |i: usize, j: usize| Complex64::new(i as f64, 100.0 * j as f64 + 0.5);
            let mut full = Array2::from_shape_fn((rows, width), |(i, j)| value(i, j));
            let stride = rows + LANE_PAD;
            let mut lanes = vec![Complex64::default(); stride * cols];
            gather_in_order(full.slice(s![.., ..cols]), &mut lanes, stride);
            for l in 0..cols {
                for i in 0..rows {
                    assert_eq!(lanes[l * stride + i], value(i, l), "lane {l}, position {i}");
                }
            }
            lanes.iter_mut().for_each(|v| *v *= 2.0);
            scatter_in_order(&lanes, stride, full.slice_mut(s![.., ..cols]));
            for ((i, j), v) in full.indexed_iter() {
                let factor = if j < cols { 2.0 } else { 1.0 };
                assert_eq!(*v, value(i, j) * factor, "row {i}, column {j}");
            }
        }
    }
}
