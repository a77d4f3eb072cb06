//! Evaluation of a state from its spectrum φ̂: φ, ∇²φ, Φ, F_sc, A, V and the explicit term,
//! with two inverse and two forward real transforms (planned once, no allocation per call).
//!
//! An evaluation is three sweeps besides the transforms: a spectral one that prepares the two
//! inverse transforms' inputs (φ̂ and −k²φ̂) and sums A, one over real space (f, f'Φ and the
//! sums of F, V, max|φ|), and a spectral one that combines the forward transforms into the
//! explicit term and sums the residual (and, for the relaxational engine's gradient, the area
//! multiplier's two sums in its metric). |k|² and the Parseval weights come from per-axis
//! tables ([`Symbols`]), not from full-size arrays. An engine that can write the two inverse
//! inputs itself, in the sweep that makes φ̂ (as the time step does), skips the first sweep
//! ([`Evaluator::finish`]).

use super::transform::Transform;
use crate::config::Laplacian;
use crate::engine::Diverged;
use crate::grid::Grid;
use crate::model::{self, bulk, bulk_derivative, Measures, AREA_PREFACTOR, C0};
use crate::numerics::PAR_CHUNK;
use ndarray::Array3;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

/// Which explicit term [`Evaluator::evaluate`] leaves in `State::nonlinear`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExplicitTerm {
    /// The conserved flow's explicit part N̂ = −2|k|² FT[f'Φ] − 2ε²|k|⁴ FT[f].
    ConservedRhs,
    /// The full gradient ĝ = FT[δF_sc/δφ] = 2 FT[f'Φ] + 2ε²|k|² FT[f] + 2ε⁴|k|⁴ φ̂, with the
    /// area multiplier's sums in the metric given (`State::multiplier_sums`).
    Gradient(Metric),
}

/// The relaxational engine's metric ⟨u, v⟩_M = Σ_k w M(k) Re(û v̂*) (DESIGN.md §7), M(k) =
/// 2ε⁴k⁴ + 8 + 8ε²k² (the Hessian of F_sc in the bulk), and the area gradient's preconditioned
/// direction q = M⁻¹â = (c_σ|k|²/M) φ̂, c_σ = 3ε/√2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metric {
    /// ε².
    pub e2: f64,
    /// c_σ = 3ε/√2 (â = c_σ |k|² φ̂).
    pub c_sigma: f64,
}

impl Metric {
    /// The metric for interface width `eps`.
    pub fn new(eps: f64) -> Self {
        Metric {
            e2: eps * eps,
            c_sigma: 3.0 / std::f64::consts::SQRT_2 * eps,
        }
    }

    /// M(k) = 2ε⁴k⁴ + 8 + 8ε²k² at |k|² = `k`.
    #[inline(always)]
    pub fn at(&self, k: f64) -> f64 {
        2.0 * self.e2 * self.e2 * k * k + 8.0 + 8.0 * self.e2 * k
    }
}

/// A state of the engine: φ in both spaces, its explicit term N̂ and its measures.
pub struct State {
    pub hat: Array3<Complex64>,
    pub nonlinear: Array3<Complex64>,
    pub phi: Array3<f64>,
    pub measures: Measures,
    /// RMS over the full box of μ − μ̄ at the σ given to [`Evaluator::evaluate`] (NaN when none
    /// was given).
    pub residual: f64,
    /// With [`ExplicitTerm::Gradient`]: (⟨q, q⟩_M, ⟨ĝ, q⟩), q = M⁻¹â, whose ratio is the area
    /// multiplier that makes M⁻¹(ĝ + σâ) tangent to A = A0 (zeros otherwise).
    pub multiplier_sums: (f64, f64),
}

