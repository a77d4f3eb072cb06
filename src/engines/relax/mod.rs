//! `"dynamics": "relaxational"`: the fastest route to the conserved flow's stationary states
//! (docs/src/theory/relaxation.md), a preconditioned L-BFGS on the constrained energy.
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
//! space; a trial point φ + α d is retracted onto A = A0 along q = M⁻¹â (a quadratic in the step,
//! as in the spectral projection), and α is backtracked until Armijo's condition on F_sc holds.
//! The memory is reset when the direction is not a descent direction. At a stationary point
//! μ = δF_sc/δφ + σ δA/δφ is constant: the residual reported is the RMS of μ − mean(μ).
//! `t` advances by the nominal `dt` per iteration and is not physical time.
//!
//! **The bilayer couple** ([`couple`]) holds M[φ] = M0 as a second constraint: q = q_A beside
//! q_M = M⁻¹m̂, σ and λ from their 2×2 Gram system, the direction projected onto both, and each
//! trial retracted onto both (the area's quadratic for each τ_M, Newton iterations on M).
//!
//! **Cost.** The two-loop recursion is run on coefficients, not on vectors (the "vector-free"
//! form): its inner products are all combinations of ⟨s_i, r⟩, ⟨y_i, r⟩, ⟨q, y_i⟩, ⟨r, r⟩,
//! ⟨q, r⟩ and of the Gram entries ⟨s_i, y_j⟩, ⟨y_i, y_j⟩, so the direction
//! d = −c_r r − Σ c_y,i y_i − Σ c_s,i s_i + c_q q is written in one sweep. An iteration is three
//! sweeps besides the evaluation:
//! * the direction, which also sums the six coefficients of the area of φ̂ + α d' + β q as a
//!   quadratic in (α, β), so that the retraction's root needs no sweep of its own;
//! * the trial state, written with the evaluation's two inverse inputs (the evaluation's last
//!   sweep sums the multiplier's ⟨q, q⟩_M and ⟨ĝ, q⟩);
//! * the gradient r of the accepted state with the new pair (s, y), which also takes the inner
//!   products of r, q and the new pair with every stored pair: the next iteration's recursion
//!   and the Gram matrix's new row and column.
//!
//! The sweeps walk the spectrum in pieces ([`crate::engines::spectral::pieces`]) whose per-wavenumber
//! factors are formed once, and the loops run over the spectra as interleaved (re, im) reals;
//! the reductions are the vectorised kernels of [`crate::engines::spectral::kernels`].
//!
//! **The pairs in single precision.** The two sweeps that read every stored pair (the
//! direction's and the gradient's) are bound by memory, so the pairs are stored as f32: s and y
//! are formed in f64 and rounded once, and every inner product and the direction use the
//! rounded values widened exactly, so the recursion is the exact L-BFGS recursion of the stored
//! pairs (a relative change of ~6e-8 in each pair, none in the state, the gradient, the
//! multiplier or the line search, which stay f64). The memory only approximates the inverse
//! Hessian, with errors far above 6e-8, and the stationary state is fixed by the f64 gradient
//! alone. Measured on the 48³ prolate (`benches/PERFORMANCE.md`): 237 iterations to
//! the residual 1e-6 against 236 with f64 pairs, and an iteration 13% (1 thread) and 7%
//! (2 threads) faster.
//!
//! **Memory.** Besides the pairs, the loop holds φ̂ and φ of the current state and of the trial,
//! one explicit-term spectrum (the trial borrows the state's during a line search), r (the
//! accepted state's written over it), the direction and the evaluator's spare spectrum: 9.9 +
//! 1.03 m f64 per point measured at 96³ with m pairs ([`crate::problem::memory`]).

mod couple;
mod engine;
mod lbfgs;
mod sweeps;
#[cfg(test)]
mod tests;

use crate::engines::spectral::evaluator::{Evaluator, Metric, State};
use crate::engines::AreaConstraint;
use couple::Couple;
use lbfgs::{Direction, InnerProducts, Pair};
use ndarray::Array3;
use num_complex::Complex64;
use std::collections::VecDeque;

/// The L-BFGS relaxation engine.
pub struct RelaxEngine {
    ev: Evaluator,
    /// The current state; its `nonlinear` holds ĝ of φ̂ between iterations.
    cur: State,
    /// The line search's trial state. It owns no `nonlinear` of its own: during a line search
    /// it takes the current state's (whose ĝ is no longer needed once r is formed), and the
    /// accepted trial hands it back with its own ĝ, so one spectrum serves both.
    trial: State,
    metric: Metric,
    /// Preconditioned projected gradient r of the current state (the accepted trial's r is
    /// written over it in place).
    grad: Array3<Complex64>,
    /// Search direction d' (without its multiple of q).
    dir: Array3<Complex64>,
    /// Pairs, oldest first.
    pairs: VecDeque<Pair>,
    /// Pairs not in use (kept so that no iteration allocates once the memory has filled).
    spare_pairs: Vec<Pair>,
    /// Gram entries ⟨s_i, y_j⟩_M and ⟨y_i, y_j⟩_M, row-major `i · MAX_MEMORY + j`.
    sy: Vec<f64>,
    yy: Vec<f64>,
    /// The current state's inner products with the pairs.
    ip: InnerProducts,
    /// This iteration's direction.
    direction: Direction,
    memory: usize,
    sigma: f64,
    residual: f64,
    area: AreaConstraint,
    /// The bilayer couple's second constraint, when the scene holds Δa ([`couple`]).
    couple: Option<Couple>,
    stalled: bool,
}
