//! The paper's finite-difference reference (DESIGN.md §2): second-order central differences,
//! explicit Euler,
//!
//! ```text
//! φ^{n+1} = φ^n + Δt ∇²_h μ_h(φ^n, σ^n),
//! μ_h     = 2[f'(φ)Φ_h − ε² ∇²_h Φ_h] − (3/√2) ε σ ∇²_h φ,   Φ_h = f(φ) − ε² ∇²_h φ,
//! ```
//!
//! with the paper's Lagrangian area update σ^{n+1} = σ^n + α (A_h^n − A0) (σ^0 = 0).
//! Stable for Δt < 1 / (λ (2 + ε²λ)² + (3/√2) ε σ λ²/2), λ = 4d/h² ([`stability_bound`]).
//!
//! The engine keeps μ_h of its current state at its current σ: the stationarity residual
//! RMS(μ_h − mean μ_h) is read from it, and the next step uses it.

use crate::config::AreaMethod;
use crate::engine::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::grid::Grid;
use crate::model::{self, bulk, bulk_derivative, Measures, C0, PHI_BLOWUP};
use crate::numerics::{nearest_root, CONSTRAINT_TOL, ENERGY_RISE_TOL, PAR_CHUNK};
use crate::stencil;
use ndarray::Array3;
use rayon::prelude::*;

/// Explicit-Euler stability bound of the FD scheme at tension σ:
/// `Δt < 1 / (λ (2 + ε²λ)² + (3/√2) ε σ λ²/2)`, λ = 4d/h² (linearisation about φ = ±1).
pub fn stability_bound(grid: &Grid, eps: f64, sigma: f64) -> f64 {
    let l = stencil::lambda_max(grid);
    let denom = l * (2.0 + eps * eps * l).powi(2)
        + 3.0 / std::f64::consts::SQRT_2 * eps * sigma * l * l / 2.0;
    if denom > 0.0 {
        1.0 / denom
    } else {
        f64::INFINITY
    }
}

/// The FD engine's state and work arrays.
pub struct FdEngine {
    grid: Grid,
    eps: f64,
    c0: C0,
    phi: Array3<f64>,
    /// ∇²_h φ of the current state.
    lap_phi: Array3<f64>,
    /// Φ_h of the current state.
    big_phi: Array3<f64>,
    /// μ_h(φ, σ) of the current state (the previous φ during a step).
    mu: Array3<f64>,
    /// Work: ∇²_h Φ_h, then ∇²_h μ_h.
    work: Array3<f64>,
    sigma: f64,
    area: AreaConstraint,
    measures: Measures,
    /// Time of the current state (for a ramped C0).
    t: f64,
    /// RMS of μ_h − mean μ_h of the current state.
    residual: f64,
    /// Largest Δt / bound(σ) seen.
    max_bound_ratio: f64,
    /// Q = −Δt (3/√2) ε ∇²_h∇²_h φⁿ of the exact projection (allocated when it is chosen).
    projection: Option<Array3<f64>>,
    /// V of the first state (held to round-off by the telescoping stencil).
    volume0: f64,
    /// Refuse steps that raise F_eff (explicit Euler below its bound is dissipative).
    energy_guard: bool,
}

