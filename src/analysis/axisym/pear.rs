//! The pear branch: where the prolate loses stability to up–down asymmetric deformations, and
//! the asymmetric (pear) shapes that bifurcate there, followed down in `v` towards the budding
//! limit shape `L_pear`, where the neck closes.
//!
//! **Bifurcation.** Write the coefficients of every mode `k ≤ K`. On an up–down symmetric
//! shape the even `k` are symmetric deformations and the odd `k` antisymmetric ones; `∇v` has
//! only even components and the closure gradient `∇G` only odd ones, so the Hessian of the
//! Lagrangian `ℒ = e + λ_v (v − v0) + λ_G G` (`λ_G = 0` on the prolate) splits into the two
//! blocks. The prolate is stable against asymmetric deformations while the odd block,
//! restricted to the tangent space of the closure (`∇G⊥`), is positive definite. Its smallest
//! eigenvalue `μ(v)` is scanned down the prolate from `v = 0.99` in steps of 0.01; the first
//! sign change is refined by the secant method to `|Δv| < 1e-9`, and its eigenvector `φ` is
//! the pear's direction.
//!
//! **Leaving the prolate.** At a pitchfork the branch is a graph over the amplitude
//! `s = φ·(a − a_b)`, not over `v` (`v − v_b ∝ s²`). The first pear shape solves the KKT
//! system with `v` free and `φ·(a − a_b) = S1` in its place; from there [`follow_pear`]
//! continues by pseudo-arclength in the coefficients (every mode, closure held by its
//! multiplier), so that the branch may fold in `v` (a subcritical pitchfork rises in `v`
//! first), until the narrowest neck falls below [`Options::neck_min`].
//!
//! **Without a bifurcation** the pear branch could still exist detached from the prolate;
//! [`follow_pear`] then descends from sphere-with-bud shapes (bud radius 0.7 … 0.3 of the
//! mother's) at fixed `v` and follows the first that stays up–down asymmetric.

use super::branches::Tracker;
use super::eigen::symmetric_eigen;
use super::functional::{Basis, Eval};
use super::map::{new_map, reproject, NeckMap};
use super::solver::{lu_solve, minimise, newton, Converged, NewtonSettings};
use super::{solution, Branch, Options, Solution};
use std::f64::consts::PI;

/// The amplitude of the first pear shape along `φ` (radians of `ψ`, `φ` a unit vector of
/// coefficients): large enough to leave the prolate, small enough that `v − v_b ∝ s²` holds.
const S1: f64 = 0.02;

/// Step of the scan for the bifurcation down the prolate.
const SCAN_DV: f64 = 0.01;

/// The scan stops at this reduced volume.
const SCAN_V_MIN: f64 = 0.3;

/// Step of the finite-difference Hessian (as in the solver).
const FD_STEP: f64 = 1e-5;

/// The radii `(R1, R2)`, `R1 ≥ R2`, in units of `R0`, of the budding limit shape `L_pear` at
/// reduced spontaneous curvature `c̄0`: two spheres joined at a point, of total area `4π R0²`
/// (`R1² + R2² = 1`), whose neck satisfies the limit-shape condition `1/R1 + 1/R2 = c̄0`
/// (in this program's convention, where a sphere of radius `R` has `2H = 2/R` and zero
/// energy at `c̄0 = 2/R`: two spheres of radius `2/c̄0` are the `e = 0` case).
///
/// With `s = R1 + R2`, `p = R1 R2`: `s = c̄0 p` and `s² − 2p = 1` give
/// `s = 1/c̄0 + √(1/c̄0² + 1)`, `p = s/c̄0`; the radii are real when `s² ≥ 4p`, i.e.
/// `c̄0 ≥ 2√2` (equal spheres `R1 = R2 = 1/√2` there). `None` below `2√2` (and for
/// non-finite `c̄0`): no two spheres of this area meet the neck condition.
pub fn l_pear_radii(c0: f64) -> Option<(f64, f64)> {
    if !c0.is_finite() || c0 < 2.0 * std::f64::consts::SQRT_2 {
        return None;
    }
    let s = 1.0 / c0 + (1.0 / (c0 * c0) + 1.0).sqrt();
    let p = s / c0;
    // s² − 4p ≥ 0 for c̄0 ≥ 2√2; clamp the round-off at the end point.
    let d = (s * s - 4.0 * p).max(0.0).sqrt();
    Some((0.5 * (s + d), 0.5 * (s - d)))
}

/// The reduced volume of the budding limit shape `L_pear` at `c̄0` (see [`l_pear_radii`]):
/// `v = R1³ + R2³ = s²(s − 3/c̄0)` with `s = 1/c̄0 + √(1/c̄0² + 1)`; `1/√2` at `c̄0 = 2√2`,
/// rising with `c̄0` towards 1 (one sphere) as `c̄0 → ∞`. `None` for `c̄0 < 2√2`, where no
/// `L_pear` exists.
pub fn l_pear(c0: f64) -> Option<f64> {
    l_pear_radii(c0).map(|(r1, r2)| r1.powi(3) + r2.powi(3))
}

