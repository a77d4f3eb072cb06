//! The (v, c̄0) shape diagram of the spontaneous-curvature model: for each c̄0 ([`slice()`]) the
//! prolate, oblate and stomatocyte branches on the grid of `v`, the pear branch from its
//! bifurcation off the prolate to the budding limit, the lowest-energy branch along `v` and
//! where it changes (`vesicle axisym --c0 LIST` writes it as CSV and draws the phase diagram).

use super::pear::{follow_pear, PearBranch};
use super::{branch_end, follow, Branch, Options, Solution};
use crate::analysis::curves::{crossings, cubic_at};
use rayon::prelude::*;

/// Odd-mode size `√Σ_{k odd} a_k²` above which a shape counts as up–down asymmetric.
pub const ASYMMETRIC: f64 = 1e-6;

/// A change of the lowest-energy branch between two grid values.
#[derive(Clone, Copy, Debug)]
pub struct Transition {
    /// Where: the crossing of the two energies, or the midpoint of the grid interval when they
    /// do not cross there (one branch ends, as the prolate at its pinch).
    pub v: f64,
    /// Lowest below `v`.
    pub below: Branch,
    /// Lowest above `v`.
    pub above: Branch,
    /// Whether `v` is an energy crossing (else a grid midpoint).
    pub crossing: bool,
}

/// Everything computed at one c̄0.
#[derive(Clone, Debug)]
pub struct Slice {
    /// Reduced spontaneous curvature.
    pub c0: f64,
    /// Prolate, oblate, stomatocyte shapes on the grid (per [`Branch::ALL`]), increasing `v`.
    pub curves: Vec<Vec<Solution>>,
    /// The pear branch in the order of its path from the bifurcation.
    pub pear: PearBranch,
    /// The lowest-energy branch at each grid value `(v, branch)` where any branch exists.
    pub lowest: Vec<(f64, Branch)>,
    /// Where the lowest-energy branch changes.
    pub transitions: Vec<Transition>,
    /// Upper limit point of the stomatocyte branch, if found.
    pub stomatocyte_end: Option<f64>,
    /// First self-contact of the oblate branch, if found.
    pub oblate_contact: Option<f64>,
}

/// The pear path split into pieces monotone in `v`, each as `(v, e)` increasing in `v`.
fn pear_pieces(pear: &PearBranch) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut dir = 0.0;
    for s in &pear.shapes {
        if let Some(&(v_last, _)) = cur.last() {
            let d = (s.v - v_last).signum();
            if dir != 0.0 && d != dir {
                let last = *cur.last().expect("non-empty");
                pieces.push(std::mem::take(&mut cur));
                cur.push(last);
            }
            dir = d;
        }
        cur.push((s.v, s.w));
    }
    pieces.push(cur);
    pieces
        .into_iter()
        .filter(|p| p.len() >= 2)
        .map(|mut p| {
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p.dedup_by(|a, b| a.0 == b.0);
            p
        })
        .collect()
}

/// The candidate energies at `v`: each branch's grid value there, and the pear pieces that
/// cover `v` (interpolated by local cubics).
fn energies_at(v: f64, curves: &[Vec<Solution>], pieces: &[Vec<(f64, f64)>]) -> Vec<(Branch, f64)> {
    let mut out: Vec<(Branch, f64)> = Branch::ALL
        .iter()
        .zip(curves)
        .filter_map(|(b, c)| c.iter().find(|s| (s.v - v).abs() < 1e-9).map(|s| (*b, s.w)))
        .collect();
    for p in pieces {
        if v >= p[0].0 && v <= p[p.len() - 1].0 {
            out.push((Branch::Pear, cubic_at(p, v)));
        }
    }
    out
}

/// The points `(v, e)` of `branch` that can be crossed with another curve near `v`.
fn points_near(
    branch: Branch,
    v: f64,
    curves: &[Vec<Solution>],
    pieces: &[Vec<(f64, f64)>],
) -> Vec<(f64, f64)> {
    match branch {
        // Of the pieces that cover v, the lowest there (past a subcritical fold the pear's
        // upper piece, from the bifurcation to the fold, covers v too).
        Branch::Pear => pieces
            .iter()
            .filter(|p| v >= p[0].0 && v <= p[p.len() - 1].0)
            .min_by(|a, b| cubic_at(a, v).total_cmp(&cubic_at(b, v)))
            .or_else(|| {
                pieces
                    .iter()
                    .find(|p| v >= p[0].0 - 0.02 && v <= p[p.len() - 1].0 + 0.02)
            })
            .cloned()
            .unwrap_or_default(),
        b => {
            let i = Branch::ALL.iter().position(|x| *x == b).expect("listed");
            curves[i].iter().map(|s| (s.v, s.w)).collect()
        }
    }
}

/// Compute the slice at `c0` on the grid `vs`.
pub fn slice(c0: f64, vs: &[f64], opts: &Options) -> Slice {
    let opts = opts.with_c0(c0);
    let v_floor = vs.iter().copied().fold(1.0, f64::min);
    let (followed, pear) = rayon::join(
        || {
            Branch::ALL
                .par_iter()
                .map(|&b| follow(b, vs, &opts))
                .collect::<Vec<_>>()
        },
        || follow_pear(v_floor, &opts),
    );
    // Where no stomatocyte exists (large c̄0) its sphere-in-sphere start descends to the
    // oblate: shapes without up–down asymmetry are not stomatocytes.
    let curves: Vec<Vec<Solution>> = followed
        .iter()
        .map(|f| {
            f.shapes
                .iter()
                .filter(|s| s.branch.up_down_symmetric() || s.asymmetry() > ASYMMETRIC)
                .cloned()
                .collect()
        })
        .collect();
    let pieces = pear_pieces(&pear);
    let mut lowest = Vec::new();
    for &v in vs {
        let best = energies_at(v, &curves, &pieces)
            .into_iter()
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((b, _)) = best {
            lowest.push((v, b));
        }
    }
    let mut transitions = Vec::new();
    for w in lowest.windows(2) {
        let ((v0, b0), (v1, b1)) = (w[0], w[1]);
        if b0 == b1 {
            continue;
        }
        let mid = 0.5 * (v0 + v1);
        let cross = crossings(
            &points_near(b0, mid, &curves, &pieces),
            &points_near(b1, mid, &curves, &pieces),
        )
        .into_iter()
        .filter(|x| *x >= v0 - 1e-9 && *x <= v1 + 1e-9)
        .min_by(|a, b| (a - mid).abs().total_cmp(&(b - mid).abs()));
        transitions.push(Transition {
            v: cross.unwrap_or(mid),
            below: b0,
            above: b1,
            crossing: cross.is_some(),
        });
    }
    let end_of = |b: Branch| {
        let i = Branch::ALL.iter().position(|x| *x == b).expect("listed");
        followed[i].end.or_else(|| branch_end(b, &opts))
    };
    Slice {
        c0,
        stomatocyte_end: end_of(Branch::Stomatocyte),
        oblate_contact: end_of(Branch::Oblate),
        curves,
        pear,
        lowest,
        transitions,
    }
}
