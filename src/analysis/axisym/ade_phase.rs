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
    /// Where: the crossing of the two energies (inside the stretch both branches cover), or
    /// the midpoint of the grid interval when they do not cross there (a branch ends or
    /// begins in it, or none exists between the two grid values).
    pub x: f64,
    /// Lowest below `x`.
    pub below: Branch,
    /// Lowest above `x`.
    pub above: Branch,
    /// Whether `x` is an energy crossing, a transition (else a grid midpoint where a branch
    /// ends: no transition).
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

/// The lowest branch along `xs` over the branches' pieces `(branch, piece)`, and where it
/// changes between two grid values from one branch to another: an energy crossing when a
/// piece of the one and a piece of the other cross inside the interval and inside the stretch
/// both pieces cover (no extrapolation past a piece's end; any pieces of the two branches, as
/// a path that turns back briefly splits into pieces of which the lowest at the grid values
/// need not be the ones that cross), else the interval's midpoint marked as no crossing.
fn lowest(pieces: &[(Branch, Vec<(f64, f64)>)], xs: &[f64]) -> Lowest {
    let covers = |p: &[(f64, f64)], x: f64| x >= p[0].0 && x <= p[p.len() - 1].0;
    let mut out = Lowest::default();
    for &x in xs {
        let lowest = pieces
            .iter()
            .filter(|(_, p)| covers(p, x))
            .map(|(b, p)| (*b, cubic_at(p, x)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((b, y)) = lowest {
            out.points.push((x, b, y));
        }
    }
    let of = |branch: Branch| pieces.iter().filter(move |(b, _)| *b == branch);
    for i in 1..out.points.len() {
        let ((x0, b0, _), (x1, b1, _)) = (out.points[i - 1], out.points[i]);
        if b0 == b1 {
            continue;
        }
        let mid = 0.5 * (x0 + x1);
        let cross = of(b0)
            .flat_map(|(_, p0)| of(b1).map(move |(_, p1)| (p0, p1)))
            .flat_map(|(p0, p1)| {
                crossings(p0, p1)
                    .into_iter()
                    .filter(move |x| covers(p0, *x) && covers(p1, *x))
            })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The oblate's piece ends at Δa = 3 and the prolate's starts at 5, their end cubics
    /// extrapolated meeting at 4 (the shape of the BC gap at v = 0.76 the earlier code reported
    /// as an "energies cross" change at Δa = 1.146): the change of the lowest branch is a
    /// branch ending, not a crossing. Where the pieces overlap and cross inside the grid
    /// interval, the change is the crossing.
    #[test]
    fn a_branch_ending_is_no_crossing() {
        let line = |lo: usize, hi: usize, a: f64, b: f64| -> Vec<(f64, f64)> {
            (lo..=hi).map(|i| (i as f64, a + b * i as f64)).collect()
        };
        let xs: Vec<f64> = (0..=8).map(f64::from).collect();
        let gap = lowest(
            &[
                (Branch::Oblate, line(0, 3, 1.0, 0.3)),
                (Branch::Prolate, line(5, 8, 3.0, -0.2)),
            ],
            &xs,
        );
        assert_eq!(gap.points.len(), 8, "nothing at Δa = 4");
        let [c] = gap.changes.as_slice() else {
            panic!("{:?}", gap.changes)
        };
        assert!(!c.crossing && (c.x - 4.0).abs() < 1e-12, "{c:?}");
        assert_eq!((c.below, c.above), (Branch::Oblate, Branch::Prolate));

        let cross = lowest(
            &[
                (Branch::Oblate, line(0, 6, 1.0, 0.3)),
                (Branch::Prolate, line(2, 8, 3.0, -0.2)),
            ],
            &xs,
        );
        let [c] = cross.changes.as_slice() else {
            panic!("{:?}", cross.changes)
        };
        assert!(c.crossing && (c.x - 4.0).abs() < 1e-9, "{c:?}");

        // The prolate's path turns back briefly between 4 and 5, so it is two pieces: the one
        // lowest at x = 5 starts past the crossing at 3.5, which the other covers (the shape of
        // the ADE pear at v = 0.86). Only the lowest pieces at 3 and 5 give no crossing.
        let grid = [0.0, 1.0, 2.0, 3.0, 5.0, 6.0, 7.0, 8.0];
        let split = lowest(
            &[
                (Branch::Oblate, line(0, 6, 1.0, 0.3)),
                (Branch::Prolate, line(1, 4, 2.75, -0.2)),
                (Branch::Prolate, line(5, 8, 2.75, -0.2)),
            ],
            &grid,
        );
        let [c] = split.changes.as_slice() else {
            panic!("{:?}", split.changes)
        };
        assert!(c.crossing && (c.x - 3.5).abs() < 1e-9, "{c:?}");
    }
}
