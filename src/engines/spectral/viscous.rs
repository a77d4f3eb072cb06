//! Unequal viscosities inside and outside the membrane (docs/src/theory/flow.md, "Unequal
//! viscosities"): the Stokes equations with a viscosity that follows the phase field,
//!
//! ```text
//! ∇·(2η(x)D(u)) − ∇p + f = 0,  ∇·u = 0,  D = (∇u + ∇uᵀ)/2,
//! η(x) = η_out + (η_in − η_out) χ,  χ = clamp((1 + φ)/2, 0, 1),
//! ```
//!
//! on the periodic box. With η = η_out + η₁(x) and u divergence-free, ∇·(2η_out D) = η_out∇²u, so
//! in Fourier space the equations are A û = P f̂ with
//!
//! ```text
//! A û = η_out |k|² û + P FT[−∇·(2η₁ D(u))],   P = I − κ̂κ̂ (the Oseen projection),
//! ```
//!
//! a symmetric positive definite operator on divergence-free fields: Σ_x v·A u =
//! η_out Σ_k w|k|² v̂*·û + Σ_x 2η₁ D(v):D(u), bounded between min η and max η times
//! Σ_k w|k|²|û|² (χ is clamped so that η stays between η_in and η_out). It is solved by conjugate
//! gradients preconditioned by the equal-viscosity solve û = P f̂/(η_out|k|²) — the flow of
//! [`super::flow`] — whose condition number is at most max(η_in, η_out)/min(η_in, η_out). The
//! first iterate is that solve, so the residual starts at −P FT[−∇·(2η₁ D(u₀))], and with
//! η_in = η_out the solve is the equal-viscosity flow exactly. Each iteration applies A once:
//! d(d + 1)/2 strain components back to the grid, multiplied by 2η₁, forward again (d(d + 1)
//! transforms: 6 in 2D, 12 in 3D).
//!
//! The power the fluid dissipates is Σ_x u·f = Σ_k w Re(û*·P f̂) (u is divergence-free), which
//! at convergence is Σ_x 2η|D(u)|²: the energy law of the equal-viscosity flow holds with the
//! local viscosity, to the solve's tolerance.
//!
//! Only periodic axes: the strain's off-diagonal components are odd across two mirror planes at
//! once, which the twisted storage of [`super::flow`] does not carry; the scene refuses mirror
//! planes and walls with unequal viscosities.

use super::evaluator::Symbols;
use super::flow::{indexed, mode_symbols, modes_mut};
use super::transform::Transform;
use crate::engines::numerics::{sum_in_fixed_tree, PAR_CHUNK};
use ndarray::{Array3, Zip};
use num_complex::Complex64;
use rayon::prelude::*;

/// The relative tolerance of the solve: the preconditioned residual norm √(r·z) against the
/// right-hand side's √(b·P₀⁻¹b).
pub const TOLERANCE: f64 = 1e-10;

/// The most iterations a solve takes: about 5× the √(condition number)·ln(2/TOLERANCE)/2 ≈ 375
/// that conjugate gradients need at a viscosity ratio of 1000 (69 were measured at 50).
pub const MAX_ITERATIONS: usize = 2000;

/// The variable-viscosity solve's constants and scratch.
pub struct Viscosities {
    outside: f64,
    inside: f64,
    /// η₁(x) = η(x) − η_out on the grid.
    excess: Array3<f64>,
    /// A grid field: each strain component (or the imposed strain's stress).
    grid: Array3<f64>,
    /// A spectrum: each strain component's, then κ·v̂/|κ|² of the projection.
    spectrum: Array3<Complex64>,
    /// Per component: the right-hand side P f̂ of each part (σ = 0, per unit σ).
    rhs: [Vec<Array3<Complex64>>; 2],
    /// Per component: the residual r, the search direction p and A p.
    residual: Vec<Array3<Complex64>>,
    direction: Vec<Array3<Complex64>>,
    product: Vec<Array3<Complex64>>,
}

impl Viscosities {
    /// The solve for η_out = `outside`, η_in = `inside`, with `components` velocity components
    /// on `transform`'s box.
    pub fn new(outside: f64, inside: f64, components: usize, transform: &Transform) -> Self {
        let spectra = || -> Vec<Array3<Complex64>> {
            (0..components)
                .map(|_| Array3::zeros(transform.spectral_shape()))
                .collect()
        };
        Viscosities {
            outside,
            inside,
            excess: Array3::zeros(transform.shape()),
            grid: Array3::zeros(transform.shape()),
            spectrum: Array3::zeros(transform.spectral_shape()),
            rhs: [spectra(), spectra()],
            residual: spectra(),
            direction: spectra(),
            product: spectra(),
        }
    }

