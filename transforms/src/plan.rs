//! The stages of a planned transform: scratch sizes and the parallel sweeps over the axes.

use ndarray::{ArrayViewMut3, Axis};
use num_complex::Complex64;
use rayon::prelude::*;

use super::{strided_piece, Direction, LastAxis, Plan, Strided, Work, COLUMN_ALIGN};
use crate::private::Private;

impl Plan {
    /// Zero the padding of a packed spectrum with odd rows (the imaginary part of each row's
    /// last value): the strided stages transform it with its column, and leave round-off there
    /// that no sweep should carry.
    pub(super) fn clear_padding(&self, y: &mut [Complex64]) {
        if self.packed && !self.shape[2].is_multiple_of(2) {
            let s2 = self.spectral[2];
            y.chunks_exact_mut(s2).for_each(|row| row[s2 - 1].im = 0.0);
        }
    }

    /// Scratch for one parallel chunk, sized for every stage.
    pub(super) fn new_work(&self) -> Work {
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
    pub(super) fn forward_slabs(&self, x: &mut [f64], y: &mut [Complex64], work: &mut Work) {
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
    pub(super) fn inverse_slabs(
        &self,
        y: &mut [Complex64],
        x: &mut [f64],
        scale: f64,
        work: &mut Work,
    ) {
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
    pub(super) fn strided_pass(
        &self,
        a: usize,
        dir: Direction,
        y: &mut [Complex64],
        works: &mut [Work],
    ) {
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
