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
//! space; a trial point φ + α d is retracted onto A = A0 along q = M⁻¹â (a quadratic in the step,
//! as in the spectral projection), and α is backtracked until Armijo's condition on F_sc holds.
//! The memory is reset when the direction is not a descent direction. At a stationary point
//! μ = δF_sc/δφ + σ δA/δφ is constant: the residual reported is the RMS of μ − mean(μ).
//! `t` advances by the nominal `dt` per iteration and is not physical time.
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

use crate::engines::numerics::nearest_root;
use crate::engines::spectral::evaluator::{
    write_inverse_value, Evaluator, ExplicitTerm, Metric, State, Symbols,
};
use crate::engines::spectral::kernels::{pair_sums, sum, wide_fn};
use crate::engines::spectral::pieces::{
    for_each_piece, mode, per_width, re_dot, reals, reals_mut, Piece, PIECE,
};
use crate::engines::spectral::saved;
use crate::engines::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::problem::config::{AreaMethod, Scene};
use crate::problem::grid::Grid;
use crate::problem::model::{Measures, C0};
use ndarray::Array3;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::collections::VecDeque;

/// Armijo constant: accept when F(φ + αd) ≤ F(φ) + c α ⟨∇F, d⟩.
const ARMIJO: f64 = 1e-4;
/// Backtracking halvings before the line search gives up.
const MAX_BACKTRACKS: usize = 40;
/// Largest L-BFGS memory (the coefficient recursion keeps its sums in fixed arrays).
pub const MAX_MEMORY: usize = 32;

/// One stored L-BFGS pair (s, y), flattened like the spectrum as interleaved (re, im) reals, in
/// single precision (see the module documentation).
struct Pair {
    s: Vec<f32>,
    y: Vec<f32>,
}

impl Pair {
    /// A pair of `reals` zeros.
    fn zeros(reals: usize) -> Self {
        Pair {
            s: vec![0.0; reals],
            y: vec![0.0; reals],
        }
    }
}

/// ⟨s_i, r⟩_M, ⟨y_i, r⟩_M and ⟨q, y_i⟩_M of the current state per pair (oldest first), and
/// ⟨r, r⟩_M, ⟨q, r⟩_M.
#[derive(Clone, Copy)]
struct InnerProducts {
    s_r: [f64; MAX_MEMORY],
    y_r: [f64; MAX_MEMORY],
    q_y: [f64; MAX_MEMORY],
    rr: f64,
    qr: f64,
}

/// The unprojected direction d' = −c_r r − Σ c_y,i y_i − Σ c_s,i s_i over the pairs from
/// position `off`, its projection coefficient (d = d' + c_q q), slope ⟨r, d⟩_M,
/// and the area sums of φ̂ + α d' + β q (see [`AreaSums`]).
#[derive(Clone, Copy)]
struct Direction {
    off: usize,
    c_r: f64,
    c_y: [f64; MAX_MEMORY],
    c_s: [f64; MAX_MEMORY],
    c_q: f64,
    slope: f64,
    area: AreaSums,
}

/// A(x + α d' + β q) = xx + 2α xd + α² dd + 2β (xq + α qd) + β² qq, the sums weighted by
/// (3/(2√2)) ε |k|² w (x = φ̂, q = (c_σ|k|²/M) φ̂).
#[derive(Clone, Copy, Default)]
struct AreaSums {
    xx: f64,
    xq: f64,
    qq: f64,
    xd: f64,
    qd: f64,
    dd: f64,
}

impl AreaSums {
    fn add(self, o: Self) -> Self {
        AreaSums {
            xx: self.xx + o.xx,
            xq: self.xq + o.xq,
            qq: self.qq + o.qq,
            xd: self.xd + o.xd,
            qd: self.qd + o.qd,
            dd: self.dd + o.dd,
        }
    }

    /// The retraction τ nearest 0 that puts x + α d' + (α c_q + τ) q on A = `target`: with
    /// b = α c_q, A = qq (τ + b)² + 2 p (τ + b) + a0, p = xq + α qd, a0 = xx + 2α xd + α² dd.
    fn retraction(&self, alpha: f64, c_q: f64, target: f64) -> Option<f64> {
        let b = alpha * c_q;
        let p = self.xq + alpha * self.qd;
        let a0 = self.xx + 2.0 * alpha * self.xd + alpha * alpha * self.dd;
        nearest_root(
            self.qq,
            self.qq * b + p,
            (self.qq * b + 2.0 * p) * b + a0 - target,
            0.0,
        )
    }
}

/// The sums of one gradient sweep ([`gradient_sweep`]).
#[derive(Clone, Copy)]
struct GradientSums {
    /// Σ_{k≠0} w |ĝ + σâ|² (the residual's square × |Ω|).
    res: f64,
    rr: f64,
    qr: f64,
    /// Per pair (the new one last): [`pair_sums`].
    pairs: [[f64; 6]; MAX_MEMORY + 1],
}

impl GradientSums {
    fn zero() -> Self {
        GradientSums {
            res: 0.0,
            rr: 0.0,
            qr: 0.0,
            pairs: [[0.0; 6]; MAX_MEMORY + 1],
        }
    }

    fn add(mut self, o: Self) -> Self {
        self.res += o.res;
        self.rr += o.rr;
        self.qr += o.qr;
        for (a, b) in self.pairs.iter_mut().zip(&o.pairs) {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        }
        self
    }

    /// The inner products of the current state with the pairs `from..to` of the sweep.
    fn inner_products(&self, from: usize, to: usize) -> InnerProducts {
        let mut ip = InnerProducts {
            s_r: [0.0; MAX_MEMORY],
            y_r: [0.0; MAX_MEMORY],
            q_y: [0.0; MAX_MEMORY],
            rr: self.rr,
            qr: self.qr,
        };
        for (i, p) in self.pairs[from..to].iter().enumerate() {
            (ip.s_r[i], ip.y_r[i], ip.q_y[i]) = (p[0], p[1], p[2]);
        }
        ip
    }
}

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
    stalled: bool,
}