/// Per-axis tables of the spectrum. At spectral index (i0, i1, i2)
///
/// ```text
/// |k|² = k2[0][i0] + k2[1][i1] + k2[2][i2],     w = weight[0][i0] · weight[1][i1] · weight[2][i2],
/// ```
///
/// with w the Parseval weight times the cell volume (and mirror factor, folded into axis 0), so
/// that ∫ u v dx = Σ_k w Re(û v̂*) over the full box, and A = Σ_k (3/(2√2)) ε |k|² w |φ̂|².
/// Passes walk the spectrum row by row (a row is the last axis): a row's first two terms are
/// taken once ([`Symbols::row`]) and the loop along the row reads the two short last-axis tables.
pub struct Symbols {
    /// |k|² per axis (or the FD symbol, see [`axis_symbol`]).
    pub k2: [Vec<f64>; 3],
    /// Parseval weight per axis, cell volume × mirror factor folded into axis 0.
    pub weight: [Vec<f64>; 3],
    /// (3/(2√2)) ε.
    pub area_prefactor: f64,
}

impl Symbols {
    /// The tables of transform `t` on `grid`.
    pub fn new(t: &Transform, grid: &Grid, eps: f64, laplacian: Laplacian) -> Self {
        let k2 = t.wavenumbers(grid.h).map(|ks| {
            ks.iter()
                .map(|&k| axis_symbol(k, grid.h, laplacian))
                .collect::<Vec<f64>>()
        });
        let mut weight = t.parseval_weights();
        let dv = grid.cell_volume() * grid.mirror_factor();
        weight[0].iter_mut().for_each(|w| *w *= dv);
        Symbols {
            k2,
            weight,
            area_prefactor: AREA_PREFACTOR * eps,
        }
    }

    /// Length of a spectral row (the last axis).
    pub fn row_len(&self) -> usize {
        self.k2[2].len()
    }

    /// Spectral values per parallel task: a whole number of rows.
    pub fn task_len(&self) -> usize {
        (PAR_CHUNK / self.row_len()).max(1) * self.row_len()
    }

    /// Axes 0 and 1's share of |k|² and of w on spectral row `r` (`i0 = r / s1`, `i1 = r % s1`).
    #[inline]
    pub fn row(&self, r: usize) -> (f64, f64) {
        let s1 = self.k2[1].len();
        let (i0, i1) = (r / s1, r % s1);
        (
            self.k2[0][i0] + self.k2[1][i1],
            self.weight[0][i0] * self.weight[1][i1],
        )
    }
}

/// Evaluates a state from its φ̂: the transforms, tables and scratch, planned once.
pub struct Evaluator {
    pub grid: Grid,
    pub eps: f64,
    pub c0: C0,
    pub transform: Transform,
    pub symbols: Symbols,
    explicit: ExplicitTerm,
    /// Spectral scratch: the input of the ∇²φ inverse transform, then FT[f] (the engines also
    /// use it between evaluations).
    pub spare: Array3<Complex64>,
    /// Real scratch: ∇²φ, then f.
    work: Array3<f64>,
    /// Real scratch: f'Φ.
    work2: Array3<f64>,
}

impl Evaluator {
    /// Plan the transforms and tables for `grid`.
    pub fn new(grid: Grid, eps: f64, c0: C0, laplacian: Laplacian, explicit: ExplicitTerm) -> Self {
        let transform = Transform::new(grid.shape, grid.kinds, rayon::current_num_threads());
        Evaluator {
            symbols: Symbols::new(&transform, &grid, eps, laplacian),
            spare: Array3::zeros(transform.spectral_shape()),
            work: grid.zeros(),
            work2: grid.zeros(),
            explicit,
            eps,
            c0,
            transform,
            grid,
        }
    }

