//! The Stokes dynamics' explicit term on the periodic box (docs/src/theory/flow.md): the fluid
//! driven by the membrane's force, solved exactly in Fourier space, and the advection it
//! carries. With the chemical potential μ of an evaluated state,
//!
//! ```text
//! f = μ∇φ,   û = (I − κ̂κ̂) f̂ / (η|k|²)  (û(0) = 0),   advection FT[u·∇φ],
//! ```
//!
//! with κ the derivative's wavenumbers (the Nyquist ones 0, so that ∇ of a real field stays
//! real) and |k|² the Laplacian's symbol. Then κ·û = 0 exactly, Σ_x u·∇φ = 0 (the advection
//! moves no volume; its k = 0 coefficient is set to 0, its round-off), and
//! Σ_x μ u·∇φ = Σ_x u·f = η Σ_k w |k|²|û|² ≥ 0: the semi-discrete energy law
//! dF_eff/dt = −M∫|∇μ|² − η∫|∇u|² holds term by term on the grid.
//!
//! μ is affine in σ (μ = μ_b + σμ_σ, μ_σ = −c_σ∇²φ), and so is u: the evaluation returns the
//! advection of u_b in the explicit term and that of u_σ apart (T̂), so that the step can
//! advect with the σ it solves for, and the area projection sees the flow's response to σ.
//!
//! With `flow.shear_rate` γ̇ the fluid also carries an imposed shear, added to u_b before the
//! advection (it does work on the membrane, so the energy law then has a source): between walls
//! across y, plane Couette flow u_x = γ̇y (y from the channel's centre line); on a periodic y
//! axis, u_x = (γ̇/k₀) sin(k₀y) (k₀ = 2π/L_y), the exact Stokes flow of a periodic (Kolmogorov)
//! body force.
//!
//! **Mirror and wall axes** (DCT axes of the transform). On such an axis a even field is a
//! cosine series; the velocity component and the force component normal to the plane, and ∂φ
//! along it, are odd: sine series, S_j = Σ_i g_i sin(q_j(i + ½)h), g_i = (2/m) Σ_j S_j
//! sin(q_j(i + ½)h), q_j = πj/(mh), j = 1..m. Since
//! sin(q_j(i + ½)h) = (−1)^i cos(q_{m−j}(i + ½)h), the DCT of (−1)^i g holds S_j at index
//! m − j: an odd component is kept *twisted* — its spectrum at the reversed index, its grid
//! values times (−1)^i — and every grid product the flow forms is of two twisted factors of the
//! same component (u_a ∂_aφ, |u_a|²) or of a twisted and an even one whose result is again
//! twisted (μ ∂_aφ), so the signs never have to be applied. In the projection an odd
//! coefficient S enters as the periodic picture's −iS (∂_a of the cosine X is the sine −q_jX,
//! the periodic derivative iκX), so the same formulas hold with that factor. The top sine mode
//! j = m (stored at index 0) is the unfolded box's Nyquist mode: κ = 0 there, as on a periodic
//! axis, so it is not projected, û = Ŝ/(η|k|²) with |k|² holding (π/h)² along the axis, and the
//! reduced box reproduces the unfolded periodic one to round-off. A wall is then
//! free-slip for the disturbance flow (u normal = 0, ∂u_tangential/∂n = 0), and a mirror plane
//! through the vesicle keeps the flow's symmetry.
//!
//! **Every axis mirrored or walled** (the 2D quarter box, the 3D eighth box): the spectrum is
//! real and packed ([`Transform::packed`]), and the flow computes a real a mode
//! (`Coefficient` `f64`), over the modes' indices [n0, n1, 2⌈n2/2⌉] (a packed row's reals,
//! the padding of an odd row a mode of κ = 0, |k|² = 0, w = 0 that stays 0). Every velocity
//! component is odd along its own axis and even along the others, so all of them are sine
//! coefficients S_a, stored twisted as above; their periodic picture −iS_a has the factor −i in
//! common, which the linear projection carries through: s = κ·S/|κ|², û_a = (S_a −
//! κ_a s)/(η|k|²), on reals, with no complex arithmetic (and the top sine mode as above).
//!
//! At a fixed tension σ_f (area method `fixed`) nothing is split: μ = μ_b + σ_fμ_σ drives one
//! flow, its whole advection goes into the explicit term and no T̂ is kept
//! ([`Flow::at_fixed_tension`]).
//!
//! Cost: 5d + 4 transforms per evaluation (μ_b, μ_σ and the d components of ∇φ back, both
//! forces forward, both velocities back, both advections forward); 3d + 2 at a fixed tension.
//! The inextensible membrane's tension solve ([`super::inextensible`]) adds its iterations
//! for each part.

use super::evaluator::Symbols;
use super::inextensible::Inextensibility;
use super::transform::Transform;
use super::viscous::Viscosities;
use crate::engines::numerics::PAR_CHUNK;
use crate::problem::config::FlowSpec;
use crate::problem::grid::{AxisKind, Grid};
use crate::problem::model::TENSION_FACTOR;
use bytemuck::Pod;
use ndarray::{Array3, Axis, Zip};
use num_complex::Complex64;
use rayon::prelude::*;
use std::ops::{Add, Div, Mul, Neg, Range, Sub};

/// What one evaluation's flow measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlowStats {
    /// max over the grid of |u|.
    pub max_speed: f64,
    /// η∫|∇u|² = η Σ_k w |k|² |û|², the rate at which the fluid dissipates energy (with
    /// unequal viscosities ∫2η|D(u)|², [`super::viscous`]).
    pub dissipation: f64,
    /// The most conjugate-gradient iterations one Stokes solve took (0 at equal viscosities,
    /// whose solve is direct), or the inextensible membrane's tension solve.
    pub solve_iterations: usize,
}

/// The flow's constants, tables and scratch (two spectra per velocity component and one
/// more, one real field per component and five more).
pub struct Flow {
    viscosity: f64,
    mobility: f64,
    /// The axes of the box longer than 1 (the velocity's components).
    axes: Vec<usize>,
    /// Per component: the length of its axis when that axis is a mirror or wall axis (the
    /// component is odd there and kept twisted, see the module documentation), else `None`.
    odd: Vec<Option<usize>>,
    /// κ per axis, over the modes' indices (periodic Nyquist 0; a packed row's padding 0).
    kappa: [Vec<f64>; 3],
    /// |k|² of a mirror axis's top sine mode, (π/h)².
    top_k2: f64,
    /// Whether the spectra are packed (every axis a mirror or wall axis): a real a mode,
    /// computed as [`Coefficient`] `f64`, else a complex value a mode.
    packed: bool,
    /// The shape of the modes' indices: the spectral shape, or of a packed spectrum
    /// [n0, n1, 2⌈n2/2⌉] (its reals, an odd row padded by one).
    modes: [usize; 3],
    /// μ̂, then iκ_aφ̂, then κ·f̂/|κ|², then FT[u·∇φ].
    spectrum: Array3<Complex64>,
    /// f̂_a, then û_a, of the flow at σ = 0 and of the flow per unit σ.
    components: [Vec<Array3<Complex64>>; 2],
    /// ∂_aφ on the grid.
    gradient: Vec<Array3<f64>>,
    /// μ_b and μ_σ, then u_b·∇φ and u_σ·∇φ.
    mu: [Array3<f64>; 2],
    /// f_a, then (u_b)_a and (u_σ)_a.
    component: [Array3<f64>; 2],
    /// |u|².
    speed_sq: Array3<f64>,
    /// The projection's row tables, one per parallel task ([`Flow::project`]).
    tables: Vec<RowTable>,
    /// The imposed shear flow u_x(y) along the y axis's points (`None`: no imposed flow).
    shear: Option<Vec<f64>>,
    /// Its strain rate u_x'(y) along the y axis's points, with unequal viscosities or the
    /// inextensible membrane (periodic Kolmogorov flow only).
    shear_gradient: Option<Vec<f64>>,
    /// σ_f of a fixed tension: one flow at μ_b + σ_fμ_σ, no part per unit σ (`None`: split).
    fixed_tension: Option<f64>,
    /// The variable-viscosity solve when η_in ≠ η_out ([`super::viscous`]; periodic boxes).
    viscosities: Option<Viscosities>,
    /// The tension field of the locally inextensible membrane ([`super::inextensible`];
    /// periodic boxes, equal viscosities).
    inextensibility: Option<Inextensibility>,
}

impl Flow {
    /// The inextensible membrane's tension solve, if the flow has one.
    pub fn inextensibility(&mut self) -> Option<&mut Inextensibility> {
        self.inextensibility.as_mut()
    }