    /// η₁(x) = (η_in − η_out) clamp((1 + φ)/2, 0, 1) of the state's grid field `phi`.
    pub fn set_state(&mut self, phi: &Array3<f64>) {
        let jump = self.inside - self.outside;
        Zip::from(&mut self.excess)
            .and(phi)
            .par_for_each(|e, &phi| *e = jump * (0.5 * (1.0 + phi)).clamp(0.0, 1.0));
    }

    /// Add to the force spectra `forces` (x, y, …) the force the imposed shear u_imp = u(y)x̂
    /// exerts where the viscosity differs from the outside's: the imposed flow is the Stokes
    /// flow of its body force at η_out, so the disturbance u' = u − u_imp obeys the equations
    /// above with the extra force ∇·(2η₁D(u_imp)). Its only strain is 2D_xy = u'(y)
    /// (`gradient`, along the y axis's points), so with τ = η₁u'(y): f_x = ∂_yτ, f_y = ∂_xτ.
    pub fn add_imposed_strain_force(
        &mut self,
        transform: &mut Transform,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        gradient: &[f64],
        forces: &mut [Array3<Complex64>],
    ) {
        let (x, y) = (axes[0], axes[1]);
        Zip::indexed(&mut self.grid)
            .and(&self.excess)
            .par_for_each(|idx, g, &e| {
                let j = [idx.0, idx.1, idx.2][y];
                *g = e * gradient[j];
            });
        transform.forward(&mut self.grid, &mut self.spectrum);
        let tau = self.spectrum.as_slice().expect("standard layout");
        let modes = transform.spectral_shape();
        for (c, along) in [(0, y), (1, x)] {
            let add =
                |i: usize, idx: [usize; 3]| Complex64::new(0.0, kappa[along][idx[along]]) * tau[i];
            let f = forces[c].as_slice_mut().expect("standard layout");
            for (i, idx) in indexed(0..f.len(), modes) {
                f[i] += add(i, idx);
            }
        }
    }

    /// Solve A û = P f̂ in place for `part` (0: σ = 0, 1: per unit σ): `velocity` holds on entry
    /// the equal-viscosity solve u₀ = P f̂/(η_out|k|²) (so P f̂ = η_out|k|² u₀ on every mode
    /// the flow moves), on return the solution. `kappa` holds κ per axis and `axes` the box's
    /// axes longer than 1 (the components'). Preconditioned conjugate gradients from u₀, with
    /// z = r/(η_out|k|²) (module documentation). Returns the iterations taken ([`MAX_ITERATIONS`]
    /// where the residual stayed above [`TOLERANCE`]).
    pub fn solve(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        part: usize,
        velocity: &mut [Array3<Complex64>],
    ) -> usize {
        let eta = self.outside;
        let modes = transform.spectral_shape();
        for (b, u) in self.rhs[part].iter_mut().zip(velocity.iter()) {
            Zip::from(&mut *b).and(u).par_for_each(|b, &u| *b = u);
            modes_mut(b, modes, sym, |_, _, (k2, _), b: &mut Complex64| {
                *b *= eta * k2
            });
        }
        let scale = self.preconditioned_dot(sym, &self.rhs[part], &self.rhs[part]);
        if scale == 0.0 {
            return 0;
        }
        // r₀ = P f̂ − A u₀ = −P FT[−∇·(2η₁ D(u₀))].
        let mut product = std::mem::take(&mut self.product);
        self.apply_excess(transform, sym, (kappa, axes), velocity, &mut product);
        for (r, n) in self.residual.iter_mut().zip(&product) {
            Zip::from(r).and(n).par_for_each(|r, &n| *r = -n);
        }
        // p₀ = z₀ = r₀/(η_out|k|²).
        for (p, r) in self.direction.iter_mut().zip(&self.residual) {
            Zip::from(&mut *p).and(r).par_for_each(|p, &r| *p = r);
            precondition(p, modes, sym, eta);
        }
        let mut rz = self.preconditioned_dot(sym, &self.residual, &self.residual);
        let mut iterations = 0;
        while rz > TOLERANCE * TOLERANCE * scale && iterations < MAX_ITERATIONS {
            // A p = η_out|k|² p + P FT[−∇·(2η₁ D(p))].
            let direction = std::mem::take(&mut self.direction);
            self.apply_excess(transform, sym, (kappa, axes), &direction, &mut product);
            for (ap, p) in product.iter_mut().zip(&direction) {
                modes_mut(ap, modes, sym, |i, _, (k2, _), ap: &mut Complex64| {
                    *ap += p.as_slice().expect("standard layout")[i] * (eta * k2);
                });
            }
            self.direction = direction;
            let alpha = rz / dot(sym, &self.direction, &product);
            for c in 0..velocity.len() {
                Zip::from(&mut velocity[c])
                    .and(&mut self.residual[c])
                    .and(&self.direction[c])
                    .and(&product[c])
                    .par_for_each(|u, r, &p, &ap| {
                        *u += p * alpha;
                        *r -= ap * alpha;
                    });
            }
            let next = self.preconditioned_dot(sym, &self.residual, &self.residual);
            let beta = next / rz;
            rz = next;
            for (p, r) in self.direction.iter_mut().zip(&self.residual) {
                modes_mut(p, modes, sym, |i, _, (k2, _), p: &mut Complex64| {
                    let z = if k2 > 0.0 {
                        r.as_slice().expect("standard layout")[i] / (eta * k2)
                    } else {
                        Complex64::default()
                    };
                    *p = z + *p * beta;
                });
            }
            iterations += 1;
        }
        self.product = product;
        iterations
    }

