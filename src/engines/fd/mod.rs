//! The paper's finite-difference reference (docs/src/theory/fd.md): second-order central differences,
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
//!
//! A step without the exact projection is one fused sweep ([`sweep`]): φ^{n+1}, μ^{n+1}, the
//! measures and the residual in one pass over the box, φ^{n+1} into a second buffer that
//! replaces the state only when the step is accepted, μ^{n+1} over μⁿ (recomputed from φⁿ when
//! the step is not). The exact projection, and the refreshes of a state (start, resume, a new
//! σ), take the multi-pass route through [`stencil`].

mod lanes;
mod sweep;

use crate::engines::numerics::{
    nearest_root, sum_in_fixed_tree, CONSTRAINT_TOL, ENERGY_RISE_TOL, PAR_CHUNK,
};
use crate::engines::stencil;
use crate::engines::{
    AreaConstraint, Diverged, Engine, Rejection, Saved, SavedArray, StepError, StepReport,
};
use crate::problem::area_difference::{
    curvature_density, curvature_variation_local, AreaDifference,
};
use crate::problem::config::AreaMethod;
use crate::problem::grid::Grid;
use crate::problem::model::{
    self, bulk, bulk_derivative, Measures, AREA_PREFACTOR, C0, PHI_BLOWUP,
};
use ndarray::Array3;
use rayon::prelude::*;
use sweep::{Coefficients, Fields, Sums, Sweep};

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
    /// φ^{n+1} of a fused step; ∇²_h φ of the current state in the multi-pass route.
    next_phi: Array3<f64>,
    /// Φ_h of the current state in the multi-pass route and the refreshes.
    next_mu: Array3<f64>,
    /// μ_h(φ, σ) of the current state (the previous φ during a multi-pass step).
    mu: Array3<f64>,
    /// Mean of μ_h over the box (the shift of the next step's residual sums).
    mu_mean: f64,
    /// Work: ∇²_h Φ_h, then ∇²_h μ_h.
    work: Array3<f64>,
    /// The fused step's per-thread buffers.
    sweep: Sweep,
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
    /// The ADE term (its λ lagged: that of the current state) and its two work arrays (φ²,
    /// then ∇²_h φ²).
    couple: Option<(AreaDifference, Array3<f64>)>,
}

