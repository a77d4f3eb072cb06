//! Starting shapes and continuation in `v` along each branch.
//!
//! * Prolate / oblate: from the one-mode shape `ψ = πt + a_2 sin 2πt` whose `v` is the target
//!   (bisection in `a_2`, `a_2 > 0` prolate, `< 0` oblate), at `v = 0.99` or above, then down.
//! * Stomatocyte: from a sphere-in-sphere curve (outer arc of radius `R1`, a narrow neck of
//!   radius `b`, an inner arc of radius `R2` traversed the other way; closed by construction),
//!   projected on the modes, solved at its own `v`, then continued both ways.
//!
//! Continuation: the next Newton start is the secant extrapolation of the last two solutions;
//! a failed solve halves the step, and a step below `dv_min` marks the end of the branch (a
//! limit point in `v`, as at the stomatocyte's upper end).

use super::functional::Basis;
use super::solver::{minimise, newton, Converged, NewtonSettings};
use super::{solution, Branch, Options, Solution};
use crate::error::{Error, Result};
use std::f64::consts::PI;

/// Largest coefficient change from the predictor accepted in one continuation step; a larger
/// one means Newton jumped to another stationary shape.
const MAX_JUMP: f64 = 0.3;

/// A branch being followed: the discretisation and the last (at most two) solutions.
pub(super) struct Tracker {
    pub(super) branch: Branch,
    pub(super) basis: Basis,
    pub(super) set: NewtonSettings,
    pub(super) opts: Options,
    pub(super) last: Vec<Converged>,
}

impl Tracker {
    pub(super) fn new(branch: Branch, opts: &Options) -> Self {
        let modes: Vec<usize> = if branch.up_down_symmetric() {
            (2..=opts.modes).step_by(2).collect()
        } else {
            (1..=opts.modes).collect()
        };
        Tracker {
            branch,
            basis: Basis::new(opts.nodes - 1, modes)
                .with_c0(opts.c0)
                .with_model(opts.model),
            set: NewtonSettings {
                tol: opts.tol,
                max_iter: opts.max_iter,
                max_step: 0.5,
            },
            opts: *opts,
            last: Vec::new(),
        }
    }

    pub(super) fn closure(&self) -> bool {
        !self.branch.up_down_symmetric()
    }

    pub(super) fn current(&self) -> &Converged {
        self.last.last().expect("tracker started")
    }

    pub(super) fn push(&mut self, c: Converged) {
        if self.last.len() == 2 {
            self.last.remove(0);
        }
        self.last.push(c);
    }

    /// Solve from the start shape of the branch; `v_hint` is where the symmetric branches
    /// start (capped at 0.99). `false` if the start does not converge (always for the pear,
    /// which [`super::pear::follow_pear`] follows by arclength).
    pub(super) fn start(&mut self, v_hint: f64) -> bool {
        self.last.clear();
        let (a0, v0) = match self.branch {
            // Not followed in v (it folds): see `follow_pear`.
            Branch::Pear => return false,
            Branch::Prolate | Branch::Oblate => {
                let v0 = v_hint.clamp(0.99, 1.0);
                (self.one_mode(v0), v0)
            }
            Branch::Stomatocyte => {
                let a0 = self.sphere_in_sphere();
                match self.basis.eval(&a0) {
                    Some(ev) => (a0, ev.v),
                    None => return false,
                }
            }
        };
        let solved = if self.branch.up_down_symmetric() {
            newton(&self.basis, &a0, v0, self.closure(), &self.set)
        } else {
            minimise(&self.basis, &a0, v0, self.closure(), &self.set)
        };
        match solved {
            Some(c) => {
                self.push(c);
                true
            }
            None => false,
        }
    }