    /// The power Σ_x u·f = Σ_k w Re(û*·P f̂) of u = u_b + σu_σ, f = f_b + σf_σ (u_b, u_σ in
    /// `velocity`; `parts` 1 at a fixed tension, whose one flow is u_b), expanded in σ so that
    /// no sum field is formed.
    pub fn dissipation(
        &self,
        sym: &Symbols,
        velocity: &[Vec<Array3<Complex64>>; 2],
        parts: usize,
        sigma: f64,
    ) -> f64 {
        let [u, b] = [velocity, &self.rhs];
        let base = dot(sym, &u[0], &b[0]);
        if parts == 1 {
            return base;
        }
        let cross = dot(sym, &u[0], &b[1]) + dot(sym, &u[1], &b[0]);
        base + sigma * cross + sigma * sigma * dot(sym, &u[1], &b[1])
    }

    /// `out` = P FT[−∇·(2η₁ D(v))] of the divergence-free field v̂ = `v`: for each pair a ≤ b,
    /// the strain 2D̂_ab = iκ_a v̂_b + iκ_b v̂_a back to the grid, times η₁, forward as τ̂_ab;
    /// out_a −= iκ_b τ̂_ab (and out_b −= iκ_a τ̂_ab for a ≠ b); then the projection P.
    fn apply_excess(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (kappa, axes): (&[Vec<f64>; 3], &[usize]),
        v: &[Array3<Complex64>],
        out: &mut [Array3<Complex64>],
    ) {
        for o in out.iter_mut() {
            o.fill(Complex64::default());
        }
        for ca in 0..axes.len() {
            for cb in ca..axes.len() {
                strain_to_grid(
                    transform,
                    sym,
                    (kappa, axes),
                    (v, (ca, cb)),
                    (&mut self.spectrum, &mut self.grid),
                );
                Zip::from(&mut self.grid)
                    .and(&self.excess)
                    .par_for_each(|g, &e| *g *= e);
                transform.forward(&mut self.grid, &mut self.spectrum);
                subtract_divergence(sym, (kappa, axes), &self.spectrum, (ca, cb), out);
            }
        }
        project(out, &mut self.spectrum, sym, (kappa, axes));
        for o in out.iter_mut() {
            transform.hermitian_symmetrize(o);
        }
    }

    /// Σ_c Σ_k w Re(x̂_c* ẑ_c) with ẑ = ŷ/(η_out|k|²) (0 where |k|² = 0).
    fn preconditioned_dot(
        &self,
        sym: &Symbols,
        x: &[Array3<Complex64>],
        y: &[Array3<Complex64>],
    ) -> f64 {
        let eta = self.outside;
        weighted_sum(
            sym,
            x,
            y,
            |k2| if k2 > 0.0 { 1.0 / (eta * k2) } else { 0.0 },
        )
    }
}

/// The strain 2D̂_ab = iκ_a v̂_b + iκ_b v̂_a of the components (`ca`, `cb`) of v̂ = `v` (along the
/// axes a = `axes[ca]`, b = `axes[cb]`) back to the grid field `grid`, through the spectrum
/// `scratch`.
pub(super) fn strain_to_grid(
    transform: &mut Transform,
    sym: &Symbols,
    (kappa, axes): (&[Vec<f64>; 3], &[usize]),
    (v, (ca, cb)): (&[Array3<Complex64>], (usize, usize)),
    (scratch, grid): (&mut Array3<Complex64>, &mut Array3<f64>),
) {
    let (a, b) = (axes[ca], axes[cb]);
    let (va, vb) = (
        v[ca].as_slice().expect("standard layout"),
        v[cb].as_slice().expect("standard layout"),
    );
    let modes = transform.spectral_shape();
    modes_mut(scratch, modes, sym, |i, idx, _, s: &mut Complex64| {
        let i_kappa = |x: usize| Complex64::new(0.0, kappa[x][idx[x]]);
        *s = i_kappa(a) * vb[i] + i_kappa(b) * va[i];
    });
    transform.inverse(scratch, grid);
}

