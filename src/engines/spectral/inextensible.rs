//! The locally inextensible membrane (docs/src/theory/flow.md, "The inextensible membrane"): a
//! tension field σ(x), a Lagrange multiplier, holds the fluid's velocity surface incompressible
//! across the diffuse interface, on top of the global tension the area method sets. With
//! g = ε∇φ (|g|² ≈ (1 − φ²)²/2 across the tanh profile) and the weight T = g gᵀ,
//!
//! ```text
//! B u = T:∇u = Σ_ab g_a g_b ∂_a u_b           (= −|g|² P_s:∇u, P_s = I − n̂n̂, where ∇·u = 0),
//! (Bᵀσ)_b = −Σ_a ∂_a(σ T_ab)                  (= ∇·(σ|g|² P_s) less the gradient ∇(σ|g|²)),
//! ```
//!
//! the constraint's operator and its adjoint (Σ_x σ Bu = Σ_x u·Bᵀσ, the same transforms read
//! both ways). The force Bᵀσ is a surface tension σ|g|² across the layer (the gradient it
//! leaves out is the pressure's), which integrates to a membrane tension (2√2/3)εσ in the sharp
//! limit. The flow is u = S(f + Bᵀσ), S = (I − κ̂κ̂)/(η|k|²) the Oseen solve, with σ from
//!
//! ```text
//! (B S Bᵀ + γR) σ = −B S f = −B u₀ + c w,   R = −∇·(T∇·),   Σ_x σ w = 0,   w = |g|².
//! ```
//!
//! - **Across the layer.** B u = 0 at every point of the layer asks the flow not to shear the
//!   layer's level sets apart, which a tension varying across the layer can enforce only
//!   with large, nearly powerless stresses: conjugate gradients stalled. R, a Laplacian along
//!   the normal only, costs such variation and nothing else: it annihilates every σ constant
//!   along the normals, so against those test fields Bu = −γRσ + cw still vanishes exactly.
//!   The membrane is held inextensible across the layer as a whole, not at each of its points.
//! - **The uniform part.** The tension's part uniform along the membrane (w, the interface's
//!   weight) is the global tension's, which the area method sets (a fixed σ, or the one the
//!   projection solves for): σ is kept orthogonal to w and the surface divergence may be the
//!   uniform c w. Without this a single mode cannot relax (its excess area is frozen).
//! - **The solve.** Conjugate gradients on σ ⊥ w, preconditioned by the smoothing
//!   exp(−ℓ²|k|²) (the tension that matters varies on the vesicle's scale), warm-started from
//!   the accepted state's σ of the same part ([`super::tensions`]). Each iteration applies
//!   B S Bᵀ (d(d + 1)/2 transforms forward and as many back), R (2d + 2) and the smoothing (2):
//!   14 transforms in 2D, 22 in 3D. The flow is updated with each search direction's S Bᵀp for
//!   the stop rule, and at the end computed once more from the final σ, u = u₀ + S Bᵀσ, the
//!   way a resumed run's replay computes it.
//! - **The stop rule.** The flow's error in the dissipation norm, estimated by the last
//!   [`DELAY`] steps' decrements α rᵀz (Hestenes & Stiefel), below [`TOLERANCE`] of the flow.
//! - **The energy law.** The tension does the work Σ_x u·Bᵀσ = Σ_x σBu = −γ∫σRσ on the flow
//!   (σ ⊥ w), so Σ_x u·f = η∫|∇u|² + γ∫∇σ·T∇σ: the regularization is a second, non-negative
//!   channel of dissipation, reported with the fluid's ([`Inextensibility::relaxation`]).
//!
//! Only periodic axes (the off-diagonal weights are odd across two mirror planes at once, which
//! the twisted storage of [`super::flow`] does not carry) and equal viscosities.

