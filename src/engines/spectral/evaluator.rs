//! Evaluation of a state from its spectrum φ̂: φ, ∇²φ, Φ, F_sc, A, V and the explicit term,
//! with two inverse and two forward real transforms (planned once, no allocation per call).
//!
//! An evaluation is three sweeps besides the transforms: a spectral one that prepares the two
//! inverse transforms' inputs (φ̂ and −k²φ̂) and sums A, one over real space (f, f'Φ and the
//! sums of F, V, max|φ|), and a spectral one that combines the forward transforms into the
//! explicit term and sums the residual (and, for the relaxational engine's gradient, the area
//! multiplier's two sums in its metric). The real-space sweep runs slab by slab between the
//! transforms' slab stages ([`Transform::round_trip`]), so that ∇²φ, f and f'Φ live in a slab
//! of cache and only φ reaches memory; a box with fewer slabs than threads (2D) takes the
//! transforms one at a time over full arrays instead. |k|² and the Parseval weights come from
//! per-axis tables ([`Symbols`]), not from full-size arrays. An engine that can write the two inverse
//! inputs itself, in the sweep that makes φ̂ (as the time step does), skips the first sweep
//! ([`Evaluator::finish`]).

use super::curvature::CurvatureScratch;
use super::flow::{Flow, FlowStats};
use super::inextensible::Inextensibility;
use super::kernels::{pointwise_sums, sum, wide_fn};
use super::pieces::{for_each_piece, mode, per_width, re_dot, reals, reals_mut, Piece, PIECE};
use super::transform::Transform;
use crate::engines::numerics::{sum_in_fixed_tree, PAR_CHUNK};
use crate::engines::Diverged;
use crate::problem::area_difference::AreaDifference;
use crate::problem::config::{FlowSpec, Laplacian};
use crate::problem::grid::Grid;
use crate::problem::model::{
    self, bulk, bulk_at_zero_c0, bulk_derivative, bulk_derivative_at_zero_c0, Measures,
    AREA_PREFACTOR, C0,
};
use ndarray::Array3;
use num_complex::Complex64;
use rayon::prelude::*;

/// Which explicit term [`Evaluator::evaluate`] leaves in `State::nonlinear`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExplicitTerm {
    /// The conserved flow's explicit part N̂ = −2|k|² FT[f'Φ] − 2ε²|k|⁴ FT[f].
    ConservedRhs,
    /// The full gradient ĝ = FT[δF_sc/δφ] = 2 FT[f'Φ] + 2ε²|k|² FT[f] + 2ε⁴|k|⁴ φ̂, with the
    /// area multiplier's sums in the metric given (`State::multiplier_sums`).
    Gradient(Metric),
}

/// The relaxational engine's metric ⟨u, v⟩_M = Σ_k w M(k) Re(û v̂*) (docs/src/theory/relaxation.md), M(k) =
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
    /// φ̂.
    pub hat: Array3<Complex64>,
    /// The explicit term: N̂ (conserved flow) or ĝ (gradient).
    pub nonlinear: Array3<Complex64>,
    /// φ on the grid.
    pub phi: Array3<f64>,
    /// F_sc, A, V.
    pub measures: Measures,
    /// RMS over the full box of μ − μ̄ at the σ given to [`Evaluator::evaluate`] (NaN when none
    /// was given).
    pub residual: f64,
    /// With [`ExplicitTerm::Gradient`]: (⟨q, q⟩_M, ⟨ĝ, q⟩), q = M⁻¹â, whose ratio is the area
    /// multiplier that makes M⁻¹(ĝ + σâ) tangent to A = A0 (zeros otherwise).
    pub multiplier_sums: (f64, f64),
    /// The explicit spectrum of the step's second affine term ([`super::curvature`]): m̂ =
    /// FT[δM/δφ] of the area-difference term, or T̂ = FT[u_σ·∇φ] of the Stokes flow
    /// ([`super::flow`]; the two never together); empty without either.
    pub curvature_hat: Array3<Complex64>,
    /// What the Stokes flow of this state measured (zeros without a flow).
    pub flow: FlowStats,
}

