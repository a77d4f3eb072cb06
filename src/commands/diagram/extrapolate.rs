//! From the cases of a diagram to its best estimates. Each point `(branch, v₀)` computed at
//! several x = ε/R0 is extrapolated to x → 0 in both of its coordinates,
//!
//! ```text
//! v(x) = v∞ + c_v x^{p_v},   e(x) = e∞ + c_e x^{p_e},
//! ```
//!
//! with the orders `p_v`, `p_e` shared by all points of the diagram (of every c̄0) and fitted by least squares
//! ([`crate::analysis::curves::common_order`]), and `v∞`, `e∞` by a least-squares fit per point at those
//! orders ([`crate::analysis::curves::power_fit`]). Both coordinates move: at finite ε the φ = 0 surface
//! relaxes to another reduced volume than the sharp start's (by about 0.01 at R0 = 24ε), so
//! the pair `(v(x), e(x))` slides along the branch as it converges, and `(v∞, e∞)` is the
//! point's sharp-interface estimate.
//!
//! **Pre-asymptotic resolutions are left out.** Where two sheets of the membrane come within a
//! few ε of each other (an oblate's centre near v = 0.59 is 0.22 R0 thick: 5.4ε at R0 = 24ε)
//! their profiles merge and e jumps by several percent instead of converging. A resolution
//! whose e differs from the next finer one's by more than [`JUMP`] is dropped (with every
//! coarser one); the point is then fitted from the rest at the shared orders.

use super::case::CaseResult;
use super::spec::SliceAt;
use crate::analysis::curves::{common_order, power_fit};

/// Largest relative change of e from one resolution to the next finer one that counts as
/// convergence (consecutive resolutions of the committed diagram differ by at most 1.4%
/// elsewhere).
pub const JUMP: f64 = 0.02;

/// One point of the diagram: a branch at a target reduced volume, at every resolution.
#[derive(Clone, Debug)]
pub struct Point {
    /// Branch name.
    pub branch: String,
    /// Target reduced volume v₀ (the sharp start's).
    pub v_target: f64,
    /// The cases used in the fit, in increasing R0/ε.
    pub cases: Vec<CaseResult>,
    /// Coarser cases left out as pre-asymptotic.
    pub dropped: Vec<CaseResult>,
    /// Extrapolated reduced volume `v∞`.
    pub v: f64,
    /// Extrapolated reduced energy `e∞` (w with ADE).
    pub e: f64,
    /// Extrapolated Δa∞ of the phase field's functional at order [`DA_ORDER`] (ADE and the
    /// bilayer couple; NaN otherwise).
    pub da: f64,
    /// Extrapolated Δa∞ of the φ = 0 surface at order [`DA_ORDER`] (NaN where a case lacks
    /// it).
    pub da_surface: f64,
}

/// The order in ε/R0 Δa is extrapolated at, the functional's and the φ = 0 surface's: the
/// profile's curvature correction, (ε/R)² (the functional's on the spheres of tests/ade.rs
/// gives 1.8). The surface's Δa is exact on a sphere; elsewhere the relaxed profile moves its
/// φ = 0 level by O(ε²κ). (A common order fitted over the bilayer-couple diagram's points runs
/// to the search's bound 0.5: at R0 ≤ 40ε the surface's series are not yet asymptotic.)
pub const DA_ORDER: f64 = 2.0;

impl Point {
    /// The finest-resolution case.
    pub fn finest(&self) -> &CaseResult {
        self.cases.last().expect("a point has cases")
    }

    /// `(ε/R0, quantity)` of the cases used.
    fn series(&self, get: fn(&CaseResult) -> f64) -> (Vec<f64>, Vec<f64>) {
        (
            self.cases.iter().map(|c| 1.0 / c.r0).collect(),
            self.cases.iter().map(get).collect(),
        )
    }
}

/// The fitted orders.
#[derive(Clone, Copy, Debug)]
pub struct Orders {
    /// Order of the φ = 0 reduced volume in ε/R0.
    pub v: f64,
    /// Order of the reduced energy in ε/R0.
    pub e: f64,
}

/// Split `cases` (increasing R0) into the pre-asymptotic coarsest ones and the rest.
fn split(mut cases: Vec<CaseResult>) -> (Vec<CaseResult>, Vec<CaseResult>) {
    let mut dropped = Vec::new();
    while cases.len() >= 2 && (cases[0].e / cases[1].e - 1.0).abs() > JUMP {
        dropped.push(cases.remove(0));
    }
    (dropped, cases)
}

/// Group `results` into points (slice, branch and target v; cases in increasing R0) and leave
/// out the pre-asymptotic resolutions; `v` and `e` are not yet extrapolated (NaN).
fn group(results: &[CaseResult]) -> Vec<Point> {
    let mut groups: Vec<(SliceAt, String, f64, Vec<CaseResult>)> = Vec::new();
    for r in results {
        match groups
            .iter_mut()
            .find(|g| g.0 == r.slice() && g.1 == r.branch && g.2 == r.v_target)
        {
            Some(g) => g.3.push(r.clone()),
            None => groups.push((r.slice(), r.branch.clone(), r.v_target, vec![r.clone()])),
        }
    }
    groups
        .into_iter()
        .map(|(_, branch, v_target, mut cases)| {
            cases.sort_by(|a, b| a.r0.total_cmp(&b.r0));
            let (dropped, cases) = split(cases);
            Point {
                branch,
                v_target,
                cases,
                dropped,
                v: f64::NAN,
                e: f64::NAN,
                da: f64::NAN,
                da_surface: f64::NAN,
            }
        })
        .collect()
}

/// The orders in ε/R0 shared by every point of `results` (of every c̄0). `None` if they cannot
/// be fitted (no point keeps three resolutions).
pub fn orders(results: &[CaseResult]) -> Option<Orders> {
    let points = group(results);
    let fitted = |get: fn(&CaseResult) -> f64| {
        let series: Vec<_> = points.iter().map(|p| p.series(get)).collect();
        common_order(&series)
    };
    Some(Orders {
        v: fitted(|c| c.v)?,
        e: fitted(|c| c.e)?,
    })
}

/// Group `results` into points, leave out the pre-asymptotic resolutions and extrapolate each
/// point at the shared `orders` ([`orders`]).
pub fn extrapolate(results: &[CaseResult], orders: Orders) -> Vec<Point> {
    let mut points = group(results);
    for p in &mut points {
        let at = |get: fn(&CaseResult) -> f64, order: f64| {
            let (x, y) = p.series(get);
            if x.len() < 2 {
                y[0]
            } else {
                power_fit(order, &x, &y).0
            }
        };
        let da = at(|c| c.da.unwrap_or(f64::NAN), DA_ORDER);
        let da_surface = at(|c| c.da_surface.unwrap_or(f64::NAN), DA_ORDER);
        (p.v, p.e, p.da, p.da_surface) =
            (at(|c| c.v, orders.v), at(|c| c.e, orders.e), da, da_surface);
    }
    points
}