    /// The same, read only.
    pub fn inextensibility_ref(&self) -> Option<&Inextensibility> {
        self.inextensibility.as_ref()
    }

    /// The flow `spec` on `grid`, transformed by `transform`.
    pub fn new(spec: FlowSpec, transform: &Transform, grid: &Grid) -> Self {
        let h = grid.h;
        let real = transform.shape();
        let shape = transform.spectral_shape();
        let packed = transform.packed();
        let mut modes = shape;
        if packed {
            modes[2] = 2 * shape[2];
        }
        let ks = transform.wavenumbers(h);
        let periodic = |a: usize| grid.kinds[a] == AxisKind::Periodic;
        let kappa = std::array::from_fn(|a| {
            let mut kappa: Vec<f64> = ks[a]
                .iter()
                .enumerate()
                .map(|(j, &k)| {
                    let nyquist = periodic(a) && real[a].is_multiple_of(2) && j == real[a] / 2;
                    if nyquist {
                        0.0
                    } else {
                        k
                    }
                })
                .collect();
            kappa.resize(modes[a], 0.0);
            kappa
        });
        let axes: Vec<usize> = (0..3).filter(|&a| real[a] > 1).collect();
        let odd = axes
            .iter()
            .map(|&a| (!periodic(a)).then_some(real[a]))
            .collect();
        let zeros = || Array3::<f64>::zeros(real);
        // u_x(y), y from the box centre along the second axis: γ̇y between walls, else
        // (γ̇/k₀) sin(k₀y).
        let shear = spec.shear_rate.map(|rate| {
            let (y, n) = (axes[1], real[axes[1]]);
            let k0 = 2.0 * std::f64::consts::PI / (n as f64 * h);
            let coords = (0..n).map(|j| (j as f64 + 0.5 - n as f64 / 2.0) * h);
            if grid.walls[y] {
                coords.map(|y| rate * y).collect()
            } else {
                coords.map(|y| rate / k0 * (k0 * y).sin()).collect()
            }
        });
        // With unequal viscosities the imposed flow is not the Stokes flow of the body force
        // that drives it: its strain rate u_x'(y) = γ̇cos(k₀y) is kept for the force it then
        // exerts ([`Viscosities::add_imposed_strain_force`]); the inextensible membrane's
        // constraint reads it too.
        let shear_gradient = spec
            .shear_rate
            .filter(|_| spec.contrast().is_some() || spec.inextensible)
            .map(|rate| {
                let n = real[axes[1]];
                let k0 = 2.0 * std::f64::consts::PI / (n as f64 * h);
                (0..n)
                    .map(|j| rate * (k0 * (j as f64 + 0.5 - n as f64 / 2.0) * h).cos())
                    .collect()
            });
        Flow {
            viscosity: spec.viscosity,
            mobility: spec.mobility,
            odd,
            kappa,
            top_k2: (std::f64::consts::PI / h).powi(2),
            packed,
            modes,
            spectrum: Array3::zeros(shape),
            components: [0, 1].map(|_| axes.iter().map(|_| Array3::zeros(shape)).collect()),
            gradient: axes.iter().map(|_| zeros()).collect(),
            mu: [zeros(), zeros()],
            component: [zeros(), zeros()],
            speed_sq: zeros(),
            tables: (0..modes.iter().product::<usize>().div_ceil(task_modes(modes)))
                .map(|_| RowTable::new(modes[2]))
                .collect(),
            shear,
            shear_gradient,
            viscosities: spec
                .contrast()
                .map(|inside| Viscosities::new(spec.viscosity, inside, axes.len(), transform)),
            inextensibility: spec
                .inextensible
                .then(|| Inextensibility::new(spec.viscosity, transform, h)),
            axes,
            fixed_tension: None,
        }
    }

    /// This flow at the fixed tension `sigma`: [`Flow::advect`] drives one flow with
    /// μ = μ_b + σμ_σ whatever σ it is given, and writes no T̂ (the scratch of the part per
    /// unit σ is dropped).
    pub fn at_fixed_tension(mut self, sigma: f64) -> Self {
        self.fixed_tension = Some(sigma);
        self.components[1] = Vec::new();
        self
    }

    /// Whether [`Flow::advect`] keeps the advection per unit σ apart (T̂): not at a fixed
    /// tension.
    pub fn splits_tension(&self) -> bool {
        self.fixed_tension.is_none()
    }

    /// Split the flow's advection into its part at σ = 0 and its part per unit σ, both of
    /// the state `(φ̂, φ)` (its spectrum and its grid field, which sets the viscosity where the
    /// two differ): replace the conserved flow's explicit term `nonlinear` (N̂) by
    /// M N̂ − FT[u_b·∇φ] and write T̂ = FT[u_σ·∇φ] into `tension`, where u_b is the Stokes flow
    /// of the force μ_b∇φ (μ at σ = 0, plus the imposed shear) and u_σ that of μ_σ∇φ with
    /// μ̂_σ = c_σ|k|²φ̂, the tension's part of μ per unit σ. The step then advects with
    /// u_b + σu_σ at the σ it solves for (docs/src/theory/flow.md, "The step"). Returns max|u|
    /// and η∫|∇u|² of u = u_b + σu_σ at `sigma`. `sym` gives |k|² and the Parseval weights,
    /// `eps` the interface width. At a fixed tension σ_f the flow is that of μ_b + σ_fμ_σ, all
    /// of its advection goes into `nonlinear`, `tension` is not touched, and `sigma` is not
    /// read. A packed spectrum is computed a real a mode (`Coefficient`).
    pub fn advect(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        tension: (f64, f64),
        state: (&Array3<Complex64>, &Array3<f64>),
        out: [&mut Array3<Complex64>; 2],
    ) -> FlowStats {
        if self.packed {
            self.advect_as::<f64>(transform, sym, tension, state, out)
        } else {
            self.advect_as::<Complex64>(transform, sym, tension, state, out)
        }
    }