/// Per-axis tables of the spectrum's modes ([`crate::engines::spectral::pieces`]). At mode (i0, i1, i2)
///
/// ```text
/// |k|² = k2[0][i0] + k2[1][i1] + k2[2][i2],     w = weight[0][i0] · weight[1][i1] · weight[2][i2],
/// ```
///
/// with w the Parseval weight times the cell volume (and mirror factor, folded into axis 0), so
/// that ∫ u v dx = Σ_k w Re(û v̂*) over the full box, and A = Σ_k (3/(2√2)) ε |k|² w |φ̂|².
/// Passes walk the spectrum row by row (a row is the last axis): a row's first two terms are
/// taken once ([`Symbols::row`]) and the loop along the row reads the two short last-axis tables.
/// A packed spectrum's row holds a mode per real, so its last-axis tables are the index's, with
/// an odd length padded by a mode of w = 0 and |k|² = 0 (its real is 0 and stays 0).
pub struct Symbols {
    /// |k|² per axis (or the FD symbol, see [`axis_symbol`]).
    pub k2: [Vec<f64>; 3],
    /// Parseval weight per axis, cell volume × mirror factor folded into axis 0.
    pub weight: [Vec<f64>; 3],
    /// (3/(2√2)) ε.
    pub area_prefactor: f64,
    /// Reals per mode: 2 (complex values), or 1 ([packed](Transform::packed) spectra).
    pub width: usize,
}

impl Symbols {
    /// The tables of transform `t` on `grid`.
    pub fn new(t: &Transform, grid: &Grid, eps: f64, laplacian: Laplacian) -> Self {
        let mut k2 = t.wavenumbers(grid.h).map(|ks| {
            ks.iter()
                .map(|&k| axis_symbol(k, grid.h, laplacian))
                .collect::<Vec<f64>>()
        });
        let mut weight = t.parseval_weights();
        let dv = grid.cell_volume() * grid.mirror_factor();
        weight[0].iter_mut().for_each(|w| *w *= dv);
        if t.packed() && !k2[2].len().is_multiple_of(2) {
            k2[2].push(0.0);
            weight[2].push(0.0);
        }
        Symbols {
            k2,
            weight,
            area_prefactor: AREA_PREFACTOR * eps,
            width: if t.packed() { 1 } else { 2 },
        }
    }

    /// Modes in a spectral row (the last axis).
    pub fn row_len(&self) -> usize {
        self.k2[2].len()
    }

    /// Modes per parallel task: a whole number of rows.
    pub fn task_len(&self) -> usize {
        (PAR_CHUNK / self.row_len()).max(1) * self.row_len()
    }

    /// Reals per parallel task ([`Symbols::task_len`] modes).
    pub fn task_reals(&self) -> usize {
        self.width * self.task_len()
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
    /// The computed grid.
    pub grid: Grid,
    /// ε, the interface width.
    pub eps: f64,
    /// εC0(x, t).
    pub c0: C0,
    /// The planned transforms.
    pub transform: Transform,
    /// |k|² and the Parseval weights per axis.
    pub symbols: Symbols,
    pub(super) explicit: ExplicitTerm,
    /// The area-difference term's scratch, when the scene has one.
    pub(super) curvature: Option<CurvatureScratch>,
    /// The area-difference term at its reference area (the gradient's λ reads it).
    pub area_difference: Option<AreaDifference>,
    /// The Stokes dynamics' flow, whose advection the explicit term carries ([`super::flow`]).
    flow: Option<Flow>,
    /// Spectral scratch: the input of the ∇²φ inverse transform, then FT[f] (the engines also
    /// use it between evaluations).
    pub spare: Array3<Complex64>,
    /// Real scratch with the transforms apart ([`pointwise_apart`]): ∇²φ, then f.
    work: Array3<f64>,
    /// Real scratch with the transforms apart: f'Φ.
    work2: Array3<f64>,
    /// The pointwise sums of each slab of the fused round trip, added in slab order.
    slab_sums: Vec<PointSums>,
}

impl Evaluator {
    /// Plan the transforms and tables for `grid`, with scratch for `threads` workers.
    pub fn new(
        grid: Grid,
        eps: f64,
        c0: C0,
        laplacian: Laplacian,
        explicit: ExplicitTerm,
        threads: usize,
    ) -> Self {
        let transform = Transform::new(grid.shape, grid.kinds, threads);
        Evaluator {
            symbols: Symbols::new(&transform, &grid, eps, laplacian),
            spare: Array3::zeros(transform.spectral_shape()),
            work: grid.zeros(),
            work2: grid.zeros(),
            slab_sums: Vec::new(),
            explicit,
            curvature: None,
            area_difference: None,
            flow: None,
            eps,
            c0,
            transform,
            grid,
        }
    }

