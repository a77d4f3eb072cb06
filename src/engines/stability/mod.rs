//! The stability of an up–down symmetric stationary state against up–down odd perturbations:
//! the lowest eigenvalue of the constrained energy's second variation on that subspace
//! (docs/src/theory/relaxation.md, "The second variation").
//!
//! At a stationary state φ* of F_sc on A = A0 and V = V0, with area multiplier σ*, the second
//! variation on the constraints' tangent space is the Lagrangian's Hessian
//!
//! ```text
//! H = ∇²F_sc + σ* ∇²A,     ∇²A x = c_σ |k|² x̂ (A = (c_σ/2)∫|∇φ|² is quadratic; V is linear),
//! ```
//!
//! its products formed by central differences of the gradient ĝ = FT[δF_sc/δφ] (the L-BFGS
//! engine's, with its c0 terms):
//!
//! ```text
//! H x ≈ [ĝ(φ̂* + τx̂) − ĝ(φ̂* − τx̂)] / (2τ) + σ* c_σ |k|² x̂     (error O(τ²)).
//! ```
//!
//! **Area difference.** With area-difference elasticity the gradient carries λ(M) δM/δφ with
//! λ = κ_λ(M − M0) ([`crate::problem::area_difference`]), and the difference above is the
//! Hessian of F_sc + F_ade. With the bilayer couple, M = M0 is a third constraint with its own
//! multiplier λ*: H = ∇²F_sc + σ*∇²A + λ*∇²M, whose products add λ*[m̂(φ̂* + τx̂) −
//! m̂(φ̂* − τx̂)]/(2τ) (m̂ = FT[δM/δφ]). σ* and λ* are then the least-squares pair that makes
//! ĝ + σ*â + λ*m̂ (â = c_σ|k|²φ̂*, the area's gradient) smallest in the norm Σ w|·|²/M(k) over
//! k ≠ 0, M(k) the relaxation metric below.
//! M is even under z → −z, like A and V, so odd perturbations are tangent to its constraint
//! too, and λ of either law does not move along them to first order: on odd fields the two
//! laws' Hessians are the same operator at the same state and multiplier (the ADE one's
//! rank-one part κ_λ ∇M ∇Mᵀ vanishes there).
//!
//! The eigenproblem is H x = λ M x with M the relaxation metric
//! ([`Metric`], the bulk Hessian 2ε⁴k⁴ + 8ε²k² + 8): B = M⁻¹H is self-adjoint in
//! ⟨u, v⟩_M = Σ_k w M(k) Re(û v̂*), and its spectrum is clustered about 1 in the bulk, with the
//! interface's soft modes below. By Sylvester's law of inertia the *sign* of the lowest
//! eigenvalue (stable or not) does not depend on the metric; its size does.
//!
//! **The subspace.** The state is even in z about the box's centre (the mid-plane between the
//! full-box points N/2 − 1 and N/2). Perturbations odd in z are tangent to both constraints by
//! symmetry (the gradients of A and V are even), the multiplier does not move along them to
//! first order, and H maps them to odd fields: on them the constrained second variation is H
//! itself, with nothing projected but the oddness. On the last (real-to-complex) axis the
//! mirror image of a real field f, g(z_i) = f(z_{N−1−i}) with z_i = (i + ½ − N/2)h, has the
//! spectrum ĝ_j = e^{2πij/N} conj(f̂_j) (the other axes are cosine axes, real), so the odd part is
//! (f̂ − ĝ)/2, exact and cheap. Translation along z, t = ∂_z φ* (t̂ = i k_z φ̂*), is odd with
//! λ = 0 in the continuum (the lattice pins it by a little): it is removed, x ⟂_M t, so that the
//! lowest eigenvalue left is the shape's own (the pear mode's near the budding onset).
//!
//! The eigenvalue is found by LOBPCG ([`lobpcg`]) in the M metric.

pub mod lobpcg;

use crate::engines::spectral::evaluator::{Evaluator, ExplicitTerm, Metric, State};
use crate::engines::Diverged;
use crate::problem::area_difference::{AreaDifference, Law};
use crate::problem::config::Laplacian;
use crate::problem::grid::Grid;
use crate::problem::model::C0;
pub use lobpcg::Lowest;
use ndarray::{Array3, Zip};
use num_complex::Complex64;