    /// [`Flow::advect`] with the modes' coefficients of type `T`.
    fn advect_as<T: Coefficient>(
        &mut self,
        transform: &mut Transform,
        sym: &Symbols,
        (eps, sigma): (f64, f64),
        (hat, phi): (&Array3<Complex64>, &Array3<f64>),
        [nonlinear, tension]: [&mut Array3<Complex64>; 2],
    ) -> FlowStats {
        let e4x2 = 2.0 * eps.powi(4);
        let c_sigma = TENSION_FACTOR * eps;
        if let Some(viscous) = self.viscosities.as_mut() {
            viscous.set_state(phi);
        }
        // The flows: at σ = 0 and per unit σ, or the one at the fixed tension.
        let (parts, fixed, sigma) = match self.fixed_tension {
            None => (2, 0.0, sigma),
            Some(f) => (1, f, f),
        };
        // μ̂_b = −N̂/|k|² + 2ε⁴|k|⁴φ̂ (k ≠ 0; a constant in μ exerts a gradient, which the
        // projection removes; plus σ_f c_σ|k|²φ̂ at a fixed tension), and μ̂_σ = c_σ|k|²φ̂.
        let (hat, nonlinear_in) = (coefficients::<T>(hat), coefficients::<T>(nonlinear));
        let modes = self.modes;
        modes_mut(
            &mut self.spectrum,
            modes,
            sym,
            |i, _, (k, _), out: &mut T| {
                *out = if k > 0.0 {
                    -nonlinear_in[i] / k + hat[i] * (e4x2 * k * k + fixed * c_sigma * k)
                } else {
                    T::default()
                };
            },
        );
        transform.inverse(&mut self.spectrum, &mut self.mu[0]);
        if parts == 2 {
            modes_mut(
                &mut self.spectrum,
                modes,
                sym,
                |i, _, (k, _), out: &mut T| {
                    *out = hat[i] * (c_sigma * k);
                },
            );
            transform.inverse(&mut self.spectrum, &mut self.mu[1]);
        }
        for (c, &a) in self.axes.iter().enumerate() {
            let (kappa, odd) = (&self.kappa[a], self.odd[c]);
            // The distance between neighbours along axis a among the modes.
            let stride: usize = modes[a + 1..].iter().product();
            // iκ_aX, or on a mirror axis the sine coefficient −q_jX stored twisted: at index j
            // the mode l = n − j (1 ≤ j < n), j·stride before it.
            modes_mut(&mut self.spectrum, modes, sym, |i, idx, _, out: &mut T| {
                let j = idx[a];
                *out = match odd {
                    None => hat[i].derivative(kappa[j]),
                    Some(n) if (1..n).contains(&j) => {
                        -hat[i - j * stride + (n - j) * stride] * kappa[n - j]
                    }
                    Some(_) => T::default(),
                };
            });
            transform.inverse(&mut self.spectrum, &mut self.gradient[c]);
            // The forces of both parts in one sweep: (f_b)_a = μ_b ∂_aφ, (f_σ)_a = μ_σ ∂_aφ.
            let [f_b, f_s] = &mut self.component;
            let g = &self.gradient[c];
            if parts == 2 {
                let [mu_b, mu_s] = &self.mu;
                Zip::from(&mut *f_b)
                    .and(&mut *f_s)
                    .and(mu_b)
                    .and(mu_s)
                    .and(g)
                    .par_for_each(|fb, fs, &mb, &ms, &g| (*fb, *fs) = (mb * g, ms * g));
            } else {
                Zip::from(&mut *f_b)
                    .and(&self.mu[0])
                    .and(g)
                    .par_for_each(|f, &mu, &g| *f = mu * g);
            }
            for part in 0..parts {
                transform.forward(&mut self.component[part], &mut self.components[part][c]);
            }
        }
        if let (Some(viscous), Some(gradient)) = (self.viscosities.as_mut(), &self.shear_gradient) {
            // Periodic axes only: no component is odd, so the picture is the storage.
            viscous.add_imposed_strain_force(
                transform,
                (&self.kappa, &self.axes),
                gradient,
                &mut self.components[0],
            );
        }
        for part in 0..parts {
            self.turn::<T>(part, T::picture);
        }
        let projected_power = self.project::<T>(sym, sigma, true);
        let mut solve_iterations = 0;
        if let Some(constraint) = self.inextensibility.as_mut() {
            // Periodic axes only: the picture is the storage.
            constraint.set_state(&self.gradient, eps);
            for part in 0..parts {
                let imposed = self.shear_gradient.as_deref().filter(|_| part == 0);
                let iterations = constraint.constrain(
                    transform,
                    sym,
                    (&self.kappa, &self.axes),
                    (part, imposed),
                    &mut self.components[part],
                );
                solve_iterations = solve_iterations.max(iterations);
            }
        }
        let dissipation = match self.viscosities.as_mut() {
            Some(viscous) => {
                for part in 0..parts {
                    let iterations = viscous.solve(
                        transform,
                        sym,
                        (&self.kappa, &self.axes),
                        part,
                        &mut self.components[part],
                    );
                    solve_iterations = solve_iterations.max(iterations);
                }
                viscous.dissipation(sym, &self.components, parts, sigma)
            }
            // The constraint's tension flow changed û after the projection.
            None if self.inextensibility.is_some() => self.project::<T>(sym, sigma, false),
            None => projected_power,
        } + match self.inextensibility.as_mut() {
            Some(constraint) => {
                constraint.relaxation(transform, sym, (&self.kappa, &self.axes), (parts, sigma))
            }
            None => 0.0,
        };
        for part in 0..parts {
            self.turn::<T>(part, T::stored);
        }
        for c in 0..self.axes.len() {
            let [ub, us] = &mut self.component;
            // The inverse transform spoils its input: û stays for [`Flow::velocity`].
            self.spectrum.assign(&self.components[0][c]);
            transform.inverse(&mut self.spectrum, ub);
            // At a fixed tension u_σ is never written: it stays the zeros it was made with.
            if parts == 2 {
                self.spectrum.assign(&self.components[1][c]);
                transform.inverse(&mut self.spectrum, us);
            }
            if let (0, Some(profile)) = (c, &self.shear) {
                let y = self.axes[1];
                for (j, mut plane) in ub.axis_iter_mut(Axis(y)).enumerate() {
                    plane += profile[j];
                }
            }
            let first = c == 0;
            let [adv_b, adv_s] = &mut self.mu;
            Zip::from(adv_b)
                .and(adv_s)
                .and(&mut self.speed_sq)
                .and(&*ub)
                .and(&*us)
                .and(&self.gradient[c])
                .par_for_each(|ab, as_, s, &u, &v, &g| {
                    let w = u + sigma * v;
                    if first {
                        (*ab, *as_, *s) = (u * g, v * g, w * w);
                    } else {
                        (*ab, *as_, *s) = (*ab + u * g, *as_ + v * g, *s + w * w);
                    }
                });
        }
        let max_speed_sq = self.speed_sq.par_iter().copied().reduce(|| 0.0, f64::max);
        transform.forward(&mut self.mu[0], &mut self.spectrum);
        coefficients_mut::<T>(&mut self.spectrum)[0] = T::default();
        let mobility = self.mobility;
        Zip::from(&mut *nonlinear)
            .and(&self.spectrum)
            .par_for_each(|n, &a| *n = *n * mobility - a);
        transform.hermitian_symmetrize(nonlinear);
        if parts == 2 {
            transform.forward(&mut self.mu[1], tension);
            coefficients_mut::<T>(tension)[0] = T::default();
            transform.hermitian_symmetrize(tension);
        }
        FlowStats {
            max_speed: max_speed_sq.sqrt(),
            dissipation,
            solve_iterations,
        }
    }

    /// The velocity u = u_b + σu_σ of the last [`Flow::advect`] on the grid, the imposed shear
    /// included: one field per component, along the box's axes longer than 1 (x, y[, z] of
    /// the scene), with an odd component's twist undone (its grid values times (−1)^i).
    pub fn velocity(&mut self, transform: &mut Transform, sigma: f64) -> Vec<Array3<f64>> {
        let mut out = Vec::with_capacity(self.axes.len());
        for (c, &a) in self.axes.iter().enumerate() {
            match self.components[1].get(c) {
                Some(per_sigma) => Zip::from(&mut self.spectrum)
                    .and(&self.components[0][c])
                    .and(per_sigma)
                    .par_for_each(|u, &b, &s| *u = b + s * sigma),
                None => self.spectrum.assign(&self.components[0][c]),
            }
            let mut field = Array3::zeros(transform.shape());
            transform.inverse(&mut self.spectrum, &mut field);
            if self.odd[c].is_some() {
                for (i, mut plane) in field.axis_iter_mut(Axis(a)).enumerate() {
                    if i % 2 == 1 {
                        plane.mapv_inplace(|v| -v);
                    }
                }
            }
            if let (0, Some(profile)) = (c, &self.shear) {
                for (j, mut plane) in field.axis_iter_mut(Axis(self.axes[1])).enumerate() {
                    plane += profile[j];
                }
            }
            out.push(field);
        }
        out
    }

    /// Every odd component's spectrum of `part` (0: σ = 0, 1: per unit σ) between its twisted
    /// storage and the logical order, in place: the index j ↔ n − j along its axis (n points)
    /// for 1 ≤ j < n, the map its own inverse; j = 0 holds the top sine mode in both, and a
    /// packed row's padding stays. Each value is mapped by `map` (into the picture of
    /// [`Coefficient`], or back; nothing to map for real coefficients), so that
    /// [`Flow::project`] reads every component at the mode it computes, with no index map.
    fn turn<T: Coefficient>(&mut self, part: usize, map: impl Fn(T) -> T + Sync) {
        let modes = self.modes;
        for (c, &a) in self.axes.iter().enumerate() {
            let Some(n) = self.odd[c] else { continue };
            let values = coefficients_mut::<T>(&mut self.components[part][c]);
            // An index along axis a is a block of `inner` values; a slab holds the axis's
            // indices at one index of the axes before it. The blocks 1..n of each slab are
            // reversed (j ↔ n − j; the j = n/2 of an even n stays).
            let inner: usize = modes[a + 1..].iter().product();
            let slab = modes[a] * inner;
            if a == 0 {
                let half = (n - 1) / 2;
                let (low, high) = values[inner..n * inner].split_at_mut(half * inner);
                let high = &mut high[(n - 1 - 2 * half) * inner..];
                low.par_chunks_mut(inner)
                    .zip(high.par_chunks_mut(inner).rev())
                    .for_each(|(x, y)| x.swap_with_slice(y));
            } else {
                values.par_chunks_mut(slab).for_each(|v| {
                    let blocks = &mut v[inner..n * inner];
                    if inner == 1 {
                        blocks.reverse();
                    } else {
                        let count = n - 1;
                        for j in 0..count / 2 {
                            let (low, high) = blocks.split_at_mut((count - 1 - j) * inner);
                            low[j * inner..(j + 1) * inner].swap_with_slice(&mut high[..inner]);
                        }
                    }
                });
            }
            if !T::REAL {
                values
                    .par_chunks_mut(PAR_CHUNK)
                    .for_each(|v| v.iter_mut().for_each(|v| *v = map(*v)));
            }
        }
    }

