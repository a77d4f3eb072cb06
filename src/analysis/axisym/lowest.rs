//! The lowest-energy branch along a grid and where it changes, shared by the spontaneous-curvature
//! `(v, c̄0)` chart ([`super::phase`], grid in `v`) and the bilayer-couple and ADE charts
//! ([`super::ade_phase`], grid in `Δa` or `Δa0`). Each branch enters as pieces `(x, energy)`
//! monotone in `x` ([`monotone_pieces`], [`grid_pieces`]); [`lowest`] picks the lowest piece at
//! each grid value and calls a change of the lowest branch a transition only where a piece of
//! the one branch and a piece of the other cross inside the stretch both cover. Every other
//! change (a branch ends or begins inside the grid interval) is no transition.

use super::Branch;
use crate::analysis::curves::{crossings, cubic_at};

/// A change of the lowest-energy branch between two grid values of `x` (`v`, `Δa` or `Δa0`).
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

/// The lowest-energy branch along a grid.
#[derive(Clone, Debug, Default)]
pub struct Lowest {
    /// `(x, branch, energy)` at each grid value where some branch exists.
    pub points: Vec<(f64, Branch, f64)>,
    /// Where the lowest branch changes.
    pub changes: Vec<Change>,
}

/// A path `(x, y)` split into pieces monotone in `x`, each sorted by `x` (pieces of fewer than
/// two points dropped).
pub fn monotone_pieces(path: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
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

/// Points `(x, y)` at values of the grid `xs` (increasing `x`, each within 1e-9 of its grid
/// value) split into pieces of consecutive grid values, each point placed at its grid value
/// (points off the grid dropped): no piece bridges a grid value where the branch has no point.
/// A lone point (its neighbours on the grid missing) is a piece of its own, the branch's
/// energy at that grid value, on which no crossing can lie.
pub fn grid_pieces(points: &[(f64, f64)], xs: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut prev: Option<usize> = None;
    for &(x, y) in points {
        let Some(i) = xs.iter().position(|g| (g - x).abs() < 1e-9) else {
            continue;
        };
        match pieces.last_mut() {
            Some(cur) if prev.is_some_and(|a| a + 1 == i) => cur.push((xs[i], y)),
            _ => pieces.push(vec![(xs[i], y)]),
        }
        prev = Some(i);
    }
    pieces
}

/// The lowest branch along `xs` over the branches' pieces `(branch, piece)`, and where it
/// changes between two grid values from one branch to another: an energy crossing when a
/// piece of the one and a piece of the other cross inside the interval and inside the stretch
/// both pieces cover (no extrapolation past a piece's end; any pieces of the two branches, as
/// a path that turns back briefly splits into pieces of which the lowest at the grid values
/// need not be the ones that cross), else the interval's midpoint marked as no crossing.
/// Energies between a piece's points are its local cubics ([`cubic_at`]); a piece of one point
/// counts only at its own `x` and has no crossing.
pub fn lowest(pieces: &[(Branch, Vec<(f64, f64)>)], xs: &[f64]) -> Lowest {
    let covers = |p: &[(f64, f64)], x: f64| x >= p[0].0 && x <= p[p.len() - 1].0;
    let mut out = Lowest::default();
    for &x in xs {
        let lowest = pieces
            .iter()
            .filter(|(_, p)| !p.is_empty() && covers(p, x))
            .map(|(b, p)| (*b, cubic_at(p, x)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((b, y)) = lowest {
            out.points.push((x, b, y));
        }
    }
    let of = |branch: Branch| {
        pieces
            .iter()
            .filter(move |(b, p)| *b == branch && p.len() >= 2)
    };
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

    /// The spontaneous-curvature chart's path (`phase::slice`): branches on a grid of `v`
    /// ([`grid_pieces`]) and a pear path with a subcritical fold ([`monotone_pieces`]), shaped
    /// as the c̄0 = 3 slice of `runs/results/axisym_c0`. The oblate ends at 0.70 and the
    /// prolate begins at 0.71, their end lines meeting at 0.705 if extrapolated: a branch
    /// ending. The pear's upper piece (bifurcation 0.7525 to the fold 0.89) lies above the
    /// prolate; its lower piece (0.89 back to 0.77, where the continuation stopped) is lowest
    /// from 0.77 and crosses the prolate at 0.8235: a branch beginning between 0.76 and 0.77,
    /// then a transition. The oblate missing at the grid value 0.65 leaves nothing there and
    /// no change around it.
    #[test]
    fn the_spontaneous_curvature_path() {
        let xs: Vec<f64> = (0..40).map(|i| 0.6 + 0.01 * f64::from(i)).collect();
        let on = |lo: f64, hi: f64, e: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
            xs.iter()
                .filter(|v| **v > lo - 1e-9 && **v < hi + 1e-9 && (**v - 0.65).abs() > 1e-9)
                .map(|&v| (v, e(v)))
                .collect()
        };
        let oblate = on(0.6, 0.7, &|v| 1.0 - 2.0 * (v - 0.705));
        let prolate = on(0.71, 0.99, &|_| 1.0);
        let mut pear: Vec<(f64, f64)> = (0..=11)
            .map(|k| 0.7525 + 0.0125 * f64::from(k))
            .map(|v| (v, 1.0 + 0.95 * (v - 0.7525)))
            .collect();
        pear.extend(
            (1..=12)
                .map(|k| 0.89 - 0.01 * f64::from(k))
                .map(|v| (v, 1.0 + 2.0 * (v - 0.8235))),
        );

        let grid = grid_pieces(&oblate, &xs);
        assert_eq!(grid.len(), 2, "split at 0.65: {grid:?}");
        assert_eq!(
            grid[1][0].0.to_bits(),
            xs[6].to_bits(),
            "placed on the grid"
        );
        let pear = monotone_pieces(&pear);
        assert_eq!(pear.len(), 2, "upper and lower piece");
        let mut pieces: Vec<(Branch, Vec<(f64, f64)>)> =
            grid.into_iter().map(|p| (Branch::Oblate, p)).collect();
        pieces.extend(
            grid_pieces(&prolate, &xs)
                .into_iter()
                .map(|p| (Branch::Prolate, p)),
        );
        pieces.extend(pear.into_iter().map(|p| (Branch::Pear, p)));
        let l = lowest(&pieces, &xs);

        assert_eq!(l.points.len(), 39, "nothing at 0.65");
        assert!(l.points.iter().all(|(v, _, _)| (v - 0.65).abs() > 1e-9));
        let of = |v: f64| {
            l.points
                .iter()
                .find(|p| (p.0 - v).abs() < 1e-9)
                .map(|p| p.1)
        };
        assert_eq!(of(0.76), Some(Branch::Prolate));
        assert_eq!(of(0.77), Some(Branch::Pear));
        assert_eq!(of(0.83), Some(Branch::Prolate));
        let [a, b, c] = l.changes.as_slice() else {
            panic!("{:?}", l.changes)
        };
        assert_eq!((a.below, a.above), (Branch::Oblate, Branch::Prolate));
        assert!(!a.crossing && (a.x - 0.705).abs() < 1e-12, "{a:?}");
        assert_eq!((b.below, b.above), (Branch::Prolate, Branch::Pear));
        assert!(!b.crossing && (b.x - 0.765).abs() < 1e-12, "{b:?}");
        assert_eq!((c.below, c.above), (Branch::Pear, Branch::Prolate));
        assert!(c.crossing && (c.x - 0.8235).abs() < 1e-9, "{c:?}");
    }

    /// Off-grid points are dropped, a lone point is a piece of its own (its energy at that
    /// grid value, no crossing), and a piece ends where the next point skips a grid value.
    #[test]
    fn grid_pieces_follow_the_grid() {
        let xs = [0.1, 0.2, 0.3, 0.4, 0.5];
        let p = grid_pieces(
            &[(0.1, 1.0), (0.2 + 1e-12, 2.0), (0.25, 9.0), (0.4, 4.0)],
            &xs,
        );
        assert_eq!(p, vec![vec![(0.1, 1.0), (0.2, 2.0)], vec![(0.4, 4.0)]]);
        let l = lowest(&[(Branch::Oblate, p[1].clone())], &xs);
        assert_eq!(l.points, vec![(0.4, Branch::Oblate, 4.0)]);
    }
}
