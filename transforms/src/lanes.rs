//! Batched one-dimensional kernels on contiguous lanes: a complex FFT, or a DCT-II/DCT-III through a complex FFT of the same length.

use std::sync::Arc;

use num_complex::Complex64;
use vesicle_fft_plans::{Fft, Planner};

use super::{
    dct_twiddle_table, dct_twiddles, makhoul_positions, Direction, LANE_BUFFER, LANE_PAD, MIN_BATCH,
};
use crate::AxisKind;

/// A batched 1D kernel along one axis: a complex FFT (periodic) or a DCT-II/DCT-III computed with
/// a complex FFT of the same length (mirror). Both act on lanes of `len` contiguous values.
pub(super) struct LaneKernel {
    pub(super) len: usize,
    /// Values from one lane's start to the next (`len`, or `len + LANE_PAD` in a strided stage).
    pub(super) stride: usize,
    /// Lanes per batch.
    pub(super) batch: usize,
    pub(super) forward: Arc<dyn Fft<f64>>,
    pub(super) inverse: Arc<dyn Fft<f64>>,
    pub(super) scratch_len: usize,
    /// Lane position of data index `i`: `i` for the FFT; for the DCT the Makhoul order
    /// `v_p = x_{2p}`, `v_{m−1−p} = x_{2p+1}`.
    pub(super) pos: Vec<usize>,
    /// Lane position of spectral index `j`: always `j`.
    pub(super) identity: Vec<usize>,
    /// DCT twiddles `w_k = e^{−iπk/(2m)}`; empty for the FFT.
    pub(super) twiddle: Vec<Complex64>,
}

impl LaneKernel {
    /// The kernel of an axis of `len` points; `padded` lanes are [`LANE_PAD`] values apart.
    pub(super) fn new(planner: &mut Planner, len: usize, kind: AxisKind, padded: bool) -> Self {
        let stride = if padded { len + LANE_PAD } else { len };
        let forward = planner.forward(len);
        let inverse = planner.inverse(len);
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
    pub(super) fn orders(&self, dir: Direction) -> (&[usize], &[usize]) {
        match dir {
            Direction::Forward => (&self.pos, &self.identity),
            Direction::Inverse => (&self.identity, &self.pos),
        }
    }

    /// Transform every lane of `lanes` (a whole number of lanes, `stride` apart) in place.
    pub(super) fn apply(&self, dir: Direction, lanes: &mut [Complex64], scratch: &mut [Complex64]) {
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