/// Where the pear branch leaves the prolate.
#[derive(Clone, Debug)]
pub struct Bifurcation {
    /// Reduced volume of the bifurcation.
    pub v: f64,
    /// Energy of the prolate (and of the pear) there.
    pub e: f64,
    /// The prolate shape at the bifurcation.
    pub prolate: Solution,
}

/// Why the pear branch stopped going down in `v`.
#[derive(Clone, Debug, PartialEq)]
pub enum PearEnd {
    /// The narrowest neck fell below [`Options::neck_min`]: the budding limit is near.
    Neck {
        /// Reduced volume of the first grid shape whose neck is below `neck_min`.
        v: f64,
        /// Its neck radius (units of `R0`).
        neck: f64,
    },
    /// The continuation in `v` failed at this `v` (a limit point, or the modes no longer
    /// resolve the shape).
    Stalled {
        /// The last reduced volume reached.
        v: f64,
    },
    /// The branch reached the bottom of the grid.
    Grid,
}

/// The pear branch followed over a grid of reduced volumes.
#[derive(Clone, Debug)]
pub struct PearBranch {
    /// Where it leaves the prolate; `None` if the prolate keeps its up–down symmetry (stable
    /// odd block) down to `v = 0.3`.
    pub bifurcation: Option<Bifurcation>,
    /// The pear shapes at the grid values, increasing `v`.
    pub shapes: Vec<Solution>,
    /// The last shape reached (the narrowest neck), off the grid.
    pub last: Option<Solution>,
    /// Why the continuation stopped.
    pub end: Option<PearEnd>,
}

/// The full basis (every `k ≤ K`) of `opts`, at its `c̄0`.
pub(super) fn full_basis(opts: &Options) -> Basis {
    Basis::new(opts.nodes - 1, (1..=opts.modes).collect())
        .with_c0(opts.c0)
        .with_model(opts.model)
}

/// The coefficients of a prolate (even modes) in the full basis.
fn embed(even: &Converged, full: &Basis) -> Vec<f64> {
    let mut a = vec![0.0; full.modes.len()];
    for (c, ac) in even.a.iter().enumerate() {
        a[2 * (c + 1) - 1] = *ac;
    }
    a
}

/// `∇ℒ = ∇e + λ_v ∇v + λ_G ∇G`.
fn lagrangian_grad(ev: &Eval, lv: f64, lg: f64) -> Vec<f64> {
    (0..ev.grad_e.len())
        .map(|k| ev.grad_e[k] + lv * ev.grad_v[k] + lg * ev.grad_g[k])
        .collect()
}

/// The smallest eigenvalue `μ` of the odd block of `∇²ℒ` on `∇G⊥`, and its eigenvector in the
/// full basis (unit, zero on the even modes), at the prolate `a` (full basis) with multiplier
/// `lv`. `None` if a perturbed shape is not admissible.
pub(super) fn odd_stability(full: &Basis, a: &[f64], lv: f64) -> Option<(f64, Vec<f64>)> {
    let odd: Vec<usize> = (0..a.len()).step_by(2).collect();
    let n = odd.len();
    // Odd block of the central-difference Hessian, symmetrised.
    let mut h = vec![0.0; n * n];
    let mut ap = a.to_vec();
    for (col, &k) in odd.iter().enumerate() {
        ap[k] = a[k] + FD_STEP;
        let gp = lagrangian_grad(&full.eval(&ap)?, lv, 0.0);
        ap[k] = a[k] - FD_STEP;
        let gm = lagrangian_grad(&full.eval(&ap)?, lv, 0.0);
        ap[k] = a[k];
        for (row, &i) in odd.iter().enumerate() {
            let d = 0.25 * (gp[i] - gm[i]) / FD_STEP;
            h[row * n + col] += d;
            h[col * n + row] += d;
        }
    }
    // Householder reflection Q = I − 2uuᵀ/(uᵀu) with Q ĝ = e_1: columns 2.. of Q span ∇G⊥.
    let g: Vec<f64> = odd
        .iter()
        .map(|&i| full.eval(a)?.grad_g.get(i).copied())
        .collect::<Option<_>>()?;
    let gn = g.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut u: Vec<f64> = g.iter().map(|x| x / gn).collect();
    let sign = if u[0] >= 0.0 { 1.0 } else { -1.0 };
    u[0] += sign;
    let uu: f64 = u.iter().map(|x| x * x).sum();
    let q = |i: usize, j: usize| f64::from(u8::from(i == j)) - 2.0 * u[i] * u[j] / uu;
    // B = Qᵀ H Q on the indices 1.., as (H Q) then Qᵀ(·).
    let m = n - 1;
    let hq: Vec<f64> = (0..n)
        .flat_map(|i| (1..n).map(move |j| (i, j)))
        .map(|(i, j)| (0..n).map(|k| h[i * n + k] * q(k, j)).sum())
        .collect();
    let b: Vec<f64> = (1..n)
        .flat_map(|i| (0..m).map(move |j| (i, j)))
        .map(|(i, j)| (0..n).map(|k| q(k, i) * hq[k * m + j]).sum())
        .collect();
    let (vals, vecs) = symmetric_eigen(&b, m);
    let y = &vecs[0];
    let mut phi = vec![0.0; a.len()];
    for (r, &i) in odd.iter().enumerate() {
        phi[i] = (0..m).map(|j| q(r, j + 1) * y[j]).sum();
    }
    Some((vals[0], phi))
}

