//! The area-difference term on the spectral grid ([`crate::problem::area_difference`]): the
//! functional M[φ] = ∫ Φ₀(1 − φ²) and its variation m = δM/δφ of an evaluated state, and the
//! sums the conserved step solves its two multipliers from.
//!
//! These passes run only for scenes with `ade` or `bilayer_couple`, mode by mode in one thread
//! ([`for_each_mode`]) besides their transforms: three transforms (∇²φ back, the local part
//! of m and φ² forward) per evaluation.

use super::evaluator::{Evaluator, ExplicitTerm, Metric, State, Symbols};
use super::pieces::{for_each_piece, reals, reals_mut};
use super::update::{Update, MAX_LEVELS};
use crate::engines::numerics::sum_in_fixed_tree;
use crate::problem::area_difference::{curvature_density, curvature_variation_local};
use ndarray::Array3;
use num_complex::Complex64;
use rayon::prelude::*;

/// The scratch of the term's evaluation: one spectrum, two real fields.
pub struct CurvatureScratch {
    spectrum: Array3<Complex64>,
    real: [Array3<f64>; 2],
}

impl CurvatureScratch {
    /// Scratch for the evaluator `ev`.
    pub fn new(ev: &Evaluator) -> Self {
        CurvatureScratch {
            spectrum: Array3::zeros(ev.transform.spectral_shape()),
            real: [ev.grid.zeros(), ev.grid.zeros()],
        }
    }
}

/// Calls `f(at, |k|², w)` for every mode of a spectrum of `total` reals, `at` its first real
/// (one real per mode in a packed spectrum, two otherwise), in order.
pub fn for_each_mode(sym: &Symbols, total: usize, mut f: impl FnMut(usize, f64, f64)) {
    for t in 0..total.div_ceil(sym.task_reals()) {
        for_task_modes(sym, total, t, &mut f);
    }
}

/// [`for_each_mode`] over the modes of task `t` alone (the reals from t · `task_reals` on).
fn for_task_modes(sym: &Symbols, total: usize, t: usize, mut f: impl FnMut(usize, f64, f64)) {
    let task = sym.task_reals();
    let len = task.min(total - t * task);
    for_each_piece(sym, t, len, |p, at| {
        for (l, (k, w)) in p.symbols().enumerate() {
            f(t * task + at + l * sym.width, k, w);
        }
    });
}

/// The reals of one mode starting at `at`.
#[inline]
pub(crate) fn at(v: &[f64], at: usize, width: usize) -> &[f64] {
    &v[at..at + width]
}