use super::evaluator::Symbols;
use super::flow::modes_mut;
use super::tensions::{Replay, Tensions};
use super::transform::Transform;
use super::viscous::{project, strain_to_grid, subtract_divergence, weighted_sum};
use crate::engines::numerics::{sum_in_fixed_tree, PAR_CHUNK};
use crate::engines::{Saved, SavedArray};
use ndarray::{Array3, Zip};
use num_complex::Complex64;
use rayon::prelude::*;

/// The relative tolerance of the solve: the flow's error in the dissipation norm over the
/// flow's own norm (module documentation).
pub const TOLERANCE: f64 = 1e-4;

/// γ of the regularization γR in units of ε²/η. On a quasi-circle of R = 16ε (L = 4R, h = ε/2)
/// six steps' dissipation read 4.0932e-7 at γ = 1 and 4.0938e-7 at γ = 10 (ℓ = 4ε); γ = 100
/// needs up to 180 iterations a step and more where ℓ is large.
const REGULARIZATION: f64 = 10.0;

/// ℓ of the preconditioner exp(−ℓ²|k|²) is the box's shortest side over this (16: ℓ = R/4 for
/// a vesicle of radius R in a box 4R wide). The same quasi-circle took 12–29 iterations a step
/// at ℓ = R/4, 19–47 at R/2 and 23–81 at R.
const SMOOTHING_PER_SIDE: f64 = 16.0;

/// The iterations whose energy drops estimate the remaining error (Hestenes & Stiefel's
/// estimate with this delay).
const DELAY: usize = 5;

/// The most iterations a solve takes.
pub const MAX_ITERATIONS: usize = 2000;

/// The constraint's weights and the solve's scratch.
pub struct Inextensibility {
    viscosity: f64,
    /// ℓ of the preconditioner H² = exp(−ℓ²|k|²).
    smoothing: f64,
    /// The pairs (a, b), a ≤ b, of velocity components (indices into the box's axes).
    pairs: Vec<(usize, usize)>,
    /// T_ab = g_a g_b per pair.
    weights: Vec<Array3<f64>>,
    /// w = |g|² = Σ_a T_aa, the interface's weight, and Σ_x w².
    interface: Array3<f64>,
    interface_norm: f64,
    /// The residual r, its smoothed z = H²r, the search direction p and B S Bᵀp on the grid.
    residual: Array3<f64>,
    smoothed: Array3<f64>,
    direction: Array3<f64>,
    product: Array3<f64>,
    /// σ of the last solve per part.
    tension: [Array3<f64>; 2],
    /// σ of the accepted states (the solves' start) and their replay on a resume.
    accepted: Tensions,
    /// The unconstrained flow û₀ per component, which the final σ's S Bᵀσ is added to.
    unconstrained: Vec<Array3<Complex64>>,
    /// The cell volume h^d: grid sums times it are integrals.
    cell: f64,
    /// γ of the regularization γR, R = −∇·(T∇·).
    regularization: f64,
    /// ∂_a p per component, and the spectrum of p, then of ∇·(T∇p).
    slope: Vec<Array3<f64>>,
    divergence: Array3<Complex64>,
    /// A grid field and a spectrum of scratch.
    grid: Array3<f64>,
    spectrum: Array3<Complex64>,
    /// S Bᵀp per velocity component.
    flow: Vec<Array3<Complex64>>,
}

