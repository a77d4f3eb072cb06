//! Walking a spectrum in pieces: the sweeps over a spectrum take |k|² and w a piece at a time
//! into two short tables, then run loops over the piece's modes, forming each mode's factors
//! (what follows from |k|² and w) where they are used, which the compiler vectorises; each
//! mode's terms of a sum go to a short scratch table, summed with the kernels of
//! [`super::kernels`].
//!
//! A *mode* is one wavenumber's coefficient: a complex value, two interleaved reals (re, im),
//! or, in a packed spectrum ([`super::transform::Transform::packed`]), one real. Every operator
//! the sweeps apply is real and even in k, so the same formulas serve both: a sweep's kernel is
//! generic over the reals per mode `W` (2 or 1), chosen by [`per_width!`], and takes each mode
//! as `[f64; W]`.
//!
//! A piece is as many whole spectral rows as fit in [`PIECE`] modes, or a part of one longer
//! row: at 48³ or 64³ (rows of 25 or 33 values) a piece is seven or ten rows, so a sweep that
//! reads many arrays (the L-BFGS pairs) reads a 4 KiB page of each per visit.

use super::evaluator::Symbols;
use super::kernels::wide_fn;
use num_complex::Complex64;

/// Modes per piece.
pub const PIECE: usize = 256;

/// |k|² and the weight w of each mode of a piece (see [`Symbols`]).
pub struct Piece {
    /// Modes in the piece (its reals are `width · len`).
    pub len: usize,
    /// Reals per mode ([`Symbols::width`]).
    width: usize,
    /// |k|² per mode.
    pub k: [f64; PIECE],
    /// w per mode.
    pub w: [f64; PIECE],
}

impl Piece {
    fn new(width: usize) -> Self {
        Piece {
            len: 0,
            width,
            k: [0.0; PIECE],
            w: [0.0; PIECE],
        }
    }

    /// The piece's reals.
    pub fn reals(&self) -> usize {
        self.width * self.len
    }

    /// The piece's modes, `W` reals each, from reals `v` starting at its first.
    #[inline(always)]
    pub fn modes<'a, const W: usize, T>(&self, v: &'a [T]) -> &'a [[T; W]] {
        debug_assert_eq!(W, self.width);
        v[..W * self.len].as_chunks::<W>().0
    }

    /// [`Piece::modes`], writable.
    #[inline(always)]
    pub fn modes_mut<'a, const W: usize, T>(&self, v: &'a mut [T]) -> &'a mut [[T; W]] {
        debug_assert_eq!(W, self.width);
        v[..W * self.len].as_chunks_mut::<W>().0
    }

    /// (|k|², w) of each mode.
    #[inline(always)]
    pub fn symbols(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let (k, w) = (&self.k[..self.len], &self.w[..self.len]);
        k.iter().copied().zip(w.iter().copied())
    }
}

/// Evaluates `call` with the const `W` set to the reals per mode of `sym` ([`Symbols::width`]):
/// `per_width!(sym, W => kernel::<W>(…))`.
macro_rules! per_width {
    ($sym:expr, $w:ident => $call:expr) => {
        if $sym.width == 1 {
            const $w: usize = 1;
            $call
        } else {
            const $w: usize = 2;
            $call
        }
    };
}
pub(crate) use per_width;

/// Re(a b*) of two modes (|a|² when b = a): a₀b₀ + a₁b₁ for complex values, ab for reals.
#[inline(always)]
pub fn re_dot<const W: usize>(a: [f64; W], b: [f64; W]) -> f64 {
    let mut d = a[0] * b[0];
    for c in 1..W {
        d += a[c] * b[c];
    }
    d
}

/// The mode whose reals are `f(0), …, f(W − 1)`.
#[inline(always)]
pub fn mode<const W: usize>(f: impl FnMut(usize) -> f64) -> [f64; W] {
    std::array::from_fn(f)
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
/// modes a task) holding `reals` reals, `at` the piece's first real within the task. Inlined,
/// with one call of `f`, so that a sweep run through [`super::kernels::wide`] is compiled whole
/// for its instructions.
#[inline(always)]
pub fn for_each_piece(sym: &Symbols, t: usize, reals: usize, mut f: impl FnMut(&Piece, usize)) {
    let (s2, width) = (sym.row_len(), sym.width);
    let (first, rows) = (t * sym.task_len() / s2, reals / (width * s2));
    let (rows_per_piece, parts) = if s2 <= PIECE {
        (PIECE / s2, 1)
    } else {
        (1, s2.div_ceil(PIECE))
    };
    let mut piece = Piece::new(width);
    for r0 in (0..rows).step_by(rows_per_piece) {
        for part in 0..parts {
            let (start, len) = (part * PIECE, PIECE.min(s2 - part * PIECE));
            for i in 0..rows_per_piece.min(rows - r0) {
                fill_piece(&mut piece, sym, (first + r0 + i, start, len), i * len);
            }
            f(&piece, width * (r0 * s2 + start));
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
    use crate::engines::spectral::transform::Transform;
    use crate::problem::config::Laplacian;
    use crate::problem::grid::Grid;

    /// Every mode of every task is visited once, in order, with its own |k|² and w: on rows
    /// shorter than a piece (several rows a piece, the last piece short) and longer ones (a row
    /// in parts), of complex spectra and of packed ones (a real a mode, odd rows padded).
    #[test]
    fn pieces_cover_each_mode_once_with_its_symbols() {
        // The last: a mirrored 12 × 16 × 82 box, 6 × 8 × 41 computed.
        let cases = [
            ([40, 20, 48], false),
            ([3, 2, 1200], false),
            ([12, 16, 82], true),
        ];
        for (shape, mirror) in cases {
            let grid = Grid::new(&shape, 1.0, &[mirror; 3]);
            let t = Transform::new(grid.shape, grid.kinds, 1);
            let sym = Symbols::new(&t, &grid, 1.0, Laplacian::Spectral);
            assert_eq!(t.packed(), mirror);
            let (s2, task, width) = (sym.row_len(), sym.task_len(), sym.width);
            let total: usize = t.spectral_shape().iter().product::<usize>() * 2 / width;
            let mut next = 0;
            for first in (0..total).step_by(task) {
                let reals = width * task.min(total - first);
                for_each_piece(&sym, first / task, reals, |p, at| {
                    assert_eq!(first + at / width, next, "pieces in order, none skipped");
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