impl RelaxEngine {
    /// Engine holding `phi`, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let metric = Metric::new(scene.eps);
        let explicit = ExplicitTerm::Gradient(metric);
        let mut ev = Evaluator::new(
            grid,
            scene.eps,
            c0,
            scene.laplacian,
            explicit,
            scene.threads(),
        );
        let cur = ev.state_of(&phi, 0.0)?;
        let zeros = Array3::zeros(cur.hat.raw_dim());
        let memory = scene.lbfgs_memory.min(MAX_MEMORY);
        // The trial's own explicit-term spectrum is never used (see `trial`): an empty array.
        let mut trial = ev.blank();
        trial.nonlinear = Array3::zeros((0, 0, 0));
        let mut e = RelaxEngine {
            trial,
            metric,
            ev,
            cur,
            grad: zeros.clone(),
            dir: zeros,
            pairs: VecDeque::with_capacity(memory),
            spare_pairs: Vec::with_capacity(memory + 1),
            sy: vec![0.0; MAX_MEMORY * MAX_MEMORY],
            yy: vec![0.0; MAX_MEMORY * MAX_MEMORY],
            ip: GradientSums::zero().inner_products(0, 0),
            direction: Direction {
                off: 0,
                c_r: 0.0,
                c_y: [0.0; MAX_MEMORY],
                c_s: [0.0; MAX_MEMORY],
                c_q: 0.0,
                slope: 0.0,
                area: AreaSums::default(),
            },
            memory,
            sigma: 0.0,
            residual: f64::INFINITY,
            area: AreaConstraint::none(),
            stalled: false,
        };
        e.refresh_gradient();
        Ok(e)
    }

    /// Pairs held in the memory (at most `lbfgs_memory`).
    pub fn memory_len(&self) -> usize {
        self.pairs.len()
    }

    fn reset_memory(&mut self) {
        self.spare_pairs.extend(self.pairs.drain(..));
    }

    /// After a line search that accepted nothing: the trial hands back the spectrum it took,
    /// and ĝ of the current state (evaluated at `t`) is formed in it again, so that a later
    /// [`RelaxEngine::refresh_gradient`] reads it. The state's measures and sums are kept as
    /// they were (a new evaluation could change them at round-off).
    fn take_back_gradient(&mut self, t: f64) -> Result<(), Diverged> {
        std::mem::swap(&mut self.cur.nonlinear, &mut self.trial.nonlinear);
        let kept = (self.cur.measures, self.cur.multiplier_sums);
        self.ev.evaluate(&mut self.cur, t, None, None)?;
        (self.cur.measures, self.cur.multiplier_sums) = kept;
        Ok(())
    }

    /// σ, r, the residual and the inner products of the current state (no pair is formed).
    fn refresh_gradient(&mut self) {
        let sigma = self.multiplier(self.cur.multiplier_sums);
        let sums = gradient_sweep(
            &self.ev.symbols,
            self.metric,
            &self.cur,
            sigma,
            self.grad.as_slice_mut().expect("standard layout"),
            &self.pairs,
            None,
        );
        self.sigma = sigma;
        self.ip = sums.inner_products(0, self.pairs.len());
        self.residual = (sums.res / self.ev.grid.full_volume()).sqrt();
    }

    /// σ = −⟨ĝ, q⟩/⟨q, q⟩_M from the state's (⟨q, q⟩_M, ⟨ĝ, q⟩) (0 without an area constraint).
    fn multiplier(&self, (qq, gq): (f64, f64)) -> f64 {
        if self.area.method == AreaMethod::None || qq <= 0.0 {
            0.0
        } else {
            -gq / qq
        }
    }

    /// The two-loop recursion on coefficients (module documentation) with the newest `n` pairs
    /// (0 gives the preconditioned steepest descent). Leaves `c_q` 0 and `slope` = ⟨r, d'⟩_M;
    /// [`RelaxEngine::write_direction`] completes both.
    fn recursion(&self, n: usize) -> Direction {
        let ip = &self.ip;
        let off = self.pairs.len() - n;
        let sy = |i: usize, j: usize| self.sy[(i + off) * MAX_MEMORY + j + off];
        let yy = |i: usize, j: usize| self.yy[(i + off) * MAX_MEMORY + j + off];
        let rho = |i: usize| 1.0 / sy(i, i);
        // First loop, newest to oldest: α_i = ρ_i ⟨s_i, r − Σ_{j>i} α_j y_j⟩.
        let mut alpha = [0.0; MAX_MEMORY];
        for i in (0..n).rev() {
            let v = ip.s_r[i + off] - (i + 1..n).map(|j| alpha[j] * sy(i, j)).sum::<f64>();
            alpha[i] = rho(i) * v;
        }
        let gamma = if n > 0 {
            sy(n - 1, n - 1) / yy(n - 1, n - 1)
        } else {
            1.0
        };
        // Second loop, oldest to newest, on z = γ(r − Σ α_j y_j) + Σ_{j<i} (α_j − β_j) s_j:
        // β_i = ρ_i ⟨y_i, z⟩; z = γ r + Σ c_y y + Σ c_s s at the end, d' = −z.
        let mut c_s = [0.0; MAX_MEMORY];
        for i in 0..n {
            let v = gamma * (ip.y_r[i + off] - (0..n).map(|j| alpha[j] * yy(i, j)).sum::<f64>())
                + (0..i).map(|j| c_s[j] * sy(j, i)).sum::<f64>();
            c_s[i] = alpha[i] - rho(i) * v;
        }
        let mut c_y = [0.0; MAX_MEMORY];
        (0..n).for_each(|j| c_y[j] = -gamma * alpha[j]);
        let rz = gamma * ip.rr
            + (0..n)
                .map(|j| c_y[j] * ip.y_r[j + off] + c_s[j] * ip.s_r[j + off])
                .sum::<f64>();
        Direction {
            off,
            c_r: gamma,
            c_y,
            c_s,
            c_q: 0.0,
            slope: -rz,
            area: AreaSums::default(),
        }
    }

    /// Write d' into `dir`, each pair added over a piece's contiguous values, summing the area
    /// coefficients ([`AreaSums`]) in the same sweep; complete `d`: the tangent projection
    /// d = d' − (⟨q, d'⟩_M/⟨q, q⟩_M) q, kept as the coefficient c_q (⟨q, d'⟩_M = 2 xd and
    /// ⟨q, q⟩_M = 2 xq: the area weight is w M q/φ̂ / 2), and the slope ⟨r, d⟩_M.
    fn write_direction(&mut self, d: &mut Direction) {
        let (sym, m) = (&self.ev.symbols, self.metric);
        let pairs = &self.pairs;
        let (r, x) = (reals(flat(&self.grad)), reals(flat(&self.cur.hat)));
        let task = sym.task_reals();
        let coefficients = *d;
        let area = reals_mut(self.dir.as_slice_mut().expect("standard layout"))
            .par_chunks_mut(task)
            .enumerate()
            .with_max_len(1)
            .map(|(t, out)| {
                let base = t * task;
                let mut acc = AreaSums::default();
                let mut terms = [[0.0; PIECE]; 6];
                for_each_piece(sym, t, out.len(), |p, at| {
                    let (o, g) = (
                        &mut out[at..at + p.reals()],
                        base + at..base + at + p.reals(),
                    );
                    direction_piece(o, &r[g.clone()], pairs, &coefficients, g.clone());
                    let x = &x[g];
                    acc = acc
                        .add(per_width!(sym, W => area_values::<W>(sym, m, p, x, o, &mut terms)));
                });
                acc
            })
            .reduce(AreaSums::default, AreaSums::add);
        let project = self.area.method != AreaMethod::None && area.xq > 0.0;
        d.c_q = if project { -area.xd / area.xq } else { 0.0 };
        d.slope += d.c_q * self.ip.qr;
        d.area = area;
    }

    /// The trial state φ̂ + α d' + β q into `trial.hat`, with the evaluation's inverse inputs
    /// (see [`Evaluator::finish`]); returns its area.
    fn write_trial(&mut self, alpha: f64, beta: f64) -> f64 {
        let (sym, m) = (&self.ev.symbols, self.metric);
        let (x, d) = (reals(flat(&self.cur.hat)), reals(flat(&self.dir)));
        let task = sym.task_reals();
        let hat = reals_mut(self.trial.hat.as_slice_mut().expect("standard layout"));
        let copy = reals_mut(self.trial.nonlinear.as_slice_mut().expect("layout"));
        let lap = reals_mut(self.ev.spare.as_slice_mut().expect("standard layout"));
        hat.par_chunks_mut(task)
            .zip(copy.par_chunks_mut(task))
            .zip(lap.par_chunks_mut(task))
            .enumerate()
            .with_max_len(1)
            .map(|(t, ((hat, copy), lap))| {
                let base = t * task;
                let mut area = 0.0;
                let mut terms = [0.0; PIECE];
                for_each_piece(sym, t, hat.len(), |p, at| {
                    let (local, g) = (at..at + p.reals(), base + at..base + at + p.reals());
                    let out = [
                        &mut hat[local.clone()],
                        &mut copy[local.clone()],
                        &mut lap[local],
                    ];
                    let spectra = (&x[g.clone()], &d[g]);
                    let step = (alpha, beta);
                    area += per_width!(sym, W => {
                        trial_values::<W>(sym, m, p, out, spectra, step, &mut terms)
                    });
                });
                area
            })
            .sum()
    }

    /// Trial state φ̂ + α d, retracted onto A = A0 along q, evaluated; returns the step's total
    /// multiple of q (α c_q + τ). `Err` if the retraction has no real root or the evaluation
    /// diverged.
    fn try_step(&mut self, alpha: f64, t: f64) -> Result<(), ()> {
        let d = &self.direction;
        let tau = if self.area.method == AreaMethod::None {
            0.0
        } else {
            d.area
                .retraction(alpha, d.c_q, self.area.target)
                .ok_or(())?
        };
        let area = self.write_trial(alpha, alpha * d.c_q + tau);
        self.ev
            .finish(&mut self.trial, area, t, None, None)
            .map(|_| ())
            .map_err(|_| ())
    }

    /// Accept the trial state: its σ, r (over the current state's), residual and inner
    /// products, and the pair (s, y) = (x_new − x, r_new − r) kept if ⟨y, s⟩_M > 0 (the oldest
    /// dropped when the memory is full), its Gram row and column from the same sweep.
    fn accept(&mut self) {
        let sigma = self.multiplier(self.trial.multiplier_sums);
        let reals = 2 * self.cur.hat.len();
        let mut pair = self.spare_pairs.pop().unwrap_or_else(|| Pair::zeros(reals));
        let sums = gradient_sweep(
            &self.ev.symbols,
            self.metric,
            &self.trial,
            sigma,
            self.grad.as_slice_mut().expect("standard layout"),
            &self.pairs,
            Some((flat(&self.cur.hat), &mut pair)),
        );
        let n = self.pairs.len();
        // The new pair's sums: [3] = ⟨y_new, s_new⟩_M, [5] = ⟨y_new, y_new⟩_M.
        let new = sums.pairs[n];
        if new[3] > 0.0 {
            let drop = usize::from(n == self.memory);
            if drop == 1 {
                self.spare_pairs.extend(self.pairs.pop_front());
                shift_gram(&mut self.sy, n);
                shift_gram(&mut self.yy, n);
            }
            let k = n - drop;
            for (i, p) in sums.pairs[drop..n].iter().enumerate() {
                self.sy[k * MAX_MEMORY + i] = p[3];
                self.sy[i * MAX_MEMORY + k] = p[4];
                self.yy[i * MAX_MEMORY + k] = p[5];
                self.yy[k * MAX_MEMORY + i] = p[5];
            }
            self.sy[k * MAX_MEMORY + k] = new[3];
            self.yy[k * MAX_MEMORY + k] = new[5];
            self.pairs.push_back(pair);
            self.ip = sums.inner_products(drop, n + 1);
        } else {
            self.spare_pairs.push(pair);
            self.ip = sums.inner_products(0, n);
        }
        std::mem::swap(&mut self.cur, &mut self.trial);
        self.sigma = sigma;
        self.residual = (sums.res / self.ev.grid.full_volume()).sqrt();
    }

    /// Gram entries of every pair (after a restore from a checkpoint that has none), by direct
    /// inner products.
    fn rebuild_gram(&mut self) {
        let n = self.pairs.len();
        for i in 0..n {
            for j in 0..n {
                let (sy, yy) = pair_dots(
                    &self.ev.symbols,
                    self.metric,
                    &self.pairs[i],
                    &self.pairs[j],
                );
                self.sy[i * MAX_MEMORY + j] = sy;
                self.yy[i * MAX_MEMORY + j] = yy;
            }
        }
    }
}