    /// The Oseen projection in place on the force's spectra of every part (0: σ = 0, 1: per
    /// unit σ, absent at a fixed tension), in logical order and in the picture of
    /// [`Coefficient`] ([`Flow::turn`]), in one sweep over the modes: at each, per part,
    /// s = κ·f̂/|κ|², then f̂_a ← (f̂_a − κ_a s)/(η|k_a|²) (0 at k = 0), now û_a. On complex
    /// spectra an odd component's coefficient S enters as −iS; on a packed spectrum every
    /// component is odd and the sine coefficients S_a project as they stand:
    /// (S_a − κ_a s)/(η|k|²) with s = κ·S/|κ|². An odd component's top sine mode sits where
    /// j_a = 0: κ_a = 0 there, so it is not projected, and |k_a|² = |k|² + (π/h)². Returns the
    /// power the projected flow dissipates at σ, η Σ_k w Σ_a |k_a|² |û_b + σû_σ|², summed in the
    /// same sweep. Without `project` the spectra are left as they are (velocities already) and
    /// only that power is summed.
    fn project<T: Coefficient>(&mut self, sym: &Symbols, sigma: f64, project: bool) -> f64 {
        let top = self.top_k2s();
        let Flow {
            axes,
            kappa,
            modes,
            viscosity: eta,
            components,
            tables,
            ..
        } = self;
        let (modes, eta, d) = (*modes, *eta, axes.len());
        let (row, task) = (modes[2], task_modes(modes));
        let parts = components.iter().filter(|p| !p.is_empty()).count();
        // Every component's coefficients, the parts one after the other (slot part·d + c).
        let mut slices: [&mut [T]; 6] = Default::default();
        for (slot, spectrum) in slices.iter_mut().zip(components.iter_mut().flatten()) {
            *slot = coefficients_mut::<T>(spectrum);
        }
        let leaf = |t: usize, chunk: &mut [&mut [T]; 6], table: &mut RowTable| {
            let mut power = 0.0;
            for r in 0..chunk[0].len() / row {
                let ([j0, j1], kb, wb) = row_symbols(sym, modes, t * task / row + r);
                table.fill((sym, [j0, j1], kb), (axes, kappa, top), eta);
                let at = r * row..(r + 1) * row;
                if project {
                    for part in 0..parts {
                        table.project(&mut chunk[part * d..(part + 1) * d], at.clone());
                    }
                }
                let base = chunk[..d].iter().map(|f| &f[at.clone()]);
                let per_sigma = chunk[d..d * parts].iter().map(|f| &f[at.clone()]);
                table.add_power(base, per_sigma, sigma);
                let weights = sym.weight[2].iter().take(row).map(|&wl| wb * wl);
                power += weights.zip(&table.power).map(|(w, p)| w * p).sum::<f64>();
            }
            power
        };
        eta * in_tasks(slices, (tables, 0), task, &leaf)
    }

    /// Per component c: (π/h)² if it is odd (its top sine mode's share of |k|² where j_a = 0 in
    /// logical order), else 0.
    fn top_k2s(&self) -> [f64; 3] {
        std::array::from_fn(|c| match self.odd.get(c) {
            Some(Some(_)) => self.top_k2,
            _ => 0.0,
        })
    }
}

/// Run `leaf(t, chunk, table)` on every task t (a chunk of `task` coefficients of each of the
/// `slices`, an empty slice staying empty) with its own of the `tables` (the first numbered
/// `first`), halving the tasks and the slices at a task boundary into two [`rayon::join`]ed
/// halves, with no allocation; returns the leaves' sum, added in that fixed tree (the same bits
/// on any number of threads).
fn in_tasks<T: Send>(
    slices: [&mut [T]; 6],
    (tables, first): (&mut [RowTable], usize),
    task: usize,
    leaf: &(impl Fn(usize, &mut [&mut [T]; 6], &mut RowTable) -> f64 + Sync),
) -> f64 {
    if let [table] = tables {
        let mut chunk = slices;
        return leaf(first, &mut chunk, table);
    }
    let half = tables.len() / 2;
    let (mut low, mut high): ([&mut [T]; 6], [&mut [T]; 6]) = Default::default();
    for ((slice, low), high) in slices.into_iter().zip(&mut low).zip(&mut high) {
        (*low, *high) = slice.split_at_mut((half * task).min(slice.len()));
    }
    let (low_tables, high_tables) = tables.split_at_mut(half);
    let (a, b) = rayon::join(
        || in_tasks(low, (low_tables, first), task, leaf),
        || in_tasks(high, (high_tables, first + half), task, leaf),
    );
    a + b
}

/// The per-mode tables of one row of modes for [`Flow::project`], so that its loops run along
/// the row over plain slices: per component c, κ_a, |k_a|² and 1/(η|k_a|²); 1/|κ|²; and scratch
/// for s = κ·f̂/|κ|² (a row's coefficients, complex or real) and each mode's power. One per
/// parallel task, made with the flow.
struct RowTable {
    kappa: [Vec<f64>; 3],
    k2: [Vec<f64>; 3],
    inverse: [Vec<f64>; 3],
    inverse_norm: Vec<f64>,
    s: Vec<Complex64>,
    power: Vec<f64>,
}

impl RowTable {
    /// Tables for rows of `len` modes.
    fn new(len: usize) -> Self {
        let zeros = || vec![0.0; len];
        RowTable {
            kappa: std::array::from_fn(|_| zeros()),
            k2: std::array::from_fn(|_| zeros()),
            inverse: std::array::from_fn(|_| zeros()),
            inverse_norm: zeros(),
            s: vec![Complex64::default(); len],
            power: zeros(),
        }
    }

    /// The tables of the row (j0, j1), whose first two axes give `kb` of |k|², for the
    /// components along `axes` (κ per axis, `top` per component: [`component_k2s`]) at
    /// viscosity `eta`.
    fn fill(
        &mut self,
        (sym, [j0, j1], kb): (&Symbols, [usize; 2], f64),
        (axes, kappa, top): (&[usize], &[Vec<f64>; 3], [f64; 3]),
        eta: f64,
    ) {
        for (j2, &kl) in sym.k2[2].iter().take(self.s.len()).enumerate() {
            let idx = [j0, j1, j2];
            let k2s = component_k2s(kb + kl, idx, axes, top);
            let mut norm = 0.0;
            for (c, &a) in axes.iter().enumerate() {
                let k = kappa[a][idx[a]];
                norm += k * k;
                self.kappa[c][j2] = k;
                self.k2[c][j2] = k2s[c];
                self.inverse[c][j2] = if k2s[c] > 0.0 {
                    1.0 / (eta * k2s[c])
                } else {
                    0.0
                };
            }
            self.inverse_norm[j2] = if norm > 0.0 { 1.0 / norm } else { 0.0 };
        }
    }

    /// The Oseen projection of one part's force along the row (the modes `at` of each
    /// component's chunk), in place: s = κ·f̂/|κ|², f̂_a ← (f̂_a − κ_a s)/(η|k_a|²).
    fn project<T: Coefficient>(&mut self, components: &mut [&mut [T]], at: Range<usize>) {
        let s = &mut coefficients_of::<T>(&mut self.s)[..at.len()];
        s.fill(T::default());
        for (f, kappa) in components.iter().zip(&self.kappa) {
            for ((s, &f), &k) in s.iter_mut().zip(&f[at.clone()]).zip(kappa) {
                *s = *s + f * k;
            }
        }
        for (s, &i) in s.iter_mut().zip(&self.inverse_norm) {
            *s = *s * i;
        }
        for ((f, kappa), inverse) in components.iter_mut().zip(&self.kappa).zip(&self.inverse) {
            let f = &mut f[at.clone()];
            for ((f, &s), (&k, &i)) in f.iter_mut().zip(&*s).zip(kappa.iter().zip(inverse)) {
                *f = (*f - s * k) * i;
            }
        }
    }

    /// Each mode's Σ_a |k_a|² |(û_b)_a + σ(û_σ)_a|² into `power`, from the row's projected
    /// components (û_σ absent at a fixed tension).
    fn add_power<'a, T: Coefficient + 'a>(
        &mut self,
        base: impl Iterator<Item = &'a [T]>,
        per_sigma: impl Iterator<Item = &'a [T]>,
        sigma: f64,
    ) {
        self.power.fill(0.0);
        let mut per_sigma = per_sigma.fuse();
        for (b, k2) in base.zip(&self.k2) {
            match per_sigma.next() {
                Some(s) => {
                    for (((p, &b), &s), &k2) in self.power.iter_mut().zip(b).zip(s).zip(k2) {
                        *p += k2 * (b + s * sigma).norm_sqr();
                    }
                }
                None => {
                    for ((p, &b), &k2) in self.power.iter_mut().zip(b).zip(k2) {
                        *p += k2 * b.norm_sqr();
                    }
                }
            }
        }
    }
}