/// Relative size of the difference step: τ‖x‖ = `STEP` ‖φ*‖ (L2 norms over the box). The
/// perturbation's amplitude at the interface is then a few times 1e-5, where the truncation
/// error O(τ²) is ~1e-9 of H x and round-off ~1e-11.
pub const STEP: f64 = 1e-5;

/// The second variation of a stationary state on its up–down odd subspace, translation removed.
pub struct OddHessian {
    ev: Evaluator,
    metric: Metric,
    /// φ̂* of the stationary state.
    hat: Array3<Complex64>,
    /// σ*, the stationary state's area multiplier.
    sigma: f64,
    /// λ*, the bilayer couple's multiplier (0 without the couple; ADE's λ is the evaluator's).
    couple: f64,
    /// ‖φ*‖ over the box.
    norm: f64,
    /// The translation t̂ = i k_z φ̂*, M-normalised.
    translation: Array3<Complex64>,
    /// e^{2πij/N} per index j of the last axis (the mirror image's phase).
    phase: Vec<Complex64>,
    /// |k|² and w per spectral index ([`Evaluator::symbols`] expanded along each axis).
    k2: Array3<f64>,
    w: Array3<f64>,
    scratch: State,
}

impl OddHessian {
    /// The second variation at `phi` (a stationary state on `grid`, even in z, with z the last
    /// axis, periodic, and x, y mirrored or periodic) of the energy with interface width `eps`,
    /// spontaneous curvature `c0` and Laplacian `laplacian`, and the area-difference term
    /// `area_difference` if any, on `threads` workers. σ* (and with the bilayer couple λ*) are
    /// the multipliers that make μ most nearly uniform at `phi` (module documentation).
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    ///
    /// # Panics
    /// If the last axis of `grid` is mirrored (an odd field cannot live on it).
    pub fn new(
        grid: Grid,
        (eps, c0, laplacian): (f64, C0, Laplacian),
        area_difference: Option<AreaDifference>,
        phi: &Array3<f64>,
        threads: usize,
    ) -> Result<Self, Diverged> {
        assert!(!grid.mirrored(2), "the odd axis (z) must be periodic");
        let metric = Metric::new(eps);
        let mut ev = Evaluator::new(
            grid,
            eps,
            c0,
            laplacian,
            ExplicitTerm::Gradient(metric),
            threads,
        );
        if area_difference.is_some() {
            ev = ev.with_curvature();
            ev.area_difference = area_difference;
        }
        let state = ev.state_of(phi, 0.0)?;
        let shape = state.hat.raw_dim();
        let sym = &ev.symbols;
        let k2 = Array3::from_shape_fn(shape, |(a, b, c)| {
            sym.k2[0][a] + sym.k2[1][b] + sym.k2[2][c]
        });
        let w = Array3::from_shape_fn(shape, |(a, b, c)| {
            sym.weight[0][a] * sym.weight[1][b] * sym.weight[2][c]
        });
        let n = ev.grid.shape[2];
        let phase = (0..shape[2])
            .map(|j| Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * j as f64 / n as f64))
            .collect();
        let kz = ev.transform.wavenumbers(ev.grid.h)[2].clone();
        let translation = Array3::from_shape_fn(shape, |(a, b, c)| {
            let k = if 2 * c == n { 0.0 } else { kz[c] };
            Complex64::new(0.0, k) * state.hat[[a, b, c]]
        });
        let (sigma, couple) = match area_difference.map(|t| t.law) {
            Some(Law::Couple { .. }) => {
                couple_multipliers(&state, metric.c_sigma, (&k2, &w), |k| metric.at(k))
            }
            _ => {
                let (qq, gq) = state.multiplier_sums;
                (if qq > 0.0 { -gq / qq } else { 0.0 }, 0.0)
            }
        };
        let scratch = ev.blank();
        let mut hessian = OddHessian {
            norm: 0.0,
            hat: state.hat,
            sigma,
            couple,
            translation,
            phase,
            k2,
            w,
            metric,
            scratch,
            ev,
        };
        hessian.norm = hessian.dot_w(&hessian.hat, &hessian.hat).sqrt();
        let mut t = std::mem::take(&mut hessian.translation);
        hessian.odd_part(&mut t);
        let tt = hessian.dot(&t, &t).sqrt();
        t.mapv_inplace(|v| v / tt);
        hessian.translation = t;
        Ok(hessian)
    }

    /// σ*, the state's area multiplier.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// λ*, the bilayer couple's multiplier of the state (0 without the couple).
    pub fn couple_multiplier(&self) -> f64 {
        self.couple
    }

    /// ⟨u, v⟩_M = Σ_k w M(k) Re(û v̂*).
    pub fn dot(&self, u: &Array3<Complex64>, v: &Array3<Complex64>) -> f64 {
        let metric = self.metric;
        Zip::from(u)
            .and(v)
            .and(&self.k2)
            .and(&self.w)
            .fold(0.0, |s, a, b, &k, &w| {
                s + w * metric.at(k) * (a.re * b.re + a.im * b.im)
            })
    }

    /// ∫ u v dx = Σ_k w Re(û v̂*).
    fn dot_w(&self, u: &Array3<Complex64>, v: &Array3<Complex64>) -> f64 {
        Zip::from(u)
            .and(v)
            .and(&self.w)
            .fold(0.0, |s, a, b, &w| s + w * (a.re * b.re + a.im * b.im))
    }

    /// x ← its odd part in z, (x − mirror image)/2.
    pub fn odd_part(&self, x: &mut Array3<Complex64>) {
        for mut lane in x.lanes_mut(ndarray::Axis(2)) {
            for (v, p) in lane.iter_mut().zip(&self.phase) {
                *v = 0.5 * (*v - p * v.conj());
            }
        }
    }

    /// x ← the odd part of x (first made a real field's spectrum) with the translation removed:
    /// P x = odd(x) − ⟨t, odd(x)⟩_M t.
    pub fn project(&self, x: &mut Array3<Complex64>) {
        self.ev.transform.hermitian_symmetrize(x);
        self.odd_part(x);
        let c = self.dot(&self.translation, x);
        Zip::from(x)
            .and(&self.translation)
            .for_each(|v, &t| *v -= c * t);
    }

    /// ⟨t, B t⟩_M of the unit translation t: the lattice's pinning of the state along z (0 in
    /// the continuum).
    ///
    /// # Errors
    /// [`Diverged`] if a perturbed state is not finite.
    pub fn translation_stiffness(&mut self) -> Result<f64, Diverged> {
        let t = self.translation.clone();
        let mut bt = Array3::zeros(t.raw_dim());
        self.apply_unprojected(&t, &mut bt)?;
        Ok(self.dot(&t, &bt))
    }

    /// `out` = P B P x (B = M⁻¹H), with P [`OddHessian::project`].
    ///
    /// # Errors
    /// [`Diverged`] if a perturbed state is not finite.
    pub fn apply(
        &mut self,
        x: &Array3<Complex64>,
        out: &mut Array3<Complex64>,
    ) -> Result<(), Diverged> {
        let mut px = x.clone();
        self.project(&mut px);
        self.apply_unprojected(&px, out)?;
        self.project(out);
        Ok(())
    }

    /// `out` = B x = M⁻¹ H x by central differences of the gradient (module documentation).
    fn apply_unprojected(
        &mut self,
        x: &Array3<Complex64>,
        out: &mut Array3<Complex64>,
    ) -> Result<(), Diverged> {
        let size = self.dot_w(x, x).sqrt();
        if size == 0.0 {
            out.fill(Complex64::new(0.0, 0.0));
            return Ok(());
        }
        let tau = STEP * self.norm / size;
        for sign in [1.0, -1.0] {
            Zip::from(&mut self.scratch.hat)
                .and(&self.hat)
                .and(x)
                .for_each(|s, &p, &v| *s = p + sign * tau * v);
            self.ev.evaluate(&mut self.scratch, 0.0, None, None)?;
            let g = &self.scratch.nonlinear;
            if sign > 0.0 {
                out.assign(g);
            } else {
                Zip::from(&mut *out).and(g).for_each(|o, &v| *o -= v);
            }
            // The couple's λ*∇²M x (its m̂ exists only with the area-difference term).
            let lambda = sign * self.couple;
            if lambda != 0.0 {
                Zip::from(&mut *out)
                    .and(&self.scratch.curvature_hat)
                    .for_each(|o, &c| *o += lambda * c);
            }
        }
        let (metric, sigma) = (self.metric, self.sigma);
        Zip::from(out).and(x).and(&self.k2).for_each(|o, &v, &k| {
            let m = metric.at(k);
            let inv = if k == 0.0 { 0.0 } else { 1.0 / m };
            *o = (*o / (2.0 * tau) + v * (sigma * metric.c_sigma * k)) * inv;
        });
        Ok(())
    }

    /// The lowest eigenvalue of P B P on the odd subspace ([`lobpcg::lowest`]), from `start`
    /// (a previous eigenvector; `None`: the odd field z³(1 − φ*²), an l = 3 shape mode at the
    /// interface), until the residual ‖Bx − θx‖_M ≤ `tolerance` or `max_iterations`.
    ///
    /// # Errors
    /// [`Diverged`] if a perturbed state is not finite.
    pub fn lowest(
        &mut self,
        start: Option<&Array3<Complex64>>,
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<Lowest, Diverged> {
        let x = match start {
            Some(s) => s.clone(),
            None => self.default_start(),
        };
        lobpcg::lowest(self, x, tolerance, max_iterations)
    }

    /// The real field of spectrum `x` on the grid.
    pub fn field(&mut self, x: &Array3<Complex64>) -> Array3<f64> {
        let mut out = self.ev.grid.zeros();
        let mut hat = x.clone();
        self.ev.transform.inverse(&mut hat, &mut out);
        out
    }

    /// The spectrum of the odd field z³(1 − φ*²) (z from the box's centre).
    fn default_start(&mut self) -> Array3<Complex64> {
        let phi = self.field(&self.hat.clone());
        let z = self.ev.grid.coords(2);
        let scale = z.last().copied().unwrap_or(1.0);
        let mut field = phi;
        for ((_, _, k), v) in field.indexed_iter_mut() {
            let zeta = z[k] / scale;
            *v = zeta * zeta * zeta * (1.0 - *v * *v);
        }
        let mut out = Array3::zeros(self.hat.raw_dim());
        self.ev.transform.forward(&mut field, &mut out);
        out
    }
}

