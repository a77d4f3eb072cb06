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

use super::transform::Transform;
use crate::config::{AdaptiveSettings, AreaMethod, Laplacian, Scene, Scheme, Stabilizer};
use crate::engine::{AreaConstraint, Diverged, Engine, StepReport};
use crate::fd::PHI_BLOWUP;
use crate::grid::Grid;
use crate::model::{self, bulk, bulk_derivative, Measures, AREA_PREFACTOR, C0};
use ndarray::{Array3, Zip};
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

/// Largest relative rise of F_eff an adaptive step may make (round-off of the sums).
pub const ENERGY_RISE_TOL: f64 = 1e-11;

/// Largest relative drift of V (and of A under projection) before the run counts as broken.
pub const CONSTRAINT_TOL: f64 = 1e-9;

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

/// A state of the engine: φ in both spaces, its explicit term N̂ and its measures.
struct State {
    hat: Array3<Complex64>,
    nonlinear: Array3<Complex64>,
    phi: Array3<f64>,
    measures: Measures,
}

/// Per-wavenumber tables.
struct Symbols {
    /// |k|².
    k2: Vec<f64>,
    /// Parseval weight × ∫-factor × (3/(2√2))ε |k|²: A = Σ area_weight |φ̂|².
    area_weight: Vec<f64>,
}

/// Evaluates a state from its φ̂: the transforms, tables and scratch, planned once.
struct Evaluator {
    grid: Grid,
    eps: f64,
    c0: C0,
    transform: Transform,
    symbols: Symbols,
    /// Q̂ of the step being taken, then scratch for transforms.
    spare: Array3<Complex64>,
    /// Real scratch: ∇²φ, then f.
    work: Array3<f64>,
    /// Real scratch: f'Φ.
    work2: Array3<f64>,
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
    sigma: f64,
    area: AreaConstraint,
    volume0: f64,
    dt_next: Option<f64>,
    /// Accepted and rejected steps.
    pub accepted: usize,
    /// Rejected attempts.
    pub rejected: usize,
}