/// A spectrum as a flat slice.
fn flat(a: &Array3<Complex64>) -> &[Complex64] {
    a.as_slice().expect("standard layout")
}

/// Drop the oldest pair's row and column of a Gram matrix of `n` pairs.
fn shift_gram(g: &mut [f64], n: usize) {
    for i in 1..n {
        for j in 1..n {
            g[(i - 1) * MAX_MEMORY + j - 1] = g[i * MAX_MEMORY + j];
        }
    }
}

wide_fn! {
/// One piece of [`RelaxEngine::write_direction`]: d' = −c_r r − Σ_j (c_y,j y_j + c_s,j s_j)
/// into `out` over the pairs from `d.off`, from the piece's reals `r` of r and the reals `g` of
/// the pairs.
fn direction_piece(
    out: &mut [f64],
    r: &[f64],
    pairs: &VecDeque<Pair>,
    d: &Direction,
    g: std::ops::Range<usize>,
) {
    for (o, r) in out.iter_mut().zip(r) {
        *o = -(r * d.c_r);
    }
    for (j, p) in pairs.iter().skip(d.off).enumerate() {
        let (cy, cs) = (d.c_y[j], d.c_s[j]);
        let (y, s) = (&p.y[g.clone()], &p.s[g.clone()]);
        for ((o, &y), &s) in out.iter_mut().zip(y).zip(s) {
            *o -= f64::from(y) * cy + f64::from(s) * cs;
        }
    }
}
}

