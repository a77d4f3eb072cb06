//! The bilayer-couple `(v, Δa)` and ADE `(v, Δa0)` diagrams: at each reduced volume the four
//! BC branches followed in `Δa` ([`v_slice`]), the lowest-energy branch along a grid of `Δa`
//! ([`bc_lowest`]: energy `e`) or of `Δa0` ([`ade_lowest`]: energy `w` of the stable ADE
//! shapes, the image of the BC branches, [`super::ade`]), and where it changes
//! (`vesicle axisym --bc --da LIST` and `--ade ALPHA --da0 LIST` write them and draw the
//! phase charts).

use super::ade::ade_image;
use super::bc::{bc_curve, BcCurve};
use super::{Branch, Options};
use crate::analysis::curves::{crossings, cubic_at};
use rayon::prelude::*;

/// The BC branches at one reduced volume.
#[derive(Clone, Debug)]
pub struct VSlice {
    /// The reduced volume.
    pub v: f64,
    /// One curve per branch of [`Branch::WITH_PEAR`], in that order.
    pub curves: Vec<BcCurve>,
}

/// Follow the four BC branches at `v` over the `Δa` window (in parallel).
pub fn v_slice(v: f64, window: (f64, f64), opts: &Options) -> VSlice {
    let curves = Branch::WITH_PEAR
        .par_iter()
        .map(|&b| bc_curve(b, v, window, opts))
        .collect();
    VSlice { v, curves }
}

/// A change of the lowest-energy branch between two grid values of `x` (`Δa` or `Δa0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Change {
    /// Where: the crossing of the two energies, or the midpoint of the grid interval when they
    /// do not cross there (a branch ends).
    pub x: f64,
    /// Lowest below `x`.
    pub below: Branch,
    /// Lowest above `x`.
    pub above: Branch,
    /// Whether `x` is an energy crossing (else a grid midpoint).
    pub crossing: bool,
}

/// The lowest-energy branch along a grid at one `v`.
#[derive(Clone, Debug, Default)]
pub struct Lowest {
    /// `(x, branch, energy)` at each grid value where some branch exists.
    pub points: Vec<(f64, Branch, f64)>,
    /// Where the lowest branch changes.
    pub changes: Vec<Change>,
}

/// A path `(x, y)` split into pieces monotone in `x`, each sorted by `x` (pieces of fewer than
/// two points dropped).
fn monotone_pieces(path: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut dir = 0.0;
    for &p in path {
        if let Some(&last) = cur.last() {
            let d = (p.0 - last.0).signum();
            if dir != 0.0 && d != dir {
                pieces.push(std::mem::take(&mut cur));
                cur.push(last);
            }
            dir = d;
        }
        cur.push(p);
    }
    pieces.push(cur);
    pieces
        .into_iter()
        .map(|mut p| {
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-12);
            p
        })
        .filter(|p| p.len() >= 2)
        .collect()
}

/// The lowest branch along `xs` over the branches' pieces `(branch, piece)`.
fn lowest(pieces: &[(Branch, Vec<(f64, f64)>)], xs: &[f64]) -> Lowest {
    let covering = |x: f64| {
        pieces
            .iter()
            .filter(move |(_, p)| x >= p[0].0 && x <= p[p.len() - 1].0)
            .map(move |(b, p)| (*b, cubic_at(p, x), p))
    };
    let mut out = Lowest::default();
    let mut best_pieces = Vec::new();
    for &x in xs {
        if let Some((b, y, p)) = covering(x).min_by(|a, b| a.1.total_cmp(&b.1)) {
            out.points.push((x, b, y));
            best_pieces.push(p);
        }
    }
    for i in 1..out.points.len() {
        let ((x0, b0, _), (x1, b1, _)) = (out.points[i - 1], out.points[i]);
        if b0 == b1 {
            continue;
        }
        let mid = 0.5 * (x0 + x1);
        let cross = crossings(best_pieces[i - 1], best_pieces[i])
            .into_iter()
            .filter(|x| *x >= x0 - 1e-9 && *x <= x1 + 1e-9)
            .min_by(|a, b| (a - mid).abs().total_cmp(&(b - mid).abs()));
        out.changes.push(Change {
            x: cross.unwrap_or(mid),
            below: b0,
            above: b1,
            crossing: cross.is_some(),
        });
    }
    out
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