/// The prolate state (tracker at `v`) and its odd stability `μ`, or `None`.
fn prolate_mu(tr: &mut Tracker, full: &Basis, v: f64) -> Option<(f64, Vec<f64>)> {
    if !tr.advance(v) {
        return None;
    }
    let c = tr.current();
    odd_stability(full, &embed(c, full), c.lambda_v)
}

/// The up–down test function of the prolate at reduced volume `v` and `opts.c0`: the smallest
/// eigenvalue `μ` of the odd block of the Hessian of the Lagrangian on the tangent space of
/// the closure (see the module docs). `μ > 0`: the prolate is stable against up–down
/// asymmetric deformations; its zero in `c̄0` at fixed `v` (or in `v` at fixed `c̄0`) is where
/// the pear bifurcates. `None` if the prolate is not found at `v`.
pub fn prolate_updown(v: f64, opts: &Options) -> Option<f64> {
    let s = super::solve(Branch::Prolate, v, opts).ok()?;
    let full = full_basis(opts);
    let mut a = vec![0.0; full.modes.len()];
    for (k, ak) in s.modes.iter().zip(&s.coefficients) {
        a[k - 1] = *ak;
    }
    odd_stability(&full, &a, s.lambda_v).map(|(mu, _)| mu)
}

/// Where the prolate at reduced volume `v` loses up–down stability as c̄0 grows: the zero of
/// its test function μ(c̄0) ([`prolate_updown`]) in the bracket `(lo, hi)`, which must hold
/// μ(lo) > 0 > μ(hi), by regula falsi with the Illinois halving until |μ| < 1e-8 or the
/// bracket is below 1e-7 (μ is smooth and nearly linear there: at v = 0.789 the zero 3.6383
/// is found in 4–6 solves). `None` if the prolate is not found or the bracket holds no sign
/// change. `opts.c0` is replaced.
pub fn prolate_updown_zero(v: f64, (lo, hi): (f64, f64), opts: &Options) -> Option<f64> {
    let mu = |c0: f64| prolate_updown(v, &opts.with_c0(c0));
    let (mut a, mut b) = (lo, hi);
    let (mut fa, mut fb) = (mu(a)?, mu(b)?);
    if !(fa > 0.0 && fb < 0.0) {
        return None;
    }
    let mut side = 0;
    for _ in 0..60 {
        let c = (a * fb - b * fa) / (fb - fa);
        let fc = mu(c)?;
        if fc.abs() < 1e-8 || (b - a) < 1e-7 {
            return Some(c);
        }
        if fc > 0.0 {
            (a, fa) = (c, fc);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            (b, fb) = (c, fc);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
    }
    Some((a * fb - b * fa) / (fb - fa))
}

/// The budding limit read off the pear branch as its neck closes ([`neck_limit`]).
#[derive(Clone, Copy, Debug)]
pub struct NeckLimit {
    /// The limit `v_L` of `v` as the neck radius `b → 0`.
    pub v: f64,
    /// The limit of the sum of the two pole curvatures ([`Solution::pole_curvatures`]); the
    /// neck condition of `L_pear` makes it `1/R1 + 1/R2 = c̄0`.
    pub pole_sum: f64,
    /// The shapes fitted (necks below [`NECK_FIT`]).
    pub points: usize,
}

/// [`neck_limit`] fits the shapes whose neck is below this (units of `R0`).
pub const NECK_FIT: f64 = 0.02;

/// The budding limit from the pear path: over the shapes past the first fold whose neck `b`
/// is below [`NECK_FIT`], the least-squares fit
/// `y = y_L + A b ln(1/b) + B b + C b² ln(1/b) + D b²` of `y = v` and of
/// `y = ψ'(0) + ψ'(L)`, whose constants `y_L` are the limits as the neck closes (the
/// logarithms are those of a catenoid neck of waist `b` between the two spheres). On the
/// c̄0 = 3 branch (K = 80, necks 0.02 … 0.005) the residuals are below 2e-6 in `v`, `v_L` is
/// the two-sphere formula's to 1e-6 and the pole sum 3 to 1e-5; with the first three terms
/// only, `v_L` is off by 7e-4. `None` with fewer than eight such shapes.
pub fn neck_limit(branch: &PearBranch) -> Option<NeckLimit> {
    let shapes = &branch.shapes;
    let top = (0..shapes.len().saturating_sub(1)).find(|&i| shapes[i + 1].v < shapes[i].v)?;
    let pts: Vec<(f64, f64, f64)> = shapes[top..]
        .iter()
        .filter_map(|s| {
            let b = s.neck().filter(|b| *b < NECK_FIT && *b > 0.0)?;
            let (p0, p1) = s.pole_curvatures();
            Some((b, s.v, p0 + p1))
        })
        .collect();
    if pts.len() < 8 {
        return None;
    }
    let cols: Vec<Vec<f64>> = (0..5)
        .map(|k| {
            pts.iter()
                .map(|p| {
                    let x = p.0 / NECK_FIT;
                    let l = (1.0 / p.0).ln();
                    [1.0, x * l, x, x * x * l, x * x][k]
                })
                .collect()
        })
        .collect();
    let v: Vec<f64> = pts.iter().map(|p| p.1).collect();
    let sum: Vec<f64> = pts.iter().map(|p| p.2).collect();
    Some(NeckLimit {
        v: least_squares(&cols, &v)?[0],
        pole_sum: least_squares(&cols, &sum)?[0],
        points: pts.len(),
    })
}

/// Linear least squares `min |Σ_k c_k col_k − y|` by modified Gram–Schmidt (`col = Q R`, then
/// `R c = Qᵀ y`). `None` if the columns are dependent to round-off.
fn least_squares(cols: &[Vec<f64>], y: &[f64]) -> Option<Vec<f64>> {
    let n = cols.len();
    let mut q: Vec<Vec<f64>> = cols.to_vec();
    let mut r = vec![0.0; n * n];
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    for k in 0..n {
        for j in 0..k {
            let d = dot(&q[j], &q[k]);
            r[j * n + k] = d;
            let qj = q[j].clone();
            for (x, z) in q[k].iter_mut().zip(&qj) {
                *x -= d * z;
            }
        }
        let norm = dot(&q[k], &q[k]).sqrt();
        if norm <= 1e-13 * dot(&cols[k], &cols[k]).sqrt() {
            return None;
        }
        r[k * n + k] = norm;
        q[k].iter_mut().for_each(|x| *x /= norm);
    }
    let mut c: Vec<f64> = q.iter().map(|qk| dot(qk, y)).collect();
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| r[k * n + j] * c[j]).sum();
        c[k] = (c[k] - s) / r[k * n + k];
    }
    Some(c)
}

