//! The Fourier semi-implicit engine (DESIGN.md §3). In Fourier space
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

use super::evaluator::{axis_symbol, Evaluator, ExplicitTerm, State};
use crate::config::{AdaptiveSettings, AreaMethod, Laplacian, Scene, Scheme, Stabilizer};
use crate::engine::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::grid::Grid;
use crate::model::{Measures, C0};
use crate::numerics::{nearest_root, CONSTRAINT_TOL, ENERGY_RISE_TOL, PAR_CHUNK};
use ndarray::Array3;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

/// Per wavenumber: S(k), 1/D(k) with D = a0 + Δt(2ε⁴k⁶ + S) and −Δt c_σ k⁴/D, recomputed only
/// when Δt or a0 change (every step of a fixed-Δt run reuses them).
#[derive(Default)]
struct UpdateTables {
    coef: Vec<[f64; 3]>,
    key: Option<(f64, f64)>,
}

impl UpdateTables {
    fn update(&mut self, k2: &[f64], eps: f64, st: &Stabilizer, dt: f64, a0: f64) {
        if self.key == Some((dt, a0)) {
            return;
        }
        let e2 = eps * eps;
        let c_sigma = 3.0 / std::f64::consts::SQRT_2 * eps;
        if self.coef.len() != k2.len() {
            self.coef = vec![[0.0; 3]; k2.len()];
        }
        self.coef
            .par_chunks_mut(PAR_CHUNK)
            .zip(k2.par_chunks(PAR_CHUNK))
            .for_each(|(c, k)| {
                for (c, &k) in c.iter_mut().zip(k) {
                    let s = st.s2 * k + st.s4 * e2 * k * k;
                    let inv = 1.0 / (a0 + dt * (2.0 * e2 * e2 * k * k * k + s));
                    *c = [s, inv, -dt * c_sigma * k * k * inv];
                }
            });
        self.key = Some((dt, a0));
    }
}

