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
//! form): its inner products are all combinations of ⟨s_i, r⟩, ⟨y_i, r⟩, ⟨q, s_i⟩, ⟨q, y_i⟩,
//! ⟨r, r⟩, ⟨q, r⟩ (one sweep, [`RelaxEngine::inner_products`]) and of the Gram entries
//! ⟨s_i, y_j⟩, ⟨y_i, y_j⟩ (kept, the newest pair's added in the same sweep), so the direction
//! d = −c_r r − Σ c_y,i y_i − Σ c_s,i s_i + c_q q is written in a second sweep. q is computed
//! from φ̂ where it is needed, and |k|², w and M(k) from the per-axis tables. An iteration is
//! six sweeps besides the evaluation: the inner products, the direction, the retraction's sums
//! and its write (which also writes the evaluation's inverse inputs), the multiplier's sums, and
//! the gradient with the new pair.

use crate::config::{AreaMethod, Scene};
use crate::engine::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::grid::Grid;
use crate::model::{Measures, C0};
use crate::numerics::nearest_root;
use crate::spectral::evaluator::{Evaluator, ExplicitTerm, State, Symbols};
use ndarray::Array3;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::collections::VecDeque;

/// Armijo constant: accept when F(φ + αd) ≤ F(φ) + c α ⟨∇F, d⟩.
const ARMIJO: f64 = 1e-4;
/// Backtracking halvings before the line search gives up.
const MAX_BACKTRACKS: usize = 40;
/// Values per piece of a row in [`RelaxEngine::inner_products`] (its per-piece factors stay in
/// L1).
const PIECE: usize = 64;
/// Largest L-BFGS memory (the coefficient recursion keeps its sums in fixed arrays).
pub const MAX_MEMORY: usize = 32;

/// One stored L-BFGS pair (s, y), flattened like the spectrum.
struct Pair {
    s: Vec<Complex64>,
    y: Vec<Complex64>,
}

/// The constants of the preconditioner M(k) and of q/φ̂ = c_σ k²/M (|k|² and w come from the
/// per-axis tables).
#[derive(Clone, Copy)]
struct Metric {
    e2: f64,
    c_sigma: f64,
}

impl Metric {
    /// M(k) = 2ε⁴k⁴ + 8 + 8ε²k² at |k|² = `k`.
    #[inline(always)]
    fn at(&self, k: f64) -> f64 {
        2.0 * self.e2 * self.e2 * k * k + 8.0 + 8.0 * self.e2 * k
    }
}

/// Re(u v*).
#[inline(always)]
fn re_dot(u: Complex64, v: Complex64) -> f64 {
    u.re * v.re + u.im * v.im
}

/// Σ_j w_j Re(u_j v_j*) in four interleaved partial sums (independent chains: the loop runs
/// at the adders' throughput, not their latency).
#[inline(always)]
fn weighted_dot(w: &[f64], u: &[Complex64], v: &[Complex64]) -> f64 {
    let mut acc = [0.0; 4];
    let quads = w
        .chunks_exact(4)
        .zip(u.chunks_exact(4))
        .zip(v.chunks_exact(4));
    for ((w, u), v) in quads {
        for j in 0..4 {
            acc[j] += w[j] * re_dot(u[j], v[j]);
        }
    }
    let tail = w.len() - w.len() % 4;
    let rest: f64 = (tail..w.len()).map(|j| w[j] * re_dot(u[j], v[j])).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}

/// The sums of [`RelaxEngine::inner_products`], indexed by pair (oldest first).
#[derive(Clone, Copy)]
struct InnerProducts {
    s_r: [f64; MAX_MEMORY],
    y_r: [f64; MAX_MEMORY],
    q_y: [f64; MAX_MEMORY],
    rr: f64,
    qr: f64,
}

impl InnerProducts {
    fn zero() -> Self {
        InnerProducts {
            s_r: [0.0; MAX_MEMORY],
            y_r: [0.0; MAX_MEMORY],
            q_y: [0.0; MAX_MEMORY],
            rr: 0.0,
            qr: 0.0,
        }
    }

    fn add(mut self, o: Self) -> Self {
        for (a, b) in [
            (&mut self.s_r, &o.s_r),
            (&mut self.y_r, &o.y_r),
            (&mut self.q_y, &o.q_y),
        ] {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        }
        self.rr += o.rr;
        self.qr += o.qr;
        self
    }

