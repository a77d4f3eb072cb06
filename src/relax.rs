//! `"dynamics": "relaxational"`: the fastest route to the conserved flow's stationary states
//! (DESIGN.md §7), a preconditioned L-BFGS on the constrained energy.
//!
//! Minimise F_sc(φ) subject to V(φ) = V0 (the k = 0 mode is never changed) and A(φ) = A0.
//! With the metric ⟨u, v⟩_M = Σ_k w M(k) Re(û v̂*), M(k) = 2ε⁴k⁴ + 8 + 8ε²k² (the Hessian of
//! F_sc in the bulk), the preconditioned gradient is
//!
//! ```text
//! r = M⁻¹ (ĝ + σ â),   ĝ = FT[δF_sc/δφ],   â = FT[δA/δφ] = (3/√2) ε k² φ̂,   r(0) = 0,
//! σ = −⟨ĝ, M⁻¹â⟩ / ⟨â, M⁻¹â⟩            (r tangent to A = A0),
//! ```
//!
//! the search direction is the two-loop recursion in the M metric, projected onto the tangent
//! space; a trial point φ + α d is retracted onto A = A0 along M⁻¹â (a quadratic in the step,
//! as in the spectral projection), and α is backtracked until Armijo's condition on F_sc holds.
//! The memory is reset when the direction is not a descent direction. At a stationary point
//! μ = δF_sc/δφ + σ δA/δφ is constant: the residual reported is the RMS of μ − mean(μ).
//! `t` advances by the nominal `dt` per iteration and is not physical time.

use crate::config::{AreaMethod, Scene};
use crate::engine::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::grid::Grid;
use crate::model::{Measures, C0};
use crate::numerics::{nearest_root, PAR_CHUNK};
use crate::spectral::evaluator::{Evaluator, ExplicitTerm, State};
use ndarray::Array3;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::collections::VecDeque;

/// Armijo constant: accept when F(φ + αd) ≤ F(φ) + c α ⟨∇F, d⟩.
const ARMIJO: f64 = 1e-4;
/// Backtracking halvings before the line search gives up.
const MAX_BACKTRACKS: usize = 40;

/// Full-size per-wavenumber tables (see [`crate::spectral::evaluator::Symbols`]).
struct Tables {
    /// |k|².
    k2: Vec<f64>,
    /// Parseval weight × cell volume: ∫ u v dx = Σ_k w Re(û v̂*).
    weight: Vec<f64>,
    /// (3/(2√2)) ε |k|² w: A = Σ_k area_weight |φ̂|².
    area_weight: Vec<f64>,
}

/// One stored L-BFGS pair (s, y) with ρ = 1/⟨y, s⟩_M and ⟨y, y⟩_M.
struct Pair {
    s: Array3<Complex64>,
    y: Array3<Complex64>,
    rho: f64,
    yy: f64,
}

/// The L-BFGS relaxation engine.
pub struct RelaxEngine {
    ev: Evaluator,
    cur: State,
    trial: State,
    /// M(k), flattened like the spectrum; M(0) is irrelevant (the mode is held).
    metric: Vec<f64>,
    /// Parseval weight × M(k): ⟨u, v⟩_M = Σ wm Re(u v*).
    wm: Vec<f64>,
    /// |k|², w and the area weights, flattened.
    tables: Tables,
    /// ⟨M⁻¹â, M⁻¹â⟩_M of the current state.
    qq: f64,
    /// Preconditioned projected gradient r of the current state.
    grad: Array3<Complex64>,
    /// r of the trial state, then scratch.
    grad_trial: Array3<Complex64>,
    /// Search direction.
    dir: Array3<Complex64>,
    /// M⁻¹â of the current state (retraction and tangent projection).
    area_dir: Array3<Complex64>,
    pairs: VecDeque<Pair>,
    spare_pairs: Vec<Pair>,
    memory: usize,
    alphas: Vec<f64>,
    sigma: f64,
    residual: f64,
    area: AreaConstraint,
    stalled: bool,
}

