//! The sharp-interface reference of a diagram at one reduced spontaneous curvature c̄0: the
//! branches of [`crate::analysis::axisym`] on a fine grid of reduced volumes, interpolated, and
//! their transition volumes.

use super::spec::{Couple, SliceAt, BRANCHES};
use crate::analysis::axisym::{self, Branch, Options};
use crate::analysis::curves::{crossings, cubic_at};
use rayon::prelude::*;

/// Grid spacing in v of the reference curves (the cubic interpolant is then exact to ~1e-8).
const DV: f64 = 0.005;

/// Where no stomatocyte exists (c̄0 ≳ 0.3) its continuation lands on the oblate: a shape on the
/// stomatocyte branch counts when its odd modes exceed this (as in `vesicle axisym --c0`).
pub use crate::analysis::axisym::phase::ASYMMETRIC;

/// Grid spacing in v of an ADE reference (each point a solve of the ADE functional, about 2 s;
/// the cubic interpolant of w(v) on it is exact to ~1e-6).
const DV_ADE: f64 = 0.02;

/// Grid spacing in v of a bilayer-couple reference: a branch at fixed Δa spans a narrow range
/// of v (the prolate ends where c̄0,eff → ∞, 0.02 in v from where it starts at Δa = 1.2).
const DV_BC: f64 = 0.005;

/// The reference branches, each `(v, e)` in increasing v (with ADE, e is w).
#[derive(Clone, Debug)]
pub struct Reference {
    /// Per branch of [`BRANCHES`].
    pub curves: Vec<Vec<(f64, f64)>>,
    /// `(v, Δa)` per branch.
    pub da_curves: Vec<Vec<(f64, f64)>>,
}

/// A transition: where two branches' energies cross.
pub const TRANSITIONS: [(Branch, Branch); 4] = [
    (Branch::Prolate, Branch::Oblate),
    (Branch::Oblate, Branch::Stomatocyte),
    (Branch::Prolate, Branch::Stomatocyte),
    (Branch::Prolate, Branch::Pear),
];

impl Reference {
    /// The reference of the diagram slice `at` over `[v_lo, v_hi]`: [`Reference::new`] at its
    /// c̄0, or with ADE the stationary ADE shape ([`axisym::ade_solution`]) of each branch of
    /// `listed` (the others are left empty: each point is a solve of its own) at α, Δa0 and c̄0
    /// every 0.02 in v, its w and Δa (the stable shape of least w where a branch has several;
    /// none where it has no stable one); with the bilayer couple its shape at Δa
    /// ([`axisym::bc_solution`]) and e, every 0.005 in v.
    pub fn at(at: SliceAt, v_lo: f64, v_hi: f64, listed: &[Branch]) -> Self {
        let Some(couple) = at.couple else {
            return Self::new(at.c0, v_lo, v_hi);
        };
        let dv = match couple {
            Couple::Ade { .. } => DV_ADE,
            Couple::Bc { .. } => DV_BC,
        };
        let lo = (v_lo / dv).floor().max(1.0) as usize;
        let hi = ((v_hi / dv).ceil() as usize).min((0.99 / dv).round() as usize);
        let opts = Options::default().with_c0(at.c0);
        let solved: Vec<Vec<(f64, f64, f64)>> = BRANCHES
            .par_iter()
            .map(|&b| {
                if !listed.contains(&b) {
                    return Vec::new();
                }
                (lo..=hi)
                    .into_par_iter()
                    .filter_map(|i| {
                        let v = i as f64 * dv;
                        let s = match couple {
                            Couple::Ade { alpha, da0 } => {
                                axisym::ade_solution(b, v, alpha, da0, &opts).ok()?
                            }
                            Couple::Bc { da } => axisym::bc_solution(b, v, da, &opts).ok()?,
                        };
                        let keep = b.up_down_symmetric() || s.asymmetry() > ASYMMETRIC;
                        let energy = match couple {
                            Couple::Ade { .. } => s.w,
                            Couple::Bc { .. } => s.e,
                        };
                        keep.then_some((s.v, energy, s.da()))
                    })
                    .collect()
            })
            .collect();
        Self::of_solved(&solved)
    }

    /// Δa of `branch` at `v` (NaN outside the branch).
    pub fn da(&self, branch: Branch, v: f64) -> f64 {
        let i = BRANCHES.iter().position(|b| *b == branch).expect("listed");
        let c = &self.da_curves[i];
        match (c.first(), c.last()) {
            (Some(lo), Some(hi)) if v >= lo.0 && v <= hi.0 && c.len() > 1 => cubic_at(c, v),
            _ => f64::NAN,
        }
    }

