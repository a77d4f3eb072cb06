//! The bilayer-couple `(v, Δa)` and ADE `(v, Δa0)` diagrams: at each reduced volume the four
//! BC branches followed in `Δa` ([`v_slice`]), the lowest-energy branch along a grid of `Δa`
//! ([`bc_lowest`]: energy `e`) or of `Δa0` ([`ade_lowest`]: energy `w` of the stable ADE
//! shapes, the image of the BC branches, [`super::ade`]), and where it changes, by the logic
//! the `(v, c̄0)` chart shares ([`super::lowest`]) (`vesicle axisym --bc --da LIST` and
//! `--ade ALPHA --da0 LIST` write them and draw the phase charts).

use super::ade::ade_image;
use super::bc::{bc_curve, updown_changes, BcCurve, UpdownChange};
use super::lowest::{lowest, monotone_pieces, Lowest};
use super::{Branch, Options};
use rayon::prelude::*;

/// The BC branches at one reduced volume.
#[derive(Clone, Debug)]
pub struct VSlice {
    /// The reduced volume.
    pub v: f64,
    /// One curve per branch of [`Branch::WITH_PEAR`], in that order.
    pub curves: Vec<BcCurve>,
    /// Where the prolate's up–down stability changes along its curve ([`updown_changes`]).
    pub updown: Vec<UpdownChange>,
}

/// Follow the four BC branches at `v` over the `Δa` window (in parallel), and the prolate's
/// up–down stability along its curve.
pub fn v_slice(v: f64, window: (f64, f64), opts: &Options) -> VSlice {
    let curves: Vec<BcCurve> = Branch::WITH_PEAR
        .par_iter()
        .map(|&b| bc_curve(b, v, window, opts))
        .collect();
    let updown = curves
        .iter()
        .flat_map(|c| updown_changes(c, opts))
        .collect();
    VSlice { v, curves, updown }
}

/// The BC diagram at one `v`: the lowest bending energy `e` among the branches at each `Δa`
/// of `das` (local cubics on the pieces of each path monotone in `Δa`), and its changes.
pub fn bc_lowest(slice: &VSlice, das: &[f64]) -> Lowest {
    let pieces: Vec<(Branch, Vec<(f64, f64)>)> = slice
        .curves
        .iter()
        .flat_map(|c| {
            let path: Vec<(f64, f64)> = c.shapes.iter().map(|s| (s.da(), s.e)).collect();
            monotone_pieces(&path)
                .into_iter()
                .map(move |p| (c.branch, p))
        })
        .collect();
    lowest(&pieces, das)
}

/// The ADE diagram of `α` at one `v` (the BC curves computed at the ADE model's `c̄0`): the
/// lowest `w` among the stable ADE shapes of every branch at each `Δa0` of `da0s`, and its
/// changes. Only stable stretches of each image enter (runs of [`super::AdePoint::stable`]).
pub fn ade_lowest(slice: &VSlice, alpha: f64, da0s: &[f64]) -> Lowest {
    let mut pieces = Vec::new();
    for c in &slice.curves {
        let img = ade_image(&c.shapes, alpha);
        let mut run: Vec<(f64, f64)> = Vec::new();
        for p in img.iter().chain(std::iter::once(&super::AdePoint {
            da0: f64::NAN,
            da: f64::NAN,
            w: f64::NAN,
            e: f64::NAN,
            c0_eff: f64::NAN,
            stable: false,
        })) {
            if p.stable {
                run.push((p.da0, p.w));
            } else if !run.is_empty() {
                pieces.extend(
                    monotone_pieces(&std::mem::take(&mut run))
                        .into_iter()
                        .map(|q| (c.branch, q)),
                );
            }
        }
    }
    lowest(&pieces, da0s)
}