    /// The state holding the real field `phi`, evaluated at time `t`.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn state_of(&mut self, phi: &Array3<f64>, t: f64) -> Result<State, Diverged> {
        let mut s = self.blank();
        self.transform.forward(phi, &mut s.hat);
        self.evaluate(&mut s, t, None, Some(0.0))?;
        Ok(s)
    }

    /// A state of the right shapes, all zeros.
    pub fn blank(&self) -> State {
        State {
            hat: Array3::zeros(self.transform.spectral_shape()),
            nonlinear: Array3::zeros(self.transform.spectral_shape()),
            phi: self.grid.zeros(),
            measures: Measures::default(),
            residual: f64::NAN,
            multiplier_sums: (0.0, 0.0),
        }
    }

    /// From `state.hat` (first projected onto the spectra of real fields), compute φ, ∇²φ, Φ,
    /// F_sc, A, V and the explicit term at time `t`; see [`Evaluator::finish`] for `previous`
    /// and `sigma`.
    pub fn evaluate(
        &mut self,
        state: &mut State,
        t: f64,
        previous: Option<&Array3<f64>>,
        sigma: Option<f64>,
    ) -> Result<f64, Diverged> {
        self.transform.hermitian_symmetrize(&mut state.hat);
        let area = inverse_inputs(
            &self.symbols,
            state.hat.as_slice().expect("standard layout"),
            state.nonlinear.as_slice_mut().expect("standard layout"),
            self.spare.as_slice_mut().expect("standard layout"),
        );
        self.finish(state, area, t, previous, sigma)
    }

    /// The evaluation after its first sweep: `state.hat` holds φ̂ (a real field's spectrum),
    /// `state.nonlinear` a copy of it, `self.spare` −|k|²φ̂, and `area` = A(φ̂) (what
    /// [`inverse_inputs`] writes and returns). Computes φ, ∇²φ, Φ, F_sc, A, V and the explicit
    /// term at time `t` (two inverse and two forward transforms).
    ///
    /// With `previous` (the state before a step) it also returns max|φ − φ_previous|, fused into
    /// the pointwise pass; otherwise 0. With `sigma` it also sets `state.residual`, the RMS of
    /// μ − μ̄ over the full box by Parseval, fused into the last spectral pass:
    /// μ̂ = 2 FT[f'Φ] + 2ε²k² FT[f] + 2ε⁴k⁴ φ̂ + (3/√2) ε σ k² φ̂ (k ≠ 0).
    ///
    /// # Errors
    /// [`Diverged`] if φ is not finite or too large.
    pub fn finish(
        &mut self,
        state: &mut State,
        area: f64,
        t: f64,
        previous: Option<&Array3<f64>>,
        sigma: Option<f64>,
    ) -> Result<f64, Diverged> {
        self.transform.inverse(&mut state.nonlinear, &mut state.phi);
        self.transform.inverse(&mut self.spare, &mut self.work);
        let r = self.c0.ramp(t);
        let (uniform, field) = self.c0.parts(r);
        let phi = state.phi.as_slice().expect("standard layout");
        let old = previous.map_or(phi, |p| p.as_slice().expect("standard layout"));
        let sums = pointwise(
            self.eps,
            phi,
            old,
            (uniform, field.map(|f| (r, f))),
            self.work.as_slice_mut().expect("standard layout"),
            self.work2.as_slice_mut().expect("standard layout"),
        );
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        state.measures = Measures {
            energy: sums.phi_sq * dv,
            area,
            // V = Σ (1 + φ)/2 h^d
            volume: 0.5 * (phi.len() as f64 + sums.phi) * dv,
        };
        if model::diverged(sums.max_abs, state.measures.energy) {
            return Err(Diverged(format!(
                "max|φ| = {:.3e}, F = {:.3e}: the state diverged",
                sums.max_abs, state.measures.energy
            )));
        }
        self.transform.forward(&self.work2, &mut state.nonlinear);
        self.transform.forward(&self.work, &mut self.spare);
        let combined = combine(
            &self.symbols,
            self.eps,
            self.explicit,
            sigma,
            state.hat.as_slice().expect("standard layout"),
            self.spare.as_slice().expect("standard layout"),
            state.nonlinear.as_slice_mut().expect("standard layout"),
        );
        self.transform.hermitian_symmetrize(&mut state.nonlinear);
        state.residual = match sigma {
            Some(_) => (combined.residual_sq / self.grid.full_volume()).sqrt(),
            None => f64::NAN,
        };
        state.multiplier_sums = (combined.qq, combined.gq);
        Ok(sums.change)
    }
}

