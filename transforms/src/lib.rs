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
//! function of k, which acts on a packed spectrum real by real (vesicle's `engines::spectral::pieces`).
//!
//! Implementation: the last (contiguous) axis is transformed row by row, periodic through a
//! complex FFT of half its length (`real_rows.rs`; `realfft` when the length is odd) or,
//! for a mirror axis, two real lanes at a time packed as one complex lane. The other axes are
//! transformed down the columns in place (`columns.rs`) when their length is a product of
//! 2s, 3s and 5s, and otherwise gathered a block of columns at a time into contiguous lanes,
//! transformed with one batched `rustfft` call and scattered back. A DCT-II of length `m` is
//! computed with one complex FFT of length `m` (Makhoul's even/odd reordering plus a twiddle); it
//! is C-linear, so a complex lane holding two real lanes (or the real and imaginary parts of one
//! complex lane) costs one FFT: a packed spectrum's columns are such lanes as they stand.
//! All buffers live in the struct: a transform call allocates nothing.
//!
//! **The crate.** [`Transform`] is the whole public interface (with [`AxisKind`], the boundary of
//! an axis): a safe API over the hand-written kernels (the column FFT, the real rows' split, the
//! AVX packing and twiddle loops), whose `unsafe` code stays inside this crate, each block with
//! the reason it is sound. The FFTs of other lengths are `rustfft`'s and `realfft`'s, planned by
//! `vesicle-fft-plans`.

// Every `unsafe` block says why it is sound, every `unsafe fn` when it may be called.
#![warn(
    unsafe_op_in_unsafe_fn,
    clippy::undocumented_unsafe_blocks,
    clippy::missing_safety_doc
)]

#[cfg(target_arch = "x86_64")]
mod avx;
mod columns;
pub mod cpu;
mod dct;
mod lanes;
mod plan;
mod private;
pub use private::Private;
mod real_rows;
mod rows;
mod strided;
#[cfg(test)]
mod tests;
mod wide;

use cpu::has_avx;
use dct::{dct_twiddle_table, dct_twiddles, makhoul_position, makhoul_positions};
use lanes::LaneKernel;
use rows::LastAxis;
use strided::{strided_piece, Strided};

use std::f64::consts::PI;
use std::fmt;

use ndarray::{Array3, ArrayView3};
use num_complex::Complex64;
use rayon::prelude::*;
use vesicle_fft_plans::Planner;

use real_rows::RealRows;

/// Boundary treatment of one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisKind {
    /// Periodic box of `n` points.
    Periodic,
    /// Upper half of an even periodic box of `2n` points: Neumann walls half-way between points.
    Mirror,
}

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
        let mut planner = Planner::new();
        let packed = kinds[2] == AxisKind::Mirror
            && (0..2).all(|a| shape[a] == 1 || kinds[a] == AxisKind::Mirror);
        let last = match kinds[2] {
            AxisKind::Periodic => match RealRows::new(&mut planner, shape[2]) {
                Some(rows) => LastAxis::Halved(rows),
                None => LastAxis::Real {
                    r2c: planner.real_forward(shape[2]),
                    c2r: planner.real_inverse(shape[2]),
                },
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
    /// the slabs' values, kept in `visits` (scratch whose allocation is reused), summed by `add`
    /// from `S::default()` in slab order (the same bits on any number of threads), or `None`, having done nothing, when the box has fewer slabs
    /// than threads.
    ///
    /// # Panics
    /// If the shapes are not those of the plan.
    pub fn round_trip<S: Send + Default>(
        &mut self,
        [a, b]: [&mut Array3<Complex64>; 2],
        real: &mut Array3<f64>,
        visits: &mut Vec<S>,
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
        // The slabs from `first_slab` of one thread: `ya`, `yb`, `x` hold just those slabs, and
        // `out` their entries of `visits`.
        let slabs = |first_slab: usize,
                     (ya, yb, x): (&mut [Complex64], &mut [Complex64], &mut [f64]),
                     out: &mut [S],
                     work: &mut Work,
                     fields: &mut [f64]| {
            let (xb, y) = fields.split_at_mut(slab);
            let ya = ya.chunks_exact_mut(spectral_slab);
            let yb = yb.chunks_exact_mut(spectral_slab);
            let slabs = ya.zip(yb).zip(x.chunks_exact_mut(slab)).zip(out);
            for (i, (((ya, yb), x), out)) in slabs.enumerate() {
                plan.inverse_slabs(ya, x, scale, work);
                plan.inverse_slabs(yb, xb, scale, work);
                *out = visit((first_slab + i) * slab, x, xb, y);
                plan.forward_slabs(y, ya, work);
                plan.forward_slabs(xb, yb, work);
            }
        };
        visits.clear();
        visits.resize_with(n0, S::default);
        if threads == 1 {
            slabs(0, (ya, yb, x), visits, &mut works[0], &mut slab_fields[0]);
        } else {
            let per = n0.div_ceil(threads);
            ya.par_chunks_mut(per * spectral_slab)
                .zip(yb.par_chunks_mut(per * spectral_slab))
                .zip(x.par_chunks_mut(per * slab))
                .zip(visits.par_chunks_mut(per))
                .zip(works.par_iter_mut().zip(slab_fields.par_iter_mut()))
                .enumerate()
                .for_each(|(t, ((((ya, yb), x), out), (work, fields)))| {
                    slabs(t * per, (ya, yb, x), out, work, fields);
                });
        }
        // In slab order, whatever thread computed which slab.
        let total = visits.drain(..).fold(S::default(), &add);
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
    /// anti-diffusive (docs/src/theory/spectral.md).
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