    /// Drop the oldest pair's entries (the memory dropped that pair).
    fn shift(&mut self) {
        for a in [&mut self.s_r, &mut self.y_r, &mut self.q_y] {
            a.copy_within(1.., 0);
        }
    }
}

/// The unprojected direction d' = −c_r r − Σ c_y,i y_i − Σ c_s,i s_i over the newest `n`
/// pairs (from position `off`), its projection coefficient (d = d' + c_q q) and slope ⟨r, d⟩_M.
#[derive(Clone, Copy)]
struct Direction {
    n: usize,
    off: usize,
    c_r: f64,
    c_y: [f64; MAX_MEMORY],
    c_s: [f64; MAX_MEMORY],
    c_q: f64,
    slope: f64,
}

/// The L-BFGS relaxation engine.
pub struct RelaxEngine {
    ev: Evaluator,
    cur: State,
    trial: State,
    metric: Metric,
    /// ⟨q, q⟩_M of the current state.
    qq: f64,
    /// Preconditioned projected gradient r of the current state.
    grad: Array3<Complex64>,
    /// r of the trial state.
    grad_trial: Array3<Complex64>,
    /// Search direction.
    dir: Array3<Complex64>,
    /// Pairs, oldest first.
    pairs: VecDeque<Pair>,
    /// Pairs not in use (kept so that no iteration allocates once the memory has filled).
    spare_pairs: Vec<Pair>,
    /// Gram entries ⟨s_i, y_j⟩_M and ⟨y_i, y_j⟩_M, row-major `i · MAX_MEMORY + j`.
    sy: Vec<f64>,
    yy: Vec<f64>,
    /// The newest pair's ⟨s_j, y_new⟩ and ⟨y_j, y_new⟩ are not known yet: they are
    /// ⟨s_j, r_new⟩ − ⟨s_j, r_old⟩ and ⟨y_j, r_new⟩ − ⟨y_j, r_old⟩, the first terms from the
    /// next iteration's inner products, the second from `last`.
    fresh: bool,
    /// This iteration's inner products (aligned with the pairs' positions).
    last: InnerProducts,
    /// This iteration's direction.
    direction: Direction,
    /// The accepted step's α and its total multiple of q, α c_q + τ (s = α d' + that × q).
    taken: (f64, f64),
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
        let mut ev = Evaluator::new(grid, scene.eps, c0, scene.laplacian, ExplicitTerm::Gradient);
        let cur = ev.state_of(&phi, 0.0)?;
        let zeros = Array3::zeros(cur.hat.raw_dim());
        let memory = scene.lbfgs_memory.min(MAX_MEMORY);
        let mut e = RelaxEngine {
            trial: ev.blank(),
            metric: Metric {
                e2: scene.eps * scene.eps,
                c_sigma: 3.0 / std::f64::consts::SQRT_2 * scene.eps,
            },
            ev,
            cur,
            qq: 0.0,
            grad: zeros.clone(),
            grad_trial: zeros.clone(),
            dir: zeros,
            pairs: VecDeque::with_capacity(memory),
            spare_pairs: Vec::with_capacity(memory + 1),
            sy: vec![0.0; MAX_MEMORY * MAX_MEMORY],
            yy: vec![0.0; MAX_MEMORY * MAX_MEMORY],
            fresh: false,
            last: InnerProducts::zero(),
            direction: Direction {
                n: 0,
                off: 0,
                c_r: 0.0,
                c_y: [0.0; MAX_MEMORY],
                c_s: [0.0; MAX_MEMORY],
                c_q: 0.0,
                slope: 0.0,
            },
            taken: (0.0, 0.0),
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
        self.fresh = false;
    }

    /// σ, r and the residual of the current state (no pair is formed).
    fn refresh_gradient(&mut self) {
        let (qq, gq) = multiplier_sums(&self.ev.symbols, self.metric, &self.cur);
        let sigma = self.multiplier(qq, gq);
        let (res_sq, _, _) = gradient_sweep(
            &self.ev.symbols,
            self.metric,
            &self.cur,
            sigma,
            self.grad.as_slice_mut().expect("standard layout"),
            None,
        );
        (self.sigma, self.qq) = (sigma, qq);
        self.residual = (res_sq / self.ev.grid.full_volume()).sqrt();
    }

