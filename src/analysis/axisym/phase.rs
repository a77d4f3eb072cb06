//! The (v, c̄0) shape diagram of the spontaneous-curvature model: for each c̄0 ([`slice()`]) the
//! prolate, oblate and stomatocyte branches on the grid of `v`, the pear branch from its
//! bifurcation off the prolate to the budding limit, the lowest-energy branch along `v` and
//! where it changes (by the logic the bilayer-couple and ADE charts share, [`super::lowest`]:
//! a transition only where two branches cross inside the stretch both cover), which
//! `vesicle axisym --c0 LIST` writes as CSV and draws as the phase diagram.

use super::lowest::{grid_pieces, lowest, monotone_pieces, Lowest};
use super::pear::{follow_pear, PearBranch};
use super::{branch_end, follow, Branch, Options, Solution};
use rayon::prelude::*;

/// Odd-mode size `√Σ_{k odd} a_k²` above which a shape counts as up–down asymmetric.
pub const ASYMMETRIC: f64 = 1e-6;

/// Everything computed at one c̄0.
#[derive(Clone, Debug)]
pub struct Slice {
    /// Reduced spontaneous curvature.
    pub c0: f64,
    /// Prolate, oblate, stomatocyte shapes on the grid (per [`Branch::ALL`]), increasing `v`.
    pub curves: Vec<Vec<Solution>>,
    /// The pear branch in the order of its path from the bifurcation.
    pub pear: PearBranch,
    /// The lowest-energy branch along the grid ([`lowest()`], `x` = `v`, energy `w`) and where
    /// it changes: a transition where two branches' energies cross, else a branch ending.
    pub lowest: Lowest,
    /// Upper limit point of the stomatocyte branch, if found.
    pub stomatocyte_end: Option<f64>,
    /// First self-contact of the oblate branch, if found.
    pub oblate_contact: Option<f64>,
}

/// The pieces `(branch, (v, w))` of the slice's branches: each grid curve split at missing
/// grid values ([`grid_pieces`]), the pear path split where it turns in `v`
/// ([`monotone_pieces`]: past a subcritical fold its upper and lower pieces cover the same `v`).
fn pieces(
    curves: &[Vec<Solution>],
    pear: &PearBranch,
    vs: &[f64],
) -> Vec<(Branch, Vec<(f64, f64)>)> {
    let vw = |shapes: &[Solution]| shapes.iter().map(|s| (s.v, s.w)).collect::<Vec<_>>();
    let mut grid: Vec<f64> = vs.to_vec();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    Branch::ALL
        .iter()
        .zip(curves)
        .flat_map(|(b, c)| grid_pieces(&vw(c), &grid).into_iter().map(|p| (*b, p)))
        .chain(
            monotone_pieces(&vw(&pear.shapes))
                .into_iter()
                .map(|p| (Branch::Pear, p)),
        )
        .collect()
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
    let lowest = lowest(&pieces(&curves, &pear, vs), vs);
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
    }
}
