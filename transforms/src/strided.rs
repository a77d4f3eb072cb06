//! The transforms along the strided axes (0 and 1): down the columns in place, or gathered into lanes.

use ndarray::{s, ArrayView2, ArrayViewMut2, ArrayViewMut3};
use num_complex::Complex64;
use vesicle_fft_plans::Planner;

use super::{has_avx, Direction, LaneKernel, Work};
use crate::columns::ColumnFft;
use crate::wide_fn;
use crate::AxisKind;

/// How a strided axis (0 or 1) is transformed.
pub(super) enum Strided {
    /// Down the columns in place: an axis whose length [`ColumnFft::new`] plans (periodic: an
    /// FFT; mirror: a DCT, [`ColumnFft::new_dct`]).
    Columns(ColumnFft),
    /// Gathered into lanes, transformed by a batched kernel and scattered back.
    Lanes(LaneKernel),
}

impl Strided {
    /// The transform of axis `a` of `shape` with walls `kinds`.
    pub(super) fn new(
        planner: &mut Planner,
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

/// Transform a piece `[outer, len, width]` of the spectrum along its middle axis: down the
/// columns in place, or a block of columns at a time gathered into contiguous lanes,
/// transformed in one batched call and scattered back.
pub(super) fn strided_piece(
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
pub(super) fn gather(block: ArrayView2<Complex64>, lanes: &mut [Complex64], stride: usize, pos: &[usize]) {
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
pub(super) fn scatter(lanes: &[Complex64], stride: usize, block: ArrayViewMut2<Complex64>, pos: &[usize]) {
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
pub(super) fn gather_in_order(
    block: ArrayView2<Complex64>,
    lanes: &mut [Complex64],
    stride: usize,
) {
    let (rows, cols) = block.dim();
    assert!(stride >= rows && lanes.len() >= stride * cols);
    assert!(cols == 1 || block.strides()[1] == 1);
    #[cfg(target_arch = "x86_64")]
    if has_avx() {
        // SAFETY: the CPU has AVX; rows are contiguous and `lanes` holds every column (asserted).
        unsafe {
            super::avx::transpose_pairs::<false>(
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
pub(super) fn scatter_in_order(
    lanes: &[Complex64],
    stride: usize,
    mut block: ArrayViewMut2<Complex64>,
) {
    let (rows, cols) = block.dim();
    assert!(stride >= rows && lanes.len() >= stride * cols);
    assert!(cols == 1 || block.strides()[1] == 1);
    #[cfg(target_arch = "x86_64")]
    if has_avx() {
        let row_stride = block.strides()[0] as usize;
        // SAFETY: the CPU has AVX; rows are contiguous and `lanes` holds every column (asserted).
        unsafe {
            super::avx::transpose_pairs::<true>(
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
