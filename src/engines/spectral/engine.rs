//! The Fourier semi-implicit engine (docs/src/theory/spectral.md). In Fourier space
//!
//! ```text
//! ∂φ̂/∂t = N̂ − 2ε⁴|k|⁶ φ̂ − c_σ σ |k|⁴ φ̂,   N̂ = −2|k|² FT[f'Φ] − 2ε²|k|⁴ FT[f],   c_σ = 3/√2 ε,
//! ```
//!
//! with the sixth-order term and a linear stabiliser S(k) = s2|k|² + s4 ε²|k|⁴ implicit and the
//! rest explicit. One variable-step SBDF formula covers both schemes (Wang & Ruuth 2008):
//!
//! ```text
//! (a0 + Δt(2ε⁴k⁶ + S)) φ̂^{n+1} = −a1 φ̂^n − a2 φ̂^{n−1}
//!         + Δt [b1 (N̂^n + Sφ̂^n) + b2 (N̂^{n−1} + Sφ̂^{n−1})] − Δt c_σ σ k⁴ (b1 φ̂^n + b2 φ̂^{n−1})
//! ```
//!
//! SBDF1: a = (1, −1, 0), b = (1, 0). SBDF2 with ω = Δt_n/Δt_{n−1}:
//! a = ((1+2ω)/(1+ω), −(1+ω), ω²/(1+ω)), b = (1+ω, −ω); its first step is SBDF1.
//! φ̂^{n+1} = P̂ + σ Q̂ is affine in σ, so the area A(φ^{n+1}) = A_PP + 2σ A_PQ + σ² A_QQ is a
//! quadratic computed by Parseval with no extra transform; the exact projection takes the root
//! nearest the last σ and rejects a step with no real root.

use super::control::{self, Rejection};
use super::evaluator::{axis_symbol, write_inverse_value, Evaluator, ExplicitTerm, State};
use super::kernels::{sum, wide_fn};
use super::pieces::{for_each_piece, mode, per_width, re_dot, reals, reals_mut, Piece, PIECE};
use super::saved::spectrum;
use crate::engines::numerics::{nearest_root, sum_in_fixed_tree};
use crate::engines::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::problem::config::{
    AdaptiveSettings, AreaMethod, Laplacian, Scene, Scheme, Stabilizer, VolumeRamp,
};
use crate::problem::grid::Grid;
use crate::problem::model::{Measures, C0};
use ndarray::Array3;
use num_complex::Complex64;
use rayon::prelude::*;

/// The SBDF update at one wavenumber (see the module documentation), for one step's Δt and
/// coefficients.
#[derive(Clone, Copy)]
struct Update {
    /// (a0, a1, a2, b1, b2).
    a: [f64; 5],
    dt: f64,
    /// s2 and s4 ε² of the stabiliser S = s2 k² + s4 ε² k⁴.
    s2: f64,
    s4e2: f64,
    /// 2ε⁴.
    e4x2: f64,
    /// c_σ = 3/√2 ε.
    c_sigma: f64,
}

impl Update {
    /// S = s2 k + s4 ε² k² at |k|² = `k`.
    #[inline(always)]
    fn stabilizer(&self, k: f64) -> f64 {
        self.s2 * k + self.s4e2 * k * k
    }

    /// 1/D = 1/(a0 + Δt(2ε⁴k⁶ + S)) at |k|² = `k`.
    #[inline(always)]
    fn inverse_denominator(&self, k: f64) -> f64 {
        1.0 / (self.a[0] + self.dt * (self.e4x2 * k * k * k + self.stabilizer(k)))
    }

    /// −Δt c_σ k⁴/D at |k|² = `k` and 1/D = `inv` (q1 = b1 times this, q0 = b2 times this).
    #[inline(always)]
    fn q_per_b(&self, k: f64, inv: f64) -> f64 {
        -self.dt * self.c_sigma * k * k * inv
    }

