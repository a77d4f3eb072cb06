//! The sharp-interface reference of the heating continuation: at one reduced volume `v`, the
//! ADE prolate and pear branches of [`crate::analysis::axisym`] against `Δa0`.
//!
//! Each branch is the ADE image of its bilayer-couple path at `v` ([`bc_curve`],
//! [`ade_image`]): a shape of area difference `Δa` and `c̄0,eff` is the stationary ADE shape at
//!
//! ```text
//! Δa0 = Δa + c̄0,eff / (2πα),     w = e + πα (Δa − Δa0)²      (c̄0 = 0)
//! ```
//!
//! and it is stable against changes of `Δa` where the image runs forward (`dΔa0/dΔa > 0`).
//! The pear path clusters its modes at the neck below 0.1 R0, so it reaches a neck of
//! [`NECK_MIN`]. The transition is continuous when the stable pear starts where it leaves
//! the prolate (the pear's smallest stable `Δa0`, its fold, is the bifurcation) and
//! discontinuous when the pear's stable stretch starts below the bifurcation (a subcritical
//! pitchfork): then the two stable branches coexist and the lowest `w` changes where their
//! energies cross, with a jump in `Δa` and in the neck.

use crate::analysis::axisym::{ade_da0, ade_image, bc_curve, l_pear_at, Branch, Options, Solution};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The pear branch is followed down to this neck (units of R0).
pub const NECK_MIN: f64 = 0.005;

/// The window in `Δa` of the BC paths (the prolate and pear at v ≥ 0.8 lie inside it).
const DA_WINDOW: (f64, f64) = (1.0, 1.45);

/// Step of the scan in `Δa0` for the crossing of the two branches' energies.
const SCAN: f64 = 1e-4;

/// One stationary ADE shape of a branch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Preferred area difference at which it is stationary.
    pub da0: f64,
    /// Its area difference.
    pub da: f64,
    /// `w = e + πα(Δa − Δa0)²`.
    pub w: f64,
    /// Its bending energy `e`.
    pub e: f64,
    /// `c̄0,eff = 2πα(Δa0 − Δa)`.
    pub c0_eff: f64,
    /// Narrowest neck (a pear's neck, a prolate's waist; units of R0; NaN without one).
    pub neck: f64,
    /// Whether the image runs forward there (a local minimum of w in Δa).
    pub stable: bool,
}

/// The reference at one `v`: the two branches in path order and where the pear takes over.
#[derive(Clone, Debug)]
pub struct Sharp {
    /// Reduced volume.
    pub v: f64,
    /// α = κ̄/κ.
    pub alpha: f64,
    /// The prolate's ADE image.
    pub prolate: Vec<Point>,
    /// The pear's ADE image, from its bifurcation both ways.
    pub pear: Vec<Point>,
    /// `Δa0` where the pear leaves the prolate (the prolate's up–down mode softens there).
    pub bifurcation: f64,
    /// Smallest `Δa0` of the stable pear (its fold; NaN without a stable pear).
    pub fold: f64,
    /// `Δa0` where the stable pear's `w` crosses the stable prolate's (NaN: no crossing).
    pub transition: f64,
    /// `Δa0` of the budding limit `L_pear` at `v` (where the pear's neck closes).
    pub l_pear: f64,
}

/// Reading of one branch at one `Δa0` (NaN off its stable stretch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// `w` of the lowest stable shape at this `Δa0`.
    pub w: f64,
    /// Its neck (units of R0).
    pub neck: f64,
    /// Its `Δa`.
    pub da: f64,
}

impl Reading {
    const NONE: Reading = Reading {
        w: f64::NAN,
        neck: f64::NAN,
        da: f64::NAN,
    };
}

impl Sharp {
    /// The prolate and pear paths at `v` for `α = alpha` with `nodes` quadrature nodes
    /// (`K = (nodes − 1)/3` modes), the two branches computed in parallel.
    pub fn at(v: f64, alpha: f64, nodes: usize) -> Self {
        let mut opts = Options::with_nodes(nodes);
        opts.neck_min = NECK_MIN;
        let curves: Vec<_> = [Branch::Prolate, Branch::Pear]
            .par_iter()
            .map(|&b| bc_curve(b, v, DA_WINDOW, &opts))
            .collect();
        let points = |shapes: &[Solution]| -> Vec<Point> {
            ade_image(shapes, alpha)
                .iter()
                .zip(shapes)
                .map(|(p, s)| Point {
                    da0: p.da0,
                    da: p.da,
                    w: p.w,
                    e: p.e,
                    c0_eff: p.c0_eff,
                    neck: s.neck().unwrap_or(f64::NAN),
                    stable: p.stable,
                })
                .collect()
        };
        let prolate = points(&curves[0].shapes);
        let pear = points(&curves[1].shapes);
        let bifurcation = curves[1]
            .bifurcation
            .as_ref()
            .map_or(f64::NAN, |s| ade_da0(s.c0, alpha, s.da(), s.c0_eff));
        let fold = pear
            .iter()
            .filter(|p| p.stable)
            .map(|p| p.da0)
            .fold(f64::NAN, f64::min);
        let mut sharp = Sharp {
            v,
            alpha,
            prolate,
            pear,
            bifurcation,
            fold,
            transition: f64::NAN,
            l_pear: l_pear_at(v).map_or(f64::NAN, |l| l.da0(alpha, 0.0)),
        };
        sharp.transition = sharp.crossing();
        sharp
    }