/// A coefficient of the flow's spectra: a complex value, or in a packed spectrum (every axis a
/// mirror or wall axis) one real. The projection reads each component in a *picture* in which
/// it is the plain Oseen projection (I − κ̂κ̂)/(η|k|²) of the components' coefficients at one
/// mode: on complex spectra the periodic picture (an odd component's stored sine coefficient S
/// as −iS, a periodic one's as stored); on a packed spectrum every component is odd, and the
/// picture is the sine coefficients themselves — the periodic picture times i, a factor common
/// to every component, which the linear projection carries through — so no complex arithmetic
/// is done.
pub(super) trait Coefficient:
    Pod
    + Default
    + Send
    + Sync
    + Add<Output = Self>
    + Sub<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// Whether a coefficient is one real (a packed spectrum's), whose picture is itself.
    const REAL: bool;
    /// An odd component's stored sine coefficient S in the picture: −iS, or S.
    fn picture(self) -> Self;
    /// The stored coefficient of an odd component whose picture is `self` (the inverse of
    /// [`Coefficient::picture`]): i·self, or self.
    fn stored(self) -> Self;
    /// iκX: the coefficient of ∂_a of the cosine coefficient X on a periodic axis a (wavenumber
    /// κ).
    fn derivative(self, kappa: f64) -> Self;
    /// |X|².
    fn norm_sqr(self) -> f64;
}

impl Coefficient for Complex64 {
    const REAL: bool = false;

    #[inline]
    fn picture(self) -> Self {
        Complex64::new(self.im, -self.re)
    }

    #[inline]
    fn stored(self) -> Self {
        Complex64::new(-self.im, self.re)
    }

    #[inline]
    fn derivative(self, kappa: f64) -> Self {
        self * Complex64::new(0.0, kappa)
    }

    #[inline]
    fn norm_sqr(self) -> f64 {
        Complex64::norm_sqr(&self)
    }
}

impl Coefficient for f64 {
    const REAL: bool = true;

    #[inline]
    fn picture(self) -> Self {
        self
    }

    #[inline]
    fn stored(self) -> Self {
        self
    }

    /// # Panics
    /// Always: a packed spectrum has no periodic axis (its components are all odd).
    fn derivative(self, _: f64) -> Self {
        unreachable!("a packed spectrum has no periodic axis")
    }

    #[inline]
    fn norm_sqr(self) -> f64 {
        self * self
    }
}

/// Call `f(i, [j0, j1, j2], (|k|², w), &mut out)` on every mode `i` of `spectrum` (its modes'
/// indices of shape `modes`, [`Coefficient`] `T` each) in parallel chunks.
pub(super) fn modes_mut<T: Coefficient>(
    spectrum: &mut Array3<Complex64>,
    modes: [usize; 3],
    sym: &Symbols,
    f: impl Fn(usize, [usize; 3], (f64, f64), &mut T) + Sync,
) {
    let (row, task) = (modes[2], task_modes(modes));
    coefficients_mut::<T>(spectrum)
        .par_chunks_mut(task)
        .enumerate()
        .for_each(|(t, chunk)| {
            for (r, out) in chunk.chunks_mut(row).enumerate() {
                let at = t * task / row + r;
                let ([j0, j1], kb, wb) = row_symbols(sym, modes, at);
                let along = sym.k2[2].iter().zip(&sym.weight[2]);
                for (j2, (out, (&kl, &wl))) in out.iter_mut().zip(along).enumerate() {
                    f(at * row + j2, [j0, j1, j2], (kb + kl, wb * wl), out);
                }
            }
        });
}

/// Modes per parallel task of the row-wise sweeps: whole rows (the last axis), about
/// [`PAR_CHUNK`] modes, at least one row.
fn task_modes(modes: [usize; 3]) -> usize {
    modes[2] * (PAR_CHUNK / modes[2]).max(1)
}

/// Row `r` of modes of index shape `modes` (the rows numbered over the first two axes): its
/// (j0, j1), and the first two axes' share of |k|² and of the weight w ([`Symbols::row`]), to
/// which the last axis's add and multiply.
#[inline]
fn row_symbols(sym: &Symbols, modes: [usize; 3], r: usize) -> ([usize; 2], f64, f64) {
    let (j0, j1) = (r / modes[1], r % modes[1]);
    let (kb, wb) = (
        sym.k2[0][j0] + sym.k2[1][j1],
        sym.weight[0][j0] * sym.weight[1][j1],
    );
    ([j0, j1], kb, wb)
}

/// The flat positions `range` among modes of index shape `modes`, each with its index
/// (j0, j1, j2): [`index_of`] of the first, the others counted on along the last axis (no
/// division a mode).
#[inline]
pub(super) fn indexed(
    range: Range<usize>,
    modes: [usize; 3],
) -> impl Iterator<Item = (usize, [usize; 3])> {
    let [_, s1, s2] = modes;
    let mut idx = index_of(range.start, modes);
    range.map(move |i| {
        let at = idx;
        idx[2] += 1;
        if idx[2] == s2 {
            idx[2] = 0;
            idx[1] += 1;
            if idx[1] == s1 {
                idx[1] = 0;
                idx[0] += 1;
            }
        }
        (i, at)
    })
}

/// The index (j0, j1, j2) of the flat position `i` among modes of index shape `modes`.
#[inline]
fn index_of(i: usize, [_, s1, s2]: [usize; 3]) -> [usize; 3] {
    [i / (s1 * s2), (i / s2) % s1, i % s2]
}

/// |k|² and the Parseval weight w of the mode at `idx`.
#[inline]
pub(super) fn mode_symbols(sym: &Symbols, [i0, i1, i2]: [usize; 3]) -> (f64, f64) {
    (
        sym.k2[0][i0] + sym.k2[1][i1] + sym.k2[2][i2],
        sym.weight[0][i0] * sym.weight[1][i1] * sym.weight[2][i2],
    )
}

/// |k_a|² of each component c (axis a = `axes[c]`) at the mode `idx` of |k|² = `k2`: |k|², plus
/// `top[c]` where j_a = 0 (an odd component's top sine mode, [`Flow::top_k2s`]).
#[inline]
fn component_k2s(k2: f64, idx: [usize; 3], axes: &[usize], top: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| match axes.get(c) {
        Some(&a) if idx[a] == 0 => k2 + top[c],
        _ => k2,
    })
}

/// A spectrum's coefficients in flat order, as [`Coefficient`] `T` (a packed spectrum's
/// reals as `f64`).
#[inline]
fn coefficients<T: Coefficient>(a: &Array3<Complex64>) -> &[T] {
    bytemuck::cast_slice(a.as_slice().expect("standard layout"))
}

/// [`coefficients`], writable.
#[inline]
fn coefficients_mut<T: Coefficient>(a: &mut Array3<Complex64>) -> &mut [T] {
    bytemuck::cast_slice_mut(a.as_slice_mut().expect("standard layout"))
}