    /// σ = −⟨ĝ, q⟩/⟨q, q⟩_M (0 without an area constraint).
    fn multiplier(&self, qq: f64, gq: f64) -> f64 {
        if self.area.method == AreaMethod::None || qq <= 0.0 {
            0.0
        } else {
            -gq / qq
        }
    }

    /// One sweep over r, q (from φ̂) and the pairs: ⟨s_i, r⟩_M, ⟨y_i, r⟩_M, ⟨q, y_i⟩_M,
    /// ⟨r, r⟩_M and ⟨q, r⟩_M. Rows are cut into pieces of at most [`PIECE`] values; per piece
    /// the factors wM and q are formed once and each pair's sums run over the piece's
    /// contiguous values.
    fn inner_products(&self) -> InnerProducts {
        let sym = &self.ev.symbols;
        let m = self.metric;
        let (r, hat) = (flat(&self.grad), flat(&self.cur.hat));
        let pairs = &self.pairs;
        let s2 = sym.row_len();
        let (rows, per_task) = (r.len() / s2, sym.task_len() / s2);
        (0..rows.div_ceil(per_task))
            .into_par_iter()
            .map(|t| {
                let mut acc = InnerProducts::zero();
                let mut wm = [0.0; PIECE];
                let mut q = [Complex64::default(); PIECE];
                for row in t * per_task..((t + 1) * per_task).min(rows) {
                    let (kb, wb) = sym.row(row);
                    for start in (0..s2).step_by(PIECE) {
                        let len = PIECE.min(s2 - start);
                        let range = row * s2 + start..row * s2 + start + len;
                        for l in 0..len {
                            let k = kb + sym.k2[2][start + l];
                            let big_m = m.at(k);
                            wm[l] = wb * sym.weight[2][start + l] * big_m;
                            q[l] = hat[range.start + l] * (m.c_sigma * k / big_m);
                        }
                        let (wm, q, r) = (&wm[..len], &q[..len], &r[range.clone()]);
                        acc.rr += weighted_dot(wm, r, r);
                        acc.qr += weighted_dot(wm, q, r);
                        for (j, p) in pairs.iter().enumerate() {
                            let (sj, yj) = (&p.s[range.clone()], &p.y[range.clone()]);
                            acc.s_r[j] += weighted_dot(wm, sj, r);
                            acc.y_r[j] += weighted_dot(wm, yj, r);
                            acc.q_y[j] += weighted_dot(wm, q, yj);
                        }
                    }
                }
                acc
            })
            .reduce(InnerProducts::zero, InnerProducts::add)
    }

    /// The newest pair's Gram column from two consecutive iterations' inner products (see
    /// `fresh`), then keep `ip` as this iteration's.
    fn record_gram(&mut self, ip: &InnerProducts) {
        let n = self.pairs.len();
        if self.fresh && n > 0 {
            let new = n - 1;
            for j in 0..new {
                self.sy[j * MAX_MEMORY + new] = ip.s_r[j] - self.last.s_r[j];
                let yy = ip.y_r[j] - self.last.y_r[j];
                self.yy[j * MAX_MEMORY + new] = yy;
                self.yy[new * MAX_MEMORY + j] = yy;
            }
        }
        self.fresh = false;
        self.last = *ip;
    }