impl Inextensibility {
    /// The constraint for viscosity `viscosity` on `transform`'s box of spacing `h`, with a
    /// velocity component along each axis longer than 1.
    pub fn new(viscosity: f64, transform: &Transform, h: f64) -> Self {
        let sides: Vec<usize> = transform.shape().into_iter().filter(|&n| n > 1).collect();
        let components = sides.len();
        let shortest = sides.iter().min().copied().unwrap_or(1) as f64 * h;
        let pairs: Vec<(usize, usize)> = (0..components)
            .flat_map(|a| (a..components).map(move |b| (a, b)))
            .collect();
        let zeros = || Array3::zeros(transform.shape());
        Inextensibility {
            viscosity,
            smoothing: shortest / SMOOTHING_PER_SIDE,
            weights: pairs.iter().map(|_| zeros()).collect(),
            interface: zeros(),
            interface_norm: 0.0,
            pairs,
            residual: zeros(),
            smoothed: zeros(),
            direction: zeros(),
            product: zeros(),
            tension: [zeros(), zeros()],
            accepted: Tensions::new(transform.shape()),
            unconstrained: (0..components)
                .map(|_| Array3::zeros(transform.spectral_shape()))
                .collect(),
            cell: h.powi(components as i32),
            regularization: 0.0,
            slope: (0..components).map(|_| zeros()).collect(),
            divergence: Array3::zeros(transform.spectral_shape()),
            grid: zeros(),
            spectrum: Array3::zeros(transform.spectral_shape()),
            flow: (0..components)
                .map(|_| Array3::zeros(transform.spectral_shape()))
                .collect(),
        }
    }

    /// T_ab = ε²∂_aφ∂_bφ and w = Σ_a T_aa from the state's gradient ∂_aφ (`gradient`, per
    /// component) and `eps`, and γ = 10ε²/η.
    pub fn set_state(&mut self, gradient: &[Array3<f64>], eps: f64) {
        let e2 = eps * eps;
        self.regularization = REGULARIZATION * e2 / self.viscosity;
        for (t, &(a, b)) in self.weights.iter_mut().zip(&self.pairs) {
            Zip::from(t)
                .and(&gradient[a])
                .and(&gradient[b])
                .par_for_each(|t, &ga, &gb| *t = e2 * ga * gb);
        }
        self.interface.fill(0.0);
        for (t, _) in self
            .weights
            .iter()
            .zip(&self.pairs)
            .filter(|(_, (a, b))| a == b)
        {
            self.interface += t;
        }
        self.interface_norm = grid_dot(&self.interface, &self.interface);
    }

    /// z = H²r: r's spectrum times exp(−ℓ²|k|²), back to the grid, its uniform part taken out
    /// ([`Inextensibility::remove_uniform`]) so that the search stays orthogonal to w.
    fn smooth(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        r: &Array3<f64>,
        z: &mut Array3<f64>,
    ) {
        let l2 = self.smoothing * self.smoothing;
        self.grid.assign(r);
        transform.forward(&mut self.grid, &mut self.spectrum);
        let modes = transform.spectral_shape();
        modes_mut(
            &mut self.spectrum,
            modes,
            sym,
            |_, _, (k2, _), s: &mut Complex64| *s *= (-l2 * k2).exp(),
        );
        transform.inverse(&mut self.spectrum, z);
        self.remove_uniform(z);
    }

    /// x ← x − (Σ_x xw / Σ_x w²) w with w = |g|²: the part of a tension (or of a surface
    /// divergence) uniform along the membrane taken out (module documentation).
    fn remove_uniform(&self, x: &mut Array3<f64>) {
        if self.interface_norm > 0.0 {
            let c = grid_dot(x, &self.interface) / self.interface_norm;
            Zip::from(x)
                .and(&self.interface)
                .par_for_each(|x, &w| *x -= c * w);
        }
    }