/// The bilayer couple's multipliers (σ*, λ*) at `state`: the least-squares solution of
/// ĝ + σâ + λm̂ ≈ 0 in the norm Σ w|·|²/M(k) over k ≠ 0 (â = c_σ|k|²φ̂, m̂ = FT[δM/δφ]; `k2`
/// and `w` per mode, `metric` the relaxation metric M(|k|²)), from the 2 × 2 normal equations
///
/// ```text
/// [⟨â,â⟩ ⟨â,m̂⟩] [σ]     [⟨ĝ,â⟩]
/// [⟨m̂,â⟩ ⟨m̂,m̂⟩] [λ] = − [⟨ĝ,m̂⟩],     ⟨u, v⟩ = Σ_k w Re(û v̂*)/M(k).
/// ```
fn couple_multipliers(
    state: &State,
    c_sigma: f64,
    (k2, w): (&Array3<f64>, &Array3<f64>),
    metric: impl Fn(f64) -> f64,
) -> (f64, f64) {
    let mut s = [0.0; 5]; // ⟨a,a⟩, ⟨a,m⟩, ⟨m,m⟩, ⟨g,a⟩, ⟨g,m⟩
    let re = |u: Complex64, v: Complex64| u.re * v.re + u.im * v.im;
    Zip::from(&state.hat)
        .and(&state.curvature_hat)
        .and(&state.nonlinear)
        .and(k2)
        .and(w)
        .for_each(|&p, &m, &g, &k, &w| {
            if k == 0.0 {
                return;
            }
            let (a, f) = (p * (c_sigma * k), w / metric(k));
            s[0] += f * re(a, a);
            s[1] += f * re(a, m);
            s[2] += f * re(m, m);
            s[3] += f * re(g, a);
            s[4] += f * re(g, m);
        });
    let det = s[0] * s[2] - s[1] * s[1];
    (
        -(s[3] * s[2] - s[4] * s[1]) / det,
        -(s[0] * s[4] - s[1] * s[3]) / det,
    )
}

#[cfg(test)]
mod tests;
