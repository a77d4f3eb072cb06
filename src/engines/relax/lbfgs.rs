//! The L-BFGS iteration: the stored pairs, the coefficient recursion, the line search with its
//! retraction onto the area, and the memory's bookkeeping.

use super::couple::Couple;
use super::sweeps::{area_values, direction_piece, gradient_sweep, pair_dots, trial_values};
use super::RelaxEngine;
use crate::engines::numerics::{nearest_root, sum_in_fixed_tree};
use crate::engines::spectral::evaluator::{Evaluator, ExplicitTerm, Metric};
use crate::engines::spectral::pieces::{for_each_piece, per_width, reals, reals_mut, PIECE};
use crate::engines::{AreaConstraint, Diverged, Rejection, StepError};
use crate::problem::config::{AreaMethod, Scene};
use crate::problem::grid::Grid;
use crate::problem::model::{Measures, C0};
use ndarray::Array3;
use num_complex::Complex64;
use rayon::prelude::*;
use std::collections::VecDeque;

/// Relative departure |A − A0|/A0 above which a state counts as off the area constraint
/// ([`RelaxEngine::retract_start`]); accepted states are on it to round-off.
const OFF_CONSTRAINT: f64 = 1e-10;

/// Armijo constant: accept when F(φ + αd) ≤ F(φ) + c α ⟨∇F, d⟩.
pub(super) const ARMIJO: f64 = 1e-4;
/// Backtracking halvings before the line search gives up.
pub(super) const MAX_BACKTRACKS: usize = 40;
/// Largest L-BFGS memory (the coefficient recursion keeps its sums in fixed arrays): the
/// scene's limit on `lbfgs_memory`.
pub(super) use crate::problem::config::MAX_LBFGS_MEMORY as MAX_MEMORY;

