//! The bilayer couple in the L-BFGS iteration: M[φ] = Δa M₁ held as a second equality
//! constraint beside the area (docs/src/theory/relaxation.md#the-bilayer-couple).
//!
//! With q_A = M⁻¹â = (c_σ|k|²/M) φ̂ and q_M = M⁻¹m̂ (m̂ = FT[δM/δφ] of the current state,
//! q_M(0) = 0: the volume) the constraints' Gram matrix in the metric is
//!
//! ```text
//! G = | ⟨q_A, q_A⟩_M   ⟨q_A, q_M⟩_M |      ⟨q_A, q_M⟩_M = Σ w (c_σ|k|²/M) Re(φ̂ m̂*),
//!     | ⟨q_M, q_A⟩_M   ⟨q_M, q_M⟩_M |      ⟨q_M, q_M⟩_M = Σ w |m̂|²/M          (k ≠ 0)
//! ```
//!
//! and it gives, each by one 2×2 solve,
//!
//! * the multipliers of the gradient r = M⁻¹(ĝ + σâ + λm̂), tangent to both constraints:
//!   G (σ, λ) = −(⟨ĝ, q_A⟩, ⟨ĝ, q_M⟩), ⟨ĝ, q_M⟩ = Σ w Re(ĝ m̂*)/M;
//! * the projection of the recursion's direction d' onto the tangent space,
//!   d = d' + c_A q_A + c_M q_M with G (c_A, c_M) = −(⟨q_A, d'⟩_M, ⟨q_M, d'⟩_M),
//!   ⟨q_M, d'⟩_M = Σ w Re(m̂ d'*).
//!
//! **The retraction.** A trial x + α d' + b_A q_A + b_M q_M is put back onto A = A0 and
//! M = M0: for a given b_M = α c_M + τ_M the area is a quadratic in b_A = α c_A + τ_A (its
//! sums by Parseval, as in the area-only retraction, with four more for q_M), solved for the
//! root τ_A nearest 0; M, a functional of φ in real space, is not, so τ_M is found by Newton
//! iterations on M(τ_M) = M0 from τ_M = 0, with M's slope at the trial along the area's
//! constraint curve, dM/dτ_M = ⟨m̂_trial, q_M + τ_A′ q_A⟩ (τ_A′ = −∂A/∂b_M / ∂A/∂b_A from the
//! area's sums; one spectral sum, no transform), until |M − M0| ≤ 1e-12 M0 (as the spectral
//! step holds it). Each iteration is an evaluation of the trial; since d is tangent to M, the
//! first trial misses M0 only at second order in α d (measured: 3–4 evaluations an iteration
//! early in a relaxation, 2 in its middle, 1 near its end).
//!
//! **λ in ĝ.** The multiplier's term λm̂ is added to the state's ĝ (and ⟨ĝ, q_A⟩ with it), so
//! that the area-only sweeps form r, the residual RMS(μ − μ̄) with μ̂ = ĝ + σâ + λm̂ and the
//! pairs' inner products unchanged; the engine keeps the λ added ([`Couple::lambda`]), and a
//! later solve on that ĝ gives the correction to it.
//!
//! The passes run mode by mode in one thread, as the term's own passes do
//! ([`crate::engines::spectral::curvature`]).

use super::lbfgs::{flat, Direction};
use super::RelaxEngine;
use crate::engines::numerics::nearest_root;
use crate::engines::spectral::curvature::{at, dot, for_each_mode};
use crate::engines::spectral::evaluator::{Metric, State, Symbols};
use crate::engines::spectral::pieces::{reals, reals_mut};
use crate::engines::spectral::stepper::{COUPLE_ITERATIONS, COUPLE_TOL};
use crate::problem::config::AreaMethod;

/// The bilayer couple's part of the engine.
#[derive(Clone, Copy, Debug)]
pub(super) struct Couple {
    /// M0 = Δa M₁, the M held.
    pub(super) target: f64,
    /// λ of the current state, already added to its ĝ as λm̂.
    pub(super) lambda: f64,
    /// The current state's sums.
    pub(super) sums: CoupleSums,
    /// This iteration's direction: its multiple c_M of q_M and the area sum with d'.
    pub(super) c_m: f64,
    /// Σ a Re(d' q_M*) (a = (3/(2√2)) ε |k|² w).
    pub(super) dm: f64,
    /// Evaluations the retractions have made (diagnostics).
    pub(super) evaluations: usize,
}