/// The first sweep of an evaluation: `copy = φ̂` and `lap = −|k|²φ̂` (the inputs of the two
/// inverse transforms, which overwrite them); returns A = Σ_k (3/(2√2)) ε |k|² w |φ̂|².
fn inverse_inputs(
    sym: &Symbols,
    hat: &[Complex64],
    copy: &mut [Complex64],
    lap: &mut [Complex64],
) -> f64 {
    let (s2, task) = (sym.row_len(), sym.task_len());
    copy.par_chunks_mut(task)
        .zip(lap.par_chunks_mut(task))
        .zip(hat.par_chunks(task))
        .enumerate()
        .map(|(t, ((copy, lap), hat))| {
            let rows = copy
                .chunks_exact_mut(s2)
                .zip(lap.chunks_exact_mut(s2))
                .zip(hat.chunks_exact(s2));
            let mut area = 0.0;
            for (r, ((copy, lap), hat)) in rows.enumerate() {
                let (kb, wb) = sym.row(t * task / s2 + r);
                let cols = copy.iter_mut().zip(lap.iter_mut()).zip(hat);
                for (((c, l), &h), (&kl, &wl)) in cols.zip(sym.k2[2].iter().zip(&sym.weight[2])) {
                    let k = kb + kl;
                    *c = h;
                    *l = h * (-k);
                    area += sym.area_prefactor * k * (wb * wl) * h.norm_sqr();
                }
            }
            area
        })
        .sum()
}

/// Sums of the pointwise pass.
struct PointSums {
    /// Σ Φ².
    phi_sq: f64,
    /// Σ φ.
    phi: f64,
    /// max |φ|.
    max_abs: f64,
    /// max |φ − φ_old|.
    change: f64,
}

/// The real-space sweep: with `lap` = ∇²φ on entry, Φ = f(φ) − ε²∇²φ, `lap ← f(φ)` and
/// `fphi ← f'(φ) Φ`, with εC0 = `uniform` or r × the field; returns Σ Φ², Σ φ, max|φ| and
/// max|φ − φ_old|.
fn pointwise(
    eps: f64,
    phi: &[f64],
    old: &[f64],
    (uniform, field): (f64, Option<(f64, &[f64])>),
    lap: &mut [f64],
    fphi: &mut [f64],
) -> PointSums {
    let e2 = eps * eps;
    let body = |p: f64, ec0: f64, o: f64, lap: &mut f64, fphi: &mut f64, acc: &mut PointSums| {
        let f = bulk(p, ec0);
        let big = f - e2 * *lap;
        *lap = f;
        *fphi = bulk_derivative(p, ec0) * big;
        acc.phi_sq += big * big;
        acc.phi += p;
        acc.max_abs = acc.max_abs.max(p.abs());
        acc.change = acc.change.max((p - o).abs());
    };
    let c = PAR_CHUNK;
    lap.par_chunks_mut(c)
        .zip(fphi.par_chunks_mut(c))
        .enumerate()
        .map(|(j, (lap, fphi))| {
            let range = j * c..j * c + lap.len();
            let mut acc = PointSums {
                phi_sq: 0.0,
                phi: 0.0,
                max_abs: 0.0,
                change: 0.0,
            };
            let points = phi[range.clone()]
                .iter()
                .zip(&old[range.clone()])
                .zip(lap.iter_mut().zip(fphi.iter_mut()));
            match field {
                Some((r, ec0)) => {
                    for (((&p, &o), (l, f)), &e) in points.zip(&ec0[range]) {
                        body(p, r * e, o, l, f, &mut acc);
                    }
                }
                None => {
                    for ((&p, &o), (l, f)) in points {
                        body(p, uniform, o, l, f, &mut acc);
                    }
                }
            }
            acc
        })
        .reduce(
            || PointSums {
                phi_sq: 0.0,
                phi: 0.0,
                max_abs: 0.0,
                change: 0.0,
            },
            |a, b| PointSums {
                phi_sq: a.phi_sq + b.phi_sq,
                phi: a.phi + b.phi,
                max_abs: a.max_abs.max(b.max_abs),
                change: a.change.max(b.change),
            },
        )
}