/// One stored L-BFGS pair (s, y), flattened like the spectrum as interleaved (re, im) reals, in
/// single precision (see the module documentation).
pub(super) struct Pair {
    pub(super) s: Vec<f32>,
    pub(super) y: Vec<f32>,
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
pub(super) struct InnerProducts {
    pub(super) s_r: [f64; MAX_MEMORY],
    pub(super) y_r: [f64; MAX_MEMORY],
    pub(super) q_y: [f64; MAX_MEMORY],
    pub(super) rr: f64,
    pub(super) qr: f64,
}

/// The unprojected direction d' = −c_r r − Σ c_y,i y_i − Σ c_s,i s_i over the pairs from
/// position `off`, its projection coefficient (d = d' + c_q q), slope ⟨r, d⟩_M,
/// and the area sums of φ̂ + α d' + β q (see [`AreaSums`]).
#[derive(Clone, Copy)]
pub(super) struct Direction {
    pub(super) off: usize,
    pub(super) c_r: f64,
    pub(super) c_y: [f64; MAX_MEMORY],
    pub(super) c_s: [f64; MAX_MEMORY],
    pub(super) c_q: f64,
    pub(super) slope: f64,
    pub(super) area: AreaSums,
}

/// A(x + α d' + β q) = xx + 2α xd + α² dd + 2β (xq + α qd) + β² qq, the sums weighted by
/// (3/(2√2)) ε |k|² w (x = φ̂, q = (c_σ|k|²/M) φ̂).
#[derive(Clone, Copy, Default)]
pub(super) struct AreaSums {
    pub(super) xx: f64,
    pub(super) xq: f64,
    pub(super) qq: f64,
    pub(super) xd: f64,
    pub(super) qd: f64,
    pub(super) dd: f64,
}

impl AreaSums {
    pub(super) fn add(self, o: Self) -> Self {
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
    pub(super) fn retraction(&self, alpha: f64, c_q: f64, target: f64) -> Option<f64> {
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
pub(super) struct GradientSums {
    /// Σ_{k≠0} w |ĝ + σâ|² (the residual's square × |Ω|).
    pub(super) res: f64,
    pub(super) rr: f64,
    pub(super) qr: f64,
    /// Per pair (the new one last): [`pair_sums`].
    pub(super) pairs: [[f64; 6]; MAX_MEMORY + 1],
}

impl GradientSums {
    pub(super) fn zero() -> Self {
        GradientSums {
            res: 0.0,
            rr: 0.0,
            qr: 0.0,
            pairs: [[0.0; 6]; MAX_MEMORY + 1],
        }
    }

    pub(super) fn add(mut self, o: Self) -> Self {
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
        if scene.ade.is_some() || scene.bilayer_couple.is_some() {
            ev = ev.with_curvature();
        }
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
            couple: None,
            stalled: false,
        };
        e.refresh_gradient();
        Ok(e)
    }

    /// The energy the iteration minimises: F_sc, plus F_ade with the area-difference term.
    pub(super) fn objective(&self, m: &Measures) -> f64 {
        m.energy
            + self
                .ev
                .area_difference
                .map_or(0.0, |t| t.energy(m.curvature))
    }

    /// Move a current state that is off the area constraint (a start whose area is not A0,
    /// e.g. a field edited between relaxations), or off M = M0 with the bilayer couple, onto
    /// it before an iteration: its retraction onto A = A0 along q (the trial at α = 0; with the
    /// couple onto both constraints) becomes the current state, the memory is
    /// cleared and its gradient formed. Every trial of the line search is retracted, so
    /// comparing trials with an unretracted state would charge the search with the
    /// retraction's own change of F, σ(A − A0) to first order, which no small step undoes on
    /// a nearly stationary state. A state on the constraint is left as it is.
    ///
    /// # Errors
    /// `Diverged` if the current state's gradient cannot be formed again after a failed
    /// retraction; [`Rejection::AreaDifferenceDrift`] if a state off M = M0 cannot be retracted
    /// onto it (a Δa out of reach of the start along q_M: the run would hold another Δa).
    pub(super) fn retract_start(&mut self, t: f64) -> Result<(), StepError> {
        let (off, off_couple) = self.off_constraints();
        if !off && !off_couple {
            return Ok(());
        }
        let mut d = self.recursion(self.pairs.len());
        self.write_direction(&mut d);
        self.direction = d;
        std::mem::swap(&mut self.cur.nonlinear, &mut self.trial.nonlinear);
        if self.try_step(0.0, t).is_ok() {
            self.accept();
            self.reset_memory();
            self.refresh_gradient();
            Ok(())
        } else {
            self.take_back_gradient(t)?;
            match self.couple {
                Some(c) if off_couple => {
                    let m = self.cur.measures.curvature;
                    Err(StepError::Rejected {
                        check: Rejection::AreaDifferenceDrift((m - c.target).abs() / c.target),
                        context: " at the start: the retraction onto the bilayer couple's Δa \
                                  did not converge (start nearer the Δa held, or continue in Δa)"
                            .into(),
                    })
                }
                _ => Ok(()),
            }
        }
    }

    /// Whether the current state is off A = A0 and off M = M0 (the bilayer couple's), each by
    /// more than [`OFF_CONSTRAINT`] relative: a start the next iteration retracts.
    pub(super) fn off_constraints(&self) -> (bool, bool) {
        let target = self.area.target;
        let off = self.area.method != AreaMethod::None
            && (self.cur.measures.area - target).abs() > OFF_CONSTRAINT * target.abs();
        let off_couple = self
            .couple
            .is_some_and(|c| c.off(self.cur.measures.curvature, OFF_CONSTRAINT));
        (off, off_couple)
    }

    /// Pairs held in the memory (at most `lbfgs_memory`).
    pub fn memory_len(&self) -> usize {
        self.pairs.len()
    }

    pub(super) fn reset_memory(&mut self) {
        self.spare_pairs.extend(self.pairs.drain(..));
    }

    /// After a line search that accepted nothing: the trial hands back the spectrum it took,
    /// and ĝ of the current state (evaluated at `t`) is formed in it again, so that a later
    /// [`RelaxEngine::refresh_gradient`] reads it. The state's measures and sums are kept as
    /// they were (a new evaluation could change them at round-off).
    pub(super) fn take_back_gradient(&mut self, t: f64) -> Result<(), Diverged> {
        std::mem::swap(&mut self.cur.nonlinear, &mut self.trial.nonlinear);
        let kept = (self.cur.measures, self.cur.multiplier_sums);
        self.ev.evaluate(&mut self.cur, t, None, None)?;
        (self.cur.measures, self.cur.multiplier_sums) = kept;
        self.restore_couple_gradient();
        Ok(())
    }

    /// σ (and λ with the couple), r, the residual and the inner products of the current state
    /// (no pair is formed).
    pub(super) fn refresh_gradient(&mut self) {
        let sigma = match self.couple {
            Some(c) => {
                let (sums, sigma, lambda) = self.hold_couple(false, c.lambda);
                self.couple = Some(Couple { sums, lambda, ..c });
                sigma
            }
            None => self.multiplier(self.cur.multiplier_sums),
        };
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
    pub(super) fn multiplier(&self, (qq, gq): (f64, f64)) -> f64 {
        if self.area.method == AreaMethod::None || qq <= 0.0 {
            0.0
        } else {
            -gq / qq
        }
    }

    /// The two-loop recursion on coefficients (module documentation) with the newest `n` pairs
    /// (0 gives the preconditioned steepest descent). Leaves `c_q` 0 and `slope` = ⟨r, d'⟩_M;
    /// [`RelaxEngine::write_direction`] completes both.
    pub(super) fn recursion(&self, n: usize) -> Direction {
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
    pub(super) fn write_direction(&mut self, d: &mut Direction) {
        let (sym, m) = (&self.ev.symbols, self.metric);
        let pairs = &self.pairs;
        let (r, x) = (reals(flat(&self.grad)), reals(flat(&self.cur.hat)));
        let task = sym.task_reals();
        let coefficients = *d;
        let partials = reals_mut(self.dir.as_slice_mut().expect("standard layout"))
            .par_chunks_mut(task)
            .enumerate()
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
            });
        let area = sum_in_fixed_tree(partials, AreaSums::default, AreaSums::add);
        d.area = area;
        if self.couple.is_some() {
            self.project_couple(d);
            return;
        }
        let project = self.area.method != AreaMethod::None && area.xq > 0.0;
        d.c_q = if project { -area.xd / area.xq } else { 0.0 };
        d.slope += d.c_q * self.ip.qr;
    }

    /// The trial state φ̂ + α d' + β q into `trial.hat`, with the evaluation's inverse inputs
    /// (see [`Evaluator::finish`]); returns its area.
    pub(super) fn write_trial(&mut self, alpha: f64, beta: f64) -> f64 {
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

    /// Trial state φ̂ + α d, retracted onto A = A0 along q (with the bilayer couple onto both
    /// constraints: [`RelaxEngine::try_couple_step`]), evaluated. `Err` if the retraction has
    /// no real root or the evaluation diverged.
    pub(super) fn try_step(&mut self, alpha: f64, t: f64) -> Result<(), ()> {
        if self.couple.is_some() {
            return self.try_couple_step(alpha, t);
        }
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
    pub(super) fn accept(&mut self) {
        let sigma = match self.couple {
            Some(c) => {
                let (sums, sigma, lambda) = self.hold_couple(true, 0.0);
                self.couple = Some(Couple { sums, lambda, ..c });
                sigma
            }
            None => self.multiplier(self.trial.multiplier_sums),
        };
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
    pub(super) fn rebuild_gram(&mut self) {
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
pub(super) fn flat(a: &Array3<Complex64>) -> &[Complex64] {
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