impl Couple {
    /// The couple holding M = `target`, no state yet.
    pub(super) fn new(target: f64) -> Self {
        Couple {
            target,
            lambda: 0.0,
            sums: CoupleSums::default(),
            c_m: 0.0,
            dm: 0.0,
            evaluations: 0,
        }
    }

    /// Whether M of a state is off M0 by more than `tol` of M0.
    pub(super) fn off(&self, m: f64, tol: f64) -> bool {
        (m - self.target).abs() > tol * self.target.abs()
    }
}

/// A state's sums for the couple, over k ≠ 0 (a = (3/(2√2)) ε |k|² w).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct CoupleSums {
    /// ⟨ĝ, q_M⟩ = Σ w Re(ĝ m̂*)/M.
    pub(super) gm: f64,
    /// G_AM = ⟨q_A, q_M⟩_M = Σ w (c_σ|k|²/M) Re(φ̂ m̂*).
    pub(super) am: f64,
    /// G_MM = ⟨q_M, q_M⟩_M = Σ w |m̂|²/M.
    pub(super) mm: f64,
    /// Σ a Re(φ̂ q_M*).
    pub(super) xm: f64,
    /// Σ a Re(q_A q_M*).
    pub(super) qm: f64,
    /// Σ a |q_M|².
    pub(super) m2: f64,
}

/// The [`CoupleSums`] of `state` (its φ̂, ĝ in `nonlinear` and m̂).
pub(super) fn state_sums(sym: &Symbols, metric: Metric, state: &State) -> CoupleSums {
    let (x, g, m) = (
        reals(flat(&state.hat)),
        reals(flat(&state.nonlinear)),
        reals(flat(&state.curvature_hat)),
    );
    let width = sym.width;
    let mut s = CoupleSums::default();
    for_each_mode(sym, x.len(), |i, k, w| {
        if k <= 0.0 {
            return;
        }
        let inv = 1.0 / metric.at(k);
        let qf = metric.c_sigma * k * inv;
        let aw = sym.area_prefactor * k * w;
        let (x, g, m) = (at(x, i, width), at(g, i, width), at(m, i, width));
        let (xm, mm) = (dot(x, m), dot(m, m));
        s.gm += w * inv * dot(g, m);
        s.am += w * qf * xm;
        s.mm += w * inv * mm;
        s.xm += aw * inv * xm;
        s.qm += aw * qf * inv * xm;
        s.m2 += aw * inv * inv * mm;
    });
    s
}

/// (x_A, x_M) solving G (x_A, x_M) = (b_A, b_M), G = [[g_aa, g_am], [g_am, g_mm]]; without the
/// area constraint (`with_area` false) the 1×1 system g_mm x_M = b_M and x_A = 0.
fn solve(g: (f64, f64, f64), b: (f64, f64), with_area: bool) -> (f64, f64) {
    let ((g_aa, g_am, g_mm), (b_a, b_m)) = (g, b);
    if !with_area {
        return (0.0, b_m / g_mm);
    }
    let det = g_aa * g_mm - g_am * g_am;
    (
        (b_a * g_mm - b_m * g_am) / det,
        (b_m * g_aa - b_a * g_am) / det,
    )
}

/// Add λm̂ to the state's ĝ (every mode: μ̂ = ĝ + σâ + λm̂).
fn add_to_gradient(state: &mut State, lambda: f64) {
    let m = reals(flat(&state.curvature_hat));
    let g = reals_mut(state.nonlinear.as_slice_mut().expect("standard layout"));
    g.iter_mut().zip(m).for_each(|(g, m)| *g += lambda * m);
}

impl RelaxEngine {
    /// Whether the area is held (the A row of the Gram system).
    fn holds_area(&self) -> bool {
        self.area.method != AreaMethod::None
    }