impl FdEngine {
    /// Engine at time `t` holding `phi`, with no area constraint, its sweeps split among
    /// `threads` workers.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(
        grid: Grid,
        eps: f64,
        c0: C0,
        phi: Array3<f64>,
        t: f64,
        threads: usize,
    ) -> Result<Self, Diverged> {
        let zeros = grid.zeros();
        let mut e = FdEngine {
            eps,
            c0,
            phi,
            next_phi: zeros.clone(),
            next_mu: zeros.clone(),
            mu: zeros.clone(),
            mu_mean: 0.0,
            work: zeros,
            sweep: Sweep::new(&grid, threads),
            sigma: 0.0,
            area: AreaConstraint::none(),
            measures: Measures::default(),
            t,
            residual: f64::NAN,
            max_bound_ratio: 0.0,
            projection: None,
            volume0: 0.0,
            energy_guard: true,
            couple: None,
            grid,
        };
        e.refresh(t)?;
        e.refresh_mu();
        e.volume0 = e.measures.volume;
        Ok(e)
    }

    /// Recompute ∇²_h φ, Φ_h and the measures of the current state at time `t`.
    fn refresh(&mut self, t: f64) -> Result<(), Diverged> {
        stencil::laplacian(&self.grid, &self.phi, &mut self.next_phi);
        let r = self.c0.ramp(t);
        let e2 = self.eps * self.eps;
        let (uniform, field) = self.c0.parts(r);
        let phi = self.phi.as_slice().expect("standard layout");
        let lap = self.next_phi.as_slice().expect("standard layout");
        let curvature = match self.couple {
            Some(_) => {
                let sum: f64 = phi
                    .iter()
                    .zip(lap)
                    .map(|(&p, &l)| curvature_density(p, l, e2))
                    .sum();
                sum * self.grid.cell_volume() * self.grid.mirror_factor()
            }
            None => 0.0,
        };
        let big = self.next_mu.as_slice_mut().expect("standard layout");
        // Φ_h = f(φ) − ε²∇²_h φ, with Σ Φ², max|φ| and Σ φ.
        let partials = big.par_chunks_mut(PAR_CHUNK).enumerate().map(|(j, b)| {
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
        });
        let (sum_sq, max_abs, sum_phi) = sum_in_fixed_tree(
            partials,
            || (0.0, 0.0, 0.0),
            |a, b| (a.0 + b.0, a.1.max(b.1), a.2 + b.2),
        );
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        self.measures = Measures {
            energy: sum_sq * dv,
            area: stencil::area(&self.grid, self.eps, &self.phi),
            // V = Σ (1 + φ)/2 h^d
            volume: 0.5 * (phi.len() as f64 + sum_phi) * dv,
            curvature,
        };
        blow_up(max_abs, self.measures.energy)
    }

    /// With the exact projection: `phi` holds P = φⁿ + Δt ∇²_h μ_h(φⁿ, σⁿ) (φⁿ in `mu`); add
    /// δQ, Q = −Δt (3/√2) ε ∇²_h∇²_h φⁿ, for the δ nearest 0 that restores A_h = A0, so that
    /// σ^{n+1} = σⁿ + δ. Returns max|φ^{n+1} − φⁿ|/Δt, or `None` without projection.
    fn project(&mut self, dt: f64) -> Result<Option<f64>, StepError> {
        let Some(q) = self.projection.as_mut() else {
            return Ok(None);
        };
        stencil::laplacian(&self.grid, &self.mu, &mut self.work);
        stencil::laplacian(&self.grid, &self.work, q);
        let scale = -dt * 3.0 / std::f64::consts::SQRT_2 * self.eps;
        q.par_mapv_inplace(|v| v * scale);
        let form = |u, v| stencil::area_form(&self.grid, self.eps, u, v);
        let (app, apq, aqq) = (form(&self.phi, &self.phi), form(&self.phi, q), form(q, q));
        let delta = nearest_root(aqq, apq, app - self.area.target, 0.0).ok_or_else(|| {
            StepError::Rejected {
                check: Rejection::NoRealRoot,
                context: " (Δt too large for the constraint)".into(),
            }
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

    /// F_ade of a state with measures `m` (0 without the term).
    fn ade_energy(&self, m: &Measures) -> f64 {
        self.couple
            .as_ref()
            .map_or(0.0, |(t, _)| t.energy(m.curvature))
    }

    /// The FD stability bound at the current σ.
    pub fn bound(&self) -> f64 {
        stability_bound(&self.grid, self.eps, self.sigma)
    }

    /// After a step of `dt` from a state with measures `before` to one with measures `m` (σ now
    /// that of the step): V held, A held under the projection, and F_eff at the step's σ not
    /// risen (unless a ramped C0 or a stability study).
    fn check(&self, before: Measures, m: Measures, dt: f64) -> Result<(), StepError> {
        let dv = (m.volume - self.volume0).abs() / self.volume0.abs().max(1e-300);
        if dv > CONSTRAINT_TOL {
            return Err(StepError::Rejected {
                check: Rejection::VolumeDrift(dv),
                context: format!(" at Δt = {dt:.4e}"),
            });
        }
        if self.area.method == AreaMethod::Projection {
            let da = (m.area - self.area.target).abs() / self.area.target;
            if da > CONSTRAINT_TOL {
                return Err(StepError::rejected(Rejection::AreaDrift(da)));
            }
        }
        if self.energy_guard && !self.c0.is_ramped() && dt > 0.0 {
            let (s, ade) = (self.sigma, |m: &Measures| self.ade_energy(m));
            let (f0, f1) = (
                before.energy + ade(&before) + s * before.area,
                m.energy + ade(&m) + s * m.area,
            );
            if f1 > f0 + ENERGY_RISE_TOL * f0.abs() {
                return Err(StepError::Rejected {
                    check: Rejection::EnergyRise {
                        before: f0,
                        after: f1,
                    },
                    context: format!(
                        ": explicit Euler is not dissipative at Δt = {dt:.4e} (bound {:.4e} at \
                         this σ)",
                        self.bound()
                    ),
                });
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

    /// `mu = μ_h(φ, σ)` from the cached ∇²_h φ and Φ_h, summed as the fused sweep sums it
    /// ((2f'Φ − (3/√2)εσ∇²φ) − 2ε²∇²Φ, so a resumed run continues bit for bit), and the residual
    /// (mean over the box of (μ_h − mean μ_h)²)^½, in two passes (the mean first: near
    /// stationarity μ_h − mean μ_h is many orders below μ_h).
    fn refresh_mu(&mut self) {
        stencil::laplacian(&self.grid, &self.next_mu, &mut self.work);
        let r = self.c0.ramp(self.t);
        let e2 = self.eps * self.eps;
        let tension = 3.0 / std::f64::consts::SQRT_2 * self.eps * self.sigma;
        let (uniform, field) = self.c0.parts(r);
        let phi = self.phi.as_slice().expect("standard layout");
        let big = self.next_mu.as_slice().expect("standard layout");
        let lap_big = self.work.as_slice().expect("standard layout");
        let lap = self.next_phi.as_slice().expect("standard layout");
        let mu = self.mu.as_slice_mut().expect("standard layout");
        let partials = mu.par_chunks_mut(PAR_CHUNK).enumerate().map(|(j, m)| {
            let start = j * PAR_CHUNK;
            let mut sum = 0.0;
            for (k, m) in m.iter_mut().enumerate() {
                let i = start + k;
                let fp = bulk_derivative(phi[i], field.map_or(uniform, |f| r * f[i]));
                *m = (2.0 * (fp * big[i]) - tension * lap[i]) - 2.0 * e2 * lap_big[i];
                sum += *m;
            }
            sum
        });
        let mut sum = sum_in_fixed_tree(partials, || 0.0, |a, b| a + b);
        if let Some((term, work)) = self.couple.as_mut() {
            sum = add_curvature_potential(
                (&self.grid, e2),
                term.multiplier(self.measures.curvature),
                [phi, lap],
                work,
                &mut self.work,
                mu,
            );
        }
        let mean = sum / mu.len() as f64;
        let partials = mu
            .par_chunks(PAR_CHUNK)
            .map(|m| m.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>());
        let sum_sq = sum_in_fixed_tree(partials, || 0.0, |a, b| a + b);
        self.residual = (sum_sq / mu.len() as f64).sqrt();
        self.mu_mean = mean;
    }

    /// σ^{n+1} of a step from the current state: σⁿ + α (A_hⁿ − A0) with the Lagrangian
    /// update, else σⁿ.
    fn next_sigma(&self) -> f64 {
        if self.area.method == AreaMethod::Lagrangian {
            self.sigma + self.area.alpha * (self.measures.area - self.area.target)
        } else {
            self.sigma
        }
    }

    /// The fused step (no exact projection): φ^{n+1} = φⁿ + Δt ∇²_h μⁿ and
    /// μ^{n+1} = μ_h(φ^{n+1}, σ^{n+1}) in one sweep into `next_phi` and over `mu`, with
    ///
    /// ```text
    /// F = Σ Φ_h² h^d,   A = −(3/(2√2)) ε Σ φ ∇²_h φ h^d,   V = Σ (1 + φ)/2 h^d
    /// ```
    ///
    /// (full-box values). A uses Σ_i Σ_axes (φ_{i+e} − φ_i)² = −h² Σ_i φ_i ∇²_h φ_i, summation
    /// by parts, exact with periodic and mirror walls. The residual comes from the shifted sums
    /// S1 = Σ(μ − c), S2 = Σ(μ − c)² with c the previous mean of μ: RMS² = S2/N − (S1/N)². The
    /// cancellation in that difference costs about ulp · (mean − c)²/RMS², and the mean moves
    /// little in a step (by Δt ∂_t mean μ), so near stationarity, where μ − mean μ is many orders
    /// below μ, the one pass keeps the accuracy of the two-pass mean-then-deviation. The state
    /// is replaced only when the step passes the checks; a rejected step leaves it as it was
    /// (its μ recomputed: [`Self::restore_mu`]).
    fn step_fused(&mut self, t: f64, dt: f64) -> Result<StepReport, StepError> {
        let sigma = self.next_sigma();
        let r = self.c0.ramp(t + dt);
        let (uniform, field) = self.c0.parts(r);
        let fields = Fields {
            phi: self.phi.as_slice().expect("standard layout"),
            c0: field,
        };
        let k = Coefficients {
            dt,
            inv_h2: 1.0 / (self.grid.h * self.grid.h),
            e2: self.eps * self.eps,
            tension: 3.0 / std::f64::consts::SQRT_2 * self.eps * sigma,
            uniform,
            ramp: r,
            shift: self.mu_mean,
        };
        let sums = self.sweep.run(
            &fields,
            &k,
            self.next_phi.as_slice_mut().expect("standard layout"),
            self.mu.as_slice_mut().expect("standard layout"),
        );
        let measures = self.measures_of(&sums);
        let checked = blow_up(sums.max_phi, measures.energy)
            .map_err(StepError::from)
            .and_then(|()| self.check(self.measures, measures, dt));
        if let Err(e) = checked {
            self.restore_mu();
            return Err(e);
        }
        std::mem::swap(&mut self.phi, &mut self.next_phi);
        let n = self.grid.len() as f64;
        let (m1, m2) = (sums.dev / n, sums.dev_sq / n);
        self.measures = measures;
        self.sigma = sigma;
        self.t = t + dt;
        self.mu_mean += m1;
        self.residual = (m2 - m1 * m1).max(0.0).sqrt();
        Ok(StepReport {
            dt,
            rate: sums.max_lap_mu,
            rejected: 0,
        })
    }

    /// μ_h(φⁿ, σⁿ) again after a fused step that failed its checks (the sweep wrote μ over it;
    /// φⁿ and σⁿ are untouched), bit for bit as the sweep computed it; the measures, the
    /// residual and its shift stay those of the state.
    fn restore_mu(&mut self) {
        let (measures, residual, mean) = (self.measures, self.residual, self.mu_mean);
        // φⁿ passed the checks when it became the state, so it is finite.
        self.refresh(self.t)
            .expect("the state before the step is finite");
        self.refresh_mu();
        (self.measures, self.residual, self.mu_mean) = (measures, residual, mean);
    }

    /// F, A, V (full-box values) from a sweep's sums (see [`Self::step_fused`]).
    fn measures_of(&self, sums: &Sums) -> Measures {
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        Measures {
            energy: sums.energy * dv,
            area: -AREA_PREFACTOR * self.eps * sums.phi_lap * dv,
            volume: 0.5 * (self.grid.len() as f64 + sums.phi) * dv,
            curvature: 0.0,
        }
    }

    /// The multi-pass step (the one for the exact projection): Laplacian of μⁿ, the update,
    /// the projection, then the refreshes of the measures and of μ^{n+1}; a failed step is
    /// undone by recomputing the state before it.
    fn step_multipass(&mut self, t: f64, dt: f64) -> Result<StepReport, StepError> {
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
        if let Err(e) = self
            .refresh(t + dt)
            .map_err(StepError::from)
            .and_then(|()| self.check(before, self.measures, dt))
        {
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
}

/// Add λ δM/δφ to `mu` (μ_h of a state, `phi` and `lap` = ∇²_h φ):
/// δM/δφ = (3φ² − 1)(1 − φ²) − 2φΦ₀ + ε²∇²_h(φ²), Φ₀ = φ³ − φ − ε²∇²_h φ, with `square` and
/// `lap_square` work arrays; returns Σ μ after it.
fn add_curvature_potential(
    (grid, e2): (&Grid, f64),
    lambda: f64,
    [phi, lap]: [&[f64]; 2],
    square: &mut Array3<f64>,
    lap_square: &mut Array3<f64>,
    mu: &mut [f64],
) -> f64 {
    square.iter_mut().zip(phi).for_each(|(s, &p)| *s = p * p);
    stencil::laplacian(grid, square, lap_square);
    let mut sum = 0.0;
    for (i, (m, &ls)) in mu.iter_mut().zip(lap_square.iter()).enumerate() {
        *m += lambda * (curvature_variation_local(phi[i], lap[i], e2) + e2 * ls);
        sum += *m;
    }
    sum
}

/// Divergence of a state with max|φ| = `max_abs` and F = `energy` ([`model::diverged`]).
fn blow_up(max_abs: f64, energy: f64) -> Result<(), Diverged> {
    if model::diverged(max_abs, energy) {
        return Err(Diverged(format!(
            "max|φ| = {max_abs:.3e}, F = {energy:.3e} (limit |φ| ≤ {PHI_BLOWUP}): the explicit scheme diverged"
        )));
    }
    Ok(())
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
    /// exact projection as the spectral engine, on the FD area). Fused without the projection,
    /// multi-pass with it.
    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, StepError> {
        self.max_bound_ratio = self.max_bound_ratio.max(dt / self.bound());
        if self.projection.is_some() || self.couple.is_some() {
            self.step_multipass(t, dt)
        } else {
            self.step_fused(t, dt)
        }
    }

    fn set_area_difference(&mut self, term: AreaDifference) -> Result<(), String> {
        self.couple = Some((term, self.grid.zeros()));
        self.refresh(self.t).map_err(|d| d.0)?;
        self.refresh_mu();
        Ok(())
    }

    fn area_difference(&self) -> Option<AreaDifference> {
        self.couple.as_ref().map(|(t, _)| *t)
    }

    fn lambda(&self) -> f64 {
        self.couple
            .as_ref()
            .map_or(0.0, |(t, _)| t.multiplier(self.measures.curvature))
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

    fn save(&self) -> Saved<'_> {
        Saved::default()
            .scalar("sigma", self.sigma)
            .scalar("max_bound_ratio", self.max_bound_ratio)
            .scalar("volume0", self.volume0)
            .scalar("mu_mean", self.mu_mean)
            .scalar("energy", self.measures.energy)
            .scalar("area", self.measures.area)
            .scalar("volume", self.measures.volume)
            .scalar("curvature", self.measures.curvature)
            .scalar("residual", self.residual)
            .array("phi", SavedArray::Real(self.phi.view().into()))
    }

    fn restore(&mut self, saved: &mut Saved<'_>, t: f64) -> Result<(), String> {
        let phi = saved.real("phi", self.phi.shape())?;
        self.phi.assign(&phi);
        self.sigma = saved.get("sigma")?;
        self.max_bound_ratio = saved.get("max_bound_ratio")?;
        self.volume0 = saved.get("volume0")?;
        self.t = t;
        self.refresh(t).map_err(|d| d.0)?;
        self.refresh_mu();
        // The running mean the next residual is shifted by (a checkpoint without it resumes
        // with the two-pass mean: residuals equal to round-off rather than bit for bit).
        if let Ok(m) = saved.get("mu_mean") {
            self.mu_mean = m;
        }
        // The measures and the residual as the step that made the state summed them: the fused
        // sweep sums A as Σ φ∇²φ, the refresh from forward differences, equal to round-off
        // only, and the Lagrangian update σ^{n+1} = σⁿ + α (Aⁿ − A0) reads Aⁿ.
        if let (Ok(energy), Ok(area), Ok(volume), Ok(residual)) = (
            saved.get("energy"),
            saved.get("area"),
            saved.get("volume"),
            saved.get("residual"),
        ) {
            self.measures = Measures {
                energy,
                area,
                volume,
                curvature: saved.get("curvature").unwrap_or(self.measures.curvature),
            };
            self.residual = residual;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::FdEngine;
    use crate::engines::stencil;
    use crate::engines::{AreaConstraint, Engine};
    use crate::problem::config::{self, AreaMethod};
    use crate::problem::setup;
    use serde_json::{json, Value};

    /// Relative difference, against a floor of `scale` (for values that may be near 0).
    fn rel(a: f64, b: f64, scale: f64) -> f64 {
        (a - b).abs() / b.abs().max(scale)
    }

    /// The engine of `scene` at t = 0 with the Lagrangian update towards 1.02 A(φ⁰) (so σ moves).
    fn engine(scene: &Value, threads: usize) -> FdEngine {
        let s = config::from_value(scene.clone()).expect("scene");
        let p = setup::build(&s).expect("problem");
        let mut e = FdEngine::new(p.grid, s.eps, p.c0, p.phi, 0.0, threads).expect("engine");
        let target = 1.02 * e.measures().area;
        e.set_area(AreaConstraint {
            method: AreaMethod::Lagrangian,
            alpha: 0.05,
            target,
            sigma: 0.0,
        });
        e
    }

    /// The fused step equals the multi-pass step to round-off: the same operators on the same
    /// values summed in the same order pointwise; only the order of the reductions differs (lanes,
    /// slabs, A from Σ φ∇²φ rather than the forward differences, the residual from shifted sums
    /// rather than two passes), and φ, μ feel it through σ. So after 12 steps
    /// φ, σ, F, A, V and the residual agree to 1e-12 relative, for a periodic box with a c0
    /// field, mirror walls on all axes, a mirror on axis 0 only, a 2D scene and a ramped c0, on
    /// 1, 2, 7 and 24 threads: slabs of every plane down to one plane each, with a shorter last
    /// slab (26 planes in slabs of 4 and of 2), so that stage 2 at a slab's end reads φ' from
    /// a neighbour's edges, from two slabs away, and across the periodic wrap and the walls.
    #[test]
    fn fused_step_equals_multipass_step() {
        let base = json!({
            "dim": 3, "n": [24, 24, 24], "h": 1.0, "eps": 1.0, "method": "fd", "dt": 4e-4,
            "initial": {"shape": "spheroid", "reduced_volume": 0.85, "r0": 4.5}
        });
        let with = |extra: Value| {
            let mut v = base.clone();
            v.as_object_mut()
                .unwrap()
                .extend(extra.as_object().unwrap().clone());
            v
        };
        let ball = json!({"inside": 0.3, "outside": 0.1, "radius": 4.0, "width": 2.0});
        let cases = [
            with(json!({"c0": ball})),
            with(json!({"symmetry": ["x", "y", "z"], "c0": 0.2})),
            with(json!({"symmetry": ["x"], "n": [26, 22, 24], "h": 1.1})),
            with(
                json!({"dim": 2, "n": [32, 28], "initial": {"shape": "spheroid",
                "reduced_volume": 0.8, "r0": 6.0}, "c0": ball}),
            ),
            with(
                json!({"c0": {"inside": 0.4, "outside": 0.0, "radius": 4.0, "width": 2.0,
                "ramp_time": 0.003}}),
            ),
        ];
        for threads in [1, 2, 7, 24] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for scene in &cases {
                pool.install(|| compare(scene, threads));
            }
        }
    }

    /// 12 steps of each path from the same state of `scene`, compared.
    fn compare(scene: &Value, threads: usize) {
        let (mut fused, mut multi) = (engine(scene, threads), engine(scene, threads));
        let dt = scene["dt"].as_f64().unwrap();
        for n in 0..12 {
            let t = n as f64 * dt;
            let a = fused.step_fused(t, dt).unwrap();
            let b = multi.step_multipass(t, dt).unwrap();
            assert!(rel(a.rate, b.rate, 0.0) <= 1e-12, "{scene}: rate");
        }
        let what = format!("{threads} thread(s), {scene}");
        let scale = fused.phi.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let dphi = fused
            .phi
            .iter()
            .zip(&multi.phi)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(dphi <= 1e-12 * scale, "{what}: φ differs by {dphi:e}");
        let (a, b) = (fused.measures(), multi.measures());
        assert!(multi.sigma() != 0.0, "{what}: σ must move");
        assert!(rel(fused.sigma(), multi.sigma(), 0.0) <= 1e-12, "{what}: σ");
        assert!(rel(a.energy, b.energy, 0.0) <= 1e-12, "{what}: F");
        assert!(rel(a.area, b.area, 0.0) <= 1e-12, "{what}: A");
        assert!(rel(a.volume, b.volume, 0.0) <= 1e-12, "{what}: V");
        let (r, s) = (fused.residual(), multi.residual());
        assert!(rel(r, s, 0.0) <= 1e-12, "{what}: residual {r:e} vs {s:e}");
        let dmu = fused
            .mu
            .iter()
            .zip(&multi.mu)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(dmu <= 1e-12 * s.max(1e-3), "{what}: μ differs by {dmu:e}");
        // The area from Σ φ∇²φ equals the forward-difference sum of `stencil::area`.
        let direct = stencil::area(&fused.grid, fused.eps, &fused.phi);
        assert!(rel(a.area, direct, 0.0) <= 1e-12, "{what}: A identity");
    }

    /// A rejected fused step (Δt far above the stability bound) leaves the state as it
    /// was, bit for bit.
    #[test]
    fn rejected_fused_step_keeps_the_state() {
        let mut e = engine(
            &json!({
                "dim": 3, "n": [16, 16, 16], "h": 1.0, "eps": 1.0, "method": "fd", "dt": 4e-4,
                "initial": {"shape": "spheroid", "reduced_volume": 0.9, "r0": 3.0}
            }),
            1,
        );
        e.step(0.0, 4e-4).unwrap();
        let (phi, mu) = (e.phi.clone(), e.mu.clone());
        let (m, s, r) = (e.measures(), e.sigma(), e.residual());
        // Far above the stability bound: the energy rises (or φ blows up).
        assert!(e.step(4e-4, 1.0).is_err());
        assert_eq!((e.phi.clone(), e.mu.clone()), (phi, mu));
        assert_eq!((e.measures(), e.sigma(), e.residual()), (m, s, r));
    }
}