    /// Follow every branch at reduced spontaneous curvature `c0` over `[v_lo, v_hi]` (clipped
    /// to (0, 1]) in steps of 0.005; a stomatocyte branch keeps only its up–down asymmetric
    /// shapes ([`ASYMMETRIC`]). The pear's curve is empty: a diagram lists it only with ADE or
    /// the bilayer couple ([`Reference::at`]).
    pub fn new(c0: f64, v_lo: f64, v_hi: f64) -> Self {
        let lo = (v_lo / DV).floor().max(1.0) as usize;
        // Below v = 1, where the prolate and oblate branches meet at the sphere.
        let hi = ((v_hi / DV).ceil() as usize).min((0.995 / DV).round() as usize);
        let vs: Vec<f64> = (lo..=hi).map(|i| i as f64 * DV).collect();
        let opts = Options::default().with_c0(c0);
        let solved: Vec<Vec<(f64, f64, f64)>> = BRANCHES
            .par_iter()
            .map(|&b| {
                if b == Branch::Pear {
                    return Vec::new();
                }
                axisym::follow(b, &vs, &opts)
                    .shapes
                    .iter()
                    .filter(|s| b.up_down_symmetric() || s.asymmetry() > ASYMMETRIC)
                    .map(|s| (s.v, s.e, s.da()))
                    .collect()
            })
            .collect();
        Self::of_solved(&solved)
    }

    /// The reference of `(v, e, Δa)` per branch of [`BRANCHES`].
    fn of_solved(solved: &[Vec<(f64, f64, f64)>]) -> Self {
        Reference {
            curves: solved
                .iter()
                .map(|c| c.iter().map(|p| (p.0, p.1)).collect())
                .collect(),
            da_curves: solved
                .iter()
                .map(|c| c.iter().map(|p| (p.0, p.2)).collect())
                .collect(),
        }
    }

    /// The curve of `branch`.
    pub fn curve(&self, branch: Branch) -> &[(f64, f64)] {
        let i = BRANCHES.iter().position(|b| *b == branch).expect("listed");
        &self.curves[i]
    }

    /// e of `branch` at `v`, NaN outside the computed part of the branch.
    pub fn e(&self, branch: Branch, v: f64) -> f64 {
        let c = self.curve(branch);
        match (c.first(), c.last()) {
            (Some(lo), Some(hi)) if v >= lo.0 && v <= hi.0 => cubic_at(c, v),
            _ => f64::NAN,
        }
    }

    /// Where the two branches cross (empty if they do not on the computed range).
    pub fn transition(&self, a: Branch, b: Branch) -> Vec<f64> {
        crossings(self.curve(a), self.curve(b))
    }

    /// Whether the crossing of `a` and `b` at `v` is a transition: the two branches are the
    /// lowest in energy there (no other branch computed at `v` lies below them). Otherwise it is
    /// a crossing of two metastable branches (prolate/stomatocyte at v ≈ 0.617, below the
    /// oblate branch) and no shape changes there.
    pub fn is_transition(&self, a: Branch, b: Branch, v: f64) -> bool {
        let e = 0.5 * (self.e(a, v) + self.e(b, v));
        e.is_finite()
            && BRANCHES
                .iter()
                .filter(|c| **c != a && **c != b)
                .all(|&c| self.e(c, v).partial_cmp(&e) != Some(std::cmp::Ordering::Less))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At c0 = 0 (Seifert, Berndl & Lipowsky 1991) the prolate/oblate crossing (v ≈ 0.652) and
    /// the oblate/stomatocyte one (v ≈ 0.592) are transitions between the lowest branches; the
    /// prolate and stomatocyte branches cross (v ≈ 0.617) above the oblate one, which is the
    /// ground state there: a crossing of metastable branches, not a transition.
    #[test]
    fn only_crossings_of_the_lowest_branches_are_transitions() {
        let r = Reference::new(0.0, 0.57, 0.68);
        let one = |a, b| match r.transition(a, b).as_slice() {
            [v] => *v,
            other => panic!("{a:?}/{b:?} crossings {other:?}"),
        };
        let po = one(Branch::Prolate, Branch::Oblate);
        let os = one(Branch::Oblate, Branch::Stomatocyte);
        let ps = one(Branch::Prolate, Branch::Stomatocyte);
        assert!((po - 0.652).abs() < 0.005 && (os - 0.592).abs() < 0.005);
        assert!((ps - 0.617).abs() < 0.005, "prolate/stomatocyte at {ps}");
        assert!(r.is_transition(Branch::Prolate, Branch::Oblate, po));
        assert!(r.is_transition(Branch::Oblate, Branch::Stomatocyte, os));
        assert!(!r.is_transition(Branch::Prolate, Branch::Stomatocyte, ps));
    }
}