impl FdEngine {
    /// Engine at time `t` holding `phi`, with no area constraint.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(grid: Grid, eps: f64, c0: C0, phi: Array3<f64>, t: f64) -> Result<Self, Diverged> {
        let zeros = grid.zeros();
        let mut e = FdEngine {
            eps,
            c0,
            phi,
            lap_phi: zeros.clone(),
            big_phi: zeros.clone(),
            mu: zeros.clone(),
            work: zeros,
            sigma: 0.0,
            area: AreaConstraint::none(),
            measures: Measures::default(),
            t,
            residual: f64::NAN,
            max_bound_ratio: 0.0,
            projection: None,
            volume0: 0.0,
            energy_guard: true,
            grid,
        };
        e.refresh(t)?;
        e.refresh_mu();
        e.volume0 = e.measures.volume;
        Ok(e)
    }

    /// Recompute ∇²_h φ, Φ_h and the measures of the current state at time `t`.
    fn refresh(&mut self, t: f64) -> Result<(), Diverged> {
        stencil::laplacian(&self.grid, &self.phi, &mut self.lap_phi);
        let r = self.c0.ramp(t);
        let e2 = self.eps * self.eps;
        let (uniform, field) = self.c0.parts(r);
        let phi = self.phi.as_slice().expect("standard layout");
        let lap = self.lap_phi.as_slice().expect("standard layout");
        let big = self.big_phi.as_slice_mut().expect("standard layout");
        // Φ_h = f(φ) − ε²∇²_h φ, with Σ Φ², max|φ| and Σ φ.
        let (sum_sq, max_abs, sum_phi) = big
            .par_chunks_mut(PAR_CHUNK)
            .enumerate()
            .map(|(j, b)| {
                let start = j * PAR_CHUNK;
                let mut acc = (0.0, 0.0f64, 0.0);
                for (k, b) in b.iter_mut().enumerate() {
                    let i = start + k;
                    let p = phi[i];
                    let ec0 = field.map_or(uniform, |f| r * f[i]);
                    *b = bulk(p, ec0) - e2 * lap[i];
                    acc = (acc.0 + *b * *b, acc.1.max(p.abs()), acc.2 + p);
                }
                acc
            })
            .reduce(
                || (0.0, 0.0, 0.0),
                |a, b| (a.0 + b.0, a.1.max(b.1), a.2 + b.2),
            );
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        self.measures = Measures {
            energy: sum_sq * dv,
            area: stencil::area(&self.grid, self.eps, &self.phi),
            // V = Σ (1 + φ)/2 h^d
            volume: 0.5 * (phi.len() as f64 + sum_phi) * dv,
        };
        if model::diverged(max_abs, self.measures.energy) {
            return Err(Diverged(format!(
                "max|φ| = {max_abs:.3e}, F = {:.3e} (limit |φ| ≤ {PHI_BLOWUP}): the explicit scheme diverged",
                self.measures.energy
            )));
        }
        Ok(())
    }

    /// With the exact projection: `phi` holds P = φⁿ + Δt ∇²_h μ_h(φⁿ, σⁿ) (φⁿ in `mu`); add
    /// δQ, Q = −Δt (3/√2) ε ∇²_h∇²_h φⁿ, for the δ nearest 0 that restores A_h = A0, so that
    /// σ^{n+1} = σⁿ + δ. Returns max|φ^{n+1} − φⁿ|/Δt, or `None` without projection.
    fn project(&mut self, dt: f64) -> Result<Option<f64>, Diverged> {
        let Some(q) = self.projection.as_mut() else {
            return Ok(None);
        };
        stencil::laplacian(&self.grid, &self.lap_phi, q);
        let scale = -dt * 3.0 / std::f64::consts::SQRT_2 * self.eps;
        q.par_mapv_inplace(|v| v * scale);
        let form = |u, v| stencil::area_form(&self.grid, self.eps, u, v);
        let (app, apq, aqq) = (form(&self.phi, &self.phi), form(&self.phi, q), form(q, q));
        let delta = nearest_root(aqq, apq, app - self.area.target, 0.0).ok_or_else(|| {
            Diverged(
                "the area projection has no real root (Δt too large for the constraint)".into(),
            )
        })?;
        let old = self.mu.as_slice().expect("standard layout");
        let q = q.as_slice().expect("standard layout");
        let change = self
            .phi
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(PAR_CHUNK)
            .zip(q.par_chunks(PAR_CHUNK))
            .zip(old.par_chunks(PAR_CHUNK))
            .map(|((p, q), o)| {
                let mut m = 0.0f64;
                for ((p, &q), &o) in p.iter_mut().zip(q).zip(o) {
                    *p += delta * q;
                    m = m.max((*p - o).abs());
                }
                m
            })
            .reduce(|| 0.0, f64::max);
        self.sigma += delta;
        Ok(Some(change / dt))
    }

    /// The FD stability bound at the current σ.
    pub fn bound(&self) -> f64 {
        stability_bound(&self.grid, self.eps, self.sigma)
    }

    /// After a step of `dt` from a state with measures `before` (σ now that of the step): V
    /// held, A held under the projection, and F_eff at the step's σ not risen (unless a ramped C0
    /// or a stability study).
    fn check(&self, before: Measures, dt: f64) -> Result<(), Diverged> {
        let m = self.measures;
        let dv = (m.volume - self.volume0).abs() / self.volume0.abs().max(1e-300);
        if dv > CONSTRAINT_TOL {
            return Err(Diverged(format!(
                "volume drifted by {dv:.2e} (relative) at Δt = {dt:.4e}"
            )));
        }
        if self.area.method == AreaMethod::Projection {
            let da = (m.area - self.area.target).abs() / self.area.target;
            if da > CONSTRAINT_TOL {
                return Err(Diverged(format!(
                    "area off its target by {da:.2e} (relative)"
                )));
            }
        }
        if self.energy_guard && !self.c0.is_ramped() && dt > 0.0 {
            let s = self.sigma;
            let (f0, f1) = (before.energy + s * before.area, m.energy + s * m.area);
            if f1 > f0 + ENERGY_RISE_TOL * f0.abs() {
                return Err(Diverged(format!(
                    "F_eff rose from {f0:.12e} to {f1:.12e} (relative {:.2e}): explicit Euler \
                     is not dissipative at Δt = {dt:.4e} (bound {:.4e} at this σ)",
                    (f1 - f0) / f0.abs(),
                    self.bound()
                )));
            }
        }
        Ok(())
    }

    /// Back to the state before a failed step (φⁿ is in `mu`, σⁿ given).
    fn undo_step(&mut self, sigma: f64) -> Result<(), Diverged> {
        std::mem::swap(&mut self.mu, &mut self.phi);
        self.sigma = sigma;
        self.refresh(self.t)?;
        self.refresh_mu();
        Ok(())
    }

    /// μ_h(φ, σ) of the current state at its σ (the discrete δF_eff/δφ divided by h^d).
    pub fn chemical_potential(&self) -> &Array3<f64> {
        &self.mu
    }

    /// `mu = μ_h(φ, σ)` from the cached ∇²_h φ and Φ_h, and the residual
    /// (mean over the box of (μ_h − mean μ_h)²)^½, in two passes (the mean first: near
    /// stationarity μ_h − mean μ_h is many orders below μ_h).
    fn refresh_mu(&mut self) {
        stencil::laplacian(&self.grid, &self.big_phi, &mut self.work);
        let r = self.c0.ramp(self.t);
        let e2 = self.eps * self.eps;
        let tension = 3.0 / std::f64::consts::SQRT_2 * self.eps * self.sigma;
        let (uniform, field) = self.c0.parts(r);
        let phi = self.phi.as_slice().expect("standard layout");
        let big = self.big_phi.as_slice().expect("standard layout");
        let lap_big = self.work.as_slice().expect("standard layout");
        let lap = self.lap_phi.as_slice().expect("standard layout");
        let mu = self.mu.as_slice_mut().expect("standard layout");
        let sum: f64 = mu
            .par_chunks_mut(PAR_CHUNK)
            .enumerate()
            .map(|(j, m)| {
                let start = j * PAR_CHUNK;
                let mut sum = 0.0;
                for (k, m) in m.iter_mut().enumerate() {
                    let i = start + k;
                    let fp = bulk_derivative(phi[i], field.map_or(uniform, |f| r * f[i]));
                    *m = 2.0 * (fp * big[i] - e2 * lap_big[i]) - tension * lap[i];
                    sum += *m;
                }
                sum
            })
            .sum();
        let mean = sum / mu.len() as f64;
        let sum_sq: f64 = mu
            .par_chunks(PAR_CHUNK)
            .map(|m| m.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>())
            .sum();
        self.residual = (sum_sq / mu.len() as f64).sqrt();
    }
}