/// Σ over a mode's reals of a·b: Re(a b*) of modes given as slices.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Evaluator {
    /// M and m̂ = FT[δM/δφ] of `state`, whose φ̂ and φ are evaluated, into
    /// `state.measures.curvature` and `state.curvature_hat`:
    ///
    /// ```text
    /// ∇²φ = FT⁻¹[−|k|²φ̂],   M = Σ Φ₀(1 − φ²) dv,
    /// m̂ = FT[(3φ² − 1)(1 − φ²) − 2φΦ₀] − ε²|k|² FT[φ²]
    /// ```
    pub(super) fn evaluate_curvature(&mut self, state: &mut State) {
        let Some(scratch) = self.curvature.as_mut() else {
            return;
        };
        let e2 = self.eps * self.eps;
        let sym = &self.symbols;
        let total = 2 * state.hat.len();
        {
            let (hat, s) = (
                reals(state.hat.as_slice().expect("standard layout")),
                reals_mut(scratch.spectrum.as_slice_mut().expect("standard layout")),
            );
            for_each_mode(sym, total, |i, k, _| {
                for c in i..i + sym.width {
                    s[c] = -k * hat[c];
                }
            });
        }
        let [lap, square] = &mut scratch.real;
        self.transform.inverse(&mut scratch.spectrum, lap);
        let mut sum = 0.0;
        for ((l, q), &p) in lap.iter_mut().zip(square.iter_mut()).zip(state.phi.iter()) {
            sum += curvature_density(p, *l, e2);
            *l = curvature_variation_local(p, *l, e2);
            *q = p * p;
        }
        self.transform.forward(lap, &mut scratch.spectrum);
        self.transform.forward(square, &mut state.curvature_hat);
        {
            let local = reals(scratch.spectrum.as_slice().expect("standard layout"));
            let m = reals_mut(state.curvature_hat.as_slice_mut().expect("standard layout"));
            for_each_mode(sym, total, |i, k, _| {
                for c in i..i + sym.width {
                    m[c] = local[c] - e2 * k * m[c];
                }
            });
        }
        self.transform
            .hermitian_symmetrize(&mut state.curvature_hat);
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        state.measures.curvature = sum * dv;
    }

    /// With the relaxational engine's gradient: ĝ ← ĝ + λ m̂ with λ = dF_ade/dM of the state,
    /// and the area multiplier's sum ⟨ĝ, q⟩ with it (q̂ = (c_σ|k|²/M(k)) φ̂): the gradient of
    /// F_sc + F_ade.
    pub(super) fn add_curvature_gradient(&self, state: &mut State) {
        let (Some(term), ExplicitTerm::Gradient(metric)) = (self.area_difference, self.explicit)
        else {
            return;
        };
        let lambda = term.multiplier(state.measures.curvature);
        let sym = &self.symbols;
        let total = 2 * state.hat.len();
        let hat = reals(state.hat.as_slice().expect("standard layout"));
        let m = reals(state.curvature_hat.as_slice().expect("standard layout"));
        let g = reals_mut(state.nonlinear.as_slice_mut().expect("standard layout"));
        let mut gq = 0.0;
        for_each_mode(sym, total, |i, k, w| {
            let qh = metric.c_sigma * k / Metric::at(&metric, k);
            gq += w * qh * dot(at(m, i, sym.width), at(hat, i, sym.width));
            for c in i..i + sym.width {
                g[c] += lambda * m[c];
            }
        });
        state.multiplier_sums.1 += lambda * gq;
    }

    /// The residual RMS over the full box of μ − μ̄ of a conserved-flow state with multipliers
    /// σ and λ: μ̂ = −N̂/|k|² + (2ε⁴|k|⁴ + (3/√2)εσ|k|²) φ̂ + λ m̂ for k ≠ 0 (N̂ holds
    /// −|k|² times the explicit part of μ̂).
    pub fn residual_with(&self, state: &State, sigma: f64, lambda: f64) -> f64 {
        let sym = &self.symbols;
        let (e2, tension) = (self.eps * self.eps, 2.0 * sym.area_prefactor * sigma);
        let hat = reals(state.hat.as_slice().expect("standard layout"));
        let n = reals(state.nonlinear.as_slice().expect("standard layout"));
        let m = reals(state.curvature_hat.as_slice().expect("standard layout"));
        let mut sum = 0.0;
        for_each_mode(sym, 2 * state.hat.len(), |i, k, w| {
            if k <= 0.0 {
                return;
            }
            let hk = 2.0 * e2 * e2 * k * k + tension * k;
            for c in i..i + sym.width {
                let mu = -n[c] / k + hk * hat[c] + lambda * m[c];
                sum += w * mu * mu;
            }
        });
        (sum / self.grid.full_volume()).sqrt()
    }
}

/// The sums the conserved step solves σ and λ from, for φ̂^{n+1} = P̂ + σQ̂ + λR̂ with
/// R̂ = −|k|² Σ_j n_j m̂^{n+1−j} (n_j = Δt b_j/D, [`super::update::ValueFactors`]):
///
/// ```text
/// A(σ, λ) = Σ a |P̂ + σQ̂ + λR̂|²        (a = (3/(2√2)) ε |k|² w)
/// M(σ, λ) ≈ Mⁿ + ⟨m̂ⁿ, P̂ − φ̂ⁿ⟩ + σ⟨m̂ⁿ, Q̂⟩ + λ⟨m̂ⁿ, R̂⟩   (⟨u, v⟩ = Σ w Re(û v̂*))
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CoupleSums {
    /// A_PP, A_PQ, A_QQ, A_PR, A_QR, A_RR.
    pub area: [f64; 6],
    /// ⟨m̂ⁿ, P̂ − φ̂ⁿ⟩, ⟨m̂ⁿ, Q̂⟩, ⟨m̂ⁿ, R̂⟩.
    pub curvature: [f64; 3],
}

impl CoupleSums {
    /// The sums of two parts of the spectrum together.
    fn add(self, o: Self) -> Self {
        CoupleSums {
            area: std::array::from_fn(|j| self.area[j] + o.area[j]),
            curvature: std::array::from_fn(|j| self.curvature[j] + o.curvature[j]),
        }
    }
}

