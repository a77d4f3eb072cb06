//! From the cases of a diagram to its best estimates, at the target reduced volumes.
//!
//! At finite ε the φ = 0 surface relaxes to another reduced volume than the sharp start's
//! (by about 0.01 at R0 = 24ε), so the energies of one point at different resolutions are at
//! different v. They are first brought to the target v₀ along their own resolution's branch:
//! `e_k(v₀)` is the cubic through the four nearest points of resolution k on that branch
//! ([`crate::curves::cubic_at`]). Then, with x = ε/R0,
//!
//! ```text
//! e_k(v₀) = e∞(v₀) + c xₖ^p,
//! ```
//!
//! the order p shared by every point of the diagram fitted by least squares
//! ([`crate::curves::common_order`]) and `e∞`, `c` per point ([`crate::curves::power_fit`]).

use super::case::CaseResult;
use crate::curves::{common_order, cubic_at, power_fit};

/// One point of the diagram: a branch at a target reduced volume, at every resolution.
#[derive(Clone, Debug)]
pub struct Point {
    /// Branch name.
    pub branch: String,
    /// Target reduced volume v₀.
    pub v: f64,
    /// The cases, in increasing R0/ε.
    pub cases: Vec<CaseResult>,
    /// `e_k(v₀)` of each case (same order).
    pub e_at_target: Vec<f64>,
    /// Extrapolated reduced energy `e∞(v₀)`.
    pub e: f64,
}

impl Point {
    /// The finest-resolution case.
    pub fn finest(&self) -> &CaseResult {
        self.cases.last().expect("a point has cases")
    }
}

/// The energy of `case` brought to its target v along the branch of its resolution in
/// `results` (the cubic through the nearest four of that branch's `(v, e)`).
fn at_target(case: &CaseResult, results: &[CaseResult]) -> f64 {
    let mut branch: Vec<(f64, f64)> = results
        .iter()
        .filter(|r| r.branch == case.branch && r.r0 == case.r0)
        .map(|r| (r.v, r.e))
        .collect();
    branch.sort_by(|a, b| a.0.total_cmp(&b.0));
    cubic_at(&branch, case.v_target)
}

/// Group `results` into points (branch and target v; cases in increasing R0), bring each
/// case to its target v and extrapolate: the points and the fitted order p. `None` if the
/// order cannot be fitted (fewer than three resolutions).
pub fn extrapolate(results: &[CaseResult]) -> Option<(Vec<Point>, f64)> {
    let mut points: Vec<Point> = Vec::new();
    for r in results {
        let e = at_target(r, results);
        match points
            .iter_mut()
            .find(|p| p.branch == r.branch && p.v == r.v_target)
        {
            Some(p) => {
                p.cases.push(r.clone());
                p.e_at_target.push(e);
            }
            None => points.push(Point {
                branch: r.branch.clone(),
                v: r.v_target,
                cases: vec![r.clone()],
                e_at_target: vec![e],
                e: f64::NAN,
            }),
        }
    }
    for p in &mut points {
        let mut order: Vec<usize> = (0..p.cases.len()).collect();
        order.sort_by(|&a, &b| p.cases[a].r0.total_cmp(&p.cases[b].r0));
        p.cases = order.iter().map(|&k| p.cases[k].clone()).collect();
        p.e_at_target = order.iter().map(|&k| p.e_at_target[k]).collect();
    }
    let x = |p: &Point| p.cases.iter().map(|c| 1.0 / c.r0).collect::<Vec<f64>>();
    let series: Vec<(Vec<f64>, Vec<f64>)> = points
        .iter()
        .map(|p| (x(p), p.e_at_target.clone()))
        .collect();
    let order = common_order(&series)?;
    for p in &mut points {
        p.e = power_fit(order, &x(p), &p.e_at_target).0;
    }
    Some((points, order))
}