impl SpectralEngine {
    /// Engine holding `phi` at t = 0, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let transform = Transform::new(grid.shape, grid.kinds, rayon::current_num_threads());
        let symbols = symbols(&transform, &grid, scene.eps, scene.laplacian);
        let mut ev = Evaluator {
            spare: Array3::zeros(transform.spectral_shape()),
            work: grid.zeros(),
            work2: grid.zeros(),
            eps: scene.eps,
            c0,
            transform,
            symbols,
            grid,
        };
        let mut cur = ev.blank();
        ev.transform.forward(&phi, &mut cur.hat);
        ev.evaluate(&mut cur, 0.0)?;
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
            stabilizer: scene.stabilizer.clone(),
            scheme: scene.scheme,
            adaptive,
            prev: None,
            dt_prev: scene.dt,
            sigma: 0.0,
            area: AreaConstraint::none(),
            dt_next: None,
            accepted: 0,
            rejected: 0,
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
        let e2 = self.ev.eps * self.ev.eps;
        let (s2, s4) = (self.stabilizer.s2, self.stabilizer.s4);
        let c_sigma = 3.0 / std::f64::consts::SQRT_2 * self.ev.eps;
        let zero = (Complex64::default(), Complex64::default());
        let cur_hat = self.cur.hat.as_slice().expect("standard layout");
        let cur_n = self.cur.nonlinear.as_slice().expect("standard layout");
        let (prev_hat, prev_n) = match &self.prev {
            Some((h, n)) if a2 != 0.0 => (
                Some(h.as_slice().expect("std")),
                Some(n.as_slice().expect("std")),
            ),
            _ => (None, None),
        };
        let p_out = self.next.hat.as_slice_mut().expect("standard layout");
        let q_out = self.ev.spare.as_slice_mut().expect("standard layout");
        let k2 = &self.ev.symbols.k2;
        let aw = &self.ev.symbols.area_weight;
        p_out
            .par_iter_mut()
            .zip(q_out.par_iter_mut())
            .enumerate()
            .map(|(i, (p, q))| {
                let k = k2[i];
                let s = s2 * k + s4 * e2 * k * k;
                let den = a0 + dt * (2.0 * e2 * e2 * k * k * k + s);
                let (h1, n1) = (cur_hat[i], cur_n[i]);
                let (h0, n0) = match (prev_hat, prev_n) {
                    (Some(h), Some(n)) => (h[i], n[i]),
                    _ => zero,
                };
                let rhs = h1 * (-a1) - h0 * a2 + ((n1 + h1 * s) * b1 + (n0 + h0 * s) * b2) * dt;
                *p = rhs / den;
                *q = (h1 * b1 + h0 * b2) * (-dt * c_sigma * k * k / den);
                let w = aw[i];
                (
                    w * p.norm_sqr(),
                    w * (p.re * q.re + p.im * q.im),
                    w * q.norm_sqr(),
                )
            })
            .reduce(|| (0.0, 0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1, x.2 + y.2))
    }

    /// σ^{n+1} for this step, or `None` if the projection has no real root.
    fn choose_sigma(&self, (app, apq, aqq): (f64, f64, f64)) -> Option<f64> {
        match self.area.method {
            AreaMethod::None => Some(0.0),
            AreaMethod::Lagrangian => Some(self.sigma),
            AreaMethod::Projection => {
                let c = app - self.area.target;
                if aqq <= 0.0 {
                    return (apq != 0.0).then(|| -c / (2.0 * apq));
                }
                let disc = apq * apq - aqq * c;
                if disc < 0.0 {
                    return None;
                }
                // Stable roots of aqq σ² + 2 apq σ + c = 0.
                let q = -(apq + apq.signum() * disc.sqrt());
                let r1 = q / aqq;
                let r2 = if q != 0.0 { c / q } else { r1 };
                Some(if (r1 - self.sigma).abs() <= (r2 - self.sigma).abs() {
                    r1
                } else {
                    r2
                })
            }
        }
    }

    /// Try one step of size `dt`: on success `next` holds the new state and its σ is returned.
    fn attempt(&mut self, t: f64, dt: f64) -> Result<f64, String> {
        let sums = self.affine_update(dt);
        let sigma = self
            .choose_sigma(sums)
            .ok_or_else(|| "the area projection has no real root".to_string())?;
        Zip::from(&mut self.next.hat)
            .and(&self.ev.spare)
            .par_for_each(|p, &q| *p += q * sigma);
        self.ev.evaluate(&mut self.next, t + dt).map_err(|d| d.0)?;
        self.check_constraints(sigma)?;
        Ok(sigma)
    }

    /// Volume (and area under projection) held; under adaptive steps F_eff must not rise.
    fn check_constraints(&self, sigma: f64) -> Result<(), String> {
        let m = self.next.measures;
        let dv = (m.volume - self.volume0).abs() / self.volume0.abs().max(1e-300);
        if dv > CONSTRAINT_TOL {
            return Err(format!("volume drifted by {dv:.2e} (relative)"));
        }
        if self.area.method == AreaMethod::Projection {
            let da = (m.area - self.area.target).abs() / self.area.target;
            if da > CONSTRAINT_TOL {
                return Err(format!("area off its target by {da:.2e} (relative)"));
            }
        }
        if self.adaptive.is_some() && !self.ev.c0.is_ramped() {
            let s = if self.area.method == AreaMethod::Lagrangian {
                self.sigma
            } else {
                sigma
            };
            let before = self.cur.measures.energy + s * self.cur.measures.area;
            let after = m.energy + s * m.area;
            if after > before + ENERGY_RISE_TOL * before.abs() {
                return Err(format!("F_eff rose from {before:.12e} to {after:.12e}"));
            }
        }
        Ok(())
    }

    /// Make `next` the current state; keep the old one for SBDF2.
    fn accept(&mut self, sigma: f64, dt: f64) {
        let area_before = self.cur.measures.area;
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
        self.sigma = match self.area.method {
            AreaMethod::Lagrangian => {
                self.sigma + self.area.alpha * (area_before - self.area.target)
            }
            _ => sigma,
        };
        self.accepted += 1;
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

impl Evaluator {
    /// A state of the right shapes, all zeros.
    fn blank(&self) -> State {
        State {
            hat: Array3::zeros(self.transform.spectral_shape()),
            nonlinear: Array3::zeros(self.transform.spectral_shape()),
            phi: self.grid.zeros(),
            measures: Measures::default(),
        }
    }

    /// From `state.hat`, compute φ, ∇²φ, Φ, F_sc, A, V and N̂ at time `t`
    /// (two inverse and two forward transforms).
    fn evaluate(&mut self, state: &mut State, t: f64) -> Result<(), Diverged> {
        let k2 = &self.symbols.k2;
        self.transform.hermitian_symmetrize(&mut state.hat);
        // φ = IFT[φ̂]
        self.spare.assign(&state.hat);
        self.transform.inverse(&mut self.spare, &mut state.phi);
        // ∇²φ = IFT[−k² φ̂]
        Zip::from(&mut self.spare)
            .and(&state.hat)
            .and(k2_view(k2, &state.hat))
            .par_for_each(|s, &h, &k| *s = h * (-k));
        self.transform.inverse(&mut self.spare, &mut self.work);
        // Φ = f − ε²∇²φ, F = ∫Φ²; work ← f, work2 ← f'Φ
        let r = self.c0.ramp(t);
        let e2 = self.eps * self.eps;
        let c0 = &self.c0;
        let phi = state.phi.as_slice().expect("standard layout");
        let (energy, max_abs) = self
            .work
            .as_slice_mut()
            .expect("standard layout")
            .par_iter_mut()
            .zip(
                self.work2
                    .as_slice_mut()
                    .expect("standard layout")
                    .par_iter_mut(),
            )
            .enumerate()
            .map(|(i, (w, w2))| {
                let p = phi[i];
                let ec0 = c0.at(i, r);
                let f = bulk(p, ec0);
                let big = f - e2 * *w;
                *w = f;
                *w2 = bulk_derivative(p, ec0) * big;
                (big * big, p.abs())
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1.max(b.1)));
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        state.measures = Measures {
            energy: energy * dv,
            area: self.area_of(&state.hat),
            volume: model::volume(&self.grid, &state.phi),
        };
        if !(max_abs <= PHI_BLOWUP) || !state.measures.energy.is_finite() {
            return Err(Diverged(format!(
                "max|φ| = {max_abs:.3e}, F = {:.3e}: the state diverged",
                state.measures.energy
            )));
        }
        // N̂ = −2k² FT[f'Φ] − 2ε²k⁴ FT[f]
        self.transform.forward(&self.work2, &mut state.nonlinear);
        self.transform.forward(&self.work, &mut self.spare);
        Zip::from(&mut state.nonlinear)
            .and(&self.spare)
            .and(k2_view(k2, &state.hat))
            .par_for_each(|n, &g, &k| *n = *n * (-2.0 * k) + g * (-2.0 * e2 * k * k));
        Ok(())
    }

    /// A = (3/(2√2)) ε ∫|∇φ|² = Σ_k area_weight |φ̂|² (Parseval).
    fn area_of(&self, hat: &Array3<Complex64>) -> f64 {
        let hs = hat.as_slice().expect("standard layout");
        hs.par_iter()
            .zip(&self.symbols.area_weight)
            .map(|(h, w)| w * h.norm_sqr())
            .sum()
    }
}

/// One axis's share of the Laplacian's symbol: k² (spectral) or (4/h²) sin²(kh/2) (the
/// second-order stencil, diagonal in the same Fourier/cosine basis).
pub fn axis_symbol(k: f64, h: f64, laplacian: Laplacian) -> f64 {
    match laplacian {
        Laplacian::Spectral => k * k,
        Laplacian::Fd => (2.0 / h * (0.5 * k * h).sin()).powi(2),
    }
}

/// |k|² (or the FD symbol) and the area weights of every spectral index (flattened, standard
/// layout).
fn symbols(t: &Transform, grid: &Grid, eps: f64, laplacian: Laplacian) -> Symbols {
    let k = t.wavenumbers(grid.h).map(|ks| {
        ks.iter()
            .map(|&k| axis_symbol(k, grid.h, laplacian))
            .collect::<Vec<f64>>()
    });
    let w = t.parseval_weights();
    let [s0, s1, s2] = t.spectral_shape();
    let mut k2 = Vec::with_capacity(s0 * s1 * s2);
    let mut area_weight = Vec::with_capacity(s0 * s1 * s2);
    let dv = grid.cell_volume() * grid.mirror_factor();
    for i in 0..s0 {
        for j in 0..s1 {
            for l in 0..s2 {
                let kk = k[0][i] + k[1][j] + k[2][l];
                k2.push(kk);
                area_weight.push(AREA_PREFACTOR * eps * dv * w[0][i] * w[1][j] * w[2][l] * kk);
            }
        }
    }
    Symbols { k2, area_weight }
}

/// View the flat |k|² table with the spectral array's shape.
fn k2_view<'a>(k2: &'a [f64], like: &Array3<Complex64>) -> ndarray::ArrayView3<'a, f64> {
    ndarray::ArrayView3::from_shape(like.raw_dim(), k2).expect("table matches spectral shape")
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
                Ok(sigma) => {
                    let f_old = self.cur.measures.energy;
                    self.accept(sigma, dt);
                    let residual = model::residual(&self.cur.phi, &self.next.phi, dt);
                    if let Some(a) = &self.adaptive {
                        let f_new = self.cur.measures.energy;
                        self.dt_next = Some(Self::propose(a, dt, f_old, f_new));
                    }
                    return Ok(StepReport {
                        dt,
                        residual,
                        rejected,
                    });
                }
                Err(reason) => {
                    if std::env::var_os("VESICLE_DEBUG").is_some() {
                        eprintln!("rejected dt {dt:.3e}: {reason}");
                    }
                    let Some(a) = &self.adaptive else {
                        return Err(Diverged(reason));
                    };
                    let dt_min = a.dt_min.unwrap_or(dt);
                    rejected += 1;
                    self.rejected += 1;
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

    fn name(&self) -> &'static str {
        "spectral"
    }
}