/// The spectra of a step with the area-difference term: φ̂, N̂ and m̂ of the current state
/// (level 1) and, with two levels, of the one before.
pub struct CoupleInputs<'a> {
    /// (φ̂, N̂, m̂) per level of history, the current state first.
    pub levels: Vec<[&'a [f64]; 3]>,
}

/// P̂, Q̂, R̂ of `u` at one mode (the first `width` reals of each) from the inputs at real `i`,
/// with the update's own factors ([`Update::at`]): R̂ = −|k|² Σ_j n_j m̂_j.
fn update_at(u: &Update, inputs: &CoupleInputs, i: usize, k: f64, width: usize) -> [[f64; 2]; 3] {
    let f = u.at::<MAX_LEVELS>(k);
    let mut out = [[0.0; 2]; 3];
    for (j, [h, n, m]) in inputs.levels.iter().enumerate() {
        for c in 0..width {
            out[0][c] += f.h[j] * h[i + c] + f.n[j] * n[i + c];
            out[1][c] += f.q[j] * h[i + c];
            out[2][c] -= k * f.n[j] * m[i + c];
        }
    }
    out
}

/// The [`CoupleSums`] of the update `u` from `inputs`, task by task in parallel, the tasks'
/// sums added in a fixed tree (the same bits on any number of threads).
pub fn couple_sums(sym: &Symbols, u: &Update, inputs: &CoupleInputs, total: usize) -> CoupleSums {
    let tasks = (0..total.div_ceil(sym.task_reals())).into_par_iter();
    let partials = tasks.map(|t| couple_sums_of_task(sym, u, inputs, total, t));
    sum_in_fixed_tree(partials, CoupleSums::default, CoupleSums::add)
}

/// [`couple_sums`] over the modes of task `t`.
fn couple_sums_of_task(
    sym: &Symbols,
    u: &Update,
    inputs: &CoupleInputs,
    total: usize,
    t: usize,
) -> CoupleSums {
    let width = sym.width;
    let [h0, _, m0] = inputs.levels[0];
    let mut s = CoupleSums::default();
    for_task_modes(sym, total, t, |i, k, w| {
        let [p, q, r] = update_at(u, inputs, i, k, width);
        let (p, q, r) = (&p[..width], &q[..width], &r[..width]);
        let aw = sym.area_prefactor * k * w;
        let pairs = [(p, p), (p, q), (q, q), (p, r), (q, r), (r, r)];
        for (acc, (a, b)) in s.area.iter_mut().zip(pairs) {
            *acc += aw * dot(a, b);
        }
        let (m, h) = (at(m0, i, width), at(h0, i, width));
        s.curvature[0] += w * (dot(m, p) - dot(m, h));
        s.curvature[1] += w * dot(m, q);
        s.curvature[2] += w * dot(m, r);
    });
    s
}

/// Add λR̂ of `u` to the written φ̂^{n+1} (`hat`) and rewrite the evaluation's inverse inputs
/// (`copy` = φ̂^{n+1}, `lap` = −|k|²φ̂^{n+1}); returns the new A(φ̂^{n+1}). Task by task in
/// parallel, the tasks' areas added in a fixed tree.
pub fn add_couple(
    sym: &Symbols,
    u: &Update,
    inputs: &CoupleInputs,
    lambda: f64,
    [hat, copy, lap]: [&mut [f64]; 3],
) -> f64 {
    let (width, task, total) = (sym.width, sym.task_reals(), hat.len());
    let chunks = hat
        .par_chunks_mut(task)
        .zip(copy.par_chunks_mut(task))
        .zip(lap.par_chunks_mut(task))
        .enumerate();
    let partials = chunks.map(|(t, ((hat, copy), lap))| {
        let mut area = 0.0;
        for_task_modes(sym, total, t, |i, k, w| {
            let [_, _, r] = update_at(u, inputs, i, k, width);
            let j = i - t * task;
            for c in 0..width {
                let v = hat[j + c] + lambda * r[c];
                hat[j + c] = v;
                copy[j + c] = v;
                lap[j + c] = -(v * k);
                area += sym.area_prefactor * k * w * v * v;
            }
        });
        area
    });
    sum_in_fixed_tree(partials, || 0.0, |a, b| a + b)
}