    /// The one-mode shape `a_2 sin 2πt` with reduced volume `v` (bisection; `a_2 = 0` at
    /// `v = 1`), of the sign of the branch.
    fn one_mode(&self, v: f64) -> Vec<f64> {
        let sign = if self.branch == Branch::Prolate {
            1.0
        } else {
            -1.0
        };
        let mut a = vec![0.0; self.basis.modes.len()];
        if v >= 1.0 {
            return a;
        }
        let vol = |x: f64, a: &mut Vec<f64>| {
            a[0] = sign * x;
            self.basis.eval(a).map_or(0.0, |e| e.v)
        };
        let (mut lo, mut hi) = (0.0, 0.05);
        while vol(hi, &mut a) > v && hi < 1.0 {
            lo = hi;
            hi += 0.05;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if vol(mid, &mut a) > v {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        a[0] = sign * 0.5 * (lo + hi);
        a
    }

    /// Coefficients of a sphere-in-sphere curve: outer arc `R1 = 1` for `ψ ∈ [0, π − β]`,
    /// neck arc of radius `b` for `ψ ∈ [π − β, 2π − γ]`, inner arc `R2` for `ψ` from `2π − γ`
    /// down to `π`; `sin γ = (R1 − b) sin β / (R2 + b)` makes `r` vanish at the end.
    /// `a_k = 2 ∫_0^1 (ψ − πt) sin(kπt) dt` (midpoint rule on 8192 cells).
    fn sphere_in_sphere(&self) -> Vec<f64> {
        let (r1, r2, b, beta) = (1.0f64, 0.55f64, 0.08f64, 0.35f64);
        let gamma = ((r1 - b) * beta.sin() / (r2 + b)).asin();
        let l1 = r1 * (PI - beta);
        let l2 = b * (PI + beta - gamma);
        let l3 = r2 * (PI - gamma);
        let len = l1 + l2 + l3;
        let psi = |t: f64| {
            let s = t * len;
            if s < l1 {
                s / r1
            } else if s < l1 + l2 {
                PI - beta + (s - l1) / b
            } else {
                2.0 * PI - gamma - (s - l1 - l2) / r2
            }
        };
        let cells = 8192;
        self.basis
            .modes
            .iter()
            .map(|&k| {
                let h = 1.0 / cells as f64;
                2.0 * h
                    * (0..cells)
                        .map(|i| {
                            let t = (i as f64 + 0.5) * h;
                            (psi(t) - PI * t) * (k as f64 * PI * t).sin()
                        })
                        .sum::<f64>()
            })
            .collect()
    }

    /// Newton start at `v`: secant extrapolation of the last two solutions (the last one if
    /// there is only one; the one-mode shape when leaving the sphere).
    fn predict(&self, v: f64) -> Vec<f64> {
        let c1 = self.current();
        if v >= 1.0 {
            // The sphere (where ∇v = 0 and Newton's system is singular, but ∇e = 0 too).
            return vec![0.0; c1.a.len()];
        }
        if c1.a.iter().all(|a| *a == 0.0) && self.branch.up_down_symmetric() {
            return self.one_mode(v);
        }
        secant_in_v(&self.last, v)
    }

    /// Continue to `target`; `false` (and the tracker at the last solution reached) if the step
    /// had to fall below `dv_min`.
    pub(super) fn advance(&mut self, target: f64) -> bool {
        let mut step = self.opts.dv_max;
        loop {
            let cur = self.current().eval.v;
            let remaining = target - cur;
            if remaining.abs() < 1e-10 {
                return true;
            }
            let h = step.min(remaining.abs()) * remaining.signum();
            let vt = if h.abs() >= remaining.abs() {
                target
            } else {
                cur + h
            };
            let a0 = self.predict(vt);
            let solved = newton(&self.basis, &a0, vt, self.closure(), &self.set)
                .filter(|c| c.a.iter().zip(&a0).all(|(a, p)| (a - p).abs() <= MAX_JUMP));
            match solved {
                Some(c) => {
                    self.push(c);
                    if vt == target {
                        return true;
                    }
                    step = (2.0 * step).min(self.opts.dv_max);
                }
                None => {
                    step = 0.5 * h.abs();
                    if step < self.opts.dv_min {
                        return false;
                    }
                }
            }
        }
    }

    pub(super) fn solution(&self) -> Solution {
        solution(self.branch, &self.basis, self.current())
    }
}

/// Check `v` and the options.
fn check(v: f64, opts: &Options) -> Result<()> {
    if !(v > 0.0 && v <= 1.0) {
        return Err(Error::config("v", format!("need 0 < v ≤ 1, got {v}")));
    }
    if opts.nodes < 9 || opts.modes < 2 {
        return Err(Error::config(
            "nodes",
            format!(
                "need at least 9 nodes and 2 modes, got {} and {}",
                opts.nodes, opts.modes
            ),
        ));
    }
    Ok(())
}

/// The stationary shape of `branch` at reduced volume `v`, followed from the branch's start.
/// Unlike [`follow`], it does not stop at self-intersection (the oblate below v ≈ 0.503): see
/// [`Solution::self_intersecting`].
///
/// # Errors
/// `Error::Config` (field `v`) if `v ∉ (0, 1]` or the branch does not reach `v` (beyond the
/// stomatocyte's limit point, or where the continuation fails; always for [`Branch::Pear`],
/// which folds in `v`: use [`super::pear::follow_pear`]); field `nodes` for too coarse a
/// discretisation.
pub fn solve(branch: Branch, v: f64, opts: &Options) -> Result<Solution> {
    check(v, opts)?;
    let mut tr = Tracker::new(branch, opts);
    if !tr.start(v) {
        return Err(Error::config(
            "v",
            format!("the {} start shape did not converge", branch.name()),
        ));
    }
    if !tr.advance(v) {
        return Err(Error::config(
            "v",
            format!(
                "the {} branch was followed to v = {:.5} but does not reach v = {v}",
                branch.name(),
                tr.current().eval.v
            ),
        ));
    }
    Ok(tr.solution())
}

/// A branch followed over a grid of reduced volumes.
#[derive(Clone, Debug)]
pub struct Followed {
    /// The shapes at the grid values where the branch exists, in increasing `v`.
    pub shapes: Vec<Solution>,
    /// Where the branch ended inside or just outside the grid: the stomatocyte's upper limit
    /// point (to about `dv_min`), the oblate's first self-contact (bisection to `dv_min`);
    /// `None` if the grid did not reach an end (always for the prolate).
    pub end: Option<f64>,
}

/// Follow `branch` over the reduced volumes `vs` (values outside `(0, 1]` are skipped): the
/// stomatocyte from its start up to its limit point and down, the oblate down to its first
/// self-intersecting shape (excluded), the prolate over the whole grid.
pub fn follow(branch: Branch, vs: &[f64], opts: &Options) -> Followed {
    let mut vs: Vec<f64> = vs
        .iter()
        .copied()
        .filter(|v| *v > 0.0 && *v <= 1.0)
        .collect();
    vs.sort_by(f64::total_cmp);
    vs.dedup();
    let mut out = Followed {
        shapes: Vec::new(),
        end: None,
    };
    let Some(&top) = vs.last() else {
        return out;
    };
    let mut tr = Tracker::new(branch, opts);
    if !tr.start(top) {
        return out;
    }
    let v_start = tr.current().eval.v;
    let start_state = tr.last.clone();
    // Upwards from the start (the stomatocyte, or symmetric targets above 0.99).
    let mut above = Vec::new();
    for &v in vs.iter().filter(|v| **v >= v_start) {
        if !tr.advance(v) {
            out.end = Some(tr.current().eval.v);
            break;
        }
        above.push(tr.solution());
    }
    // Downwards from the start.
    tr.last = start_state;
    for &v in vs.iter().rev().filter(|v| **v < v_start) {
        let good = tr.last.clone();
        if !tr.advance(v) {
            break;
        }
        let s = tr.solution();
        if s.self_intersecting() {
            out.end = contact(&mut tr, good, v);
            break;
        }
        out.shapes.push(s);
    }
    out.shapes.reverse();
    out.shapes.extend(above);
    out
}

/// The secant extrapolation to `v` of the last two solutions of `last` (in `v`),
/// a1 + (v − v1)/(v1 − v0)·(a1 − a0), or the last one's coefficients where there is one or
/// the two share their `v`.
pub(super) fn secant_in_v(last: &[Converged], v: f64) -> Vec<f64> {
    match last {
        [c0, c1] if (c1.eval.v - c0.eval.v).abs() > 1e-12 => {
            let f = (v - c1.eval.v) / (c1.eval.v - c0.eval.v);
            c1.a.iter()
                .zip(&c0.a)
                .map(|(a1, a0)| a1 + f * (a1 - a0))
                .collect()
        }
        [.., c] => c.a.clone(),
        [] => Vec::new(),
    }
}

/// Bisection for the first self-contact between the tracker state `good` (not
/// self-intersecting) and `bad` (self-intersecting), to `dv_min`.
fn contact(tr: &mut Tracker, mut good: Vec<Converged>, bad: f64) -> Option<f64> {
    let mut lo = bad;
    while good.last()?.eval.v - lo > tr.opts.dv_min {
        let mid = 0.5 * (lo + good.last()?.eval.v);
        tr.last = good.clone();
        if !tr.advance(mid) {
            return None;
        }
        if tr.solution().self_intersecting() {
            lo = mid;
        } else {
            good = tr.last.clone();
        }
    }
    Some(0.5 * (lo + good.last()?.eval.v))
}

/// The shapes of `branch` at the reduced volumes `vs` where the branch exists, in increasing
/// `v` ([`follow`] without the end).
pub fn branch_curve(branch: Branch, vs: &[f64], opts: &Options) -> Vec<Solution> {
    follow(branch, vs, opts).shapes
}

/// Where `branch` ends: the stomatocyte's upper limit point in `v`, the oblate's first
/// self-contact (both to about `opts.dv_min`); `None` for the prolate or if nothing is found.
/// Follows the branch on a grid of step 0.02 over the part that leads to the end.
pub fn branch_end(branch: Branch, opts: &Options) -> Option<f64> {
    let range = match branch {
        Branch::Prolate | Branch::Pear => return None,
        Branch::Oblate => (0.30, 0.99),
        Branch::Stomatocyte => (0.60, 0.99),
    };
    let n = ((range.1 - range.0) / 0.02f64).round() as usize;
    let vs: Vec<f64> = (0..=n).map(|i| range.0 + 0.02 * i as f64).collect();
    follow(branch, &vs, opts).end
}

/// Reduced volumes where the energies (`w`: `e` for SC) of two branches cross
/// ([`crate::analysis::curves::crossings`] of their `(v, w)`: local cubics, bisection at each
/// sign change on the shared range).
pub fn crossings(a: &[Solution], b: &[Solution]) -> Vec<f64> {
    let points = |c: &[Solution]| c.iter().map(|s| (s.v, s.w)).collect::<Vec<_>>();
    crate::analysis::curves::crossings(&points(a), &points(b))
}