wide_fn! {
/// The area sums of one piece ([`AreaSums`]) mode by mode, x = φ̂ and d = d' as reals: with
/// the area weight a = (3/(2√2)) ε |k|² w and q/φ̂ = c_σ|k|²/M,
/// xx = Σ a |x|², xq = Σ a (q/φ̂) |x|², qq = Σ a (q/φ̂)² |x|², xd = Σ a Re(x d*),
/// qd = Σ a (q/φ̂) Re(x d*), dd = Σ a |d|² (`t` scratch for each mode's terms).
fn area_values<const W: usize>(
    sym: &Symbols,
    metric: Metric,
    p: &Piece,
    x: &[f64],
    d: &[f64],
    t: &mut [[f64; PIECE]; 6],
) -> AreaSums {
    let len = p.len;
    let [txx, txq, tqq, txd, tqd, tdd] = t;
    let terms = (txx.iter_mut().zip(txq.iter_mut()).zip(tqq.iter_mut()))
        .zip(txd.iter_mut().zip(tqd.iter_mut()).zip(tdd.iter_mut()));
    let values = p.modes::<W, _>(x).iter().zip(p.modes::<W, _>(d));
    for ((((xx, xq), qq), ((xd, qd), dd)), ((&x, &d), (k, w))) in terms.zip(values.zip(p.symbols())) {
        let aw = sym.area_prefactor * k * w;
        let (_, qf) = inverse_metric(metric, k, metric.at(k));
        let (aq, aqq) = (aw * qf, aw * qf * qf);
        let (x2, xd2, d2) = (re_dot(x, x), re_dot(x, d), re_dot(d, d));
        (*xx, *xq, *qq) = (aw * x2, aq * x2, aqq * x2);
        (*xd, *qd, *dd) = (aw * xd2, aq * xd2, aw * d2);
    }
    let [xx, xq, qq, xd, qd, dd] =
        [&*txx, &*txq, &*tqq, &*txd, &*tqd, &*tdd].map(|v| sum(&v[..len]));
    AreaSums {
        xx,
        xq,
        qq,
        xd,
        qd,
        dd,
    }
}
}

wide_fn! {
/// One piece of [`RelaxEngine::write_trial`], mode by mode: φ̂ + α d' + β q into `hat`, and
/// the inverse transforms' inputs ([`write_inverse_value`]) into `copy` and `lap`, from the
/// piece's reals of φ̂ and d' (`(x, d)`); returns its area (`terms` scratch).
fn trial_values<const W: usize>(
    sym: &Symbols,
    metric: Metric,
    p: &Piece,
    out: [&mut [f64]; 3],
    spectra: (&[f64], &[f64]),
    step: (f64, f64),
    terms: &mut [f64; PIECE],
) -> f64 {
    let ((x, d), (alpha, beta), len) = (spectra, step, p.len);
    let [hat, copy, lap] = out.map(|o| p.modes_mut::<W, _>(o).iter_mut());
    let outputs = hat.zip(copy.zip(lap)).zip(&mut terms[..len]);
    let inputs = p.modes::<W, _>(x).iter().zip(p.modes::<W, _>(d)).zip(p.symbols());
    for (((hat, (copy, lap)), term), ((x, d), (k, w))) in outputs.zip(inputs) {
        let (_, qf) = inverse_metric(metric, k, metric.at(k));
        *hat = mode(|c| x[c] + d[c] * alpha + x[c] * qf * beta);
        *term = write_inverse_value(*hat, k, sym.area_prefactor * k * w, copy, lap);
    }
    sum(&terms[..len])
}
}