impl Engine for FdEngine {
    fn phi(&self) -> &Array3<f64> {
        &self.phi
    }

    fn sigma(&self) -> f64 {
        self.sigma
    }

    fn measures(&self) -> Measures {
        self.measures
    }

    fn residual(&self) -> f64 {
        self.residual
    }

    fn set_area(&mut self, area: AreaConstraint) {
        if area.method == AreaMethod::None && self.sigma != 0.0 {
            self.sigma = 0.0;
            self.refresh_mu();
        }
        self.projection = (area.method == AreaMethod::Projection).then(|| self.grid.zeros());
        self.area = area;
    }

    /// One explicit Euler step from the cached μ_h(φⁿ, σⁿ). Lagrangian: σ^{n+1} from the area of
    /// the state before the step. Projection: φ^{n+1} = P + δQ with P the step at σⁿ and
    /// Q = −Δt (3/√2) ε ∇²_h∇²_h φⁿ, σ^{n+1} = σⁿ + δ the root of A_h = A0 nearest σⁿ (the same
    /// exact projection as the spectral engine, on the FD area).
    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, Diverged> {
        self.max_bound_ratio = self.max_bound_ratio.max(dt / self.bound());
        stencil::laplacian(&self.grid, &self.mu, &mut self.work);
        // Keep φ^n in `mu` so a blow-up can restore it; μ is recomputed after the step.
        std::mem::swap(&mut self.mu, &mut self.phi);
        // φ^{n+1} = φ^n + Δt ∇²_h μ; rate = max|∇²_h μ|.
        let old = self.mu.as_slice().expect("standard layout");
        let lap_mu = self.work.as_slice().expect("standard layout");
        let rate = self
            .phi
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(PAR_CHUNK)
            .zip(old.par_chunks(PAR_CHUNK))
            .zip(lap_mu.par_chunks(PAR_CHUNK))
            .map(|((new, old), lap_mu)| {
                let mut m = 0.0f64;
                for ((n, &o), &l) in new.iter_mut().zip(old).zip(lap_mu) {
                    *n = o + dt * l;
                    m = m.max(l.abs());
                }
                m
            })
            .reduce(|| 0.0, f64::max);
        let sigma_before = self.sigma;
        let rate = match self.project(dt) {
            Ok(Some(r)) => r,
            Ok(None) => rate,
            Err(e) => {
                self.undo_step(sigma_before)?;
                return Err(e);
            }
        };
        let before = self.measures;
        if let Err(e) = self.refresh(t + dt).and_then(|()| self.check(before, dt)) {
            self.undo_step(sigma_before)?;
            return Err(e);
        }
        let area_before = before.area;
        if self.area.method == AreaMethod::Lagrangian {
            self.sigma += self.area.alpha * (area_before - self.area.target);
        }
        self.t = t + dt;
        self.refresh_mu();
        Ok(StepReport {
            dt,
            rate,
            rejected: 0,
        })
    }

    fn max_dt_over_bound(&self) -> Option<f64> {
        Some(self.max_bound_ratio)
    }

    fn guard_energy(&mut self, on: bool) {
        self.energy_guard = on;
    }

    fn name(&self) -> &'static str {
        "fd"
    }

    fn save(&self) -> Saved {
        Saved::default()
            .scalar("sigma", self.sigma)
            .scalar("max_bound_ratio", self.max_bound_ratio)
            .scalar("volume0", self.volume0)
            .array("phi", SavedArray::Real(self.phi.clone()))
    }

    fn restore(&mut self, saved: &Saved, t: f64) -> Result<(), String> {
        let phi = saved.real("phi", self.phi.shape())?;
        self.phi.assign(phi);
        self.sigma = saved.get("sigma")?;
        self.max_bound_ratio = saved.get("max_bound_ratio")?;
        self.volume0 = saved.get("volume0")?;
        self.t = t;
        self.refresh(t).map_err(|d| d.0)?;
        self.refresh_mu();
        Ok(())
    }
}