    /// The evaluator with the area-difference term's functional M and variation m̂ in every
    /// evaluation ([`super::curvature`]); its law is set later ([`Evaluator::area_difference`]).
    pub fn with_curvature(mut self) -> Self {
        self.curvature = Some(CurvatureScratch::new(&self));
        self
    }

    /// The evaluator with the Stokes flow `spec` in the explicit term ([`super::flow`]).
    pub fn with_flow(mut self, spec: FlowSpec) -> Self {
        self.flow = Some(Flow::new(spec, &self.transform, &self.grid));
        self
    }

    /// The inextensible membrane's tension solve, if the evaluator's flow has one.
    pub fn inextensibility(&mut self) -> Option<&mut Inextensibility> {
        self.flow.as_mut().and_then(Flow::inextensibility)
    }

    /// The same, read only.
    pub fn inextensibility_ref(&self) -> Option<&Inextensibility> {
        self.flow.as_ref().and_then(Flow::inextensibility_ref)
    }

    /// Whether the explicit term carries the Stokes flow's advection.
    pub fn has_flow(&self) -> bool {
        self.flow.is_some()
    }

    /// The evaluator's flow at the fixed tension `sigma` ([`Flow::at_fixed_tension`]): no T̂.
    ///
    /// # Panics
    /// Without a flow.
    pub fn with_fixed_tension(mut self, sigma: f64) -> Self {
        let flow = self.flow.take().expect("a flow");
        self.flow = Some(flow.at_fixed_tension(sigma));
        self
    }

    /// Whether the explicit term carries a Stokes flow split in σ ([`Flow::splits_tension`]):
    /// the state's second spectrum is then the flow's advection per unit σ, T̂.
    pub fn splits_flow(&self) -> bool {
        self.flow.as_ref().is_some_and(Flow::splits_tension)
    }

    /// Whether a state carries the spectrum of a second affine term (`State::curvature_hat`):
    /// the area-difference term's m̂ or the Stokes flow's T̂ (not at a fixed tension).
    pub fn has_second_term(&self) -> bool {
        self.curvature.is_some() || self.splits_flow()
    }

    /// The state holding the real field `phi`, evaluated at time `t` with multiplier 0.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn state_of(&mut self, phi: &Array3<f64>, t: f64) -> Result<State, Diverged> {
        self.state_at(phi, t, 0.0)
    }

    /// The state holding the real field `phi`, evaluated at time `t` with multiplier `sigma`.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn state_at(&mut self, phi: &Array3<f64>, t: f64, sigma: f64) -> Result<State, Diverged> {
        let mut s = self.blank();
        // The state's own real field is the forward transform's scratch (the evaluation
        // rewrites it), so a 3D run never touches the pages of `work`.
        s.phi.assign(phi);
        self.transform.forward(&mut s.phi, &mut s.hat);
        self.evaluate(&mut s, t, None, Some(sigma))?;
        Ok(s)
    }

    /// The Stokes velocity of the real field `phi` at multiplier `sigma` ([`Flow::velocity`]):
    /// one field per component along the box's axes longer than 1; `None` without a flow.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn velocity_at(
        &mut self,
        phi: &Array3<f64>,
        sigma: f64,
    ) -> Result<Option<Vec<Array3<f64>>>, Diverged> {
        self.state_at(phi, 0.0, sigma)?;
        Ok(self
            .flow
            .as_mut()
            .map(|f| f.velocity(&mut self.transform, sigma)))
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
            curvature_hat: if self.has_second_term() {
                Array3::zeros(self.transform.spectral_shape())
            } else {
                Array3::zeros((0, 0, 0))
            },
            flow: FlowStats::default(),
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
        let r = self.c0.ramp(t);
        let (uniform, field) = self.c0.parts(r);
        let (eps, c0) = (self.eps, (uniform, field.map(|f| (r, f))));
        let previous = previous.map(|p| p.as_slice().expect("standard layout"));
        let spectra = [&mut state.nonlinear, &mut self.spare];
        // φ, ∇²φ → f, f'Φ slab by slab, or (fewer slabs than threads) a transform at a time.
        let fused = self.transform.round_trip(
            spectra,
            &mut state.phi,
            &mut self.slab_sums,
            |first, phi, lap, fphi| {
                let range = first..first + phi.len();
                let old = previous.map_or(phi, |p| &p[range.clone()]);
                pointwise_range(eps, phi, old, slice_c0(c0, range), lap, fphi)
            },
            PointSums::add,
        );
        let sums = match fused {
            Some(sums) => sums,
            None => pointwise_apart(
                &mut self.transform,
                [&mut state.nonlinear, &mut self.spare],
                &mut state.phi,
                [&mut self.work, &mut self.work2],
                (eps, previous, c0),
            ),
        };
        let phi = state.phi.as_slice().expect("standard layout");
        let dv = self.grid.cell_volume() * self.grid.mirror_factor();
        state.measures = Measures {
            energy: sums.phi_sq * dv,
            area,
            // V = Σ (1 + φ)/2 h^d
            volume: 0.5 * (phi.len() as f64 + sums.phi) * dv,
            curvature: 0.0,
        };
        if model::diverged(sums.max_abs, state.measures.energy) {
            return Err(Diverged(format!(
                "max|φ| = {:.3e}, F = {:.3e}: the state diverged",
                sums.max_abs, state.measures.energy
            )));
        }
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
        self.evaluate_curvature(state);
        self.add_curvature_gradient(state);
        if let Some(flow) = self.flow.as_mut() {
            let tension = (self.eps, sigma.unwrap_or(0.0));
            state.flow = flow.advect(
                &mut self.transform,
                &self.symbols,
                tension,
                (&state.hat, &state.phi),
                [&mut state.nonlinear, &mut state.curvature_hat],
            );
        }
        Ok(sums.change)
    }
}