/// The pear of `branch` after its first fold, solved at reduced volume `v`: the piece of the
/// path from its first local maximum of `v` down to the next turn, the state there nearest to
/// `v` as the start of Newton at fixed `v` (closure held). On a subcritical branch this is the
/// piece that bends back below the prolate, where the pear is the local minimum. `None` if that
/// piece does not cover `v` or Newton fails.
pub fn pear_at(v: f64, branch: &PearBranch, opts: &Options) -> Option<Solution> {
    let shapes = &branch.shapes;
    if shapes.is_empty() {
        return None;
    }
    // The first fold: the first state after which v falls (the path's first local maximum of
    // v; the start itself when the branch falls from the outset).
    let top = (0..shapes.len() - 1)
        .find(|&i| shapes[i + 1].v < shapes[i].v)
        .unwrap_or(shapes.len() - 1);
    let mut end = top;
    while end + 1 < shapes.len() && shapes[end + 1].v < shapes[end].v {
        end += 1;
    }
    let piece = &shapes[top..=end];
    if piece.len() < 2 || v > piece[0].v || v < piece[piece.len() - 1].v {
        return None;
    }
    // Starts: the linear interpolation in v between the two states around v (when they share
    // a map), then each of the two.
    let i = (0..piece.len() - 1)
        .find(|&i| piece[i + 1].v <= v)
        .unwrap_or(piece.len() - 2);
    let (hi, lo) = (&piece[i], &piece[i + 1]);
    let mut starts: Vec<(NeckMap, Vec<f64>)> = Vec::new();
    if hi.map == lo.map && hi.v > lo.v {
        let f = (v - lo.v) / (hi.v - lo.v);
        let a = lo
            .coefficients
            .iter()
            .zip(&hi.coefficients)
            .map(|(x, y)| x + f * (y - x))
            .collect();
        starts.push((lo.map, a));
    }
    starts.push((lo.map, lo.coefficients.clone()));
    starts.push((hi.map, hi.coefficients.clone()));
    // Near a narrow neck the finite-difference Hessian is less accurate and Newton slower.
    let set = NewtonSettings {
        tol: opts.tol,
        max_iter: 3 * opts.max_iter,
        max_step: 0.5,
    };
    starts.into_iter().find_map(|(map, a)| {
        let full = full_basis(opts).with_map(map);
        let c = newton(&full, &a, v, true, &set)?;
        Some(solution(Branch::Pear, &full, &c))
    })
}

/// The bifurcation internals: the prolate tracker at `v_b`, its full-basis coefficients and
/// the direction `φ`.
struct Onset {
    prolate: Tracker,
    a: Vec<f64>,
    phi: Vec<f64>,
}