/// Complex scratch as [`Coefficient`] `T` (a complex value each, or two reals).
#[inline]
fn coefficients_of<T: Coefficient>(v: &mut [Complex64]) -> &mut [T] {
    bytemuck::cast_slice_mut(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::spectral::evaluator::{Evaluator, ExplicitTerm};
    use crate::problem::config::Laplacian;
    use crate::problem::grid::Grid;
    use crate::problem::model::{SpontaneousCurvature, C0};

    /// The conserved flow's evaluator on `grid` (ε = 1, c0 = 0, one thread).
    fn plain_evaluator(grid: &Grid) -> Evaluator {
        let c0 = C0 {
            shape: SpontaneousCurvature::Zero,
            ramp_time: None,
        };
        let explicit = ExplicitTerm::ConservedRhs;
        Evaluator::new(grid.clone(), 1.0, c0, Laplacian::Spectral, explicit, 1)
    }

    /// With no membrane (φ ≡ −1: μ = 0, no force) the velocity is the imposed shear alone, at
    /// every point to 1e-14: γ̇y between walls across y, (γ̇/k₀) sin(k₀y) on the periodic box
    /// (y from the box's centre), and u_y = 0.
    #[test]
    fn an_empty_box_carries_the_imposed_shear() {
        let rate = 0.01;
        for walls in [false, true] {
            let grid = Grid::new(&[12, 16], 0.5, &[false, false]).with_walls(&[false, walls]);
            let mut ev = plain_evaluator(&grid).with_flow(FlowSpec {
                viscosity: 1.0,
                mobility: 0.01,
                shear_rate: Some(rate),
                viscosity_inside: None,
                inextensible: false,
            });
            let u = ev
                .velocity_at(&Array3::from_elem(grid.shape, -1.0), 0.0)
                .expect("finite")
                .expect("a flow");
            let k0 = 2.0 * std::f64::consts::PI / 8.0;
            for (((_, _, j), &ux), &uy) in u[0].indexed_iter().zip(u[1].iter()) {
                let y = grid.coords(2)[j];
                let expected = if walls {
                    rate * y
                } else {
                    rate / k0 * (k0 * y).sin()
                };
                assert!(
                    (ux - expected).abs() < 1e-14 && uy.abs() < 1e-14,
                    "walls {walls}: {ux} {uy}"
                );
            }
        }
    }

    /// Unequal viscosities under the imposed Kolmogorov shear: a box filled with the inside's
    /// fluid (φ ≡ 1: μ = 0, no membrane force; η = η_in everywhere) is driven by the same body
    /// force η_out γ̇k₀ sin(k₀y) x̂ as the outside's, so its flow is the imposed one slowed by
    /// η_out/η_in: u_x = (η_out/η_in)(γ̇/k₀) sin(k₀y), u_y = 0, to the solve's tolerance (1e-9
    /// of γ̇/k₀), at η_in/η_out = 4 and 1/4. A box of the outside's fluid (φ ≡ −1) carries the
    /// imposed flow unchanged. Leaving the imposed strain's force out would give the imposed
    /// flow in both.
    #[test]
    fn the_inside_fluid_carries_the_shear_slowed_by_its_viscosity() {
        let rate = 0.01;
        let grid = Grid::new(&[12, 16], 0.5, &[false, false]);
        let k0 = 2.0 * std::f64::consts::PI / 8.0;
        for inside in [4.0, 0.25] {
            for (phi, slowed) in [(1.0, 1.0 / inside), (-1.0, 1.0)] {
                let mut ev = plain_evaluator(&grid).with_flow(FlowSpec {
                    viscosity: 1.0,
                    mobility: 0.01,
                    shear_rate: Some(rate),
                    viscosity_inside: Some(inside),
                    inextensible: false,
                });
                let u = ev
                    .velocity_at(&Array3::from_elem(grid.shape, phi), 0.0)
                    .expect("finite")
                    .expect("a flow");
                for (((_, _, j), &ux), &uy) in u[0].indexed_iter().zip(u[1].iter()) {
                    let y = grid.coords(2)[j];
                    let expected = slowed * rate / k0 * (k0 * y).sin();
                    assert!(
                        (ux - expected).abs() < 1e-9 * rate / k0 && uy.abs() < 1e-9 * rate / k0,
                        "inside {inside}, φ {phi}: {ux} against {expected}, u_y {uy}"
                    );
                }
            }
        }
    }

    /// The semi-discrete energy law term by term (module documentation), on 2D and 3D fields
    /// with odd and even lengths, periodic, mirrored (a velocity component twisted, with its top
    /// sine mode), walled, and with every axis mirrored or walled (the quarter and eighth boxes'
    /// packed spectra, computed a real a mode, with an odd row's padding), at σ = 0.3: with FT[u·∇φ] = M N̂_conserved − N̂_flow +
    /// σT̂ (the same state evaluated without and with the flow; N̂_flow holds the advection at
    /// σ = 0, T̂ the advection per unit σ) and μ̂ = −N̂_conserved/|k|² +
    /// 2ε⁴|k|⁴φ̂ + c_σσ|k|²φ̂, Σ_x μ u·∇φ = Σ_k w Re(μ̂ FT[u·∇φ]*) equals the reported
    /// dissipation η Σ_k w |k|²|û|² to 1e-10, and the advection's k = 0 coefficient is 0 (it
    /// moves no volume). The same at the fixed tension σ_f = σ, where N̂_flow holds the whole
    /// advection and there is no T̂. A sign slip, a missing projection or a wrong weight misses
    /// by O(1).
    #[test]
    fn the_advection_dissipates_what_the_fluid_does() {
        let (sigma, spec) = (
            0.3,
            FlowSpec {
                viscosity: 1.7,
                mobility: 0.05,
                shear_rate: None,
                viscosity_inside: None,
                inextensible: false,
            },
        );
        let boxes: [(&[usize], &[bool], &[bool]); 9] = [
            (&[24, 19], &[false, false], &[false, false]),
            (&[12, 11, 10], &[false; 3], &[false; 3]),
            (&[24, 20], &[false, true], &[false, false]),
            (&[12, 11, 10], &[false; 3], &[true, false, false]),
            (&[12, 10, 10], &[false, true, false], &[false, false, true]),
            (&[24, 20], &[true, true], &[false, false]),
            (&[24, 22], &[true, false], &[false, true]),
            (&[12, 10, 14], &[true; 3], &[false; 3]),
            (&[12, 9, 10], &[true, false, true], &[false, true, false]),
        ];
        for ((n, mirror, walls), fixed) in boxes.into_iter().flat_map(|b| [(b, false), (b, true)]) {
            let grid = Grid::new(n, 0.8, mirror).with_walls(walls);
            assert_energy_law(&grid, spec, sigma, fixed);
        }
    }

    /// φ of the energy-law tests: an off-centre tilted ellipsoid on `grid`.
    fn tilted_ellipsoid(grid: &Grid) -> Array3<f64> {
        Array3::from_shape_fn(grid.shape, |(i, j, k)| {
            let (x, y, z) = (i as f64 - 5.5, j as f64 - 10.0, k as f64 - 9.0);
            (2.2 - (0.04 * x * x + 0.03 * y * y + 0.05 * z * z + 0.01 * x * y).sqrt()).tanh()
        })
    }

    /// Σ_x μ u·∇φ equals the reported dissipation (to 1e-10 of it, or to `tolerance`) and the
    /// advection's k = 0 coefficient is 0, for the flow `spec` at σ on `grid` (split, or at the
    /// fixed tension σ): see [`the_advection_dissipates_what_the_fluid_does`]. Returns the
    /// dissipation.
    fn assert_energy_law(grid: &Grid, spec: FlowSpec, sigma: f64, fixed: bool) -> f64 {
        assert_energy_law_at(grid, &tilted_ellipsoid(grid), spec, sigma, fixed)
    }

    /// [`assert_energy_law`] at the state `phi`.
    fn assert_energy_law_at(
        grid: &Grid,
        phi: &Array3<f64>,
        spec: FlowSpec,
        sigma: f64,
        fixed: bool,
    ) -> f64 {
        let tolerance = if spec.viscosity_inside.is_some() {
            1e-8
        } else if spec.inextensible {
            3e-3
        } else {
            1e-10
        };
        let evaluator = |flow: bool| {
            let ev = plain_evaluator(grid);
            match (flow, fixed) {
                (false, _) => ev,
                (true, false) => ev.with_flow(spec),
                (true, true) => ev.with_flow(spec).with_fixed_tension(sigma),
            }
        };
        let plain = evaluator(false).state_at(phi, 0.0, sigma).expect("finite");
        let mut ev = evaluator(true);
        let flowing = ev.state_at(phi, 0.0, sigma).expect("finite");
        let (sym, t) = (&ev.symbols, &ev.transform);
        let (e4x2, tension) = (2.0, TENSION_FACTOR * sigma);
        let mut power = 0.0;
        assert_eq!(flowing.curvature_hat.is_empty(), fixed);
        let reduced = (0..3).filter(|&a| grid.shape[a] > 1);
        let all_reduced = reduced
            .into_iter()
            .all(|a| grid.kinds[a] != AxisKind::Periodic);
        assert_eq!(t.packed(), all_reduced);
        // Every spectrum in the index layout (a packed one's reals as complex values).
        let index = |s: &Array3<Complex64>| t.unpacked(s.view());
        let per_sigma = (!fixed).then(|| index(&flowing.curvature_hat));
        let per_sigma = |i: usize| per_sigma.as_ref().map(|t| t.as_slice().unwrap()[i]);
        let (n_plain, n_flow, hat) = (
            index(&plain.nonlinear),
            index(&flowing.nonlinear),
            index(&plain.hat),
        );
        let shape = t.index_shape();
        for (i, ((&n, &nf), &h)) in n_plain
            .iter()
            .zip(n_flow.iter())
            .zip(hat.iter())
            .enumerate()
        {
            let t = per_sigma(i).unwrap_or_default();
            let (k, w) = mode_symbols(sym, index_of(i, shape));
            let advection = n * spec.mobility - nf + t * sigma;
            if k == 0.0 {
                assert!(advection.norm() < 1e-12 * n.norm().max(1.0), "{advection}");
                continue;
            }
            let mu = -n / k + h * (e4x2 * k * k + tension * k);
            power += w * (mu * advection.conj()).re;
        }
        let d = flowing.flow.dissipation;
        assert!(d > 0.0);
        assert!(
            (power - d).abs() <= tolerance * d,
            "{:?} {:?} fixed {fixed}: Σ μ u·∇φ = {power:e}, dissipation {d:e}",
            grid.shape,
            grid.kinds
        );
        d
    }

    /// Unequal viscosities (η_in = 4η_out and η_out/4) on periodic 2D and 3D boxes, split and at
    /// a fixed tension: the energy law holds to the solve's tolerance (1e-8 of the
    /// dissipation), and the dissipation is that of the local viscosity in the solve's discrete
    /// form, η_out Σ_k w|k|²|û|² + Σ_x 2η₁(x)|D(u)|² h^d, η₁ = (η_in − η_out)clamp((1 + φ)/2),
    /// of the velocity on the grid (its strain by spectral derivatives), to 1e-8. The
    /// outside's part alone misses by O(1), and so does the equal-viscosity flow's dissipation.
    #[test]
    fn unequal_viscosities_dissipate_with_the_local_viscosity() {
        let sigma = 0.3;
        for n in [&[24usize, 19][..], &[12, 11, 10][..]] {
            let grid = Grid::new(n, 0.8, &vec![false; n.len()]);
            for inside in [4.0, 0.25] {
                for fixed in [false, true] {
                    let spec = FlowSpec {
                        viscosity: 1.0,
                        mobility: 0.05,
                        shear_rate: None,
                        viscosity_inside: Some(inside),
                        inextensible: false,
                    };
                    let d = assert_energy_law(&grid, spec, sigma, fixed);
                    let equal = FlowSpec {
                        viscosity_inside: None,
                        inextensible: false,
                        ..spec
                    };
                    let d_equal = assert_energy_law(&grid, equal, sigma, fixed);
                    let phi = tilted_ellipsoid(&grid);
                    let mut ev = plain_evaluator(&grid).with_flow(spec);
                    if fixed {
                        ev = ev.with_fixed_tension(sigma);
                    }
                    let u = ev.velocity_at(&phi, sigma).expect("finite").expect("flow");
                    let [local, outside] =
                        strain_power((&mut ev.transform, &ev.symbols), &grid, &u, &phi, inside);
                    let label = format!("{n:?} inside {inside} fixed {fixed}");
                    assert!((local - d).abs() <= 1e-8 * d, "{label}: {local:e} {d:e}");
                    assert!((outside - d).abs() > 0.05 * d, "{label}: {outside:e} {d:e}");
                    assert!((d_equal - d).abs() > 0.05 * d, "{label}: {d_equal:e} {d:e}");
                }
            }
        }
    }

    /// η = 1 inside and out at mobility `mobility`, no imposed shear; the membrane
    /// inextensible or a drop.
    fn unit_fluid(mobility: f64, inextensible: bool) -> FlowSpec {
        FlowSpec {
            viscosity: 1.0,
            mobility,
            shear_rate: None,
            viscosity_inside: None,
            inextensible,
        }
    }

    /// The inextensible membrane on a periodic 2D box (a capsule of radius 4.8ε around a
    /// segment 7.7ε long, axes 1.8 : 1, with the tanh profile of its distance), split and at
    /// a fixed tension. The energy law holds with the regularization's channel,
    /// Σ_x μ u·∇φ = η∫|∇u|² + γ∫∇σ·T∇σ, to 3e-3 (measured 1e-3: the solve stops on the flow's
    /// error, 1e-4, and the tension's work on the last residual is what is left). And the
    /// flow keeps the membrane's area where it is: the rate at which it moves area along the
    /// capsule, ∫τ(P_s:∇u) dA ([`area_rate`]), read across the layer as −(3/(2√2ε))∫τT:∇u dx
    /// (∫ε|∇φ|² dn = 2√2/3 across the tanh profile) with ∇u by central differences (not the
    /// solve's spectral ones), is below a quarter of the drop's at the same state (measured
    /// 1/8.7 and 1/8.2: the constraint holds across the layer, not at each of its points).
    /// 3D is left to the rates study: the same capsule at 3.2ε in 3D takes the solve's 2 000
    /// iterations and three minutes.
    #[test]
    fn the_inextensible_flow_keeps_the_membrane_area() {
        let sigma = 0.3;
        let grid = Grid::new(&[1, 64, 48], 0.5, &[false; 3]);
        let axes: Vec<usize> = (0..3).filter(|&a| grid.shape[a] > 1).collect();
        let shortest = axes.iter().map(|&a| grid.shape[a]).min().unwrap() as f64 * grid.h;
        let (radius, half) = (0.2 * shortest, 0.16 * shortest);
        let phi = Array3::from_shape_fn(grid.shape, |(i, j, k)| {
            let at = [i, j, k];
            let c = |a: usize| (at[a] as f64 - grid.shape[a] as f64 / 2.0 + 0.5) * grid.h;
            // The distance to the segment |x| ≤ half on the long axis.
            let along = c(axes[0]).abs() - (c(axes[0]).abs()).min(half);
            let r2: f64 = along * along + axes[1..].iter().map(|&a| c(a) * c(a)).sum::<f64>();
            ((radius - r2.sqrt()) / std::f64::consts::SQRT_2).tanh()
        });
        for fixed in [false, true] {
            let rates: Vec<f64> = [false, true]
                .into_iter()
                .map(|inextensible| {
                    let spec = unit_fluid(0.05, inextensible);
                    if inextensible {
                        assert_energy_law_at(&grid, &phi, spec, sigma, fixed);
                    }
                    let mut ev = plain_evaluator(&grid).with_flow(spec);
                    if fixed {
                        ev = ev.with_fixed_tension(sigma);
                    }
                    let u = ev.velocity_at(&phi, sigma).expect("finite").expect("flow");
                    area_rate(&grid, &phi, &u, (radius, half))
                })
                .collect();
            assert!(
                rates[1].abs() < 0.25 * rates[0].abs(),
                "fixed {fixed}: drop {:e}, inextensible {:e}",
                rates[0],
                rates[1]
            );
        }
    }

    /// The membrane's own velocity on a quasi-circle (R = 16ε, mode n = 2 at amplitude 0.02, on
    /// a periodic box 8R wide, h = ε/2, fixed tension 0): sampled on the circle r = R and
    /// projected on cos 2θ (u_r) and sin 2θ (u_θ), the inextensible flow meets the sharp
    /// constraint u_r + ∂_θu_θ = 0, |V_r + 2V_θ| below 5% of |V_r| (measured 1.6%). The drop's
    /// flow at the same state misses it by 93% (measured; asserted above 50%): where the sharp drop's tangential
    /// velocity is u_θ = −u_r/n at the membrane, the phase-field drop's is nearly zero there
    /// (docs/src/validation/flow.md, "The inextensible membrane").
    #[test]
    fn the_inextensible_circle_does_not_stretch_its_membrane() {
        let (r0, n, h) = (16.0, 256, 0.5);
        let grid = Grid::new(&[1, n, n], h, &[false; 3]);
        let c = |m: usize| (m as f64 - n as f64 / 2.0 + 0.5) * h;
        let phi = Array3::from_shape_fn(grid.shape, |(_, j, k)| {
            let (x, y) = (c(j), c(k));
            let radius = r0 * (1.0 + 0.02 * (2.0 * y.atan2(x)).cos());
            ((radius - x.hypot(y)) / std::f64::consts::SQRT_2).tanh()
        });
        let misses: Vec<f64> = [false, true]
            .into_iter()
            .map(|inextensible| {
                let spec = unit_fluid(0.01, inextensible);
                let mut ev = plain_evaluator(&grid)
                    .with_flow(spec)
                    .with_fixed_tension(0.0);
                let u = ev.velocity_at(&phi, 0.0).expect("finite").expect("flow");
                // Bilinear samples on r = R, projected on the mode.
                let sample = |f: &Array3<f64>, x: f64, y: f64| {
                    let (fi, fj) = (x / h + n as f64 / 2.0 - 0.5, y / h + n as f64 / 2.0 - 0.5);
                    let (i, j) = (fi.floor() as usize, fj.floor() as usize);
                    let (a, b) = (fi - i as f64, fj - j as f64);
                    f[[0, i, j]] * (1.0 - a) * (1.0 - b)
                        + f[[0, i + 1, j]] * a * (1.0 - b)
                        + f[[0, i, j + 1]] * (1.0 - a) * b
                        + f[[0, i + 1, j + 1]] * a * b
                };
                let points = 720;
                let (mut v_r, mut v_t) = (0.0, 0.0);
                for q in 0..points {
                    let t = 2.0 * std::f64::consts::PI * q as f64 / points as f64;
                    let (x, y) = (r0 * t.cos(), r0 * t.sin());
                    let (ux, uy) = (sample(&u[0], x, y), sample(&u[1], x, y));
                    v_r += (ux * t.cos() + uy * t.sin()) * (2.0 * t).cos();
                    v_t += (uy * t.cos() - ux * t.sin()) * (2.0 * t).sin();
                }
                ((v_r + 2.0 * v_t) / v_r).abs()
            })
            .collect();
        assert!(misses[1] < 0.05, "inextensible: {}", misses[1]);
        assert!(misses[0] > 0.5, "drop: {}", misses[0]);
    }

    /// The rate at which the flow moves membrane area along the capsule of
    /// [`the_inextensible_flow_keeps_the_membrane_area`], −(3/(2√2ε))Σ_x τ T:∇u h^d
    /// (T = ε²∇φ∇φ, ε = 1, ∇ by central differences on the periodic grid), with the pattern
    /// τ = (x_c/9)² of the closest surface point's coordinate x_c along the long axis (so τ is
    /// constant along the normals), less its mean over the layer (Σ_x τ|∇φ|² = 0: the uniform
    /// part, the total area's rate, is the global tension's).
    fn area_rate(
        grid: &Grid,
        phi: &Array3<f64>,
        u: &[Array3<f64>],
        (radius, half): (f64, f64),
    ) -> f64 {
        let axes: Vec<usize> = (0..3).filter(|&a| grid.shape[a] > 1).collect();
        let derivative = |f: &Array3<f64>, idx: (usize, usize, usize), a: usize| {
            let n = grid.shape[a];
            let mut at = [[idx.0, idx.1, idx.2]; 2];
            at[0][a] = (at[0][a] + 1) % n;
            at[1][a] = (at[1][a] + n - 1) % n;
            (f[at[0]] - f[at[1]]) / (2.0 * grid.h)
        };
        let pattern = |idx: (usize, usize, usize)| {
            let at = [idx.0, idx.1, idx.2];
            let c = |a: usize| (at[a] as f64 - grid.shape[a] as f64 / 2.0 + 0.5) * grid.h;
            let (x, rho) = (
                c(axes[0]),
                axes[1..].iter().map(|&a| c(a) * c(a)).sum::<f64>().sqrt(),
            );
            // Past the segment's end e = ±half the closest point is on the cap, radially
            // from e.
            let end = x.clamp(-half, half);
            let x_c = if x.abs() > half {
                end + radius * (x - end) / ((x - end).powi(2) + rho * rho).sqrt()
            } else {
                x
            };
            (x_c / (radius + half)).powi(2)
        };
        let (mut weighted, mut weight, mut rate, mut uniform) = (0.0, 0.0, 0.0, 0.0);
        for idx in phi.indexed_iter().map(|(idx, _)| idx) {
            let g: Vec<f64> = axes.iter().map(|&a| derivative(phi, idx, a)).collect();
            let mut strain = 0.0;
            for (ca, &a) in axes.iter().enumerate() {
                for (cb, _) in axes.iter().enumerate() {
                    strain += g[ca] * g[cb] * derivative(&u[cb], idx, a);
                }
            }
            let (tau, w) = (pattern(idx), g.iter().map(|g| g * g).sum::<f64>());
            weighted += tau * w;
            weight += w;
            rate += tau * strain;
            uniform += strain;
        }
        let tau_mean = weighted / weight;
        -3.0 / (2.0 * std::f64::consts::SQRT_2)
            * (rate - tau_mean * uniform)
            * grid.h.powi(axes.len() as i32)
    }

    /// [η_out Σ_k w|k|²|û|² + Σ_x 2η₁(x)|D(u)|² h^d, η_out Σ_k w|k|²|û|²] of the grid
    /// velocity `u` (η_out = 1, η₁ = (`inside` − 1)clamp((1 + φ)/2)), its strain
    /// D_ab = (∂_a u_b + ∂_b u_a)/2 by spectral derivatives (the Nyquist wavenumbers 0).
    fn strain_power(
        (t, sym): (&mut Transform, &Symbols),
        grid: &Grid,
        u: &[Array3<f64>],
        phi: &Array3<f64>,
        inside: f64,
    ) -> [f64; 2] {
        let axes: Vec<usize> = (0..3).filter(|&a| grid.shape[a] > 1).collect();
        let ks = t.wavenumbers(grid.h);
        let spectral = t.spectral_shape();
        let mut outside = 0.0;
        for f in u {
            let mut spectrum = Array3::zeros(spectral);
            t.forward(&mut f.clone(), &mut spectrum);
            for (i, c) in spectrum.iter().enumerate() {
                let (k2, w) = mode_symbols(sym, index_of(i, spectral));
                outside += w * k2 * c.norm_sqr();
            }
        }
        let derivative = |t: &mut Transform, f: &Array3<f64>, a: usize| {
            let mut spectrum = Array3::zeros(spectral);
            t.forward(&mut f.clone(), &mut spectrum);
            let n = grid.shape[a];
            for (idx, c) in spectrum.indexed_iter_mut() {
                let j = [idx.0, idx.1, idx.2][a];
                let nyquist = n.is_multiple_of(2) && j == n / 2;
                let k = if nyquist { 0.0 } else { ks[a][j] };
                *c *= Complex64::new(0.0, k);
            }
            let mut out = Array3::zeros(grid.shape);
            t.inverse(&mut spectrum, &mut out);
            out
        };
        let mut excess = 0.0;
        for (ca, &a) in axes.iter().enumerate() {
            for (cb, &b) in axes.iter().enumerate() {
                let d = (derivative(t, &u[cb], a) + derivative(t, &u[ca], b)) * 0.5;
                for (&dab, &p) in d.iter().zip(phi) {
                    let eta1 = (inside - 1.0) * (0.5 * (1.0 + p)).clamp(0.0, 1.0);
                    excess += 2.0 * eta1 * dab * dab;
                }
            }
        }
        [outside + excess * grid.cell_volume(), outside]
    }

    /// A circle (R = 16ε, 256², h = ε/2, at σ = 0) in the imposed Kolmogorov shear answers the
    /// strain with 2/(1 + λ) of what it does at equal viscosities (the drop's response to a
    /// regular incident flow, docs/src/theory/flow.md): the rate of its quadrupole moment,
    /// dQ/dt = Σ_x χ(u_x y + u_y x) (Q = Σ_x χxy, u divergence-free), over its value at
    /// λ = 1 is 0.5 at λ = 3 and 4/3 at λ = 1/2 to 0.5% (measured 3e-4 and 1.2e-3 off, relative; at
    /// R = 8ε 4.0% and 1.6%: the phase field's O(ε/R)). A solve that took the outside's
    /// viscosity for the strain's force, or none, gives 1.
    #[test]
    fn a_circle_answers_the_imposed_strain_with_two_over_one_plus_lambda() {
        let (n, r0) = (256usize, 16.0);
        let grid = Grid::new(&[n, n], 0.5, &[false, false]);
        let (x, y) = (grid.coords(1), grid.coords(2));
        let phi = Array3::from_shape_fn(grid.shape, |(_, i, j)| {
            let r = x[i].hypot(y[j]);
            ((r0 - r) / std::f64::consts::SQRT_2).tanh()
        });
        let quadrupole_rate = |inside: f64| {
            let spec = FlowSpec {
                viscosity: 1.0,
                mobility: 0.01,
                shear_rate: Some(1e-3),
                viscosity_inside: Some(inside),
                inextensible: false,
            };
            let mut ev = plain_evaluator(&grid)
                .with_flow(spec)
                .with_fixed_tension(0.0);
            let u = ev.velocity_at(&phi, 0.0).expect("finite").expect("a flow");
            phi.indexed_iter()
                .zip(u[0].iter().zip(u[1].iter()))
                .map(|(((_, i, j), &p), (&ux, &uy))| 0.5 * (1.0 + p) * (ux * y[j] + uy * x[i]))
                .sum::<f64>()
        };
        let equal = quadrupole_rate(1.0);
        for inside in [3.0, 0.5] {
            let ratio = quadrupole_rate(inside) / equal;
            let expected = 2.0 / (1.0 + inside);
            assert!(
                (ratio / expected - 1.0).abs() < 5e-3,
                "λ {inside}: {ratio} against {expected}"
            );
        }
    }
}