/// [`Evaluator::finish`]'s round trip through real space a transform at a time (when
/// [`Transform::round_trip`] declines): φ (into `phi`) and ∇²φ into full arrays, the
/// real-space sweep over them in parallel chunks, and the forward transforms of f'Φ into the
/// first spectrum and of f into the second (`lap` holds ∇²φ, then f).
fn pointwise_apart(
    transform: &mut Transform,
    [first, second]: [&mut Array3<Complex64>; 2],
    phi: &mut Array3<f64>,
    [lap, fphi]: [&mut Array3<f64>; 2],
    (eps, previous, c0): (f64, Option<&[f64]>, EpsC0),
) -> PointSums {
    transform.inverse(first, phi);
    transform.inverse(second, lap);
    let phi = phi.as_slice().expect("standard layout");
    let c = PAR_CHUNK;
    let partials = lap
        .as_slice_mut()
        .expect("standard layout")
        .par_chunks_mut(c)
        .zip(
            fphi.as_slice_mut()
                .expect("standard layout")
                .par_chunks_mut(c),
        )
        .enumerate()
        .map(|(j, (lap, fphi))| {
            let range = j * c..j * c + lap.len();
            let old = previous.map_or(&phi[range.clone()], |p| &p[range.clone()]);
            let phi = &phi[range.clone()];
            pointwise_range(eps, phi, old, slice_c0(c0, range), lap, fphi)
        });
    let sums = sum_in_fixed_tree(partials, PointSums::default, PointSums::add);
    transform.forward(fphi, first);
    transform.forward(lap, second);
    sums
}

/// εC0 as the real-space sweep takes it: the uniform value, or the ramp r and the field (εC0 =
/// r × field).
type EpsC0<'a> = (f64, Option<(f64, &'a [f64])>);

/// εC0 on the values `range` of the box.
fn slice_c0((uniform, field): EpsC0, range: std::ops::Range<usize>) -> EpsC0 {
    (uniform, field.map(|(r, f)| (r, &f[range])))
}

/// The first sweep of an evaluation: `copy = φ̂` and `lap = −|k|²φ̂` (the inputs of the two
/// inverse transforms, which overwrite them); returns A = Σ_k (3/(2√2)) ε |k|² w |φ̂|².
fn inverse_inputs(
    sym: &Symbols,
    hat: &[Complex64],
    copy: &mut [Complex64],
    lap: &mut [Complex64],
) -> f64 {
    let task = sym.task_reals();
    let (hat, copy, lap) = (reals(hat), reals_mut(copy), reals_mut(lap));
    copy.par_chunks_mut(task)
        .zip(lap.par_chunks_mut(task))
        .enumerate()
        .with_max_len(1)
        .map(|(t, (copy, lap))| {
            let mut terms = [0.0; PIECE];
            let mut area = 0.0;
            for_each_piece(sym, t, copy.len(), |p, at| {
                let r = at..at + p.reals();
                let (h, copy, lap) = (
                    &hat[t * task..][r.clone()],
                    &mut copy[r.clone()],
                    &mut lap[r],
                );
                area += per_width!(sym, W => inverse_inputs_piece::<W>(sym, p, h, copy, lap, &mut terms));
            });
            area
        })
        .sum()
}