/// Scan the prolate for the first zero of `μ(v)` below 0.99 and refine it.
fn onset(opts: &Options) -> Option<Onset> {
    let full = full_basis(opts);
    let mut tr = Tracker::new(Branch::Prolate, opts);
    if !tr.start(0.99) {
        return None;
    }
    let mut v_hi = 0.99;
    let (mut mu_hi, _) = prolate_mu(&mut tr, &full, v_hi)?;
    let mut hi_state = tr.last.clone();
    let mut v_lo = v_hi;
    let mut mu_lo = mu_hi;
    while mu_lo > 0.0 {
        if v_lo - SCAN_DV < SCAN_V_MIN {
            return None;
        }
        v_hi = v_lo;
        mu_hi = mu_lo;
        hi_state = tr.last.clone();
        v_lo -= SCAN_DV;
        mu_lo = prolate_mu(&mut tr, &full, v_lo)?.0;
    }
    // Secant (regula falsi with the Illinois modification) between v_lo (μ ≤ 0) and v_hi.
    let mut side = 0i8;
    for _ in 0..60 {
        let v = v_lo - mu_lo * (v_hi - v_lo) / (mu_hi - mu_lo);
        tr.last = hi_state.clone();
        let (mu, _) = prolate_mu(&mut tr, &full, v)?;
        if mu > 0.0 {
            v_hi = v;
            mu_hi = mu;
            hi_state = tr.last.clone();
            if side == 1 {
                mu_lo *= 0.5;
            }
            side = 1;
        } else {
            v_lo = v;
            mu_lo = mu;
            if side == -1 {
                mu_hi *= 0.5;
            }
            side = -1;
        }
        if v_hi - v_lo < 1e-9 || mu == 0.0 {
            break;
        }
    }
    let v_b = 0.5 * (v_lo + v_hi);
    tr.last = hi_state;
    let (_, phi) = prolate_mu(&mut tr, &full, v_b)?;
    let a = embed(tr.current(), &full);
    Some(Onset {
        prolate: tr,
        a,
        phi,
    })
}

/// Where the pear branch leaves the prolate at `opts.c0`: the first `v` below 0.99 (down to
/// 0.3) where the prolate loses stability against up–down asymmetric deformations; `None` if
/// it does not.
pub fn pear_bifurcation(opts: &Options) -> Option<Bifurcation> {
    let o = onset(opts)?;
    let prolate = o.prolate.solution();
    Some(Bifurcation {
        v: prolate.v,
        e: prolate.e,
        prolate,
    })
}

/// Newton for the stationary shape with amplitude `φ·(a − a_b) = s` and `v` free: the KKT
/// system `∇e + λ_v ∇v + λ_G ∇G = 0`, `G = 0`, `φ·(a − a_b) − s = 0` in `(a, λ_v, λ_G)`
/// (without the closure row and `λ_G` on an up–down symmetric basis, `closure = false`).
fn newton_amplitude(
    full: &Basis,
    a_b: &[f64],
    phi: &[f64],
    s: f64,
    start: (&[f64], f64, f64),
    set: &NewtonSettings,
) -> Option<Converged> {
    newton_amplitude_with(full, a_b, phi, s, start, set, true)
}

/// [`newton_amplitude`] with or without the closure.
fn newton_amplitude_with(
    full: &Basis,
    a_b: &[f64],
    phi: &[f64],
    s: f64,
    start: (&[f64], f64, f64),
    set: &NewtonSettings,
    closure: bool,
) -> Option<Converged> {
    let n = a_b.len();
    let nc = usize::from(closure);
    let (mut a, mut lv, mut lg) = (start.0.to_vec(), start.1, start.2);
    if !closure {
        lg = 0.0;
    }
    let mut hess: Option<Vec<f64>> = None;
    let mut last_residual = f64::INFINITY;
    for iter in 0..=set.max_iter {
        let ev = full.eval(&a)?;
        let grad = lagrangian_grad(&ev, lv, lg);
        let amp: f64 = phi
            .iter()
            .zip(a.iter().zip(a_b))
            .map(|(p, (x, y))| p * (x - y))
            .sum();
        let mut rhs: Vec<f64> = grad.iter().map(|g| -g).collect();
        if closure {
            rhs.push(-ev.g);
        }
        rhs.push(-(amp - s));
        let residual = rhs.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        if residual < set.tol {
            return Some(Converged {
                a,
                lambda_v: lv,
                lambda_g: lg,
                lambda_j: 0.0,
                eval: ev,
                iterations: iter,
                residual,
            });
        }
        if iter == set.max_iter || !residual.is_finite() {
            return None;
        }
        // The Hessian block is rebuilt only when the last step reduced the residual by less
        // than REBUILD (a chord method otherwise, as in the solver).
        if hess.is_none() || residual > REBUILD * last_residual {
            hess = Some(hessian(full, &a, lv, lg)?);
        }
        last_residual = residual;
        let h = hess.as_ref().expect("built above");
        let dim = n + 1 + nc;
        let mut jac = vec![0.0; dim * dim];
        for i in 0..n {
            jac[i * dim..i * dim + n].copy_from_slice(&h[i * n..(i + 1) * n]);
        }
        for i in 0..n {
            jac[i * dim + n] = ev.grad_v[i];
            if closure {
                jac[i * dim + n + 1] = ev.grad_g[i];
                jac[n * dim + i] = ev.grad_g[i];
            }
            jac[(n + nc) * dim + i] = phi[i];
        }
        let dx = lu_solve(&mut jac, &mut rhs, dim)?;
        let big = dx[..n].iter().fold(0.0f64, |m, d| m.max(d.abs()));
        let f = if big > set.max_step {
            set.max_step / big
        } else {
            1.0
        };
        for (x, d) in a.iter_mut().zip(&dx) {
            *x += f * d;
        }
        lv += f * dx[n];
        if closure {
            lg += f * dx[n + 1];
        }
    }
    None
}