/// 1/M(k), 0 at k = 0 (r(0) = 0), and q/φ̂ = c_σ |k|²/M(k) at |k|² = `k` and M(k) = `m`: a select
/// of the quotient (a conditional store of the zero compiles to a masked store, which is
/// microcoded and slow on AMD's cores).
#[inline(always)]
fn inverse_metric(metric: Metric, k: f64, m: f64) -> (f64, f64) {
    let inv = 1.0 / m;
    let inv_m = if k == 0.0 { 0.0 } else { inv };
    (inv_m, metric.c_sigma * k * inv_m)
}

wide_fn! {
/// A piece of [`gradient_sweep`], mode by mode: q = (q/φ̂) φ̂ and r = M⁻¹ĝ + σq from the
/// piece's reals of φ̂ and ĝ (`(x, g)`), r into `r`, q and the weighted copies w M r, w M q into
/// `out` = [q, wr, wq]; returns [Σ wM |r|², Σ wM² |r|², Σ wM Re(r q*)] (`t` scratch for each
/// mode's terms).
fn gradient_values<const W: usize>(
    metric: Metric,
    p: &Piece,
    spectra: (&[f64], &[f64]),
    sigma: f64,
    r: &mut [f64],
    out: [&mut [f64]; 3],
    t: &mut [[f64; PIECE]; 3],
) -> [f64; 3] {
    let ((xs, gs), len) = (spectra, p.len);
    let [q, wr, wq] = out;
    let [r, q, wr, wq] = [r, q, wr, wq].map(|o| p.modes_mut::<W, _>(o).iter_mut());
    let [trr, tres, tqr] = t;
    let terms = trr.iter_mut().zip(tres.iter_mut()).zip(tqr.iter_mut());
    let outputs = r.zip(q).zip(wr.zip(wq)).zip(terms);
    let inputs = p.modes::<W, _>(xs).iter().zip(p.modes::<W, _>(gs)).zip(p.symbols());
    for ((((r, q), (wr, wq)), ((rr, res), qr)), ((x, g), (k, w))) in outputs.zip(inputs) {
        let m = metric.at(k);
        let (inv_m, qf) = inverse_metric(metric, k, m);
        let wm = w * m;
        *q = mode(|c| qf * x[c]);
        *r = mode(|c| g[c] * inv_m + x[c] * (sigma * qf));
        (*wr, *wq) = (r.map(|v| wm * v), q.map(|v| wm * v));
        let r2 = re_dot(*r, *r);
        (*rr, *res) = (wm * r2, w * m * m * r2);
        *qr = wm * re_dot(*r, *q);
    }
    [&*trr, &*tres, &*tqr].map(|v| sum(&v[..len]))
}
}

wide_fn! {
/// A piece of the new pair in [`gradient_sweep`], mode by mode: s = φ̂ − x_old, y = r − r_old rounded to
/// single precision from the piece's reals of (φ̂, r) and (x_old, r_old), and w M s, w M y of
/// the rounded values, so that the pair's sums are those of the pair as stored.
fn pair_values<const W: usize>(
    metric: Metric,
    p: &Piece,
    new: (&[f64], &[f64]),
    old: (&[f64], &[f64]),
    pair: [&mut [f32]; 2],
    weighted: [&mut [f64]; 2],
) {
    let ((xs, rs), (x_old, r_old), [s, y], [ws, wy]) = (new, old, pair, weighted);
    let [xs, rs, x_old, r_old] = [xs, rs, x_old, r_old].map(|v| p.modes::<W, _>(v));
    let [s, y] = [s, y].map(|v| p.modes_mut::<W, _>(v).iter_mut());
    let [ws, wy] = [ws, wy].map(|v| p.modes_mut::<W, _>(v).iter_mut());
    let outputs = s.zip(y).zip(ws.zip(wy));
    let values = xs.iter().zip(x_old).zip(rs.iter().zip(r_old));
    let inputs = values.zip(p.symbols());
    for (((s, y), (ws, wy)), (((x, xo), (r, ro)), (k, w))) in outputs.zip(inputs) {
        let wm = w * metric.at(k);
        *s = std::array::from_fn(|c| (x[c] - xo[c]) as f32);
        *y = std::array::from_fn(|c| (r[c] - ro[c]) as f32);
        (*ws, *wy) = (s.map(|v| wm * f64::from(v)), y.map(|v| wm * f64::from(v)));
    }
}
}

/// ⟨u, v⟩_M = Σ_k w M(k) Re(û v̂*) by a plain sum over spectra held as interleaved reals (no
/// pieces, no kernels: the reference the sweeps' sums are checked against, and the Gram of a
/// restored memory).
fn dot_m<A: Copy + Into<f64>, B: Copy + Into<f64>>(
    sym: &Symbols,
    m: Metric,
    u: &[A],
    v: &[B],
) -> f64 {
    let (s2, width) = (sym.row_len(), sym.width);
    let modes = u.chunks_exact(width).zip(v.chunks_exact(width)).enumerate();
    modes.fold(0.0, |acc, (i, (a, b))| {
        let (kb, wb) = sym.row(i / s2);
        let k = kb + sym.k2[2][i % s2];
        let re: f64 = a.iter().zip(b).map(|(&a, &b)| a.into() * b.into()).sum();
        acc + wb * sym.weight[2][i % s2] * m.at(k) * re
    })
}