wide_fn! {
/// One piece of [`inverse_inputs`], mode by mode ([`write_inverse_value`]; `terms` scratch for
/// each mode's area): returns its area.
fn inverse_inputs_piece<const W: usize>(
    sym: &Symbols,
    p: &Piece,
    h: &[f64],
    copy: &mut [f64],
    lap: &mut [f64],
    terms: &mut [f64; PIECE],
) -> f64 {
    let len = p.len;
    let [copy, lap] = [copy, lap].map(|o| p.modes_mut::<W, _>(o).iter_mut());
    let outputs = copy.zip(lap).zip(&mut terms[..len]);
    let inputs = p.modes::<W, _>(h).iter().zip(p.symbols());
    for (((copy, lap), term), (h, (k, w))) in outputs.zip(inputs) {
        *term = write_inverse_value(*h, k, sym.area_prefactor * k * w, copy, lap);
    }
    sum(&terms[..len])
}
}

/// The inputs of an evaluation's inverse transforms at one mode φ̂ = `h` with |k|² = `k` and
/// area weight `aw` = (3/(2√2)) ε |k|² w: `copy = φ̂` and `lap = −|k|²φ̂`; returns its area
/// term a |φ̂|². Every sweep that makes a new φ̂ (the evaluation's first, the time step's update,
/// the L-BFGS trial) ends with it.
#[inline(always)]
pub(crate) fn write_inverse_value<const W: usize>(
    h: [f64; W],
    k: f64,
    aw: f64,
    copy: &mut [f64; W],
    lap: &mut [f64; W],
) -> f64 {
    *copy = h;
    *lap = h.map(|v| -(v * k));
    aw * re_dot(h, h)
}

/// Sums of the pointwise pass (zero by default).
#[derive(Default)]
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

impl PointSums {
    fn add(self, o: Self) -> Self {
        PointSums {
            phi_sq: self.phi_sq + o.phi_sq,
            phi: self.phi + o.phi,
            max_abs: self.max_abs.max(o.max_abs),
            change: self.change.max(o.change),
        }
    }
}

/// Real-space values per run of [`pointwise_range`]: its Φ are kept for the sums (4 KiB).
const RUN: usize = 512;

/// The real-space sweep over a range of values: with `lap` = ∇²φ on entry, Φ = f(φ) − ε²∇²φ,
/// `lap ← f(φ)` and `fphi ← f'(φ) Φ`, with εC0 = `uniform` or r × the field (given on the
/// range); returns Σ Φ², Σ φ, max|φ| and max|φ − φ_old|. A run of values at a time: the
/// element-wise loop, then the sums of the run.
fn pointwise_range(
    eps: f64,
    phi: &[f64],
    old: &[f64],
    (uniform, field): EpsC0,
    lap: &mut [f64],
    fphi: &mut [f64],
) -> PointSums {
    let mut acc = PointSums::default();
    let mut big = [0.0; RUN];
    let runs = lap.chunks_mut(RUN).zip(fphi.chunks_mut(RUN));
    for (i, (lap, fphi)) in runs.enumerate() {
        let range = i * RUN..i * RUN + lap.len();
        let (p, o, big) = (
            &phi[range.clone()],
            &old[range.clone()],
            &mut big[..lap.len()],
        );
        let ec0 = field.map(|(r, f)| (r, &f[range]));
        pointwise_run(eps, p, (uniform, ec0), lap, fphi, big);
        let [phi_sq, sum, max_abs, change] = pointwise_sums(p, o, big);
        acc = acc.add(PointSums {
            phi_sq,
            phi: sum,
            max_abs,
            change,
        });
    }
    acc
}