/// The fold (limit point in `v`) of an up–down symmetric `branch` below `v_start`: the branch
/// solved at `v_start` and `v_start − 0.002`, then followed by pseudo-arclength in its even
/// modes (as in [`follow_pear`], without the closure) until `v` turns back up; the fold is the
/// vertex of the parabola `v(σ)` through the three states around the smallest `v` (σ the
/// arclength). Returns the state of smallest `v` and the vertex `v`. `None` if the branch is
/// not found at `v_start`, or if 300 steps (or a stalled step) do not reach a turn.
pub fn symmetric_fold(branch: Branch, v_start: f64, opts: &Options) -> Option<(Solution, f64)> {
    if !branch.up_down_symmetric() {
        return None;
    }
    let mut tr = Tracker::new(branch, opts);
    if !tr.start(v_start) || !tr.advance(v_start) {
        return None;
    }
    let first = tr.current().clone();
    if !tr.advance(v_start - 0.002) {
        return None;
    }
    let mut cur = tr.current().clone();
    let mut prev = first;
    let basis = &tr.basis;
    let set = tr.set;
    let mut path: Vec<(f64, Converged)> = vec![(0.0, prev.clone())];
    let mut sigma = dist(&cur.a, &prev.a);
    path.push((sigma, cur.clone()));
    let mut h = H0;
    for _ in 0..300 {
        let diff: Vec<f64> = cur.a.iter().zip(&prev.a).map(|(x, y)| x - y).collect();
        let norm = diff.iter().map(|x| x * x).sum::<f64>().sqrt();
        let d: Vec<f64> = diff.iter().map(|x| x / norm).collect();
        let next = loop {
            let p: Vec<f64> = cur.a.iter().zip(&d).map(|(x, d)| x + h * d).collect();
            let lv = cur.lambda_v + h / norm * (cur.lambda_v - prev.lambda_v);
            let solved = newton_amplitude_with(basis, &p, &d, 0.0, (&p, lv, 0.0), &set, false)
                .filter(|c| {
                    c.a.iter()
                        .zip(&p)
                        .all(|(a, q)| (a - q).abs() <= 0.5 * h.max(0.02))
                });
            match solved {
                Some(c) => break Some(c),
                None => {
                    h *= 0.5;
                    if h < H_MIN {
                        break None;
                    }
                }
            }
        };
        let next = next?;
        h = (1.5 * h).min(0.02);
        sigma += dist(&next.a, &cur.a);
        prev = std::mem::replace(&mut cur, next);
        path.push((sigma, cur.clone()));
        let k = path.len();
        if path[k - 1].1.eval.v > path[k - 2].1.eval.v {
            let (x0, c0) = &path[k - 3];
            let (x1, c1) = &path[k - 2];
            let (x2, c2) = &path[k - 1];
            let vertex = parabola_vertex(*x0, *x1, *x2, c0.eval.v, c1.eval.v, c2.eval.v);
            return Some((solution(branch, basis, c1), vertex));
        }
    }
    None
}

/// Euclidean distance of two coefficient vectors.
fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// The extreme value of the parabola through `(x0, y0)`, `(x1, y1)`, `(x2, y2)`.
fn parabola_vertex(x0: f64, x1: f64, x2: f64, y0: f64, y1: f64, y2: f64) -> f64 {
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let c = (d12 - d01) / (x2 - x0);
    if c == 0.0 {
        return y1;
    }
    let b = d01 - c * (x0 + x1);
    let x = -b / (2.0 * c);
    y1 + b * (x - x1) + c * (x * x - x1 * x1)
}

/// Residual reduction per Newton step below which [`newton_amplitude`] keeps its Hessian.
const REBUILD: f64 = 0.05;

/// Central-difference Hessian of `ℒ = e + λ_v v + λ_G G` at `a` (row-major, symmetrised);
/// `None` if a perturbed shape is not admissible.
fn hessian(full: &Basis, a: &[f64], lv: f64, lg: f64) -> Option<Vec<f64>> {
    let n = a.len();
    let mut h = vec![0.0; n * n];
    let mut ap = a.to_vec();
    for k in 0..n {
        ap[k] = a[k] + FD_STEP;
        let gp = lagrangian_grad(&full.eval(&ap)?, lv, lg);
        ap[k] = a[k] - FD_STEP;
        let gm = lagrangian_grad(&full.eval(&ap)?, lv, lg);
        ap[k] = a[k];
        for i in 0..n {
            let d = 0.25 * (gp[i] - gm[i]) / FD_STEP;
            h[i * n + k] += d;
            h[k * n + i] += d;
        }
    }
    Some(h)
}

