//! Walking a spectrum in pieces: the sweeps over a spectrum take |k|² and w a piece at a time
//! into two short tables, then run loops over the piece's values as (re, im) pairs of
//! interleaved reals, forming each value's factors (what follows from |k|² and w) where they are
//! used, which the compiler vectorises; each value's terms of a sum go to a short scratch table,
//! summed with the kernels of [`super::kernels`].
//!
//! A piece is as many whole spectral rows as fit in [`PIECE`] values, or a part of one longer
//! row: at 48³ or 64³ (rows of 25 or 33 values) a piece is seven or ten rows, so a sweep that
//! reads many arrays (the L-BFGS pairs) reads a 4 KiB page of each per visit.

use super::evaluator::Symbols;
use super::kernels::wide_fn;
use rustfft::num_complex::Complex64;

/// Values per piece.
pub const PIECE: usize = 256;

/// |k|² and the weight w of each value of a piece (see [`Symbols`]).
pub struct Piece {
    /// Values in the piece (its reals are `2 len`).
    pub len: usize,
    /// |k|² per value.
    pub k: [f64; PIECE],
    /// w per value.
    pub w: [f64; PIECE],
}

impl Piece {
    fn new() -> Self {
        Piece {
            len: 0,
            k: [0.0; PIECE],
            w: [0.0; PIECE],
        }
    }

    /// The piece's reals.
    pub fn reals(&self) -> usize {
        2 * self.len
    }

    /// The piece's values as (re, im) pairs, from reals `v` starting at its first.
    #[inline(always)]
    pub fn pairs<'a, T>(&self, v: &'a [T]) -> &'a [[T; 2]] {
        v[..self.reals()].as_chunks::<2>().0
    }

    /// [`Piece::pairs`], writable.
    #[inline(always)]
    pub fn pairs_mut<'a, T>(&self, v: &'a mut [T]) -> &'a mut [[T; 2]] {
        v[..self.reals()].as_chunks_mut::<2>().0
    }

    /// (|k|², w) of each value.
    #[inline(always)]
    pub fn symbols(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let (k, w) = (&self.k[..self.len], &self.w[..self.len]);
        k.iter().copied().zip(w.iter().copied())
    }
}

/// Re(a b*) of two values given as (re, im); |a|² when b = a.
#[inline(always)]
pub fn re_dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

wide_fn! {
/// The values `start..start + len` of spectral row `row` (`at`) into `piece`, placed after its
/// first `offset` values.
fn fill_piece(piece: &mut Piece, sym: &Symbols, at: (usize, usize, usize), offset: usize) {
    let (row, start, len) = at;
    let (kb, wb) = sym.row(row);
    let axis = sym.k2[2][start..start + len]
        .iter()
        .zip(&sym.weight[2][start..start + len]);
    let out = piece.k[offset..offset + len]
        .iter_mut()
        .zip(&mut piece.w[offset..offset + len]);
    for ((k, w), (&kl, &wl)) in out.zip(axis) {
        (*k, *w) = (kb + kl, wb * wl);
    }
    piece.len = offset + len;
}
}

/// Calls `f(piece, at)` for every piece of parallel task `t` (whole rows, [`Symbols::task_len`]
/// values a task) holding `reals` reals, `at` the piece's first real within the task. Inlined,
/// with one call of `f`, so that a sweep run through [`super::kernels::wide`] is compiled whole
/// for its instructions.
#[inline(always)]
pub fn for_each_piece(sym: &Symbols, t: usize, reals: usize, mut f: impl FnMut(&Piece, usize)) {
    let s2 = sym.row_len();
    let (first, rows) = (t * sym.task_len() / s2, reals / (2 * s2));
    let (rows_per_piece, parts) = if s2 <= PIECE {
        (PIECE / s2, 1)
    } else {
        (1, s2.div_ceil(PIECE))
    };
    let mut piece = Piece::new();
    for r0 in (0..rows).step_by(rows_per_piece) {
        for part in 0..parts {
            let (start, len) = (part * PIECE, PIECE.min(s2 - part * PIECE));
            for i in 0..rows_per_piece.min(rows - r0) {
                fill_piece(&mut piece, sym, (first + r0 + i, start, len), i * len);
            }
            f(&piece, 2 * (r0 * s2 + start));
        }
    }
}

/// A spectrum as interleaved (re, im) reals.
pub fn reals(c: &[Complex64]) -> &[f64] {
    bytemuck::cast_slice(c)
}

/// A spectrum as interleaved (re, im) reals, writable.
pub fn reals_mut(c: &mut [Complex64]) -> &mut [f64] {
    bytemuck::cast_slice_mut(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Laplacian;
    use crate::grid::Grid;
    use crate::spectral::transform::Transform;

    /// Every value of every task is visited once, in order, with its own |k|² and w: on rows
    /// shorter than a piece (several rows a piece, the last piece short) and longer ones (a row
    /// in parts).
    #[test]
    fn pieces_cover_each_value_once_with_its_symbols() {
        for shape in [[40, 20, 48], [3, 2, 1200]] {
            let grid = Grid::new(&shape, 1.0, &[false; 3]);
            let t = Transform::new(shape, grid.kinds, 1);
            let sym = Symbols::new(&t, &grid, 1.0, Laplacian::Spectral);
            let (s2, task) = (sym.row_len(), sym.task_len());
            let total: usize = t.spectral_shape().iter().product();
            let mut next = 0;
            for first in (0..total).step_by(task) {
                let reals = 2 * task.min(total - first);
                for_each_piece(&sym, first / task, reals, |p, at| {
                    assert_eq!(first + at / 2, next, "pieces in order, none skipped");
                    assert!(p.len <= PIECE);
                    for l in 0..p.len {
                        let i = next + l;
                        let (kb, wb) = sym.row(i / s2);
                        assert_eq!(p.k[l], kb + sym.k2[2][i % s2]);
                        assert_eq!(p.w[l], wb * sym.weight[2][i % s2]);
                    }
                    next += p.len;
                });
            }
            assert_eq!(next, total);
        }
    }
}