    /// The multipliers of the state `trial` (or the current one) whose ĝ holds λ₀m̂ with
    /// λ₀ = `added`: its sums, G (σ, δλ) = −(⟨ĝ, q_A⟩, ⟨ĝ, q_M⟩), δλm̂ added to its ĝ
    /// (and δλ G_AM to ⟨ĝ, q_A⟩); returns the sums, σ and λ = λ₀ + δλ.
    pub(super) fn hold_couple(&mut self, trial: bool, added: f64) -> (CoupleSums, f64, f64) {
        let with_area = self.holds_area();
        let state = if trial {
            &mut self.trial
        } else {
            &mut self.cur
        };
        let sums = state_sums(&self.ev.symbols, self.metric, state);
        let (qq, gq) = state.multiplier_sums;
        let with_area = with_area && qq > 0.0;
        let (sigma, dl) = solve((qq, sums.am, sums.mm), (-gq, -sums.gm), with_area);
        add_to_gradient(state, dl);
        state.multiplier_sums.1 += dl * sums.am;
        (sums, sigma, added + dl)
    }

    /// After a re-evaluation of the current state (a failed line search): its ĝ gains the λm̂
    /// it held before.
    pub(super) fn restore_couple_gradient(&mut self) {
        if let Some(c) = self.couple {
            add_to_gradient(&mut self.cur, c.lambda);
        }
    }

    /// Project the recursion's direction d' (in `dir`, its area sums in `d`) onto the tangent
    /// space of both constraints: c_A (into `d.c_q`) and c_M from
    /// G (c_A, c_M) = −(⟨q_A, d'⟩_M, ⟨q_M, d'⟩_M), with ⟨q_A, d'⟩_M = 2 xd and
    /// ⟨q_A, q_A⟩_M = 2 xq as the area-only projection takes them, and the slope
    /// ⟨r, d'⟩_M + c_A ⟨r, q_A⟩_M + c_M ⟨r, q_M⟩_M.
    pub(super) fn project_couple(&mut self, d: &mut Direction) {
        let Some(mut c) = self.couple else {
            return;
        };
        let sym = &self.ev.symbols;
        let (dp, r, m) = (
            reals(flat(&self.dir)),
            reals(flat(&self.grad)),
            reals(flat(&self.cur.curvature_hat)),
        );
        let width = sym.width;
        let (mut md, mut mr, mut dm) = (0.0, 0.0, 0.0);
        for_each_mode(sym, dp.len(), |i, k, w| {
            if k <= 0.0 {
                return;
            }
            let inv = 1.0 / self.metric.at(k);
            let (dp, r, m) = (at(dp, i, width), at(r, i, width), at(m, i, width));
            let (d_m, r_m) = (dot(dp, m), dot(r, m));
            md += w * d_m;
            mr += w * r_m;
            dm += sym.area_prefactor * k * w * inv * d_m;
        });
        let with_area = self.holds_area() && d.area.xq > 0.0;
        let g = (2.0 * d.area.xq, c.sums.am, c.sums.mm);
        let (c_a, c_m) = solve(g, (-2.0 * d.area.xd, -md), with_area);
        d.c_q = c_a;
        d.slope += c_a * self.ip.qr + c_m * mr;
        (c.c_m, c.dm) = (c_m, dm);
        self.couple = Some(c);
    }

    /// The trial φ̂ + α d' + b_A q_A + b_M q_M into `trial.hat` (q_M(0) = 0), evaluated at `t`.
    fn write_couple_trial(&mut self, alpha: f64, (b_a, b_m): (f64, f64), t: f64) -> Result<(), ()> {
        let sym = &self.ev.symbols;
        let width = sym.width;
        let (x, d, m) = (
            reals(flat(&self.cur.hat)),
            reals(flat(&self.dir)),
            reals(flat(&self.cur.curvature_hat)),
        );
        let hat = reals_mut(self.trial.hat.as_slice_mut().expect("standard layout"));
        let metric = self.metric;
        for_each_mode(sym, x.len(), |i, k, _| {
            let (inv, qf) = if k <= 0.0 {
                (0.0, 0.0)
            } else {
                let inv = 1.0 / metric.at(k);
                (inv, metric.c_sigma * k * inv)
            };
            for c in i..i + width {
                hat[c] = x[c] + alpha * d[c] + b_a * qf * x[c] + b_m * inv * m[c];
            }
        });
        self.ev
            .evaluate(&mut self.trial, t, None, None)
            .map(|_| ())
            .map_err(|_| ())
    }