/// A point of the continuation: coefficients, `λ_v`, `λ_G`.
type State = (Vec<f64>, f64, f64);

/// First arclength step (Euclidean norm of the coefficient change).
const H0: f64 = 0.02;
/// Largest arclength step.
const H_MAX: f64 = 0.08;
/// Arclength step below which the continuation counts as stalled.
const H_MIN: f64 = 1e-4;
/// Most arclength steps.
const MAX_STEPS: usize = 400;

/// Follow the pear branch from its bifurcation (or, without one, from a sphere-with-bud start
/// that stays asymmetric, see the module docs) by pseudo-arclength continuation in the
/// coefficients: from the last two states `a_{i−1}`, `a_i`, the secant direction
/// `d = (a_i − a_{i−1})/|a_i − a_{i−1}|`, the predictor `p = a_i + h d`, and the corrector
/// solves the KKT system with `v` free and `d·(a − p) = 0` (so the branch may turn in `v`: a
/// subcritical pitchfork first rises in `v`, folds, and comes back down). Steps grow by 1.5
/// after a success (at most `H_MAX`) and halve after a failure. The continuation stops when
/// the narrowest neck falls below `opts.neck_min` ([`PearEnd::Neck`]), when `v` falls below
/// `v_floor` ([`PearEnd::Grid`]), or when the step falls below `H_MIN` or `MAX_STEPS` are
/// taken ([`PearEnd::Stalled`]). `shapes` holds every state in the order of the path.
pub fn follow_pear(v_floor: f64, opts: &Options) -> PearBranch {
    let mut out = PearBranch {
        bifurcation: None,
        shapes: Vec::new(),
        last: None,
        end: None,
    };
    let full = full_basis(opts);
    let set = NewtonSettings {
        tol: opts.tol,
        max_iter: opts.max_iter,
        max_step: 0.5,
    };
    let Some(o) = onset(opts) else {
        // No bifurcation: a pear branch detached from the prolate, if one exists here.
        if let Some((prev, cur)) = bud_start(&full, &set) {
            arclength(&full, &set, prev, cur, v_floor, opts, &mut out);
        }
        return out;
    };
    let prolate = o.prolate.solution();
    out.bifurcation = Some(Bifurcation {
        v: prolate.v,
        e: prolate.e,
        prolate,
    });
    let v_b = o.prolate.current().eval.v;
    let lv0 = o.prolate.current().lambda_v;
    // The first state: amplitude S1 along φ.
    let a0: Vec<f64> = o.a.iter().zip(&o.phi).map(|(ab, p)| ab + S1 * p).collect();
    let Some(first) = newton_amplitude(&full, &o.a, &o.phi, S1, (&a0, lv0, 0.0), &set) else {
        out.end = Some(PearEnd::Stalled { v: v_b });
        return out;
    };
    // The bifurcation point itself is the state before it (the prolate, in the full basis).
    arclength(
        &full,
        &set,
        (o.a.clone(), lv0, 0.0),
        first,
        v_floor,
        opts,
        &mut out,
    );
    out
}

/// Move the continuation onto `map`: the basis `full` with `map`, `prev` re-projected, `cur`
/// re-projected and solved again at its `v` (closure held). `None` if that solve fails.
fn remap(
    full: &Basis,
    map: NeckMap,
    prev: &State,
    cur: &Converged,
    set: &NewtonSettings,
) -> Option<(Basis, State, Converged)> {
    let nb = Basis::new(full.len() - 1, full.modes.clone())
        .with_c0(full.c0)
        .with_map(map);
    let a_prev = reproject(&prev.0, &full.map, &map, &full.modes);
    let a_cur = reproject(&cur.a, &full.map, &map, &full.modes);
    let c = newton(&nb, &a_cur, cur.eval.v, true, set)?;
    Some((nb, (a_prev, prev.1, prev.2), c))
}