/// The sums of [`combine`].
#[derive(Clone, Copy, Default)]
struct CombineSums {
    /// Σ_{k≠0} w |μ̂|².
    residual_sq: f64,
    /// ⟨q, q⟩_M = Σ w M |q̂|², q̂ = (c_σ k²/M) φ̂.
    qq: f64,
    /// ⟨ĝ, q⟩ = Σ w Re(ĝ q̂*).
    gq: f64,
}

impl CombineSums {
    fn add(self, o: Self) -> Self {
        CombineSums {
            residual_sq: self.residual_sq + o.residual_sq,
            qq: self.qq + o.qq,
            gq: self.gq + o.gq,
        }
    }
}

/// The last spectral sweep: from FT[f'Φ] (in `n`), FT[f] (`g`) and φ̂ (`h`) write the explicit
/// term into `n`: N̂ = −2k² FT[f'Φ] − 2ε²k⁴ FT[f] (conserved) or ĝ = 2 FT[f'Φ] + 2ε²k² FT[f] +
/// 2ε⁴k⁴ φ̂ (gradient, with the multiplier's sums ⟨q, q⟩_M and ⟨ĝ, q⟩ in its metric). With
/// `sigma` it also sums Σ_{k≠0} w |μ̂|², μ̂ = ĝ + (3/√2) ε σ k² φ̂.
fn combine(
    sym: &Symbols,
    eps: f64,
    explicit: ExplicitTerm,
    sigma: Option<f64>,
    h: &[Complex64],
    g: &[Complex64],
    n: &mut [Complex64],
) -> CombineSums {
    let e2 = eps * eps;
    let with_residual = sigma.is_some();
    let tension = 2.0 * sym.area_prefactor * sigma.unwrap_or(0.0);
    let (s2, task) = (sym.row_len(), sym.task_len());
    n.par_chunks_mut(task)
        .zip(g.par_chunks(task))
        .zip(h.par_chunks(task))
        .enumerate()
        .map(|(t, ((n, g), h))| {
            let rows = n
                .chunks_exact_mut(s2)
                .zip(g.chunks_exact(s2))
                .zip(h.chunks_exact(s2));
            let mut sums = CombineSums::default();
            for (r, ((n, g), h)) in rows.enumerate() {
                let (kb, wb) = sym.row(t * task / s2 + r);
                let cols = n.iter_mut().zip(g).zip(h);
                for (((n, &g), &h), (&kl, &wl)) in cols.zip(sym.k2[2].iter().zip(&sym.weight[2])) {
                    let k = kb + kl;
                    let w = wb * wl;
                    let gradient = *n * 2.0 + g * (2.0 * e2 * k) + h * (2.0 * e2 * e2 * k * k);
                    *n = match explicit {
                        ExplicitTerm::ConservedRhs => *n * (-2.0 * k) + g * (-2.0 * e2 * k * k),
                        ExplicitTerm::Gradient(m) => {
                            // w M |q̂|² = w c_σ k (c_σ k/M) |φ̂|².
                            let q_over_h = m.c_sigma * k / m.at(k);
                            sums.qq += w * m.c_sigma * k * q_over_h * h.norm_sqr();
                            sums.gq += w * q_over_h * (gradient.re * h.re + gradient.im * h.im);
                            gradient
                        }
                    };
                    if with_residual && k > 0.0 {
                        sums.residual_sq += w * (gradient + h * (tension * k)).norm_sqr();
                    }
                }
            }
            sums
        })
        .reduce(CombineSums::default, CombineSums::add)
}

/// One axis's share of the Laplacian's symbol: k² (spectral) or (4/h²) sin²(kh/2) (the
/// second-order stencil, diagonal in the same Fourier/cosine basis).
pub fn axis_symbol(k: f64, h: f64, laplacian: Laplacian) -> f64 {
    match laplacian {
        Laplacian::Spectral => k * k,
        Laplacian::Fd => (2.0 / h * (0.5 * k * h).sin()).powi(2),
    }
}