    /// The two-loop recursion on coefficients (module documentation) with the newest `n` pairs
    /// (0 gives the preconditioned steepest descent). Leaves `c_q` 0 and `slope` = ⟨r, d'⟩_M;
    /// [`RelaxEngine::write_direction`] completes both.
    fn recursion(&self, ip: &InnerProducts, n: usize) -> Direction {
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
            n,
            off,
            c_r: gamma,
            c_y,
            c_s,
            c_q: 0.0,
            slope: -rz,
        }
    }

    /// Write d' into `dir`, a row at a time, each pair added over the row's contiguous values,
    /// and complete `d`: the tangent projection d = d' − (⟨q, d'⟩_M/⟨q, q⟩_M) q (kept as the
    /// coefficient c_q: q is formed from φ̂ where it is used) and the slope ⟨r, d⟩_M.
    fn write_direction(&mut self, d: &mut Direction) {
        let sym = &self.ev.symbols;
        let m = self.metric;
        let off = d.off;
        let pairs = &self.pairs;
        let (r, hat) = (flat(&self.grad), flat(&self.cur.hat));
        let (s2, task) = (sym.row_len(), sym.task_len());
        let (c_r, c_y, c_s) = (d.c_r, d.c_y, d.c_s);
        let qd: f64 = self
            .dir
            .as_slice_mut()
            .expect("standard layout")
            .par_chunks_mut(task)
            .enumerate()
            .map(|(t, out)| {
                let mut qd = 0.0;
                for (rr, out) in out.chunks_exact_mut(s2).enumerate() {
                    let row = t * task / s2 + rr;
                    let range = row * s2..(row + 1) * s2;
                    let (r, hat) = (&r[range.clone()], &hat[range.clone()]);
                    for (o, r) in out.iter_mut().zip(r) {
                        *o = -(r * c_r);
                    }
                    for (j, p) in pairs.iter().skip(off).enumerate() {
                        let (cy, cs) = (c_y[j], c_s[j]);
                        let (y, s) = (&p.y[range.clone()], &p.s[range.clone()]);
                        for ((o, y), s) in out.iter_mut().zip(y).zip(s) {
                            *o -= y * cy + s * cs;
                        }
                    }
                    let (kb, wb) = sym.row(row);
                    for (l, o) in out.iter().enumerate() {
                        let k = kb + sym.k2[2][l];
                        // w M ⟨q, d'⟩ with q = (c_σ k²/M) φ̂: the M cancels.
                        qd += wb * sym.weight[2][l] * m.c_sigma * k * re_dot(hat[l], *o);
                    }
                }
                qd
            })
            .sum();
        let project = self.area.method != AreaMethod::None && self.qq > 0.0;
        d.c_q = if project { -qd / self.qq } else { 0.0 };
        d.slope += d.c_q * self.last.qr;
    }

    /// Sums of the area of t + τq, t = φ̂ + α d: (A_tt, A_tq, A_qq) with A(t + τq) =
    /// A_tt + 2τ A_tq + τ² A_qq. A read-only sweep.
    fn retraction_sums(&self, alpha: f64) -> (f64, f64, f64) {
        let sym = &self.ev.symbols;
        let m = self.metric;
        let (x, d) = (flat(&self.cur.hat), flat(&self.dir));
        let along_q = alpha * self.direction.c_q;
        let s2 = sym.row_len();
        let (rows, per_task) = (x.len() / s2, sym.task_len() / s2);
        let [a, b, c] = (0..rows.div_ceil(per_task))
            .into_par_iter()
            .map(|t| {
                let mut acc = [0.0; 3];
                for row in t * per_task..((t + 1) * per_task).min(rows) {
                    let (kb, wb) = sym.row(row);
                    for l in 0..s2 {
                        let i = row * s2 + l;
                        let k = kb + sym.k2[2][l];
                        let aw = sym.area_prefactor * k * (wb * sym.weight[2][l]);
                        let qi = x[i] * (m.c_sigma * k / m.at(k));
                        let tv = x[i] + d[i] * alpha + qi * along_q;
                        acc[0] += aw * tv.norm_sqr();
                        acc[1] += aw * re_dot(tv, qi);
                        acc[2] += aw * qi.norm_sqr();
                    }
                }
                acc
            })
            .reduce(|| [0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
        (a, b, c)
    }

    /// The trial state φ̂ + α d' + `along_q` q into `trial.hat`, with the evaluation's inverse
    /// inputs (see [`Evaluator::finish`]); returns its area.
    fn write_trial(&mut self, alpha: f64, along_q: f64) -> f64 {
        let sym = &self.ev.symbols;
        let m = self.metric;
        let (x, d) = (flat(&self.cur.hat), flat(&self.dir));
        let (s2, task) = (sym.row_len(), sym.task_len());
        let hat = self.trial.hat.as_slice_mut().expect("standard layout");
        let copy = self
            .trial
            .nonlinear
            .as_slice_mut()
            .expect("standard layout");
        let lap = self.ev.spare.as_slice_mut().expect("standard layout");
        hat.par_chunks_mut(task)
            .zip(copy.par_chunks_mut(task))
            .zip(lap.par_chunks_mut(task))
            .enumerate()
            .map(|(t, ((hat, copy), lap))| {
                let mut area = 0.0;
                for (j, h) in hat.iter_mut().enumerate() {
                    let i = t * task + j;
                    let l = j % s2;
                    let (kb, wb) = sym.row(i / s2);
                    let k = kb + sym.k2[2][l];
                    let qi = x[i] * (m.c_sigma * k / m.at(k));
                    let v = x[i] + d[i] * alpha + qi * along_q;
                    *h = v;
                    copy[j] = v;
                    lap[j] = v * (-k);
                    area += sym.area_prefactor * k * (wb * sym.weight[2][l]) * v.norm_sqr();
                }
                area
            })
            .sum()
    }

    /// Trial state φ̂ + α d, retracted onto A = A0 along q, evaluated; on success `taken` holds
    /// α and the step's total multiple of q. `Err` if the retraction has no real root or the
    /// evaluation diverged.
    fn try_step(&mut self, alpha: f64, t: f64) -> Result<(), ()> {
        let tau = if self.area.method == AreaMethod::None {
            0.0
        } else {
            let (a, b, c) = self.retraction_sums(alpha);
            nearest_root(c, b, a - self.area.target, 0.0).ok_or(())?
        };
        let along_q = alpha * self.direction.c_q + tau;
        let area = self.write_trial(alpha, along_q);
        self.taken = (alpha, along_q);
        self.ev
            .finish(&mut self.trial, area, t, None, None)
            .map(|_| ())
            .map_err(|_| ())
    }

    /// ⟨s_new, y_j⟩_M for every pair j before the new one, from s_new = α d' + β q:
    /// α (−c_r ⟨r, y_j⟩ − Σ c_y,i ⟨y_i, y_j⟩ − Σ c_s,i ⟨s_i, y_j⟩) + β ⟨q, y_j⟩.
    fn new_pair_row(&self) -> [f64; MAX_MEMORY] {
        let d = &self.direction;
        let (alpha, beta) = self.taken;
        let mut row = [0.0; MAX_MEMORY];
        for (j, v) in row.iter_mut().enumerate().take(self.pairs.len()) {
            let dy = -d.c_r * self.last.y_r[j]
                - (0..d.n)
                    .map(|i| {
                        let p = i + d.off;
                        d.c_y[i] * self.yy[p * MAX_MEMORY + j]
                            + d.c_s[i] * self.sy[p * MAX_MEMORY + j]
                    })
                    .sum::<f64>();
            *v = alpha * dy + beta * self.last.q_y[j];
        }
        row
    }

    /// Accept the trial state: its σ, r and residual, and the pair (s, y) = (x_new − x,
    /// r_new − r) kept if ⟨y, s⟩_M > 0 (the oldest dropped when the memory is full).
    fn accept(&mut self) {
        let (qq, gq) = multiplier_sums(&self.ev.symbols, self.metric, &self.trial);
        let sigma = self.multiplier(qq, gq);
        let len = self.cur.hat.len();
        let mut pair = self.spare_pairs.pop().unwrap_or_else(|| Pair {
            s: vec![Complex64::default(); len],
            y: vec![Complex64::default(); len],
        });
        let (res_sq, ys, yy) = gradient_sweep(
            &self.ev.symbols,
            self.metric,
            &self.trial,
            sigma,
            self.grad_trial.as_slice_mut().expect("standard layout"),
            Some((flat(&self.cur.hat), flat(&self.grad), &mut pair)),
        );
        if ys > 0.0 {
            let mut row = self.new_pair_row();
            if self.pairs.len() == self.memory {
                self.spare_pairs.extend(self.pairs.pop_front());
                shift_gram(&mut self.sy, self.memory);
                shift_gram(&mut self.yy, self.memory);
                self.last.shift();
                row.copy_within(1.., 0);
            }
            let new = self.pairs.len();
            self.sy[new * MAX_MEMORY..new * MAX_MEMORY + new].copy_from_slice(&row[..new]);
            self.sy[new * MAX_MEMORY + new] = ys;
            self.yy[new * MAX_MEMORY + new] = yy;
            self.pairs.push_back(pair);
            self.fresh = true;
        } else {
            self.spare_pairs.push(pair);
        }
        std::mem::swap(&mut self.cur, &mut self.trial);
        std::mem::swap(&mut self.grad, &mut self.grad_trial);
        (self.sigma, self.qq) = (sigma, qq);
        self.residual = (res_sq / self.ev.grid.full_volume()).sqrt();
    }

    /// Gram entries of every pair (after a restore), by direct inner products.
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
        self.fresh = false;
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

/// (⟨s_a, y_b⟩_M, ⟨y_a, y_b⟩_M).
fn pair_dots(sym: &Symbols, m: Metric, a: &Pair, b: &Pair) -> (f64, f64) {
    let s2 = sym.row_len();
    let mut acc = (0.0, 0.0);
    for (i, (sa, ya)) in a.s.iter().zip(&a.y).enumerate() {
        let (kb, wb) = sym.row(i / s2);
        let k = kb + sym.k2[2][i % s2];
        let wm = wb * sym.weight[2][i % s2] * m.at(k);
        acc.0 += wm * re_dot(*sa, b.y[i]);
        acc.1 += wm * re_dot(*ya, b.y[i]);
    }
    acc
}

/// (⟨q, q⟩_M, ⟨ĝ, q⟩) of `state`, q = M⁻¹â = (c_σ k²/M) φ̂, ĝ in `state.nonlinear`.
fn multiplier_sums(sym: &Symbols, m: Metric, state: &State) -> (f64, f64) {
    let (hat, g) = (flat(&state.hat), flat(&state.nonlinear));
    let s2 = sym.row_len();
    let (rows, per_task) = (hat.len() / s2, sym.task_len() / s2);
    (0..rows.div_ceil(per_task))
        .into_par_iter()
        .map(|t| {
            let mut acc = (0.0, 0.0);
            for row in t * per_task..((t + 1) * per_task).min(rows) {
                let (kb, wb) = sym.row(row);
                for l in 0..s2 {
                    let i = row * s2 + l;
                    let k = kb + sym.k2[2][l];
                    let (big_m, w) = (m.at(k), wb * sym.weight[2][l]);
                    let qi = hat[i] * (m.c_sigma * k / big_m);
                    acc.0 += w * big_m * qi.norm_sqr();
                    acc.1 += w * re_dot(g[i], qi);
                }
            }
            acc
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// r = M⁻¹ĝ + σq into `grad` (r(0) = 0), returning Σ_{k≠0} w |ĝ + σâ|² (the residual's
/// square × |Ω|); with `pair` = (x_old, r_old, pair) also s = φ̂ − x_old and y = r − r_old into
/// the pair, returning ⟨y, s⟩_M and ⟨y, y⟩_M (else zeros).
fn gradient_sweep(
    sym: &Symbols,
    m: Metric,
    state: &State,
    sigma: f64,
    grad: &mut [Complex64],
    pair: Option<(&[Complex64], &[Complex64], &mut Pair)>,
) -> (f64, f64, f64) {
    let (hat, g) = (flat(&state.hat), flat(&state.nonlinear));
    let (s2, task) = (sym.row_len(), sym.task_len());
    // Value i = row · s2 + l of a task starting at a row boundary.
    let body = |i: usize, (kb, wb): (f64, f64), l: usize, r: &mut Complex64| {
        let k = kb + sym.k2[2][l];
        let (big_m, w) = (m.at(k), wb * sym.weight[2][l]);
        if k == 0.0 {
            *r = Complex64::default();
            return (w, big_m, 0.0);
        }
        *r = g[i] / big_m + hat[i] * (sigma * m.c_sigma * k / big_m);
        (w, big_m, w * (*r * big_m).norm_sqr())
    };
    match pair {
        None => {
            let res: f64 = grad
                .par_chunks_mut(task)
                .enumerate()
                .map(|(t, rs)| {
                    let mut sum = 0.0;
                    for (rr, rs) in rs.chunks_exact_mut(s2).enumerate() {
                        let row = t * task / s2 + rr;
                        let base = sym.row(row);
                        for (l, r) in rs.iter_mut().enumerate() {
                            sum += body(row * s2 + l, base, l, r).2;
                        }
                    }
                    sum
                })
                .sum();
            (res, 0.0, 0.0)
        }
        Some((x_old, r_old, pair)) => grad
            .par_chunks_mut(task)
            .zip(pair.s.par_chunks_mut(task))
            .zip(pair.y.par_chunks_mut(task))
            .enumerate()
            .map(|(t, ((rs, ss), ys))| {
                let mut acc = (0.0, 0.0, 0.0);
                let rows = rs
                    .chunks_exact_mut(s2)
                    .zip(ss.chunks_exact_mut(s2))
                    .zip(ys.chunks_exact_mut(s2));
                for (rr, ((rs, ss), ys)) in rows.enumerate() {
                    let row = t * task / s2 + rr;
                    let base = sym.row(row);
                    for (l, ((r, s), y)) in rs.iter_mut().zip(ss).zip(ys).enumerate() {
                        let i = row * s2 + l;
                        let (w, big_m, res) = body(i, base, l, r);
                        *s = hat[i] - x_old[i];
                        *y = *r - r_old[i];
                        let wm = w * big_m;
                        acc.0 += res;
                        acc.1 += wm * re_dot(*y, *s);
                        acc.2 += wm * y.norm_sqr();
                    }
                }
                acc
            })
            .reduce(|| (0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2)),
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
        let ip = self.inner_products();
        self.record_gram(&ip);
        let mut d = self.recursion(&ip, self.pairs.len());
        self.write_direction(&mut d);
        if d.slope >= 0.0 {
            self.reset_memory();
            d = self.recursion(&ip, 0);
            self.write_direction(&mut d);
        }
        self.direction = d;
        let f0 = self.cur.measures.energy;
        let mut alpha = 1.0;
        let mut rejected = 0;
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

    fn save(&self) -> Saved {
        let mut saved = Saved::default()
            .scalar("stalled", if self.stalled { 1.0 } else { 0.0 })
            .scalar("pairs", self.pairs.len() as f64)
            .array("phi_hat", SavedArray::Complex(self.cur.hat.clone()));
        let shape = self.cur.hat.raw_dim();
        let array = |v: &Vec<Complex64>| {
            SavedArray::Complex(Array3::from_shape_vec(shape, v.clone()).expect("spectral shape"))
        };
        // The Gram entries and this iteration's inner products as they were accumulated, so
        // that a resumed run is bitwise the uninterrupted one.
        let n = self.pairs.len();
        let gram = Array3::from_shape_fn((2, n, n), |(g, i, j)| {
            [&self.sy, &self.yy][g][i * MAX_MEMORY + j]
        });
        let last = Array3::from_shape_fn((1, 2, n), |(_, g, j)| {
            [&self.last.s_r, &self.last.y_r][g][j]
        });
        saved = saved
            .scalar("fresh", if self.fresh { 1.0 } else { 0.0 })
            .array("gram", SavedArray::Real(gram))
            .array("inner_products", SavedArray::Real(last));
        for (i, p) in self.pairs.iter().enumerate() {
            saved = saved
                .scalar(&format!("rho_{i}"), 1.0 / self.sy[i * MAX_MEMORY + i])
                .scalar(&format!("yy_{i}"), self.yy[i * MAX_MEMORY + i])
                .array(&format!("s_{i}"), array(&p.s))
                .array(&format!("y_{i}"), array(&p.y));
        }
        saved
    }

    fn restore(&mut self, saved: &Saved, t: f64) -> Result<(), String> {
        let shape = self.cur.hat.shape().to_vec();
        self.cur.hat.assign(saved.complex("phi_hat", &shape)?);
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
            let read = |name: &str| -> Result<Vec<Complex64>, String> {
                Ok(saved.complex(name, &shape)?.iter().copied().collect())
            };
            let pair = Pair {
                s: read(&format!("s_{i}"))?,
                y: read(&format!("y_{i}"))?,
            };
            self.pairs.push_back(pair);
        }
        let n = n as usize;
        match (
            saved.real("gram", &[2, n, n]),
            saved.real("inner_products", &[1, 2, n]),
        ) {
            (Ok(gram), Ok(last)) => {
                for ((g, i, j), v) in gram.indexed_iter() {
                    [&mut self.sy, &mut self.yy][g][i * MAX_MEMORY + j] = *v;
                }
                for ((_, g, j), v) in last.indexed_iter() {
                    [&mut self.last.s_r, &mut self.last.y_r][g][j] = *v;
                }
                self.fresh = saved.get("fresh")? != 0.0;
            }
            // A checkpoint from before the Gram was kept: recompute it.
            _ => self.rebuild_gram(),
        }
        self.ev
            .evaluate(&mut self.cur, t, None, None)
            .map_err(|d| d.0)?;
        self.refresh_gradient();
        Ok(())
    }
}