    /// The real factors of the update at |k|² = `k` (see [`ValueFactors`]); `PREV` false
    /// leaves h0, n0 and q0 zero (SBDF1).
    #[inline(always)]
    fn at<const PREV: bool>(&self, k: f64) -> ValueFactors {
        let [_, a1, a2, b1, b2] = self.a;
        let (dt, s) = (self.dt, self.stabilizer(k));
        let inv = self.inverse_denominator(k);
        let qc = self.q_per_b(k, inv);
        let mut f = ValueFactors {
            h1: (-a1 + dt * b1 * s) * inv,
            n1: dt * b1 * inv,
            q1: b1 * qc,
            h0: 0.0,
            n0: 0.0,
            q0: 0.0,
        };
        if PREV {
            f.h0 = (-a2 + dt * b2 * s) * inv;
            f.n0 = dt * b2 * inv;
            f.q0 = b2 * qc;
        }
        f
    }
}

/// The update at one wavenumber as real factors (k standing for |k|²):
///
/// ```text
/// P̂ = h1 φ̂ⁿ + n1 N̂ⁿ + h0 φ̂ⁿ⁻¹ + n0 N̂ⁿ⁻¹,   Q̂ = q1 φ̂ⁿ + q0 φ̂ⁿ⁻¹,
/// h1 = (−a1 + Δt b1 S)/D, n1 = Δt b1/D, h0 = (−a2 + Δt b2 S)/D, n0 = Δt b2/D,
/// q1 = −Δt c_σ k⁴ b1/D, q0 = −Δt c_σ k⁴ b2/D,   D = a0 + Δt(2ε⁴k⁶ + S).
/// ```
struct ValueFactors {
    h1: f64,
    n1: f64,
    h0: f64,
    n0: f64,
    q1: f64,
    q0: f64,
}

impl ValueFactors {
    /// (P̂, Q̂) at one mode from φ̂ⁿ, N̂ⁿ, φ̂ⁿ⁻¹, N̂ⁿ⁻¹ there (`PREV` false: the last two
    /// unread).
    #[inline(always)]
    fn apply<const PREV: bool, const W: usize>(
        &self,
        [x, n, x0, n0]: [&[f64; W]; 4],
    ) -> ([f64; W], [f64; W]) {
        let mut p = [0.0; W];
        let mut q = [0.0; W];
        for c in 0..W {
            p[c] = x[c] * self.h1 + n[c] * self.n1;
            q[c] = x[c] * self.q1;
            if PREV {
                p[c] += x0[c] * self.h0 + n0[c] * self.n0;
                q[c] += x0[c] * self.q0;
            }
        }
        (p, q)
    }
}