    /// dM/dτ of the trial along q_M + `tau_a` q_A: Σ_{k≠0} w Re(m̂_t (m̂/M + τ_A' (c_σ|k|²/M) φ̂)*)
    /// with m̂_t the trial's m̂ and m̂, φ̂ the current state's.
    fn trial_slope(&self, tau_a: f64) -> f64 {
        let sym = &self.ev.symbols;
        let width = sym.width;
        let (x, m, mt) = (
            reals(flat(&self.cur.hat)),
            reals(flat(&self.cur.curvature_hat)),
            reals(flat(&self.trial.curvature_hat)),
        );
        let mut slope = 0.0;
        for_each_mode(sym, x.len(), |i, k, w| {
            if k <= 0.0 {
                return;
            }
            let inv = 1.0 / self.metric.at(k);
            let qf = self.metric.c_sigma * k * inv;
            let (x, m, mt) = (at(x, i, width), at(m, i, width), at(mt, i, width));
            slope += w * (inv * dot(mt, m) + tau_a * qf * dot(mt, x));
        });
        slope
    }

    /// The trial at step `alpha` on both constraints (module documentation): for each τ_M the
    /// area's root τ_A, then an evaluation, until |M − M0| ≤ [`COUPLE_TOL`] M0. `Err` if the
    /// area has no real root, an evaluation diverged, or M0 is not reached in
    /// [`COUPLE_ITERATIONS`] evaluations.
    pub(super) fn try_couple_step(&mut self, alpha: f64, t: f64) -> Result<(), ()> {
        let Some(c) = self.couple else {
            return Err(());
        };
        let d = self.direction;
        let (s, a, target) = (c.sums, d.area, self.area.target);
        let with_area = self.holds_area() && a.xq > 0.0;
        let b_a0 = alpha * d.c_q;
        // The area of x + α d' + b_M q_M + b_A q_A as qq b_A² + 2 p b_A + a0.
        let area_root = |b_m: f64| -> Option<f64> {
            if !with_area {
                return Some(0.0);
            }
            let p = a.xq + alpha * a.qd + b_m * s.qm;
            let a0 = a.xx
                + 2.0 * alpha * a.xd
                + alpha * alpha * a.dd
                + 2.0 * b_m * (s.xm + alpha * c.dm)
                + b_m * b_m * s.m2;
            let q = a.qq;
            nearest_root(
                q,
                q * b_a0 + p,
                (q * b_a0 + 2.0 * p) * b_a0 + a0 - target,
                0.0,
            )
        };
        let mut tau = 0.0;
        for _ in 0..COUPLE_ITERATIONS {
            let b_m = alpha * c.c_m + tau;
            let b_a = b_a0 + area_root(b_m).ok_or(())?;
            self.write_couple_trial(alpha, (b_a, b_m), t)?;
            if let Some(c) = self.couple.as_mut() {
                c.evaluations += 1;
            }
            let off = self.trial.measures.curvature - c.target;
            if off.abs() <= COUPLE_TOL * c.target.abs() {
                return Ok(());
            }
            // Newton's step with M's slope at the trial along the constraint curve: τ_M moves
            // the trial by q_M + τ_A' q_A, τ_A' = −∂A/∂b_M / ∂A/∂b_A.
            let zm = s.xm + alpha * c.dm + b_m * s.m2 + b_a * s.qm;
            let zq = a.xq + alpha * a.qd + b_m * s.qm + b_a * a.qq;
            let tau_a = if with_area { -zm / zq } else { 0.0 };
            let slope = self.trial_slope(tau_a);
            tau -= off / slope;
        }
        Err(())
    }
}