    /// Constrain the flow `velocity` of `part` (0: σ_g = 0, 1: per unit global tension; û per
    /// component, the Oseen solve of the force) in place: add S Bᵀσ with σ ⊥ w from
    /// (B S Bᵀ + γR)σ = −B(u + u_imp) + c w, where u_imp is the imposed shear u(y)x̂ of strain
    /// rate `imposed` = u'(y) along the y axis's points (`None`: no imposed flow), so that the
    /// whole flow is surface incompressible up to a uniform dilation. `kappa` holds κ per axis
    /// and `axes` the box's axes longer than 1. Preconditioned conjugate gradients from the
    /// accepted state's σ of the same part (module documentation), or in a replay
    /// ([`Inextensibility::set_replay`]) the held σ with no solve. Returns the iterations taken
    /// ([`MAX_ITERATIONS`] where the error estimate stayed above the tolerance).
    pub fn constrain(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        (part, imposed): (usize, Option<&[f64]>),
        velocity: &mut [Array3<Complex64>],
    ) -> usize {
        for (u0, u) in self.unconstrained.iter_mut().zip(&*velocity) {
            u0.assign(u);
        }
        let mut tension = std::mem::take(&mut self.tension[part]);
        let iterations = match self.accepted.replayed(part) {
            Some(held) => {
                tension.assign(held);
                0
            }
            None => {
                let iterations = self.solve(
                    transform,
                    sym,
                    (kappa, axes),
                    (part, imposed),
                    velocity,
                    &mut tension,
                );
                self.accepted.solved(part, &tension);
                iterations
            }
        };
        // u = u₀ + S Bᵀσ of the final σ: in a replay, bit for bit the solve's.
        let mut flow = std::mem::take(&mut self.flow);
        self.apply_force_flow(transform, sym, (kappa, axes), &tension, &mut flow);
        for ((u, u0), f) in velocity.iter_mut().zip(&self.unconstrained).zip(&flow) {
            Zip::from(u)
                .and(u0)
                .and(f)
                .par_for_each(|u, &u0, &f| *u = u0 + f);
        }
        self.flow = flow;
        self.tension[part] = tension;
        iterations
    }

    /// [`Inextensibility::constrain`]'s conjugate gradients: `tension` from the accepted
    /// state's σ of `part` (or zero) to the solve's σ, `velocity` updated along (for the stop
    /// rule's norm). Returns the iterations taken.
    fn solve(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        (part, imposed): (usize, Option<&[f64]>),
        velocity: &mut [Array3<Complex64>],
        tension: &mut Array3<f64>,
    ) -> usize {
        let mut flow = std::mem::take(&mut self.flow);
        match self.accepted.start(part) {
            Some(start) => {
                tension.assign(start);
                self.apply_force_flow(transform, sym, (kappa, axes), tension, &mut flow);
                add_scaled(velocity, &flow, 1.0);
            }
            None => tension.fill(0.0),
        }
        let mut residual = std::mem::take(&mut self.residual);
        self.apply_constraint(transform, sym, (kappa, axes), velocity, &mut residual);
        if let Some(rate) = imposed {
            // B u_imp = T_xy u'(y): the pair (0, 1) is the second.
            let y = axes[1];
            Zip::indexed(&mut residual)
                .and(&self.weights[1])
                .par_for_each(|idx, r, &t| *r += t * rate[[idx.0, idx.1, idx.2][y]]);
        }
        self.add_regularization(transform, sym, (kappa, axes), tension, &mut residual);
        residual.mapv_inplace(|r| -r);
        self.remove_uniform(&mut residual);
        let mut smoothed = std::mem::take(&mut self.smoothed);
        self.smooth(transform, sym, &residual, &mut smoothed);
        let mut rz = grid_dot(&residual, &smoothed);
        let mut direction = std::mem::take(&mut self.direction);
        direction.assign(&smoothed);
        let mut product = std::mem::take(&mut self.product);
        let mut recent = [f64::INFINITY; DELAY];
        let mut iterations = 0;
        while recent.iter().sum::<f64>() > TOLERANCE * TOLERANCE * self.energy(sym, velocity)
            && iterations < MAX_ITERATIONS
        {
            self.apply_force_flow(transform, sym, (kappa, axes), &direction, &mut flow);
            self.apply_constraint(transform, sym, (kappa, axes), &flow, &mut product);
            self.add_regularization(transform, sym, (kappa, axes), &direction, &mut product);
            self.remove_uniform(&mut product);
            let curvature = grid_dot(&direction, &product);
            if curvature <= 0.0 {
                break;
            }
            let alpha = rz / curvature;
            add_scaled(velocity, &flow, alpha);
            Zip::from(&mut *tension)
                .and(&direction)
                .par_for_each(|s, &p| *s += alpha * p);
            Zip::from(&mut residual)
                .and(&product)
                .par_for_each(|r, &ap| *r -= alpha * ap);
            let drop = self.cell * alpha * rz;
            recent[iterations % DELAY] = drop;
            self.smooth(transform, sym, &residual, &mut smoothed);
            let next = grid_dot(&residual, &smoothed);
            let beta = next / rz;
            rz = next;
            Zip::from(&mut direction)
                .and(&smoothed)
                .par_for_each(|p, &z| *p = z + beta * *p);
            iterations += 1;
        }
        (
            self.residual,
            self.smoothed,
            self.direction,
            self.product,
            self.flow,
        ) = (residual, smoothed, direction, product, flow);
        iterations
    }

