//! Evaluation of a state from its spectrum φ̂: φ, ∇²φ, Φ, F_sc, A, V and the explicit term,
//! with two inverse and two forward real transforms (planned once, no allocation per call).

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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExplicitTerm {
    /// The conserved flow's explicit part N̂ = −2|k|² FT[f'Φ] − 2ε²|k|⁴ FT[f].
    ConservedRhs,
    /// The full gradient ĝ = FT[δF_sc/δφ] = 2 FT[f'Φ] + 2ε²|k|² FT[f] + 2ε⁴|k|⁴ φ̂.
    Gradient,
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
}

/// Per-wavenumber tables.
pub struct Symbols {
    /// |k|² (or the FD symbol).
    pub k2: Vec<f64>,
    /// Parseval weight × cell volume: ∫ u v dx = Σ_k weight Re(û v̂*). Kept only for the
    /// gradient (relaxational) evaluator; empty for the conserved one, which needs no inner
    /// products (half a value per grid point saved).
    pub weight: Vec<f64>,
    /// (3/(2√2)) ε |k|² × weight: A = Σ_k area_weight |φ̂|².
    pub area_weight: Vec<f64>,
}

/// Evaluates a state from its φ̂: the transforms, tables and scratch, planned once.
pub struct Evaluator {
    pub grid: Grid,
    pub eps: f64,
    pub c0: C0,
    pub transform: Transform,
    pub symbols: Symbols,
    explicit: ExplicitTerm,
    /// Spectral scratch (the engines also use it between evaluations).
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
            symbols: symbols(
                &transform,
                &grid,
                eps,
                laplacian,
                explicit == ExplicitTerm::Gradient,
            ),
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
        }
    }

    /// From `state.hat`, compute φ, ∇²φ, Φ, F_sc, A, V and N̂ at time `t`
    /// (two inverse and two forward transforms).
    ///
    /// With `previous` (the state before a step) it also returns max|φ − φ_previous|, fused into
    /// the pointwise pass; otherwise 0. With `sigma` it also sets `state.residual`, the RMS of
    /// μ − μ̄ over the full box by Parseval, fused into the last spectral pass:
    /// μ̂ = 2 FT[f'Φ] + 2ε²k² FT[f] + 2ε⁴k⁴ φ̂ + (3/√2) ε σ k² φ̂ (k ≠ 0).
    pub fn evaluate(
        &mut self,
        state: &mut State,
        t: f64,
        previous: Option<&Array3<f64>>,
        sigma: Option<f64>,
    ) -> Result<f64, Diverged> {
        self.transform.hermitian_symmetrize(&mut state.hat);
        // φ = IFT[φ̂]
        self.spare.assign(&state.hat);
        self.transform.inverse(&mut self.spare, &mut state.phi);
        // ∇²φ = IFT[−k² φ̂], and A = Σ area_weight |φ̂|² in the same pass.
        let (k2, aw) = (&self.symbols.k2, &self.symbols.area_weight);
        let hat = state.hat.as_slice().expect("standard layout");
        let c = PAR_CHUNK;
        let area: f64 = self
            .spare
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(c)
            .zip(hat.par_chunks(c))
            .zip(k2.par_chunks(c))
            .zip(aw.par_chunks(c))
            .map(|(((s, h), k), w)| {
                let mut a = 0.0;
                for (((s, h), k), w) in s.iter_mut().zip(h).zip(k).zip(w) {
                    *s = h * (-k);
                    a += w * h.norm_sqr();
                }
                a
            })
            .sum();
        self.transform.inverse(&mut self.spare, &mut self.work);
        // Φ = f − ε²∇²φ, F = ∫Φ²; work ← f, work2 ← f'Φ
        let r = self.c0.ramp(t);
        let e2 = self.eps * self.eps;
        let (uniform, field) = self.c0.parts(r);
        let phi = state.phi.as_slice().expect("standard layout");
        let old = previous.map_or(phi, |p| p.as_slice().expect("standard layout"));
        let c = PAR_CHUNK;
        // Per point: f, Φ = f − ε²∇²φ, f'Φ; sums Φ², max|φ|, Σφ, max|φ − φ_old|.
        let body = |p: f64, ec0: f64, lap: &mut f64, fphi: &mut f64, o: f64| {
            let f = bulk(p, ec0);
            let big = f - e2 * *lap;
            *lap = f;
            *fphi = bulk_derivative(p, ec0) * big;
            (big * big, p.abs(), p, (p - o).abs())
        };
        let add = |a: (f64, f64, f64, f64), b: (f64, f64, f64, f64)| {
            (a.0 + b.0, a.1.max(b.1), a.2 + b.2, a.3.max(b.3))
        };
        let zero = (0.0, 0.0, 0.0, 0.0);
        let (energy, max_abs, sum_phi, change) = self
            .work
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(c)
            .zip(
                self.work2
                    .as_slice_mut()
                    .expect("standard layout")
                    .par_chunks_mut(c),
            )
            .enumerate()
            .map(|(j, (w, w2))| {
                let range = j * c..j * c + w.len();
                let points = phi[range.clone()]
                    .iter()
                    .zip(&old[range.clone()])
                    .zip(w.iter_mut())
                    .zip(w2.iter_mut());
                match field {
                    Some(ec0) => points
                        .zip(&ec0[range])
                        .map(|((((&p, &o), lap), fphi), &e)| body(p, r * e, lap, fphi, o))
                        .fold(zero, add),
                    None => points
                        .map(|(((&p, &o), lap), fphi)| body(p, uniform, lap, fphi, o))
                        .fold(zero, add),
                }
            })
            .reduce(|| zero, add);
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        state.measures = Measures {
            energy: energy * dv,
            area,
            // V = Σ (1 + φ)/2 h^d
            volume: 0.5 * (phi.len() as f64 + sum_phi) * dv,
        };
        if model::diverged(max_abs, state.measures.energy) {
            return Err(Diverged(format!(
                "max|φ| = {max_abs:.3e}, F = {:.3e}: the state diverged",
                state.measures.energy
            )));
        }
        self.transform.forward(&self.work2, &mut state.nonlinear);
        self.transform.forward(&self.work, &mut self.spare);
        let explicit = self.explicit;
        let with_residual = sigma.is_some();
        let tension = AREA_PREFACTOR * 2.0 * self.eps * sigma.unwrap_or(0.0);
        // 1/weight = (3/(2√2)) ε k² / area_weight, so w|μ̂|² = area_weight |μ̂|² / ((3/(2√2)) ε k²).
        let per_weight = AREA_PREFACTOR * self.eps;
        // N̂ (or ĝ) from FT[f'Φ] (in n), FT[f] (g) and φ̂ (h); returns w|μ̂|² (0 at k = 0).
        let combine = |n: &mut Complex64, g: Complex64, h: Complex64, k: f64, aw: f64| {
            let gradient = *n * 2.0 + g * (2.0 * e2 * k) + h * (2.0 * e2 * e2 * k * k);
            *n = match explicit {
                // N̂ = −2k² FT[f'Φ] − 2ε²k⁴ FT[f]
                ExplicitTerm::ConservedRhs => *n * (-2.0 * k) + g * (-2.0 * e2 * k * k),
                // ĝ = 2 FT[f'Φ] + 2ε²k² FT[f] + 2ε⁴k⁴ φ̂
                ExplicitTerm::Gradient => gradient,
            };
            if with_residual && k > 0.0 {
                (gradient + h * (tension * k)).norm_sqr() * aw / (per_weight * k)
            } else {
                0.0
            }
        };
        let hat = state.hat.as_slice().expect("standard layout");
        let weighted_sq: f64 = state
            .nonlinear
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(c)
            .zip(
                self.spare
                    .as_slice()
                    .expect("standard layout")
                    .par_chunks(c),
            )
            .zip(hat.par_chunks(c))
            .zip(self.symbols.k2.par_chunks(c))
            .zip(self.symbols.area_weight.par_chunks(c))
            .map(|((((n, g), h), k), aw)| {
                let mut sum = 0.0;
                for ((((n, &g), &h), &k), &aw) in n.iter_mut().zip(g).zip(h).zip(k).zip(aw) {
                    sum += combine(n, g, h, k, aw);
                }
                sum
            })
            .sum();
        state.residual = match sigma {
            Some(_) => (weighted_sq / self.grid.full_volume()).sqrt(),
            None => f64::NAN,
        };
        Ok(change)
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
pub fn symbols(
    t: &Transform,
    grid: &Grid,
    eps: f64,
    laplacian: Laplacian,
    keep_weight: bool,
) -> Symbols {
    let k = t.wavenumbers(grid.h).map(|ks| {
        ks.iter()
            .map(|&k| axis_symbol(k, grid.h, laplacian))
            .collect::<Vec<f64>>()
    });
    let w = t.parseval_weights();
    let [s0, s1, s2] = t.spectral_shape();
    let mut k2 = Vec::with_capacity(s0 * s1 * s2);
    let mut area_weight = Vec::with_capacity(s0 * s1 * s2);
    let mut weight = Vec::with_capacity(if keep_weight { s0 * s1 * s2 } else { 0 });
    let dv = grid.cell_volume() * grid.mirror_factor();
    for i in 0..s0 {
        for j in 0..s1 {
            for l in 0..s2 {
                let kk = k[0][i] + k[1][j] + k[2][l];
                k2.push(kk);
                let wt = dv * w[0][i] * w[1][j] * w[2][l];
                if keep_weight {
                    weight.push(wt);
                }
                area_weight.push(AREA_PREFACTOR * eps * kk * wt);
            }
        }
    }
    Symbols {
        k2,
        weight,
        area_weight,
    }
}