/// The modes of a piece in the reals `inputs` = [φ̂ⁿ, N̂ⁿ, φ̂ⁿ⁻¹, N̂ⁿ⁻¹], zipped with the
/// piece's |k|² and w. Without a previous step the last two inputs may be any reals of the piece
/// (the SBDF1 sweeps do not read them).
#[inline(always)]
fn values<'a, const W: usize>(
    p: &'a Piece,
    inputs: [&'a [f64]; 4],
) -> impl Iterator<Item = ([&'a [f64; W]; 4], (f64, f64))> + 'a {
    let [x, n, x0, n0] = inputs.map(|v| p.modes::<W, _>(v).iter());
    x.zip(n)
        .zip(x0.zip(n0))
        .zip(p.symbols())
        .map(|(((x, n), (x0, n0)), kw)| ([x, n, x0, n0], kw))
}

wide_fn! {
/// One piece of [`SpectralEngine::area_quadratic`], mode by mode from the piece's reals
/// `inputs` ([`values`]): with P̂, Q̂ of [`ValueFactors`] and the area weight
/// a = (3/(2√2)) ε |k|² w, returns (A_PP, A_PQ, A_QQ) = Σ a (|P̂|², Re P̂Q̂*, |Q̂|²). Each mode's
/// factors are formed and used at once (`t` scratch for its three terms).
fn quadratic_values<const PREV: bool, const W: usize>(
    u: &Update,
    p: &Piece,
    area_prefactor: f64,
    inputs: [&[f64]; 4],
    t: &mut [[f64; PIECE]; 3],
) -> [f64; 3] {
    let len = p.len;
    let [tpp, tpq, tqq] = t;
    let terms = tpp[..len].iter_mut().zip(&mut tpq[..len]).zip(&mut tqq[..len]);
    for (((pp, pq), qq), (v, (k, w))) in terms.zip(values::<W>(p, inputs)) {
        let (pv, qv) = u.at::<PREV>(k).apply::<PREV, W>(v);
        let aw = area_prefactor * k * w;
        *pp = aw * re_dot(pv, pv);
        *pq = aw * re_dot(pv, qv);
        *qq = aw * re_dot(qv, qv);
    }
    [&tpp[..len], &tpq[..len], &tqq[..len]].map(sum)
}
}

wide_fn! {
/// One piece of [`SpectralEngine::write_update`], mode by mode: φ̂^{n+1} = P̂ + σQ̂ into
/// `hat`, and the inverse transforms' inputs ([`write_inverse_value`]) into `copy` and `lap`;
/// returns the piece's area (`t` scratch for each mode's term).
fn write_values<const PREV: bool, const W: usize>(
    u: &Update,
    p: &Piece,
    area_prefactor: f64,
    sigma: f64,
    inputs: [&[f64]; 4],
    out: [&mut [f64]; 3],
    t: &mut [f64; PIECE],
) -> f64 {
    let [hat, copy, lap] = out.map(|o| p.modes_mut::<W, _>(o).iter_mut());
    let outputs = hat.zip(copy.zip(lap)).zip(&mut t[..p.len]);
    for (((hat, (copy, lap)), term), (v, (k, w))) in outputs.zip(values::<W>(p, inputs)) {
        let (pv, qv) = u.at::<PREV>(k).apply::<PREV, W>(v);
        *hat = mode(|c| pv[c] + sigma * qv[c]);
        *term = write_inverse_value(*hat, k, area_prefactor * k * w, copy, lap);
    }
    sum(&t[..p.len])
}
}

/// φ̂ⁿ, N̂ⁿ and (SBDF2) φ̂ⁿ⁻¹, N̂ⁿ⁻¹, as interleaved reals.
#[derive(Clone, Copy)]
struct Inputs<'a> {
    cur: (&'a [f64], &'a [f64]),
    prev: Option<(&'a [f64], &'a [f64])>,
}

impl<'a> Inputs<'a> {
    /// The inputs of a step from `cur` (and `prev` when the formula uses it, a2 ≠ 0).
    fn new(
        cur: &'a State,
        prev: Option<&'a (Array3<Complex64>, Array3<Complex64>)>,
        a2: f64,
    ) -> Self {
        let flat = |a: &'a Array3<Complex64>| reals(a.as_slice().expect("standard layout"));
        Inputs {
            cur: (flat(&cur.hat), flat(&cur.nonlinear)),
            prev: prev.filter(|_| a2 != 0.0).map(|(h, n)| (flat(h), flat(n))),
        }
    }

    /// The reals `range` of φ̂ⁿ, N̂ⁿ, φ̂ⁿ⁻¹, N̂ⁿ⁻¹ (without a previous step the last two are
    /// φ̂ⁿ, N̂ⁿ again: the SBDF1 sweeps do not read them).
    #[inline]
    fn reals(&self, range: std::ops::Range<usize>) -> [&'a [f64]; 4] {
        let (h, n) = (&self.cur.0[range.clone()], &self.cur.1[range.clone()]);
        match self.prev {
            Some((h0, n0)) => [h, n, &h0[range.clone()], &n0[range]],
            None => [h, n, h, n],
        }
    }
}

/// Frozen-coefficient stability bound of the semi-implicit step at σ = 0:
/// with the bulk linearisation −2k²(2 + ε²k²)² split into implicit b = 2ε⁴k⁶ + S and explicit
/// a = 8k² + 8ε²k⁴, the amplification (1 + Δt(S − a))/(1 + Δt(b + S)) stays in [−1, 1] for
/// Δt ≤ 2 / max_k (a − b − 2S). Infinite when a − b − 2S ≤ 0 for every k (e.g. S ≥ a/2).
pub fn stability_bound(grid: &Grid, eps: f64, s: &Stabilizer, laplacian: Laplacian) -> f64 {
    let k2_max: f64 = (0..3)
        .filter(|&a| grid.shape[a] > 1)
        .map(|_| axis_symbol(std::f64::consts::PI / grid.h, grid.h, laplacian))
        .sum();
    let e2 = eps * eps;
    let worst = (0..=4000)
        .map(|i| {
            let k2 = k2_max * i as f64 / 4000.0;
            let a = 8.0 * k2 + 8.0 * e2 * k2 * k2;
            let b = 2.0 * e2 * e2 * k2 * k2 * k2;
            let stab = s.s2 * k2 + s.s4 * e2 * k2 * k2;
            a - b - 2.0 * stab
        })
        .fold(0.0f64, f64::max);
    if worst > 0.0 {
        2.0 / worst
    } else {
        f64::INFINITY
    }
}

/// The spectral engine.
pub struct SpectralEngine {
    ev: Evaluator,
    stabilizer: Stabilizer,
    scheme: Scheme,
    /// Controller settings with dt_min and dt_max resolved.
    adaptive: Option<AdaptiveSettings>,
    cur: State,
    next: State,
    /// φ̂^{n−1} and N̂^{n−1} (SBDF2).
    prev: Option<(Array3<Complex64>, Array3<Complex64>)>,
    dt_prev: f64,
    /// max|φ^{n+1} − φ^n| of the last attempt.
    max_change: f64,
    sigma: f64,
    area: AreaConstraint,
    /// V of the prepared initial field: the volume held, or V_init of the ramp.
    volume0: f64,
    /// The scene's time-dependent volume target, if any.
    volume_ramp: Option<VolumeRamp>,
    dt_next: Option<f64>,
    /// Reject steps that raise F_eff (see `check_constraints`).
    energy_guard: bool,
}

impl SpectralEngine {
    /// Engine holding `phi` at t = 0, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let mut ev = Evaluator::new(
            grid,
            scene.eps,
            c0,
            scene.laplacian,
            ExplicitTerm::ConservedRhs,
            scene.threads(),
        );
        let cur = ev.state_of(&phi, 0.0)?;
        let adaptive = control::adaptive_settings(scene);
        Ok(SpectralEngine {
            volume0: cur.measures.volume,
            next: ev.blank(),
            cur,
            ev,
            stabilizer: scene.stabilizer(),
            scheme: scene.scheme,
            adaptive,
            prev: None,
            dt_prev: scene.dt,
            max_change: 0.0,
            sigma: 0.0,
            area: AreaConstraint::none(),
            volume_ramp: scene.volume,
            dt_next: None,
            energy_guard: true,
        })
    }

    /// SBDF coefficients (a0, a1, a2, b1, b2) for this step.
    fn coefficients(&self, dt: f64) -> [f64; 5] {
        control::sbdf_coefficients(self.scheme, self.prev.is_some(), dt, self.dt_prev)
    }

    /// The step's update at this Δt.
    fn update(&self, dt: f64) -> Update {
        let e2 = self.ev.eps * self.ev.eps;
        Update {
            a: self.coefficients(dt),
            dt,
            s2: self.stabilizer.s2,
            s4e2: self.stabilizer.s4 * e2,
            e4x2: 2.0 * e2 * e2,
            c_sigma: 3.0 / std::f64::consts::SQRT_2 * self.ev.eps,
        }
    }

    /// The area of the step's result as a function of σ, A(P̂ + σQ̂) = A_PP + 2σ A_PQ + σ² A_QQ:
    /// returns (A_PP, A_PQ, A_QQ) = Σ_k a (|P̂|², Re(P̂ Q̂*), |Q̂|²), a = (3/(2√2)) ε |k|² w.
    /// A read-only sweep: nothing is stored.
    fn area_quadratic(&self, dt: f64) -> (f64, f64, f64) {
        if self.uses_prev(dt) {
            self.area_quadratic_with::<true>(dt)
        } else {
            self.area_quadratic_with::<false>(dt)
        }
    }

    /// Whether this step's formula reads φ̂ⁿ⁻¹, N̂ⁿ⁻¹ (SBDF2 after its first step).
    fn uses_prev(&self, dt: f64) -> bool {
        self.prev.is_some() && self.coefficients(dt)[2] != 0.0
    }

    /// [`SpectralEngine::area_quadratic`]; `PREV` false takes the SBDF1 form (no φ̂ⁿ⁻¹,
    /// N̂ⁿ⁻¹ terms).
    fn area_quadratic_with<const PREV: bool>(&self, dt: f64) -> (f64, f64, f64) {
        let u = self.update(dt);
        let inputs = Inputs::new(&self.cur, self.prev.as_ref(), u.a[2]);
        let sym = &self.ev.symbols;
        let (task, total) = (sym.task_reals(), 2 * self.cur.hat.len());
        let partials = (0..total.div_ceil(task)).into_par_iter().map(|t| {
            let mut acc = [0.0; 3];
            let mut terms = [[0.0; PIECE]; 3];
            let (a, len) = (sym.area_prefactor, task.min(total - t * task));
            for_each_piece(sym, t, len, |p, at| {
                let x = inputs.reals(t * task + at..t * task + at + p.reals());
                let s = per_width!(sym, W => quadratic_values::<PREV, W>(&u, p, a, x, &mut terms));
                acc = [acc[0] + s[0], acc[1] + s[1], acc[2] + s[2]];
            });
            acc
        });
        let [pp, pq, qq] = sum_in_fixed_tree(
            partials,
            || [0.0; 3],
            |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
        );
        (pp, pq, qq)
    }

    /// φ̂^{n+1} = P̂ + σQ̂ into `next.hat`, with the inputs of the evaluation's inverse
    /// transforms written in the same sweep (a copy into `next.nonlinear`, −|k|²φ̂^{n+1} into
    /// the evaluator's spare; see [`Evaluator::finish`]); returns A(φ̂^{n+1}).
    fn write_update(&mut self, dt: f64, sigma: f64) -> f64 {
        if self.uses_prev(dt) {
            self.write_update_with::<true>(dt, sigma)
        } else {
            self.write_update_with::<false>(dt, sigma)
        }
    }

    /// [`SpectralEngine::write_update`]; `PREV` as in [`SpectralEngine::area_quadratic_with`].
    fn write_update_with<const PREV: bool>(&mut self, dt: f64, sigma: f64) -> f64 {
        let u = self.update(dt);
        let inputs = Inputs::new(&self.cur, self.prev.as_ref(), u.a[2]);
        let sym = &self.ev.symbols;
        let task = sym.task_reals();
        let hat = reals_mut(self.next.hat.as_slice_mut().expect("standard layout"));
        let copy = reals_mut(self.next.nonlinear.as_slice_mut().expect("standard layout"));
        let lap = reals_mut(self.ev.spare.as_slice_mut().expect("standard layout"));
        hat.par_chunks_mut(task)
            .zip(copy.par_chunks_mut(task))
            .zip(lap.par_chunks_mut(task))
            .enumerate()
            .with_max_len(1)
            .map(|(t, ((hat, copy), lap))| {
                let mut terms = [0.0; PIECE];
                let mut area = 0.0;
                for_each_piece(sym, t, hat.len(), |p, at| {
                    let r = at..at + p.reals();
                    let x = inputs.reals(t * task + r.start..t * task + r.end);
                    let out = [&mut hat[r.clone()], &mut copy[r.clone()], &mut lap[r]];
                    let a = sym.area_prefactor;
                    area += per_width!(sym, W => {
                        write_values::<PREV, W>(&u, p, a, sigma, x, out, &mut terms)
                    });
                });
                area
            })
            .sum()
    }

    /// σ used in this step's update, or `None` if the projection has no real root (only the
    /// projection needs the sweep of [`SpectralEngine::area_quadratic`]).
    fn choose_sigma(&self, dt: f64) -> Option<f64> {
        match self.area.method {
            AreaMethod::None => Some(0.0),
            AreaMethod::Lagrangian => Some(self.sigma),
            AreaMethod::Projection => {
                let (app, apq, aqq) = self.area_quadratic(dt);
                nearest_root(aqq, apq, app - self.area.target, self.sigma)
            }
        }
    }

    /// σ of the state after a step that used `step_sigma`: the same, except under the Lagrangian
    /// update σ^{n+1} = σ^n + α (A^n − A0).
    fn sigma_after(&self, step_sigma: f64) -> f64 {
        control::sigma_after(&self.area, self.sigma, self.cur.measures.area, step_sigma)
    }

    /// The volume the state must have at time `t`: V0(t) of the ramp, else V of the prepared
    /// field.
    fn volume_target(&self, t: f64) -> f64 {
        match &self.volume_ramp {
            Some(ramp) => ramp.target(self.volume0, t),
            None => self.volume0,
        }
    }

    /// Under a volume ramp, set the k = 0 coefficient of the written update (and of its copy,
    /// the inverse transform's input) so that V(φ^{n+1}) = V0(`t`): with V = (N + Σφ) dv/2 over
    /// the N stored points (dv the cell volume times the mirror factor) and the unnormalised
    /// forward transforms (X₀ = Σφ on every axis kind, the real part of the first stored
    /// value, packed or not), X₀ = 2 V0/dv − N. This adds one constant to φ^{n+1}; the area
    /// (weight |k|² = 0 there) and every other mode are untouched, so the area projection's σ
    /// stands. Without a ramp the conserved update keeps X₀ itself and nothing is written.
    fn set_volume(&mut self, t: f64) {
        if self.volume_ramp.is_none() {
            return;
        }
        let grid = &self.ev.grid;
        let dv = grid.cell_volume() * grid.mirror_factor();
        let mean_mode = 2.0 * self.volume_target(t) / dv - grid.len() as f64;
        self.next.hat[[0, 0, 0]].re = mean_mode;
        self.next.nonlinear[[0, 0, 0]].re = mean_mode;
    }

    /// Try one step of size `dt`: on success `next` holds the new state (its residual at the
    /// new σ) and the σ of the update and of the new state are returned.
    fn attempt(&mut self, t: f64, dt: f64) -> Result<(f64, f64), Rejection> {
        let sigma = self.choose_sigma(dt).ok_or(Rejection::NoRealRoot)?;
        let area = self.write_update(dt, sigma);
        self.set_volume(t + dt);
        let sigma_after = self.sigma_after(sigma);
        self.max_change = self
            .ev
            .finish(
                &mut self.next,
                area,
                t + dt,
                Some(&self.cur.phi),
                Some(sigma_after),
            )
            .map_err(Rejection::Diverged)?;
        self.check_constraints(sigma, t, t + dt)?;
        Ok((sigma, sigma_after))
    }

    /// Volume (and area under projection) held; F_eff (at the σ of the update) must not rise
    /// where the scheme guarantees that it falls: adaptive steps, and fixed SBDF1 steps (the
    /// stabilised first-order step is dissipative; SBDF2 is not guaranteed to be, and a ramped
    /// C0 may raise F legitimately). Off when the energy guard is off (stability studies), and
    /// for a step that starts (time `t`) while a volume ramp runs: deflating does work on the
    /// vesicle, so F may rise; once V0 is constant the guard holds again. The volume is checked
    /// against its target at the step's end, `t_new`.
    fn check_constraints(&self, sigma: f64, t: f64, t_new: f64) -> Result<(), Rejection> {
        let ramping = self.volume_ramp.is_some_and(|r| t < r.ramp_time);
        let guard = self.energy_guard
            && control::dissipative(self.adaptive.as_ref(), self.scheme)
            && !ramping
            && !self.ev.c0.is_ramped();
        let target = self.volume_target(t_new);
        control::check_step(
            &self.cur.measures,
            &self.next.measures,
            sigma,
            target,
            &self.area,
            guard,
        )
    }

    /// Make `next` the current state with multiplier `sigma`; keep the old one for SBDF2.
    fn accept(&mut self, sigma: f64, dt: f64) {
        std::mem::swap(&mut self.cur, &mut self.next);
        if self.scheme == Scheme::Sbdf2 {
            match &mut self.prev {
                Some((h, n)) => {
                    std::mem::swap(h, &mut self.next.hat);
                    std::mem::swap(n, &mut self.next.nonlinear);
                }
                None => self.prev = Some((self.next.hat.clone(), self.next.nonlinear.clone())),
            }
        }
        self.dt_prev = dt;
        self.sigma = sigma;
    }
}