impl RelaxEngine {
    /// Engine holding `phi`, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let mut ev = Evaluator::new(grid, scene.eps, c0, scene.laplacian, ExplicitTerm::Gradient);
        let cur = ev.state_of(&phi, 0.0)?;
        let e2 = scene.eps * scene.eps;
        let metric_at = |k: f64| 2.0 * e2 * e2 * k * k + 8.0 + 8.0 * e2 * k;
        let sym = &ev.symbols;
        let metric = sym.table(|k, _| metric_at(k));
        let wm = sym.table(|k, w| metric_at(k) * w);
        let tables = Tables {
            k2: sym.table(|k, _| k),
            weight: sym.table(|_, w| w),
            area_weight: sym.table(|k, w| sym.area_prefactor * k * w),
        };
        let zeros = Array3::zeros(cur.hat.raw_dim());
        let mut e = RelaxEngine {
            trial: ev.blank(),
            ev,
            cur,
            metric,
            wm,
            tables,
            qq: 0.0,
            grad: zeros.clone(),
            grad_trial: zeros.clone(),
            dir: zeros.clone(),
            area_dir: zeros,
            pairs: VecDeque::new(),
            spare_pairs: Vec::new(),
            memory: scene.lbfgs_memory,
            alphas: vec![0.0; scene.lbfgs_memory],
            sigma: 0.0,
            residual: f64::INFINITY,
            area: AreaConstraint::none(),
            stalled: false,
        };
        e.refresh_gradient();
        Ok(e)
    }

    /// ⟨u, v⟩_M = Σ w M Re(u v*).
    fn dot_m(&self, u: &Array3<Complex64>, v: &Array3<Complex64>) -> f64 {
        weighted_dot(&self.wm, u, v)
    }

    /// For the current state: M⁻¹â, σ, r = M⁻¹(ĝ + σâ) and the residual.
    fn refresh_gradient(&mut self) {
        let g = gradient(
            &self.ev,
            &self.tables,
            &self.metric,
            &self.wm,
            self.area.method,
            &self.cur,
            &mut self.area_dir,
            &mut self.grad,
        );
        (self.sigma, self.residual, self.qq) = g;
    }

    /// `dir = −H r` by the two-loop recursion in the M metric, projected on the tangent space
    /// of A (d ← d − (⟨â, d⟩/⟨â, M⁻¹â⟩) M⁻¹â). Each vector update is fused with the inner
    /// product the next one needs: n + 2 passes for n pairs.
    fn direction(&mut self) {
        let n = self.pairs.len();
        let project = self.area.method != AreaMethod::None && self.qq > 0.0;
        self.dir.assign(&self.grad);
        // First loop, newest to oldest: α_i = ρ_i ⟨s_i, q⟩_M, q ← q − α_i y_i.
        let mut dot = match self.pairs.back() {
            Some(p) => self.dot_m(&p.s, &self.dir),
            None => 0.0,
        };
        for i in (0..n).rev() {
            let a = self.pairs[i].rho * dot;
            self.alphas[i] = a;
            let next = if i > 0 {
                &self.pairs[i - 1].s
            } else {
                &self.pairs[0].y
            };
            dot = scale_axpy_dot(
                &mut self.dir,
                1.0,
                -a,
                &self.pairs[i].y,
                Some(next),
                &self.wm,
            );
        }
        // Second loop, oldest to newest, starting from z = γ q with γ = ⟨s, y⟩_M/⟨y, y⟩_M:
        // β_i = ρ_i ⟨y_i, z⟩_M, z ← z + (α_i − β_i) s_i.
        let gamma = self.pairs.back().map_or(1.0, |p| 1.0 / (p.rho * p.yy));
        let mut scale = gamma;
        dot *= gamma;
        for i in 0..n {
            let b = self.pairs[i].rho * dot;
            let next = if i + 1 < n {
                Some(&self.pairs[i + 1].y)
            } else if project {
                Some(&self.area_dir)
            } else {
                None
            };
            let coeff = self.alphas[i] - b;
            dot = scale_axpy_dot(
                &mut self.dir,
                scale,
                coeff,
                &self.pairs[i].s,
                next,
                &self.wm,
            );
            scale = 1.0;
        }
        if n == 0 && project {
            dot = self.dot_m(&self.area_dir, &self.dir);
        }
        // d = −z, minus its component along M⁻¹â.
        let c = if project { dot / self.qq } else { 0.0 };
        scale_axpy_dot(&mut self.dir, -scale, c, &self.area_dir, None, &self.wm);
    }

    /// Trial state φ̂ + α d, retracted onto A = A0 along M⁻¹â. `None` if no real root.
    fn retract(&mut self, alpha: f64) -> Option<()> {
        let (x, d) = (
            self.cur.hat.as_slice().expect("std"),
            self.dir.as_slice().expect("std"),
        );
        let q = self.area_dir.as_slice().expect("std");
        let aw = &self.tables.area_weight;
        // t = x + α d, with the sums of A(t + τq) = A_PP + 2τ A_PQ + τ² A_QQ in the same pass.
        let (app, apq, aqq) = self
            .trial
            .hat
            .as_slice_mut()
            .expect("std")
            .par_iter_mut()
            .with_min_len(PAR_CHUNK)
            .enumerate()
            .map(|(i, t)| {
                *t = x[i] + d[i] * alpha;
                let (a, b) = (*t, q[i]);
                (
                    aw[i] * a.norm_sqr(),
                    aw[i] * (a.re * b.re + a.im * b.im),
                    aw[i] * b.norm_sqr(),
                )
            })
            .reduce(|| (0.0, 0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1, x.2 + y.2));
        if self.area.method == AreaMethod::None {
            return Some(());
        }
        let tau = nearest_root(aqq, apq, app - self.area.target, 0.0)?;
        scale_axpy_dot(
            &mut self.trial.hat,
            1.0,
            tau,
            &self.area_dir,
            None,
            &self.wm,
        );
        Some(())
    }

    /// Store the pair (s, y) = (x_new − x, r_new − r) if ⟨y, s⟩_M > 0, dropping the oldest pair
    /// when the memory is full; a rejected pair leaves the memory as it was.
    fn remember(&mut self) {
        let mut pair = self.spare_pairs.pop().unwrap_or_else(|| Pair {
            s: Array3::zeros(self.dir.raw_dim()),
            y: Array3::zeros(self.dir.raw_dim()),
            rho: 0.0,
            yy: 0.0,
        });
        let (xs, xo) = (
            self.trial.hat.as_slice().expect("std"),
            self.cur.hat.as_slice().expect("std"),
        );
        let (rs, ro) = (
            self.grad_trial.as_slice().expect("std"),
            self.grad.as_slice().expect("std"),
        );
        let wm = &self.wm;
        let (ys, yy) = pair
            .s
            .as_slice_mut()
            .expect("std")
            .par_iter_mut()
            .zip(pair.y.as_slice_mut().expect("std").par_iter_mut())
            .with_min_len(PAR_CHUNK)
            .enumerate()
            .map(|(i, (s, y))| {
                *s = xs[i] - xo[i];
                *y = rs[i] - ro[i];
                (wm[i] * (y.re * s.re + y.im * s.im), wm[i] * y.norm_sqr())
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        if ys <= 0.0 {
            self.spare_pairs.push(pair);
            return;
        }
        pair.rho = 1.0 / ys;
        pair.yy = yy;
        if self.pairs.len() == self.memory {
            let oldest = self.pairs.pop_front().expect("memory is full");
            self.spare_pairs.push(oldest);
        }
        self.pairs.push_back(pair);
    }

    /// Pairs held in the memory (at most `lbfgs_memory`).
    pub fn memory_len(&self) -> usize {
        self.pairs.len()
    }

    fn reset_memory(&mut self) {
        self.spare_pairs.extend(self.pairs.drain(..));
    }
}

/// For `state`: q = M⁻¹â into `area_dir`, σ = −⟨ĝ, q⟩/⟨q, q⟩_M (0 without an area
/// constraint), r = M⁻¹ĝ + σq into `grad` with r(0) = 0; returns σ, the residual
/// RMS(μ − mean μ) = (Σ_{k≠0} w |ĝ + σâ|² / |Ω|)^½ (w the Parseval weights of the full box Ω,
/// so a reduced box reads the same as the full one) and ⟨q, q⟩_M.
fn gradient(
    ev: &Evaluator,
    tables: &Tables,
    metric: &[f64],
    wm: &[f64],
    method: AreaMethod,
    state: &State,
    area_dir: &mut Array3<Complex64>,
    grad: &mut Array3<Complex64>,
) -> (f64, f64, f64) {
    let c_sigma = 3.0 / std::f64::consts::SQRT_2 * ev.eps;
    let k2 = &tables.k2;
    let weight = &tables.weight;
    let hat = state.hat.as_slice().expect("standard layout");
    area_dir
        .as_slice_mut()
        .expect("standard layout")
        .par_iter_mut()
        .with_min_len(PAR_CHUNK)
        .enumerate()
        .for_each(|(i, q)| *q = hat[i] * (c_sigma * k2[i] / metric[i]));
    // ⟨â, M⁻¹â⟩ = ⟨q, q⟩_M and ⟨ĝ, M⁻¹â⟩ = ⟨ĝ, q⟩.
    let qq = weighted_dot(wm, area_dir, area_dir);
    let sigma = if method == AreaMethod::None || qq <= 0.0 {
        0.0
    } else {
        -weighted_dot(weight, &state.nonlinear, area_dir) / qq
    };
    let g = state.nonlinear.as_slice().expect("standard layout");
    let q = area_dir.as_slice().expect("standard layout");
    let sum_sq: f64 = grad
        .as_slice_mut()
        .expect("standard layout")
        .par_iter_mut()
        .with_min_len(PAR_CHUNK)
        .enumerate()
        .map(|(i, r)| {
            if k2[i] == 0.0 {
                *r = Complex64::default();
                return 0.0;
            }
            *r = g[i] / metric[i] + q[i] * sigma;
            weight[i] * (*r * metric[i]).norm_sqr()
        })
        .sum();
    (sigma, (sum_sq / ev.grid.full_volume()).sqrt(), qq)
}

/// Σ w Re(u v*).
fn weighted_dot(w: &[f64], u: &Array3<Complex64>, v: &Array3<Complex64>) -> f64 {
    let (u, v) = (u.as_slice().expect("std"), v.as_slice().expect("std"));
    u.par_chunks(PAR_CHUNK)
        .zip(v.par_chunks(PAR_CHUNK))
        .zip(w.par_chunks(PAR_CHUNK))
        .map(|((u, v), w)| {
            u.iter()
                .zip(v)
                .zip(w)
                .map(|((u, v), w)| w * (u.re * v.re + u.im * v.im))
                .sum::<f64>()
        })
        .sum()
}

/// t ← c t + a x, returning Σ w Re(t next*) of the updated t (0 without `next`).
fn scale_axpy_dot(
    t: &mut Array3<Complex64>,
    c: f64,
    a: f64,
    x: &Array3<Complex64>,
    next: Option<&Array3<Complex64>>,
    w: &[f64],
) -> f64 {
    let (t, x) = (t.as_slice_mut().expect("std"), x.as_slice().expect("std"));
    let update = |t: &mut [Complex64], x: &[Complex64]| {
        for (t, x) in t.iter_mut().zip(x) {
            *t = *t * c + *x * a;
        }
    };
    match next {
        None => {
            t.par_chunks_mut(PAR_CHUNK)
                .zip(x.par_chunks(PAR_CHUNK))
                .for_each(|(t, x)| update(t, x));
            0.0
        }
        Some(n) => t
            .par_chunks_mut(PAR_CHUNK)
            .zip(x.par_chunks(PAR_CHUNK))
            .zip(n.as_slice().expect("std").par_chunks(PAR_CHUNK))
            .zip(w.par_chunks(PAR_CHUNK))
            .map(|(((t, x), n), w)| {
                update(t, x);
                t.iter()
                    .zip(n)
                    .zip(w)
                    .map(|((t, n), w)| w * (t.re * n.re + t.im * n.im))
                    .sum::<f64>()
            })
            .sum(),
    }
}

impl Engine for RelaxEngine {
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
        self.residual
    }

    fn set_area(&mut self, area: AreaConstraint) {
        self.area = area;
        self.reset_memory();
        self.refresh_gradient();
    }

    /// One L-BFGS iteration (its line search may take several evaluations).
    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, Diverged> {
        self.direction();
        if self.dot_m(&self.grad, &self.dir) >= 0.0 {
            self.reset_memory();
            self.direction();
        }
        let slope = self.dot_m(&self.grad, &self.dir);
        let f0 = self.cur.measures.energy;
        let mut alpha = 1.0;
        let mut rejected = 0;
        loop {
            let accepted = self.retract(alpha).is_some()
                && self
                    .ev
                    .evaluate(&mut self.trial, t + dt, None, None)
                    .is_ok()
                && self.trial.measures.energy <= f0 + ARMIJO * alpha * slope;
            if accepted {
                break;
            }
            rejected += 1;
            alpha *= 0.5;
            if rejected >= MAX_BACKTRACKS {
                self.stalled = true;
                self.reset_memory();
                return Ok(StepReport {
                    dt,
                    rate: f64::NAN,
                    rejected,
                });
            }
        }
        let (sigma, residual, qq) = gradient(
            &self.ev,
            &self.tables,
            &self.metric,
            &self.wm,
            self.area.method,
            &self.trial,
            &mut self.area_dir,
            &mut self.grad_trial,
        );
        self.remember();
        std::mem::swap(&mut self.cur, &mut self.trial);
        std::mem::swap(&mut self.grad, &mut self.grad_trial);
        (self.sigma, self.residual, self.qq) = (sigma, residual, qq);
        // `t` is nominal here, so max|Δφ|/Δt would mean nothing: the rate column is NaN.
        Ok(StepReport {
            dt,
            rate: f64::NAN,
            rejected,
        })
    }

    fn stalled(&self) -> bool {
        self.stalled
    }

    fn name(&self) -> &'static str {
        "relaxational (L-BFGS)"
    }

    fn save(&self) -> Saved {
        let mut saved = Saved::default()
            .scalar("stalled", if self.stalled { 1.0 } else { 0.0 })
            .scalar("pairs", self.pairs.len() as f64)
            .array("phi_hat", SavedArray::Complex(self.cur.hat.clone()));
        for (i, p) in self.pairs.iter().enumerate() {
            saved = saved
                .scalar(&format!("rho_{i}"), p.rho)
                .scalar(&format!("yy_{i}"), p.yy)
                .array(&format!("s_{i}"), SavedArray::Complex(p.s.clone()))
                .array(&format!("y_{i}"), SavedArray::Complex(p.y.clone()));
        }
        saved
    }

    fn restore(&mut self, saved: &Saved, t: f64) -> Result<(), String> {
        let shape = self.cur.hat.shape().to_vec();
        self.cur.hat.assign(saved.complex("phi_hat", &shape)?);
        self.stalled = saved.get("stalled")? != 0.0;
        let n = saved.get("pairs")?;
        if !(0.0..=self.memory as f64).contains(&n) || n.fract() != 0.0 {
            return Err(format!(
                "the saved L-BFGS memory holds {n} pairs; lbfgs_memory is {}",
                self.memory
            ));
        }
        self.reset_memory();
        for i in 0..n as usize {
            let mut pair = self.spare_pairs.pop().unwrap_or_else(|| Pair {
                s: Array3::zeros(self.dir.raw_dim()),
                y: Array3::zeros(self.dir.raw_dim()),
                rho: 0.0,
                yy: 0.0,
            });
            pair.s.assign(saved.complex(&format!("s_{i}"), &shape)?);
            pair.y.assign(saved.complex(&format!("y_{i}"), &shape)?);
            pair.rho = saved.get(&format!("rho_{i}"))?;
            pair.yy = saved.get(&format!("yy_{i}"))?;
            self.pairs.push_back(pair);
        }
        self.ev
            .evaluate(&mut self.cur, t, None, None)
            .map_err(|d| d.0)?;
        self.refresh_gradient();
        Ok(())
    }
}