/// The pseudo-arclength continuation of [`follow_pear`] from the states `prev` (coefficients
/// and multipliers) and `cur`, appending to `out.shapes` and setting `out.end`, `out.last`.
/// Once the neck is narrower than 0.1 R0 the modes are sines in a parameter stretched
/// at the neck ([`NeckMap::at_neck`]), made again as the neck narrows or moves ([`new_map`]).
fn arclength(
    full: &Basis,
    set: &NewtonSettings,
    mut prev: State,
    mut cur: Converged,
    v_floor: f64,
    opts: &Options,
    out: &mut PearBranch,
) {
    let mut basis = full.clone();
    let mut mapped: Option<f64> = None;
    let mut h = H0;
    out.end = Some(PearEnd::Stalled { v: cur.eval.v });
    let mut steps = 0;
    loop {
        let mut s = solution(Branch::Pear, &basis, &cur);
        if let Some((map, b)) = new_map(&s, &basis.map, mapped) {
            if let Some((nb, p, c)) = remap(&basis, map, &prev, &cur, set) {
                basis = nb;
                prev = p;
                cur = c;
                mapped = Some(b);
                s = solution(Branch::Pear, &basis, &cur);
            }
        }
        if let Some(neck) = s.neck().filter(|r| *r < opts.neck_min) {
            out.end = Some(PearEnd::Neck { v: s.v, neck });
            out.last = Some(s.clone());
            out.shapes.push(s);
            break;
        }
        if s.v < v_floor {
            out.end = Some(PearEnd::Grid);
            out.last = Some(s.clone());
            out.shapes.push(s);
            break;
        }
        out.shapes.push(s);
        steps += 1;
        if steps > MAX_STEPS {
            out.end = Some(PearEnd::Stalled { v: cur.eval.v });
            break;
        }
        let diff: Vec<f64> = cur.a.iter().zip(&prev.0).map(|(x, y)| x - y).collect();
        let norm = diff.iter().map(|x| x * x).sum::<f64>().sqrt();
        let d: Vec<f64> = diff.iter().map(|x| x / norm).collect();
        let next = loop {
            let p: Vec<f64> = cur.a.iter().zip(&d).map(|(x, d)| x + h * d).collect();
            let f = h / norm;
            let lv = cur.lambda_v + f * (cur.lambda_v - prev.1);
            let lg = cur.lambda_g + f * (cur.lambda_g - prev.2);
            let solved = newton_amplitude(&basis, &p, &d, 0.0, (&p, lv, lg), set).filter(|c| {
                c.a.iter()
                    .zip(&p)
                    .all(|(a, q)| (a - q).abs() <= 0.5 * h.max(0.02))
            });
            match solved {
                Some(c) => {
                    h = (1.5 * h).min(H_MAX);
                    break Some(c);
                }
                None => {
                    h *= 0.5;
                    if h < H_MIN {
                        break None;
                    }
                }
            }
        };
        let Some(next) = next else {
            out.end = Some(PearEnd::Stalled { v: cur.eval.v });
            break;
        };
        prev = (cur.a.clone(), cur.lambda_v, cur.lambda_g);
        cur = next;
    }
    if out.last.is_none() {
        out.last = out.shapes.last().cloned();
    }
}

/// A start on a pear branch that does not bifurcate from the prolate: a sphere with a bud
/// (outer arc of radius 1 for `ψ ∈ [0, π − β]`, a neck arc of radius `b` turning back to
/// `ψ = γ`, a bud arc of radius `R2` up to `ψ = π`; `sin γ = (1 + b) sin β / (R2 + b)` closes
/// it), projected on the modes and descended to a local minimum at its own `v` (about 0.8);
/// then a second state at `v − 0.005`, so that the secant heads towards the closing neck.
/// `None` if the descent ends on an up–down symmetric shape (no pear minimum there) or fails.
fn bud_start(full: &Basis, set: &NewtonSettings) -> Option<(State, Converged)> {
    BUD_RADII
        .iter()
        .find_map(|&r2| bud_start_with(full, set, r2))
}

/// Bud radii (mother radius 1) tried by [`bud_start`], in order.
const BUD_RADII: [f64; 4] = [0.7, 0.5, 0.4, 0.3];

/// [`bud_start`] with bud radius `r2`.
fn bud_start_with(full: &Basis, set: &NewtonSettings, r2: f64) -> Option<(State, Converged)> {
    let (r1, b, beta) = (1.0f64, 0.15f64, 0.3f64);
    let gamma = ((r1 + b) * beta.sin() / (r2 + b)).asin();
    let l1 = r1 * (PI - beta);
    let l2 = b * (PI - beta - gamma);
    let l3 = r2 * (PI - gamma);
    let len = l1 + l2 + l3;
    let psi = |t: f64| {
        let s = t * len;
        if s < l1 {
            s / r1
        } else if s < l1 + l2 {
            PI - beta - (s - l1) / b
        } else {
            gamma + (s - l1 - l2) / r2
        }
    };
    let a0 = project_modes(&full.modes, psi);
    let v0 = full.eval(&a0)?.v;
    let first = minimise(full, &a0, v0, true, set);
    let first = first?;
    let odd = first.a.iter().step_by(2).map(|x| x * x).sum::<f64>().sqrt();
    if odd < 1e-3 {
        return None;
    }
    let second = newton(full, &first.a, first.eval.v - 0.005, true, set)?;
    Some(((first.a.clone(), first.lambda_v, first.lambda_g), second))
}

/// `a_k = 2 ∫_0^1 (ψ − πt) sin(kπt) dt` for the listed `k` (midpoint rule on 8192 cells).
fn project_modes(modes: &[usize], psi: impl Fn(f64) -> f64) -> Vec<f64> {
    let cells = 8192;
    let h = 1.0 / cells as f64;
    modes
        .iter()
        .map(|&k| {
            2.0 * h
                * (0..cells)
                    .map(|i| {
                        let t = (i as f64 + 0.5) * h;
                        (psi(t) - PI * t) * (k as f64 * PI * t).sin()
                    })
                    .sum::<f64>()
        })
        .collect()
}