impl Engine for SpectralEngine {
    fn phi(&self) -> &Array3<f64> {
        &self.cur.phi
    }

    fn sigma(&self) -> f64 {
        self.sigma
    }

    fn measures(&self) -> Measures {
        self.cur.measures
    }

    fn residual(&self) -> f64 {
        self.cur.residual
    }

    fn set_area(&mut self, area: AreaConstraint) {
        if area.method == AreaMethod::None {
            self.sigma = 0.0;
        }
        self.area = area;
    }

    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, Diverged> {
        let adaptive = self.adaptive.clone();
        let ((_, sigma_after), dt, rejected) =
            control::with_retries(adaptive.as_ref(), dt, |dt| Ok(self.attempt(t, dt)))?;
        let f_old = self.cur.measures.energy;
        self.accept(sigma_after, dt);
        let rate = self.max_change / dt;
        if let Some(a) = &self.adaptive {
            self.dt_next = Some(control::propose(a, dt, f_old, self.cur.measures.energy));
        }
        Ok(StepReport { dt, rate, rejected })
    }

    fn next_dt(&self, dt: f64) -> f64 {
        self.dt_next.unwrap_or(dt)
    }

    fn guard_energy(&mut self, on: bool) {
        self.energy_guard = on;
    }

    fn name(&self) -> &'static str {
        "spectral"
    }

    fn save(&self) -> Saved<'_> {
        let mut saved = Saved::default()
            .scalar("sigma", self.sigma)
            .scalar("volume0", self.volume0)
            .scalar("dt_prev", self.dt_prev)
            .scalar("dt_next", self.dt_next.unwrap_or(f64::NAN))
            .array("phi_hat", SavedArray::Complex(self.cur.hat.view().into()));
        if let Some((hat, nonlinear)) = &self.prev {
            saved = saved
                .array("prev_phi_hat", SavedArray::Complex(hat.view().into()))
                .array(
                    "prev_nonlinear",
                    SavedArray::Complex(nonlinear.view().into()),
                );
        }
        saved
    }

    fn restore(&mut self, saved: &mut Saved<'_>, t: f64) -> Result<(), String> {
        let transform = &self.ev.transform;
        self.cur.hat.assign(&spectrum(saved, "phi_hat", transform)?);
        self.sigma = saved.get("sigma")?;
        self.volume0 = saved.get("volume0")?;
        self.dt_prev = saved.get("dt_prev")?;
        let dt_next = saved.get("dt_next")?;
        self.dt_next = (!dt_next.is_nan()).then_some(dt_next);
        self.prev = match (self.scheme, spectrum(saved, "prev_phi_hat", transform)) {
            (Scheme::Sbdf2, Ok(hat)) => Some((
                hat.into_owned(),
                spectrum(saved, "prev_nonlinear", transform)?.into_owned(),
            )),
            _ => None,
        };
        self.ev
            .evaluate(&mut self.cur, t, None, Some(self.sigma))
            .map_err(|d| d.0)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The area quadratic A(σ) = A_PP + 2σ A_PQ + σ² A_QQ of a step (SBDF1, and SBDF2 with its
    /// φ̂ⁿ⁻¹, N̂ⁿ⁻¹ terms) equals the area of the update written at that σ, to 1e-12 (relative),
    /// at σ = −0.3, 0, 0.7 on an odd-sized box (pieces filled unevenly): a term or a weight wrong
    /// in either sweep would miss by far more.
    #[test]
    fn area_quadratic_predicts_the_written_area() {
        for scheme in ["sbdf1", "sbdf2"] {
            let scene = json!({"dim": 3, "n": [21, 20, 23], "h": 1.0, "eps": 1.0,
                "method": "spectral", "scheme": scheme, "dt": 0.5, "max_steps": 3,
                "initial": {"shape": "ellipsoid", "axes": [7.0, 5.0, 5.0]}});
            let scene = crate::problem::config::from_value(scene).expect("scene");
            let pb = crate::problem::setup::build(&scene).expect("problem");
            let mut e = SpectralEngine::new(&scene, pb.grid, pb.c0, pb.phi).expect("engine");
            for n in 0..2 {
                e.step(n as f64 * 0.5, 0.5).expect("step");
            }
            assert_eq!(e.uses_prev(0.7), scheme == "sbdf2");
            let (app, apq, aqq) = e.area_quadratic(0.7);
            for sigma in [-0.3, 0.0, 0.7] {
                let predicted = app + 2.0 * sigma * apq + sigma * sigma * aqq;
                let written = e.write_update(0.7, sigma);
                let rel = (predicted - written).abs() / written;
                assert!(
                    rel <= 1e-12,
                    "{scheme} σ {sigma}: {predicted} against {written}"
                );
            }
        }
    }
}