    /// A step was accepted: its state's σ (the last solves') becomes the accepted one.
    pub fn accept(&mut self) {
        self.accepted.accept(&self.tension);
    }

    /// The accepted states' σ for a checkpoint ([`Tensions::saved`]).
    pub fn saved(&self) -> Vec<(String, SavedArray<'_>)> {
        self.accepted.saved()
    }

    /// Hold the accepted states' σ of a checkpoint ([`Tensions::restore`]).
    ///
    /// # Errors
    /// If a field has another shape than the box's.
    pub fn restore(&mut self, saved: &Saved<'_>) -> Result<(), String> {
        self.accepted.restore(saved)
    }

    /// Evaluate with the held σ `which` in place of solves, or (`None`) solve again.
    pub fn set_replay(&mut self, which: Option<Replay>) {
        self.accepted.set_replay(which);
    }

    /// The power the regularization dissipates, γ∫σRσ = γ∫∇σ·T∇σ, of σ = σ_0 + sσ_1 (the
    /// last solves' tensions; σ_0 alone for `parts` 1): the energy law's second channel
    /// (module documentation).
    pub fn relaxation(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        (parts, s): (usize, f64),
    ) -> f64 {
        let mut tension = std::mem::take(&mut self.residual);
        tension.assign(&self.tension[0]);
        if parts == 2 {
            Zip::from(&mut tension)
                .and(&self.tension[1])
                .par_for_each(|t, &t1| *t += s * t1);
        }
        let mut product = std::mem::take(&mut self.product);
        product.fill(0.0);
        self.add_regularization(transform, sym, (kappa, axes), &tension, &mut product);
        let power = self.cell * grid_dot(&tension, &product);
        (self.residual, self.product) = (tension, product);
        power
    }

    /// η Σ_k w|k|²|û|² over the components: the power the flow dissipates.
    fn energy(&self, sym: &Symbols, velocity: &[Array3<Complex64>]) -> f64 {
        self.viscosity * weighted_sum(sym, velocity, velocity, |k2| k2)
    }

    /// `out` = B v = Σ_ab T_ab ∂_a v_b of the divergence-free field v̂ = `v`: for each pair
    /// a ≤ b the strain 2D̂_ab = iκ_a v̂_b + iκ_b v̂_a back to the grid, times T_ab (T_aa/2 on the
    /// diagonal).
    fn apply_constraint(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        v: &[Array3<Complex64>],
        out: &mut Array3<f64>,
    ) {
        out.fill(0.0);
        for (&(ca, cb), t) in self.pairs.iter().zip(&self.weights) {
            strain_to_grid(
                transform,
                sym,
                (kappa, axes),
                (v, (ca, cb)),
                (&mut self.spectrum, &mut self.grid),
            );
            let share = if ca == cb { 0.5 } else { 1.0 };
            Zip::from(&mut *out)
                .and(&self.grid)
                .and(t)
                .par_for_each(|o, &s, &t| *o += share * t * s);
        }
    }

