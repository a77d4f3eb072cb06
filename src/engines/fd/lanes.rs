//! Row kernels with reductions in [`LANES`] partial sums, written once for a point (`f64`) and
//! for a block of [`LANES`] consecutive points ([`Block`]), so that the computing loop and its
//! sums vectorise together while every lane adds its points in the order of a scalar loop: the
//! blocks of a plane's rows lane by lane, the rows' tails point by point into a value of their
//! own ([`Acc`]).

use std::ops::{Add, Mul, Sub};

/// Partial sums per lane in the reductions (one AVX register of f64).
pub(super) const LANES: usize = 4;

/// `M` accumulators of [`LANES`] partial sums.
pub(super) type Lanes<const M: usize> = [[f64; LANES]; M];

/// What a kernel computes with: one point (`f64`) or a block of [`LANES`] points, each
/// operation lane by lane with the scalar operation (no reassociation, no contraction).
pub(super) trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// `x` in every lane.
    fn splat(x: f64) -> Self;
    /// `f(self, o)` lane by lane.
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self;
    /// |self| lane by lane.
    fn abs(self) -> Self {
        self.zip(self, |a, _| a.abs())
    }
    /// [`larger`] lane by lane.
    fn larger(self, o: Self) -> Self {
        self.zip(o, larger)
    }
}

impl Lane for f64 {
    fn splat(x: f64) -> Self {
        x
    }
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        f(self, o)
    }
}

/// [`LANES`] consecutive points of a row.
#[derive(Clone, Copy, Debug)]
pub(super) struct Block([f64; LANES]);

impl Lane for Block {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Block([x; LANES])
    }
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Block(std::array::from_fn(|j| f(self.0[j], o.0[j])))
    }
}

impl Add for Block {
    type Output = Block;
    #[inline(always)]
    fn add(self, o: Block) -> Block {
        self.zip(o, |a, b| a + b)
    }
}

impl Sub for Block {
    type Output = Block;
    #[inline(always)]
    fn sub(self, o: Block) -> Block {
        self.zip(o, |a, b| a - b)
    }
}

impl Mul for Block {
    type Output = Block;
    #[inline(always)]
    fn mul(self, o: Block) -> Block {
        self.zip(o, |a, b| a * b)
    }
}

/// A pointwise computation on a row with `I` inputs and `O` outputs (whose values before the
/// point are also inputs), reducing into `M` accumulators.
pub(super) trait Kernel<const I: usize, const O: usize, const M: usize> {
    /// The outputs of a point (or block) from its inputs, its outputs' previous values, adding
    /// its terms to `acc`.
    fn point<T: Lane>(&self, acc: &mut [T; M], ins: [T; I], outs: [T; O]) -> [T; O];
}

/// A kernel's `M` accumulators over the rows of a plane: [`LANES`] partial values for the
/// rows' blocks (each lane takes its blocks' points in row order, row after row) and one value
/// for the rows' tails (the points past the last whole block, in order).
pub(super) struct Acc<const M: usize> {
    blocks: [Block; M],
    tail: [f64; M],
}

impl<const M: usize> Acc<M> {
    /// Every accumulator 0.
    pub(super) fn zero() -> Self {
        Acc {
            blocks: [Block::splat(0.0); M],
            tail: [0.0; M],
        }
    }

    /// The lanes and the tails.
    ///
    /// The lanes pass through [`std::hint::black_box`] (a store and a load per plane): seen
    /// through, their uses after the rows' loops lead LLVM's SLP vectoriser to pair the
    /// accumulators instead of the lanes, and the loops run on scalars and pairs (measured:
    /// 1.47 → 1.23 ms, minimum of 6 × 200 steps of 64³, one thread). Once per plane rather than
    /// once per row: reloading part of a just-stored register stalls store forwarding, which
    /// cost 7–8% of the sweep when it was paid on every row.
    #[inline(always)]
    pub(super) fn finish(&self) -> (Lanes<M>, [f64; M]) {
        (std::hint::black_box(self.blocks.map(|b| b.0)), self.tail)
    }
}

/// `kernel` over the rows `ins`, `outs` (of `outs[0]`'s length, O ≥ 1): the outputs written,
/// the terms added to `acc` (the blocks lane by lane, the tail into the tails).
#[inline(always)]
pub(super) fn in_lanes<const I: usize, const O: usize, const M: usize>(
    kernel: &impl Kernel<I, O, M>,
    ins: [&[f64]; I],
    outs: [&mut [f64]; O],
    acc: &mut Acc<M>,
) {
    let n = outs[0].len();
    let ins = ins.map(|x| x[..n].as_chunks::<LANES>());
    let mut outs = outs.map(|x| x.as_chunks_mut::<LANES>());
    for b in 0..n / LANES {
        let x = std::array::from_fn(|i| Block(ins[i].0[b]));
        let y = kernel.point(
            &mut acc.blocks,
            x,
            std::array::from_fn(|o| Block(outs[o].0[b])),
        );
        for (o, y) in outs.iter_mut().zip(y) {
            o.0[b] = y.0;
        }
    }
    for k in 0..n % LANES {
        let x = std::array::from_fn(|i| ins[i].1[k]);
        let y = kernel.point(&mut acc.tail, x, std::array::from_fn(|o| outs[o].1[k]));
        for (o, y) in outs.iter_mut().zip(y) {
            o.1[k] = y;
        }
    }
}

/// max(a, b) for the maxima of magnitudes (a plain compare: one vector instruction; a NaN `b`
/// is skipped as `f64::max` skips it).
#[inline(always)]
pub(super) fn larger(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

/// Sum of the lanes and the tail.
pub(super) fn total(lanes: [f64; LANES], tail: f64) -> f64 {
    lanes.iter().sum::<f64>() + tail
}

/// Largest of the lanes, the tail and `m`.
pub(super) fn largest(lanes: [f64; LANES], tail: f64, m: f64) -> f64 {
    lanes.iter().fold(larger(m, tail), |a, &b| larger(a, b))
}