/// (⟨s_a, y_b⟩_M, ⟨y_a, y_b⟩_M).
fn pair_dots(sym: &Symbols, m: Metric, a: &Pair, b: &Pair) -> (f64, f64) {
    (dot_m(sym, m, &a.s, &b.y), dot_m(sym, m, &a.y, &b.y))
}

/// One task's share of a new pair in [`gradient_sweep`]: x_old (the whole spectrum) and its
/// part of s and y.
type NewPairPart<'a> = (&'a [f64], &'a mut [f32], &'a mut [f32]);

/// r = M⁻¹ĝ + σq of `state` into `grad` (r(0) = 0) with its sums: the residual's
/// Σ_{k≠0} w |ĝ + σâ|² = Σ w M²|r|², ⟨r, r⟩_M, ⟨q, r⟩_M and every stored pair's
/// [`pair_sums`]. With `new` = (x_old, pair), `grad` holds r_old on entry: the sweep also writes
/// s = φ̂ − x_old and y = r − r_old into `pair` (each piece of r_old copied aside before r
/// overwrites it) and takes its sums (last in `pairs`).
fn gradient_sweep(
    sym: &Symbols,
    m: Metric,
    state: &State,
    sigma: f64,
    grad: &mut [Complex64],
    pairs: &VecDeque<Pair>,
    new: Option<(&[Complex64], &mut Pair)>,
) -> GradientSums {
    let (x, g) = (reals(flat(&state.hat)), reals(flat(&state.nonlinear)));
    let task = sym.task_reals();
    let n_pairs = pairs.len();
    // One task: the reals from `t · task`; `new` = (x_old, s, y) of its values.
    let run = |t: usize, r: &mut [f64], mut new: Option<NewPairPart>| {
        let base = t * task;
        let mut acc = GradientSums::zero();
        // The piece's w M r, w M q, w M s_new, w M y_new (the last two 0 without a new pair),
        // q and each value's terms of the sums.
        let mut v = [[0.0; 2 * PIECE]; 4];
        let mut q = [0.0; 2 * PIECE];
        let mut r_old = [0.0; 2 * PIECE];
        let mut terms = [[0.0; PIECE]; 3];
        for_each_piece(sym, t, r.len(), |p, at| {
            let (n, local, gl) = (
                p.reals(),
                at..at + p.reals(),
                base + at..base + at + p.reals(),
            );
            let (xs, gs, rs) = (&x[gl.clone()], &g[gl.clone()], &mut r[local.clone()]);
            if new.is_some() {
                r_old[..n].copy_from_slice(rs);
            }
            let [wr, wq, ws, wy] = &mut v;
            let out = [&mut q[..n], &mut wr[..n], &mut wq[..n]];
            let [rr, res, qr] = per_width!(sym, W => {
                gradient_values::<W>(m, p, (xs, gs), sigma, rs, out, &mut terms)
            });
            (acc.rr, acc.res, acc.qr) = (acc.rr + rr, acc.res + res, acc.qr + qr);
            if let Some((x_old, s, y)) = new.as_mut() {
                let (s, y) = (&mut s[local.clone()], &mut y[local.clone()]);
                let old = (&x_old[gl.clone()], &r_old[..n]);
                let weighted = [&mut ws[..n], &mut wy[..n]];
                per_width!(sym, W => pair_values::<W>(m, p, (xs, rs), old, [s, y], weighted));
            }
            let v = v.each_ref().map(|v| &v[..n]);
            for (p, sums) in pairs.iter().zip(&mut acc.pairs) {
                let add = pair_sums(&p.s[gl.clone()], &p.y[gl.clone()], v);
                sums.iter_mut().zip(add).for_each(|(a, b)| *a += b);
            }
            if let Some((_, s, y)) = new.as_ref() {
                let add = pair_sums(&s[local.clone()], &y[local.clone()], v);
                acc.pairs[n_pairs]
                    .iter_mut()
                    .zip(add)
                    .for_each(|(a, b)| *a += b);
            }
        });
        acc
    };
    let grad = reals_mut(grad);
    match new {
        None => grad
            .par_chunks_mut(task)
            .enumerate()
            .with_max_len(1)
            .map(|(t, r)| run(t, r, None))
            .reduce(GradientSums::zero, GradientSums::add),
        Some((x_old, pair)) => grad
            .par_chunks_mut(task)
            .zip(pair.s.par_chunks_mut(task))
            .zip(pair.y.par_chunks_mut(task))
            .enumerate()
            .with_max_len(1)
            .map(|(t, ((r, s), y))| run(t, r, Some((reals(x_old), s, y))))
            .reduce(GradientSums::zero, GradientSums::add),
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
        let mut d = self.recursion(self.pairs.len());
        self.write_direction(&mut d);
        if d.slope >= 0.0 {
            self.reset_memory();
            d = self.recursion(0);
            self.write_direction(&mut d);
        }
        self.direction = d;
        let f0 = self.cur.measures.energy;
        let mut alpha = 1.0;
        let mut rejected = 0;
        std::mem::swap(&mut self.cur.nonlinear, &mut self.trial.nonlinear);
        loop {
            let accepted = self.try_step(alpha, t + dt).is_ok()
                && self.trial.measures.energy <= f0 + ARMIJO * alpha * self.direction.slope;
            if accepted {
                break;
            }
            rejected += 1;
            alpha *= 0.5;
            if rejected >= MAX_BACKTRACKS {
                self.stalled = true;
                self.reset_memory();
                self.take_back_gradient(t)?;
                return Ok(StepReport {
                    dt,
                    rate: f64::NAN,
                    rejected,
                });
            }
        }
        self.accept();
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

    fn save(&self) -> Saved<'_> {
        let mut saved = Saved::default()
            .scalar("stalled", if self.stalled { 1.0 } else { 0.0 })
            .scalar("pairs", self.pairs.len() as f64)
            .array("phi_hat", SavedArray::Complex(self.cur.hat.view().into()));
        let (n0, n1, n2) = self.cur.hat.dim();
        let shape = [n0, n1, n2];
        // The Gram entries as they were accumulated, so that a resumed run is bitwise the
        // uninterrupted one (the inner products of the state are recomputed by the same sweep).
        let n = self.pairs.len();
        let gram = Array3::from_shape_fn((2, n, n), |(g, i, j)| {
            [&self.sy, &self.yy][g][i * MAX_MEMORY + j]
        });
        saved = saved.array("gram", SavedArray::Real(gram.into()));
        for (i, p) in self.pairs.iter().enumerate() {
            saved = saved
                .array(&format!("s_{i}"), SavedArray::Single(shape, p.s[..].into()))
                .array(&format!("y_{i}"), SavedArray::Single(shape, p.y[..].into()));
        }
        saved
    }

    fn restore(&mut self, saved: &mut Saved<'_>, t: f64) -> Result<(), String> {
        let transform = &self.ev.transform;
        self.cur
            .hat
            .assign(&saved::spectrum(saved, "phi_hat", transform)?);
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
            let transform = &self.ev.transform;
            let pair = Pair {
                s: saved::take_single(saved, &format!("s_{i}"), transform)?,
                y: saved::take_single(saved, &format!("y_{i}"), transform)?,
            };
            self.pairs.push_back(pair);
        }
        let n = n as usize;
        // An older checkpoint may lack the Gram, or hold it with the newest pair's column still
        // to come ("fresh" = 1): recompute it then.
        match saved.real("gram", &[2, n, n]) {
            Ok(gram) if saved.get("fresh").map_or(true, |f| f == 0.0) => {
                for ((g, i, j), v) in gram.indexed_iter() {
                    [&mut self.sy, &mut self.yy][g][i * MAX_MEMORY + j] = *v;
                }
            }
            _ => self.rebuild_gram(),
        }
        self.ev
            .evaluate(&mut self.cur, t, None, None)
            .map_err(|d| d.0)?;
        self.refresh_gradient();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The Gram matrix and the inner products ⟨s_i, r⟩_M, ⟨y_i, r⟩_M that the sweeps sum piece
    /// by piece equal direct sums over the spectrum to round-off (1e-11 of the largest entry),
    /// after 12 iterations with the area held, on boxes whose rows fill the pieces unevenly:
    /// 2D (rows of 18 values, 14 to a piece), odd-sized 3D (rows of 12), mirror axes (rows of
    /// 13, the last axis a DCT). A piece that summed the wrong values, or skipped the last
    /// partial piece of a task, would miss by O(1).
    #[test]
    fn piecewise_sums_equal_direct_inner_products() {
        for mut e in cases().into_iter().map(engine_with_area) {
            for i in 0..12 {
                e.step(i as f64, 1.0).expect("iteration");
            }
            let case = e.ev.grid.shape;
            let n = e.pairs.len();
            assert!(n >= 3, "{case:?}: {n} pairs");
            let (sy, yy) = (e.sy.clone(), e.yy.clone());
            let (sym, m) = (&e.ev.symbols, e.metric);
            let r = reals(flat(&e.grad));
            let direct: Vec<(f64, f64)> = e
                .pairs
                .iter()
                .map(|p| (dot_m(sym, m, &p.s, r), dot_m(sym, m, &p.y, r)))
                .collect();
            let summed: Vec<(f64, f64)> = (0..n).map(|i| (e.ip.s_r[i], e.ip.y_r[i])).collect();
            e.rebuild_gram();
            let largest = sy.iter().chain(&yy).fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..n {
                for j in 0..n {
                    let at = i * MAX_MEMORY + j;
                    for (what, a, b) in [("sy", sy[at], e.sy[at]), ("yy", yy[at], e.yy[at])] {
                        assert!(
                            (a - b).abs() <= 1e-11 * largest,
                            "{case:?}: {what}[{i}][{j}] {a} {b}"
                        );
                    }
                }
            }
            let scale = direct
                .iter()
                .fold(0.0f64, |a, d| a.max(d.0.abs()).max(d.1.abs()));
            for (i, (d, s)) in direct.iter().zip(&summed).enumerate() {
                assert!(
                    (d.0 - s.0).abs() <= 1e-11 * scale,
                    "{case:?}: ⟨s_{i}, r⟩ {} {}",
                    d.0,
                    s.0
                );
                assert!(
                    (d.1 - s.1).abs() <= 1e-11 * scale,
                    "{case:?}: ⟨y_{i}, r⟩ {} {}",
                    d.1,
                    s.1
                );
            }
        }
    }

    /// The newest pair is the step and the change of r: s = φ̂_new − φ̂_old and
    /// y = r_new − r_old to single precision (2⁻²⁴ of the largest value, the rounding of the
    /// stored pair), although r_new is written over r_old in the same sweep. A sweep that read
    /// r after overwriting it would store y = 0.
    #[test]
    fn the_newest_pair_is_the_step_and_the_change_of_r() {
        for mut e in cases().into_iter().map(engine_with_area) {
            for i in 0..6 {
                let (x_old, r_old) = (e.cur.hat.clone(), e.grad.clone());
                let kept = e.pairs.len();
                e.step(i as f64, 1.0).expect("iteration");
                assert!(e.pairs.len() > kept.min(4), "iteration {i}: no pair kept");
                let newest = e.pairs.back().expect("a pair");
                let s = (&e.cur.hat - &x_old).mapv(|v| [v.re, v.im]);
                let y = (&e.grad - &r_old).mapv(|v| [v.re, v.im]);
                for (what, exact, stored) in [("s", s, &newest.s), ("y", y, &newest.y)] {
                    let exact: Vec<f64> = exact.iter().flatten().copied().collect();
                    let largest = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                    assert!(largest > 0.0, "iteration {i}: {what} = 0");
                    for (a, b) in exact.iter().zip(stored.iter()) {
                        let tol = largest * f64::from(f32::EPSILON);
                        assert!((a - f64::from(*b)).abs() <= tol, "{what}: {a} {b}");
                    }
                }
            }
        }
    }

    /// A line search that accepts nothing hands the current state's ĝ back intact: the trial
    /// evaluated meanwhile wrote its own ĝ into the spectrum it took, and the gradient and the
    /// residual formed afterwards (by `set_area`) equal those before, to round-off (1e-12).
    #[test]
    fn a_failed_line_search_leaves_the_gradient_of_the_current_state() {
        for mut e in cases().into_iter().map(engine_with_area) {
            e.step(0.0, 1.0).expect("iteration");
            let (r, residual) = (e.grad.clone(), e.residual);
            let mut d = e.recursion(e.pairs.len());
            e.write_direction(&mut d);
            e.direction = d;
            std::mem::swap(&mut e.cur.nonlinear, &mut e.trial.nonlinear);
            e.try_step(0.5, 1.0).expect("trial");
            e.take_back_gradient(1.0).expect("evaluation");
            e.set_area(e.area);
            let largest = r.iter().fold(0.0f64, |a, v| a.max(v.norm()));
            let change = (&e.grad - &r).iter().fold(0.0f64, |a, v| a.max(v.norm()));
            assert!(change <= 1e-12 * largest, "max|Δr| = {change:e}");
            assert!((e.residual - residual).abs() <= 1e-12 * residual);
        }
    }

    /// The iterates stay spectra of real fields. Every direction of 30 iterations is one to the
    /// last bit: a value on a self-conjugate plane is the conjugate of its partner's (the
    /// Hermitian projection changes nothing). The state starts so ([`Evaluator::state_of`]
    /// projects it), r is so (ĝ is projected, M and q/φ̂ are even in k), and each pair's values
    /// are formed and rounded value by value, so d' is; a rounding that depended on where a
    /// value lies breaks it (half-precision pairs with a scale per piece failed at iteration 1).
    /// And after them φ̂ equals the transform of its own φ, with the area and energy measured
    /// from that φ equal to the state's, to round-off (1e-12): a part of φ̂ off the real
    /// fields' spectra is dropped by the inverse transform but counted by the area sums, so
    /// the area held would differ from φ's, and with σ < 0 that part grows (scaling one value
    /// of d' on the plane j2 = 0 by 1 + 1e-3 fails the first check at direction 0 and, with
    /// that check removed, this one by max|Δφ̂| = 2e-2 of max|φ̂|).
    #[test]
    fn iterates_stay_spectra_of_real_fields() {
        for mut e in cases().into_iter().map(engine_with_area) {
            let case = e.ev.grid.shape;
            for i in 0..30 {
                let mut d = e.recursion(e.pairs.len());
                e.write_direction(&mut d);
                let mut projected = e.dir.clone();
                e.ev.transform.hermitian_symmetrize(&mut projected);
                assert!(projected == e.dir, "{case:?}: direction {i}");
                e.step(i as f64, 1.0).expect("iteration");
            }
            let phi = e.cur.phi.clone();
            let fresh = e.ev.state_of(&phi, 30.0).expect("evaluation");
            let largest = e.cur.hat.iter().fold(0.0f64, |a, v| a.max(v.norm()));
            let ghost = (&fresh.hat - &e.cur.hat)
                .iter()
                .fold(0.0f64, |a, v| a.max(v.norm()));
            assert!(ghost <= 1e-12 * largest, "{case:?}: max|Δφ̂| = {ghost:e}");
            let (held, measured) = (e.cur.measures, fresh.measures);
            for (what, a, b) in [
                ("area", held.area, measured.area),
                ("energy", held.energy, measured.energy),
            ] {
                assert!((a - b).abs() <= 1e-12 * a.abs(), "{case:?}: {what} {a} {b}");
            }
        }
    }

    /// Boxes whose rows fill the pieces unevenly: 2D (rows of 18 values, 14 to a piece),
    /// odd-sized 3D (rows of 12), mirror axes (rows of 13, the last axis a DCT).
    fn cases() -> Vec<serde_json::Value> {
        vec![
            json!({"dim": 2, "n": [36, 34], "initial": {"shape": "ellipsoid", "axes": [12.0, 8.0]}}),
            json!({"dim": 3, "n": [21, 20, 23], "initial": {"shape": "ellipsoid", "axes": [7.0, 5.0, 5.0]}}),
            json!({"dim": 3, "n": [24, 22, 26], "symmetry": ["x", "z"],
                   "initial": {"shape": "ellipsoid", "axes": [8.0, 5.0, 5.0]}}),
        ]
    }

    /// An L-BFGS engine (memory 5) on `case`, holding its initial area.
    fn engine_with_area(mut case: serde_json::Value) -> RelaxEngine {
        let fields = json!({"h": 1.0, "eps": 1.0, "method": "spectral",
            "dynamics": "relaxational", "dt": 1.0, "max_steps": 12, "lbfgs_memory": 5});
        case.as_object_mut()
            .unwrap()
            .extend(fields.as_object().unwrap().clone());
        let scene = crate::problem::config::from_value(case).expect("scene");
        let p = crate::problem::setup::build(&scene).expect("problem");
        let mut e = RelaxEngine::new(&scene, p.grid, p.c0, p.phi).expect("engine");
        let target = e.measures().area;
        e.set_area(crate::engines::AreaConstraint {
            method: AreaMethod::Projection,
            alpha: 0.0,
            target,
        });
        e
    }
}