/// The divergence of the symmetric tensor's component τ̂_ab = `tau` (the pair (`ca`, `cb`) of
/// velocity components) taken from the force spectra `out`: out_ca −= iκ_b τ̂ and, for
/// ca ≠ cb, out_cb −= iκ_a τ̂.
pub(super) fn subtract_divergence(
    sym: &Symbols,
    (kappa, axes): (&[Vec<f64>; 3], &[usize]),
    tau: &Array3<Complex64>,
    (ca, cb): (usize, usize),
    out: &mut [Array3<Complex64>],
) {
    let modes = [tau.dim().0, tau.dim().1, tau.dim().2];
    let tau = tau.as_slice().expect("standard layout");
    let mut subtract = |c: usize, x: usize| {
        modes_mut(&mut out[c], modes, sym, |i, idx, _, o: &mut Complex64| {
            *o -= Complex64::new(0.0, kappa[x][idx[x]]) * tau[i];
        });
    };
    subtract(ca, axes[cb]);
    if ca != cb {
        subtract(cb, axes[ca]);
    }
}

/// z = r/(η|k|²) in place (0 where |k|² = 0).
fn precondition(r: &mut Array3<Complex64>, modes: [usize; 3], sym: &Symbols, eta: f64) {
    modes_mut(r, modes, sym, |_, _, (k2, _), r: &mut Complex64| {
        *r = if k2 > 0.0 {
            *r / (eta * k2)
        } else {
            Complex64::default()
        };
    });
}

/// The Oseen projection P = I − κ̂κ̂ in place on the components `v` (κ = 0: unchanged), with
/// κ·v̂/|κ|² written into `dots`.
pub(super) fn project(
    v: &mut [Array3<Complex64>],
    dots: &mut Array3<Complex64>,
    sym: &Symbols,
    (kappa, axes): (&[Vec<f64>; 3], &[usize]),
) {
    let modes = [dots.dim().0, dots.dim().1, dots.dim().2];
    {
        let slices: Vec<&[Complex64]> = v
            .iter()
            .map(|c| c.as_slice().expect("standard layout"))
            .collect();
        modes_mut(dots, modes, sym, |i, idx, _, out: &mut Complex64| {
            let (mut dot, mut norm) = (Complex64::default(), 0.0);
            for (c, &a) in axes.iter().enumerate() {
                let k = kappa[a][idx[a]];
                dot += slices[c][i] * k;
                norm += k * k;
            }
            *out = if norm > 0.0 {
                dot / norm
            } else {
                Complex64::default()
            };
        });
    }
    let dots = dots.as_slice().expect("standard layout");
    for (c, &a) in axes.iter().enumerate() {
        modes_mut(&mut v[c], modes, sym, |i, idx, _, x: &mut Complex64| {
            *x -= dots[i] * kappa[a][idx[a]];
        });
    }
}

/// Σ_c Σ_k w Re(x̂_c* ŷ_c).
fn dot(sym: &Symbols, x: &[Array3<Complex64>], y: &[Array3<Complex64>]) -> f64 {
    weighted_sum(sym, x, y, |_| 1.0)
}

/// Σ_c Σ_k w g(|k|²) Re(x̂_c* ŷ_c), summed in a fixed tree (the same on any thread count).
pub(super) fn weighted_sum(
    sym: &Symbols,
    x: &[Array3<Complex64>],
    y: &[Array3<Complex64>],
    g: impl Fn(f64) -> f64 + Sync,
) -> f64 {
    let modes = [x[0].dim().0, x[0].dim().1, x[0].dim().2];
    let len = modes.iter().product::<usize>();
    let partials = (0..len.div_ceil(PAR_CHUNK)).into_par_iter().map(|t| {
        indexed(t * PAR_CHUNK..((t + 1) * PAR_CHUNK).min(len), modes)
            .map(|(i, idx)| {
                let (k2, w) = mode_symbols(sym, idx);
                let s: f64 = x
                    .iter()
                    .zip(y)
                    .map(|(a, b)| {
                        let (a, b) = (a.as_slice().unwrap()[i], b.as_slice().unwrap()[i]);
                        (a.conj() * b).re
                    })
                    .sum();
                w * g(k2) * s
            })
            .sum::<f64>()
    });
    sum_in_fixed_tree(partials, || 0.0, |a, b| a + b)
}