/// Why an attempted step was rejected (no allocation: adaptive runs reject routinely).
#[derive(Debug)]
enum Rejection {
    /// A(φ^{n+1}(σ)) = A0 has no real root.
    NoRealRoot,
    /// The new state is not finite or |φ| is too large.
    Diverged(Diverged),
    /// V drifted by this relative amount.
    VolumeDrift(f64),
    /// A is off its target by this relative amount (projection).
    AreaDrift(f64),
    /// F_eff rose (adaptive steps).
    EnergyRise { before: f64, after: f64 },
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rejection::NoRealRoot => write!(f, "the area projection has no real root"),
            Rejection::Diverged(d) => write!(f, "{}", d.0),
            Rejection::VolumeDrift(d) => write!(f, "volume drifted by {d:.2e} (relative)"),
            Rejection::AreaDrift(d) => write!(f, "area off its target by {d:.2e} (relative)"),
            Rejection::EnergyRise { before, after } => write!(
                f,
                "F_eff rose from {before:.12e} to {after:.12e} (relative {:.2e}): the step is not \
                 dissipative at this Δt; lower dt or use adaptive steps",
                (after - before) / before.abs()
            ),
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
    /// Per-wavenumber coefficients of the update for the current Δt.
    tables: UpdateTables,
    /// φ̂^{n−1} and N̂^{n−1} (SBDF2).
    prev: Option<(Array3<Complex64>, Array3<Complex64>)>,
    dt_prev: f64,
    /// max|φ^{n+1} − φ^n| of the last attempt.
    max_change: f64,
    sigma: f64,
    area: AreaConstraint,
    volume0: f64,
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
        );
        let cur = ev.state_of(&phi, 0.0)?;
        let adaptive = scene.adaptive.settings().map(|a| AdaptiveSettings {
            dt_min: Some(a.dt_min.unwrap_or(1e-3 * scene.dt)),
            dt_max: Some(a.dt_max.unwrap_or(1e3 * scene.dt)),
            ..a
        });
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
            tables: UpdateTables::default(),
            sigma: 0.0,
            area: AreaConstraint::none(),
            dt_next: None,
            energy_guard: true,
        })
    }

    /// SBDF coefficients (a0, a1, a2, b1, b2) for this step.
    fn coefficients(&self, dt: f64) -> [f64; 5] {
        match (&self.scheme, &self.prev) {
            (Scheme::Sbdf2, Some(_)) => {
                let w = dt / self.dt_prev;
                [
                    (1.0 + 2.0 * w) / (1.0 + w),
                    -(1.0 + w),
                    w * w / (1.0 + w),
                    1.0 + w,
                    -w,
                ]
            }
            _ => [1.0, -1.0, 0.0, 1.0, 0.0],
        }
    }

    /// Write P̂ into `next.hat` and Q̂ into `spare`; return (A_PP, A_PQ, A_QQ).
    fn affine_update(&mut self, dt: f64) -> (f64, f64, f64) {
        let [a0, a1, a2, b1, b2] = self.coefficients(dt);
        let c = PAR_CHUNK;
        let cur_hat = self.cur.hat.as_slice().expect("standard layout");
        let cur_n = self.cur.nonlinear.as_slice().expect("standard layout");
        let prev = match &self.prev {
            Some((h, n)) if a2 != 0.0 => {
                Some((h.as_slice().expect("std"), n.as_slice().expect("std")))
            }
            _ => None,
        };
        self.tables
            .update(&self.ev.symbols.k2, self.ev.eps, &self.stabilizer, dt, a0);
        let coef = &self.tables.coef;
        let p_out = self.next.hat.as_slice_mut().expect("standard layout");
        let q_out = self.ev.spare.as_slice_mut().expect("standard layout");
        let aw = &self.ev.symbols.area_weight;
        // P = [−a1 φ̂ⁿ − a2 φ̂ⁿ⁻¹ + Δt(b1(N̂ⁿ + Sφ̂ⁿ) + b2(N̂ⁿ⁻¹ + Sφ̂ⁿ⁻¹))]/D,
        // Q = −Δt c_σ k⁴ (b1 φ̂ⁿ + b2 φ̂ⁿ⁻¹)/D, D = a0 + Δt(2ε⁴k⁶ + S); returns w k²-weighted
        // |P|², Re(P Q*), |Q|².
        let body = |[s, inv, qc]: [f64; 3],
                    w: f64,
                    h1: Complex64,
                    n1: Complex64,
                    h0: Complex64,
                    n0: Complex64,
                    p: &mut Complex64,
                    q: &mut Complex64| {
            let rhs = h1 * (-a1) - h0 * a2 + ((n1 + h1 * s) * b1 + (n0 + h0 * s) * b2) * dt;
            *p = rhs * inv;
            *q = (h1 * b1 + h0 * b2) * qc;
            (
                w * p.norm_sqr(),
                w * (p.re * q.re + p.im * q.im),
                w * q.norm_sqr(),
            )
        };
        let add = |x: (f64, f64, f64), y: (f64, f64, f64)| (x.0 + y.0, x.1 + y.1, x.2 + y.2);
        p_out
            .par_chunks_mut(c)
            .zip(q_out.par_chunks_mut(c))
            .enumerate()
            .map(|(j, (p, q))| {
                let r = j * c..j * c + p.len();
                let (k, w, h1, n1) = (
                    &coef[r.clone()],
                    &aw[r.clone()],
                    &cur_hat[r.clone()],
                    &cur_n[r.clone()],
                );
                let rows = p.iter_mut().zip(q.iter_mut()).zip(k).zip(w).zip(h1).zip(n1);
                match prev {
                    Some((h0, n0)) => rows
                        .zip(&h0[r.clone()])
                        .zip(&n0[r])
                        .map(|(((((((p, q), &k), &w), &h1), &n1), &h0), &n0)| {
                            body(k, w, h1, n1, h0, n0, p, q)
                        })
                        .fold((0.0, 0.0, 0.0), add),
                    None => rows
                        .map(|(((((p, q), &k), &w), &h1), &n1)| {
                            body(
                                k,
                                w,
                                h1,
                                n1,
                                Complex64::default(),
                                Complex64::default(),
                                p,
                                q,
                            )
                        })
                        .fold((0.0, 0.0, 0.0), add),
                }
            })
            .reduce(|| (0.0, 0.0, 0.0), add)
    }

    /// σ used in this step's update, or `None` if the projection has no real root.
    fn choose_sigma(&self, (app, apq, aqq): (f64, f64, f64)) -> Option<f64> {
        match self.area.method {
            AreaMethod::None => Some(0.0),
            AreaMethod::Lagrangian => Some(self.sigma),
            AreaMethod::Projection => nearest_root(aqq, apq, app - self.area.target, self.sigma),
        }
    }

    /// σ of the state after a step that used `step_sigma`: the same, except under the Lagrangian
    /// update σ^{n+1} = σ^n + α (A^n − A0).
    fn sigma_after(&self, step_sigma: f64) -> f64 {
        match self.area.method {
            AreaMethod::Lagrangian => {
                self.sigma + self.area.alpha * (self.cur.measures.area - self.area.target)
            }
            _ => step_sigma,
        }
    }

    /// Try one step of size `dt`: on success `next` holds the new state (its residual at the
    /// new σ) and the σ of the update and of the new state are returned.
    fn attempt(&mut self, t: f64, dt: f64) -> Result<(f64, f64), Rejection> {
        let sums = self.affine_update(dt);
        let sigma = self.choose_sigma(sums).ok_or(Rejection::NoRealRoot)?;
        let q = self.ev.spare.as_slice().expect("standard layout");
        self.next
            .hat
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(PAR_CHUNK)
            .zip(q.par_chunks(PAR_CHUNK))
            .for_each(|(p, q)| p.iter_mut().zip(q).for_each(|(p, q)| *p += q * sigma));
        let sigma_after = self.sigma_after(sigma);
        self.max_change = self
            .ev
            .evaluate(
                &mut self.next,
                t + dt,
                Some(&self.cur.phi),
                Some(sigma_after),
            )
            .map_err(Rejection::Diverged)?;
        self.check_constraints(sigma)?;
        Ok((sigma, sigma_after))
    }

    /// Volume (and area under projection) held; F_eff (at the σ of the update) must not rise
    /// where the scheme guarantees that it falls: adaptive steps, and fixed SBDF1 steps (the
    /// stabilised first-order step is dissipative; SBDF2 is not guaranteed to be, and a ramped
    /// C0 may raise F legitimately). Off when the energy guard is off (stability studies).
    fn check_constraints(&self, sigma: f64) -> Result<(), Rejection> {
        let m = self.next.measures;
        let dv = (m.volume - self.volume0).abs() / self.volume0.abs().max(1e-300);
        if dv > CONSTRAINT_TOL {
            return Err(Rejection::VolumeDrift(dv));
        }
        if self.area.method == AreaMethod::Projection {
            let da = (m.area - self.area.target).abs() / self.area.target;
            if da > CONSTRAINT_TOL {
                return Err(Rejection::AreaDrift(da));
            }
        }
        let dissipative = self.adaptive.is_some() || self.scheme == Scheme::Sbdf1;
        if self.energy_guard && dissipative && !self.ev.c0.is_ramped() {
            let before = self.cur.measures.energy + sigma * self.cur.measures.area;
            let after = m.energy + sigma * m.area;
            if after > before + ENERGY_RISE_TOL * before.abs() {
                return Err(Rejection::EnergyRise { before, after });
            }
        }
        Ok(())
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

    /// Energy-based proposal for the next step (Qiao–Zhang–Tang), limited by `growth`:
    /// `clamp(dt_max / √(1 + α (Ḟ/F)²), dt_min, growth · Δt)`.
    fn propose(a: &AdaptiveSettings, dt: f64, f_old: f64, f_new: f64) -> f64 {
        let rate = (f_new - f_old).abs() / dt / f_new.abs().max(1e-300);
        let (dt_min, dt_max) = (a.dt_min.unwrap_or(dt), a.dt_max.unwrap_or(dt));
        let target = dt_max / (1.0 + a.energy_alpha * rate * rate).sqrt();
        target
            .clamp(dt_min, (a.growth * dt).max(dt_min))
            .min(dt_max)
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
        let mut dt = dt;
        let mut rejected = 0;
        loop {
            match self.attempt(t, dt) {
                Ok((_, sigma_after)) => {
                    let f_old = self.cur.measures.energy;
                    self.accept(sigma_after, dt);
                    let rate = self.max_change / dt;
                    if let Some(a) = &self.adaptive {
                        let f_new = self.cur.measures.energy;
                        self.dt_next = Some(Self::propose(a, dt, f_old, f_new));
                    }
                    return Ok(StepReport { dt, rate, rejected });
                }
                Err(reason) => {
                    let Some(a) = &self.adaptive else {
                        return Err(Diverged(reason.to_string()));
                    };
                    let dt_min = a.dt_min.unwrap_or(dt);
                    rejected += 1;
                    if dt <= dt_min {
                        return Err(Diverged(format!(
                            "step rejected at the smallest step dt_min = {dt_min:.3e}: {reason}"
                        )));
                    }
                    dt = (dt * a.shrink).max(dt_min);
                }
            }
        }
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

    fn save(&self) -> Saved {
        let mut saved = Saved::default()
            .scalar("sigma", self.sigma)
            .scalar("volume0", self.volume0)
            .scalar("dt_prev", self.dt_prev)
            .scalar("dt_next", self.dt_next.unwrap_or(f64::NAN))
            .array("phi_hat", SavedArray::Complex(self.cur.hat.clone()));
        if let Some((hat, nonlinear)) = &self.prev {
            saved = saved
                .array("prev_phi_hat", SavedArray::Complex(hat.clone()))
                .array("prev_nonlinear", SavedArray::Complex(nonlinear.clone()));
        }
        saved
    }

    fn restore(&mut self, saved: &Saved, t: f64) -> Result<(), String> {
        let shape = self.cur.hat.shape().to_vec();
        self.cur.hat.assign(saved.complex("phi_hat", &shape)?);
        self.sigma = saved.get("sigma")?;
        self.volume0 = saved.get("volume0")?;
        self.dt_prev = saved.get("dt_prev")?;
        let dt_next = saved.get("dt_next")?;
        self.dt_next = (!dt_next.is_nan()).then_some(dt_next);
        self.prev = match (self.scheme, saved.complex("prev_phi_hat", &shape)) {
            (Scheme::Sbdf2, Ok(hat)) => Some((
                hat.clone(),
                saved.complex("prev_nonlinear", &shape)?.clone(),
            )),
            _ => None,
        };
        self.ev
            .evaluate(&mut self.cur, t, None, Some(self.sigma))
            .map_err(|d| d.0)?;
        Ok(())
    }
}