wide_fn! {
/// One run of [`pointwise_range`]'s element-wise loop: `lap ← f(φ)`, `fphi ← f'(φ) Φ` and
/// `big ← Φ` (f and f' without their C0 terms when C0 = 0).
fn pointwise_run(
    eps: f64,
    phi: &[f64],
    c0: (f64, Option<(f64, &[f64])>),
    lap: &mut [f64],
    fphi: &mut [f64],
    big: &mut [f64],
) {
    let ((uniform, field), e2) = (c0, eps * eps);
    let body = |f: f64, df: f64, lap: &mut f64, fphi: &mut f64, big: &mut f64| {
        *big = f - e2 * *lap;
        *lap = f;
        *fphi = df * *big;
    };
    let out = lap.iter_mut().zip(fphi.iter_mut()).zip(big.iter_mut());
    match field {
        Some((r, ec0)) => {
            for (((l, f), b), (&p, &e)) in out.zip(phi.iter().zip(ec0)) {
                let c = r * e;
                body(bulk(p, c), bulk_derivative(p, c), l, f, b);
            }
        }
        None if uniform == 0.0 => {
            for (((l, f), b), &p) in out.zip(phi) {
                body(bulk_at_zero_c0(p), bulk_derivative_at_zero_c0(p), l, f, b);
            }
        }
        None => {
            for (((l, f), b), &p) in out.zip(phi) {
                body(bulk(p, uniform), bulk_derivative(p, uniform), l, f, b);
            }
        }
    }
}
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

/// Each value's terms of [`combine`]'s sums (a piece's scratch).
struct CombineTerms {
    /// w |μ̂|² (0 at k = 0 and without the residual).
    residual: [f64; PIECE],
    /// w M |q̂|² and w Re(ĝ q̂*) (gradient).
    qq: [f64; PIECE],
    gq: [f64; PIECE],
}

/// The last spectral sweep: from FT[f'Φ] (in `n`), FT[f] (`g`) and φ̂ (`h`) write the explicit
/// term into `n`: N̂ = −2k² FT[f'Φ] − 2ε²k⁴ FT[f] (conserved) or ĝ = 2 FT[f'Φ] + 2ε²k² FT[f] +
/// 2ε⁴k⁴ φ̂ (gradient, with the multiplier's sums ⟨q, q⟩_M and ⟨ĝ, q⟩ in its metric). With
/// `sigma` it also sums Σ_{k≠0} w |μ̂|², μ̂ = ĝ + (3/√2) ε σ k² φ̂. (k stands for |k|².)
fn combine(
    sym: &Symbols,
    eps: f64,
    explicit: ExplicitTerm,
    sigma: Option<f64>,
    h: &[Complex64],
    g: &[Complex64],
    n: &mut [Complex64],
) -> CombineSums {
    let task = sym.task_reals();
    let (h, g, n) = (reals(h), reals(g), reals_mut(n));
    let how = Combine {
        e2: eps * eps,
        explicit,
        with_residual: sigma.is_some(),
        tension: 2.0 * sym.area_prefactor * sigma.unwrap_or(0.0),
    };
    let partials = n.par_chunks_mut(task).enumerate().map(|(t, n)| {
        let z = [0.0; PIECE];
        let mut terms = CombineTerms {
            residual: z,
            qq: z,
            gq: z,
        };
        let mut sums = CombineSums::default();
        for_each_piece(sym, t, n.len(), |p, at| {
            let r = at..at + p.reals();
            let (g, h) = (&g[t * task..][r.clone()], &h[t * task..][r.clone()]);
            let n = &mut n[r];
            let piece = per_width!(sym, W => combine_piece::<W>(&how, p, g, h, n, &mut terms));
            sums = sums.add(piece);
        });
        sums
    });
    sum_in_fixed_tree(partials, CombineSums::default, CombineSums::add)
}

/// What [`combine`] forms.
struct Combine {
    e2: f64,
    explicit: ExplicitTerm,
    with_residual: bool,
    /// (3/√2) ε σ.
    tension: f64,
}

wide_fn! {
/// One piece of [`combine`], mode by mode (`t` scratch for each mode's terms).
fn combine_piece<const W: usize>(
    how: &Combine,
    p: &Piece,
    g: &[f64],
    h: &[f64],
    n: &mut [f64],
    t: &mut CombineTerms,
) -> CombineSums {
    let (e2, tension, len) = (how.e2, how.tension, p.len);
    let (g, h) = (p.modes::<W, _>(g), p.modes::<W, _>(h));
    let values = p.modes_mut::<W, _>(n).iter_mut().zip(g.iter().zip(h));
    let symbols = p.symbols();
    let terms = t.residual[..len].iter_mut().zip(t.qq[..len].iter_mut().zip(&mut t.gq[..len]));
    // The residual's weight: w, 0 at k = 0 and when the residual is not wanted.
    let residual_weight = |k: f64, w: f64| if how.with_residual && k > 0.0 { w } else { 0.0 };
    let mut sums = CombineSums::default();
    match how.explicit {
        ExplicitTerm::ConservedRhs => {
            for (((o, (g, h)), (k, w)), (res, _)) in values.zip(symbols).zip(terms) {
                let (fnl, fg) = (-2.0 * k, -2.0 * e2 * k * k);
                let (gk, hk) = (2.0 * e2 * k, 2.0 * e2 * e2 * k * k + tension * k);
                let nl = *o;
                let mu = mode::<W>(|c| nl[c] * 2.0 + g[c] * gk + h[c] * hk);
                *o = mode(|c| nl[c] * fnl + g[c] * fg);
                *res = residual_weight(k, w) * re_dot(mu, mu);
            }
        }
        ExplicitTerm::Gradient(m) => {
            for (((o, (g, h)), (k, w)), (res, (qq, gq))) in values.zip(symbols).zip(terms) {
                let (gk, hk, tk) = (2.0 * e2 * k, 2.0 * e2 * e2 * k * k, tension * k);
                let qh = m.c_sigma * k / m.at(k);
                let gradient = mode::<W>(|c| o[c] * 2.0 + g[c] * gk + h[c] * hk);
                *o = gradient;
                let mu = mode::<W>(|c| gradient[c] + h[c] * tk);
                *res = residual_weight(k, w) * re_dot(mu, mu);
                *qq = w * m.c_sigma * k * qh * re_dot(*h, *h);
                *gq = w * qh * re_dot(gradient, *h);
            }
            sums.qq = sum(&t.qq[..len]);
            sums.gq = sum(&t.gq[..len]);
        }
    }
    sums.residual_sq = sum(&t.residual[..len]);
    sums
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::model::SpontaneousCurvature;

    /// The evaluation slab by slab ([`Transform::round_trip`], 1 thread) and a transform at a
    /// time (4 threads on 3 slabs, where the round trip declines) agree to round-off on a
    /// C0 field half ramped in: F, A, V and max|φ − φ_old| to 1e-13 (relative), N̂ to 1e-12 of
    /// its largest value. A field value taken at the wrong place (the slab's offset into φ_old
    /// or εC0) would miss by far more.
    #[test]
    fn slab_round_trip_and_transforms_apart_agree() {
        let shape = [3, 10, 12];
        let grid = Grid::new(&shape, 0.7, &[false; 3]);
        let field = |f: fn(f64, f64, f64) -> f64| {
            Array3::from_shape_fn(shape, |(i, j, k)| f(i as f64, j as f64, k as f64))
        };
        let phi = field(|i, j, k| (0.9 * (0.7 * i + 0.4 * j).sin() * (0.3 * k).cos()).tanh());
        let old = field(|i, j, k| 0.8 * (0.5 * i - 0.2 * j + 0.6 * k).sin());
        let c0 = C0 {
            shape: SpontaneousCurvature::Field(field(|i, j, k| 0.1 * (i + 0.5 * j - 0.3 * k))),
            ramp_time: Some(2.0),
        };
        let evaluate = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| {
                let mut ev = Evaluator::new(
                    grid.clone(),
                    1.0,
                    c0.clone(),
                    Laplacian::Spectral,
                    ExplicitTerm::ConservedRhs,
                    threads,
                );
                let mut s = ev.state_of(&phi, 1.0).expect("finite");
                let change = ev
                    .evaluate(&mut s, 1.0, Some(&old), Some(0.3))
                    .expect("finite");
                (s, change)
            })
        };
        let ((slabs, change_slabs), (apart, change_apart)) = (evaluate(1), evaluate(4));
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * b.abs();
        let (m, n) = (slabs.measures, apart.measures);
        assert!(close(m.energy, n.energy) && close(m.area, n.area) && close(m.volume, n.volume));
        assert!(
            close(change_slabs, change_apart),
            "{change_slabs} {change_apart}"
        );
        assert!(close(slabs.residual, apart.residual));
        let largest = apart.nonlinear.iter().map(|z| z.norm()).fold(0.0, f64::max);
        let diff = (&slabs.nonlinear - &apart.nonlinear)
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);
        assert!(
            diff <= 1e-12 * largest,
            "N̂ differs by {diff:e} of {largest:e}"
        );
    }
}