    /// The stable prolate at `da0`.
    pub fn prolate_at(&self, da0: f64) -> Reading {
        read(&self.prolate, da0, self.alpha)
    }

    /// The stable pear at `da0`.
    pub fn pear_at(&self, da0: f64) -> Reading {
        read(&self.pear, da0, self.alpha)
    }

    /// The last pear state of the path with the narrowest neck: `(Δa0, neck)`.
    pub fn narrowest(&self) -> (f64, f64) {
        self.pear
            .iter()
            .filter(|p| p.stable && p.neck.is_finite())
            .min_by(|a, b| a.neck.total_cmp(&b.neck))
            .map_or((f64::NAN, f64::NAN), |p| (p.da0, p.neck))
    }

    /// Whether the transition is continuous: the stable pear begins at the bifurcation
    /// (within `tol` in `Δa0`) instead of below it.
    pub fn continuous(&self, tol: f64) -> bool {
        self.fold >= self.bifurcation - tol
    }

    /// The first `Δa0`, scanned upwards from the pear's fold in steps of [`SCAN`] and refined
    /// linearly, where `w_prolate − w_pear` turns positive; the fold itself if the pear is
    /// already the lower where it appears.
    fn crossing(&self) -> f64 {
        if !self.fold.is_finite() {
            return f64::NAN;
        }
        let gap = |x: f64| self.prolate_at(x).w - self.pear_at(x).w;
        let hi = self.pear.iter().map(|p| p.da0).fold(f64::NAN, f64::max);
        let mut prev: Option<(f64, f64)> = None;
        let mut x = self.fold;
        while x <= hi {
            let g = gap(x);
            if g.is_finite() {
                match prev {
                    None if g >= 0.0 => return x,
                    Some((x0, g0)) if g0 < 0.0 && g >= 0.0 => return x0 + (x - x0) * g0 / (g0 - g),
                    _ => prev = Some((x, g)),
                }
            }
            x += SCAN;
        }
        f64::NAN
    }
}

/// The lowest stable state of `path` at `da0` for `α = alpha`: `e`, `Δa` and the neck
/// interpolated linearly in `Δa0` between two consecutive stable points that bracket it, and
/// `w = e + πα(Δa − Δa0)²` evaluated there (the penalty is quadratic in `Δa0` while `Δa` is
/// nearly constant: near v = 1 the prolate's points lie 0.2 apart in `Δa0`);
/// [`Reading::NONE`] if none bracket it.
fn read(path: &[Point], da0: f64, alpha: f64) -> Reading {
    path.windows(2)
        .filter(|p| p[0].stable && p[1].stable && (p[0].da0 - da0) * (p[1].da0 - da0) <= 0.0)
        .filter(|p| p[0].da0 != p[1].da0)
        .map(|p| {
            let f = (da0 - p[0].da0) / (p[1].da0 - p[0].da0);
            let lerp = |a: f64, b: f64| a + f * (b - a);
            let da = lerp(p[0].da, p[1].da);
            Reading {
                w: lerp(p[0].e, p[1].e) + PI * alpha * (da - da0).powi(2),
                neck: lerp(p[0].neck, p[1].neck),
                da,
            }
        })
        .min_by(|a, b| a.w.total_cmp(&b.w))
        .unwrap_or(Reading::NONE)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(da0: f64, w: f64, neck: f64, stable: bool) -> Point {
        // Δa = Δa0: no penalty, w = e.
        Point {
            da0,
            da: da0,
            w,
            e: w,
            c0_eff: 0.0,
            neck,
            stable,
        }
    }

    /// A subcritical pear: it leaves the prolate at Δa0 = 1.7 (unstable, running back to a fold
    /// at 1.5), then runs forward, stable, with w rising by 2 per unit Δa0 from 2.0; the
    /// prolate's w rises by 4 per unit from 1.8 at Δa0 = 1.5. The energies cross where
    /// 1.8 + 4x = 2.0 + 2x, x = 0.1: Δa0 = 1.6; discontinuous (fold 0.2 below the
    /// bifurcation); the pear reads halfway between its points at 1.55.
    #[test]
    fn the_crossing_and_the_fold_of_a_subcritical_pear() {
        let sharp = Sharp {
            v: 0.85,
            alpha: 1.4,
            prolate: vec![pt(1.4, 1.4, 0.6, true), pt(1.8, 3.0, 0.5, true)],
            pear: vec![
                pt(1.7, 3.0, 0.6, false),
                pt(1.5, 2.0, 0.2, true),
                pt(1.6, 2.2, 0.1, true),
                pt(1.8, 2.6, 0.01, true),
            ],
            bifurcation: 1.7,
            fold: 1.5,
            transition: f64::NAN,
            l_pear: 1.9,
        };
        assert!(
            (sharp.crossing() - 1.6).abs() < 1e-9,
            "{}",
            sharp.crossing()
        );
        assert!(!sharp.continuous(0.01));
        let r = sharp.pear_at(1.55);
        assert!((r.w - 2.1).abs() < 1e-12 && (r.neck - 0.15).abs() < 1e-12);
        assert!(sharp.prolate_at(1.9).w.is_nan());
        assert_eq!(sharp.narrowest(), (1.8, 0.01));
    }
}