    /// `out` += γR p = −γ∇·(T∇p): ∇p spectrally, T∇p on the grid, its divergence spectrally.
    fn add_regularization(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        p: &Array3<f64>,
        out: &mut Array3<f64>,
    ) {
        let modes = transform.spectral_shape();
        self.grid.assign(p);
        let mut hat = std::mem::take(&mut self.divergence);
        transform.forward(&mut self.grid, &mut hat);
        for (c, &a) in axes.iter().enumerate() {
            let source = hat.as_slice().expect("standard layout");
            modes_mut(
                &mut self.spectrum,
                modes,
                sym,
                |i, idx, _, s: &mut Complex64| {
                    *s = Complex64::new(0.0, kappa[a][idx[a]]) * source[i];
                },
            );
            transform.inverse(&mut self.spectrum, &mut self.slope[c]);
        }
        hat.fill(Complex64::default());
        for (c, &along) in axes.iter().enumerate() {
            // The flux (T∇p)_c = Σ_b T_cb ∂_b p.
            self.grid.fill(0.0);
            for (&(a, b), t) in self.pairs.iter().zip(&self.weights) {
                let other = match (a == c, b == c) {
                    (true, _) => b,
                    (_, true) => a,
                    _ => continue,
                };
                Zip::from(&mut self.grid)
                    .and(t)
                    .and(&self.slope[other])
                    .par_for_each(|f, &t, &d| *f += t * d);
            }
            transform.forward(&mut self.grid, &mut self.spectrum);
            let flux = self.spectrum.as_slice().expect("standard layout");
            modes_mut(&mut hat, modes, sym, |i, idx, _, h: &mut Complex64| {
                *h -= Complex64::new(0.0, kappa[along][idx[along]]) * flux[i];
            });
        }
        transform.hermitian_symmetrize(&mut hat);
        transform.inverse(&mut hat, &mut self.grid);
        let gamma = self.regularization;
        Zip::from(out)
            .and(&self.grid)
            .par_for_each(|o, &r| *o += gamma * r);
        self.divergence = hat;
    }

    /// `out` = S Bᵀp: for each pair a ≤ b, τ̂ = FT[p T_ab], f̂_b −= iκ_a τ̂ (and f̂_a −= iκ_b τ̂ for
    /// a ≠ b); then the Oseen solve (I − κ̂κ̂)f̂/(η|k|²) (0 at k = 0).
    fn apply_force_flow(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        p: &Array3<f64>,
        out: &mut [Array3<Complex64>],
    ) {
        let modes = transform.spectral_shape();
        for o in out.iter_mut() {
            o.fill(Complex64::default());
        }
        for (&pair, t) in self.pairs.iter().zip(&self.weights) {
            Zip::from(&mut self.grid)
                .and(p)
                .and(t)
                .par_for_each(|g, &p, &t| *g = p * t);
            transform.forward(&mut self.grid, &mut self.spectrum);
            subtract_divergence(sym, (kappa, axes), &self.spectrum, pair, out);
        }
        project(out, &mut self.spectrum, sym, (kappa, axes));
        let eta = self.viscosity;
        for o in out.iter_mut() {
            modes_mut(o, modes, sym, |_, _, (k2, _), o: &mut Complex64| {
                *o = if k2 > 0.0 {
                    *o / (eta * k2)
                } else {
                    Complex64::default()
                };
            });
            transform.hermitian_symmetrize(o);
        }
    }
}

/// u_c += a·q_c for every component.
fn add_scaled(u: &mut [Array3<Complex64>], q: &[Array3<Complex64>], a: f64) {
    for (u, q) in u.iter_mut().zip(q) {
        Zip::from(u).and(q).par_for_each(|u, &q| *u += q * a);
    }
}

/// Σ_x a b, summed in a fixed tree (the same on any thread count).
fn grid_dot(a: &Array3<f64>, b: &Array3<f64>) -> f64 {
    let (a, b) = (
        a.as_slice().expect("standard layout"),
        b.as_slice().expect("standard layout"),
    );
    let partials = a
        .par_chunks(PAR_CHUNK)
        .zip(b.par_chunks(PAR_CHUNK))
        .map(|(x, y)| x.iter().zip(y).map(|(x, y)| x * y).sum::<f64>());
    sum_in_fixed_tree(partials, || 0.0, |x, y| x + y)
}
