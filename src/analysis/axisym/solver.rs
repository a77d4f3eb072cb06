//! Newton's method on the Lagrangian of the constrained Ritz problem.
//!
//! Minimise `e(a)` subject to `v(a) = v0` and, for shapes without up–down symmetry, the
//! closure `G(a) = 0` (an up–down symmetric `ψ` has `G ≡ 0`, [`super::functional`]). With
//! `ℒ = e + λ_v (v − v0) + λ_G G`, Newton solves the KKT system
//!
//! ```text
//! [ ∇²ℒ   ∇v  ∇G ] [ δa  ]     [ ∇ℒ     ]
//! [ ∇vᵀ   0   0  ] [ δλ_v ] = − [ v − v0 ]
//! [ ∇Gᵀ   0   0  ] [ δλ_G ]     [ G      ]
//! ```
//!
//! For the bilayer couple ([`super::Model::Bc`]) the constraint `J − Δa = 0` joins them, with
//! its multiplier `λ_J`, as a further row and column.
//!
//! The gradients are exact; `∇²ℒ` is the central difference of `∇ℒ` (step `1e-5`: truncation
//! `≈ 1e-10`, round-off `≈ 1e-11` relative), which leaves Newton's convergence quadratic down to
//! that level and linear with a factor `≈ 1e-10` below it.

use super::functional::{Basis, Eval};
use super::Model;

/// Settings of the Newton iteration.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NewtonSettings {
    /// Stop when `max |∇ℒ|, |v − v0|, |G|` falls below this.
    pub tol: f64,
    /// Give up after this many iterations.
    pub max_iter: usize,
    /// Largest change of any coefficient in one step (radians of `ψ`).
    pub max_step: f64,
}

/// A converged constrained stationary point.
#[derive(Clone, Debug)]
pub(crate) struct Converged {
    /// Coefficients `a_k`.
    pub a: Vec<f64>,
    /// Multiplier of `v − v0`.
    pub lambda_v: f64,
    /// Multiplier of the closure `G` (0 for up–down symmetric shapes).
    pub lambda_g: f64,
    /// Multiplier of the bilayer-couple constraint `J − Δa` (0 for the other models).
    pub lambda_j: f64,
    /// The functional at `a`.
    pub eval: Eval,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Final `max |KKT residual|`.
    pub residual: f64,
}

/// Newton gives up when the residual grows this much above its starting value (a start
/// outside the basin: the step is halved by the continuation instead).
const DIVERGED: f64 = 100.0;

/// Relative step of the finite-difference Hessian.
const FD_STEP: f64 = 1e-5;

/// Residual reduction per Newton step below which the Hessian is kept for the next step.
const REBUILD: f64 = 0.05;

/// The active constraints at `ev` as `(value, gradient)`: `v − v0`; the closure `G` if
/// `closure`; `J − Δa` for the bilayer couple. Multipliers are listed in the same order.
pub(crate) fn constraints<'a>(
    basis: &Basis,
    ev: &'a Eval,
    v0: f64,
    closure: bool,
) -> Vec<(f64, &'a [f64])> {
    let mut c = vec![(ev.v - v0, ev.grad_v.as_slice())];
    if closure {
        c.push((ev.g, ev.grad_g.as_slice()));
    }
    if let (Model::Bc { da }, Some(gj)) = (basis.model, &ev.grad_j) {
        c.push((ev.j - da, gj.as_slice()));
    }
    c
}

/// The multipliers `λ` (in [`constraints`] order) as `(λ_v, λ_G, λ_J)`.
fn split(basis: &Basis, lam: &[f64], closure: bool) -> (f64, f64, f64) {
    let lg = if closure { lam[1] } else { 0.0 };
    let lj = if matches!(basis.model, Model::Bc { .. }) {
        lam[lam.len() - 1]
    } else {
        0.0
    };
    (lam[0], lg, lj)
}

/// Central-difference Hessian of `ℒ` at `a` (row-major `n × n`, symmetrised); `None` if a
/// perturbed shape is not admissible.
pub(crate) fn fd_hessian(basis: &Basis, a: &[f64], lam: &[f64], closure: bool) -> Option<Vec<f64>> {
    let n = a.len();
    let mut hess = vec![0.0; n * n];
    let mut ap = a.to_vec();
    for k in 0..n {
        ap[k] = a[k] + FD_STEP;
        let gp = lagrangian_grad(basis, &basis.eval(&ap)?, lam, closure);
        ap[k] = a[k] - FD_STEP;
        let gm = lagrangian_grad(basis, &basis.eval(&ap)?, lam, closure);
        ap[k] = a[k];
        for i in 0..n {
            let h = 0.25 * (gp[i] - gm[i]) / FD_STEP;
            hess[i * n + k] += h;
            hess[k * n + i] += h;
        }
    }
    Some(hess)
}

/// `∇ℒ = ∇e + Σ λ_i ∇c_i` over the [`constraints`].
pub(crate) fn lagrangian_grad(basis: &Basis, ev: &Eval, lam: &[f64], closure: bool) -> Vec<f64> {
    let mut g = ev.grad_e.clone();
    for ((_, grad), l) in constraints(basis, ev, 0.0, closure).iter().zip(lam) {
        for (g, c) in g.iter_mut().zip(grad.iter()) {
            *g += l * c;
        }
    }
    g
}

/// The KKT matrix `[[H, Cᵀ], [C, 0]]` (row-major, `n + nc` square) of the Hessian `h` and the
/// constraint gradients `rows`, with `mu` added to the diagonal of `H`.
pub(crate) fn kkt_matrix(h: &[f64], rows: &[&[f64]], n: usize, mu: f64) -> Vec<f64> {
    let dim = n + rows.len();
    let mut kkt = vec![0.0; dim * dim];
    for i in 0..n {
        kkt[i * dim..i * dim + n].copy_from_slice(&h[i * n..(i + 1) * n]);
        kkt[i * dim + i] += mu;
        for (r, row) in rows.iter().enumerate() {
            kkt[i * dim + n + r] = row[i];
            kkt[(n + r) * dim + i] = row[i];
        }
    }
    kkt
}

/// The [`Converged`] state of `a` with multipliers `lam`.
fn converged(
    basis: &Basis,
    a: Vec<f64>,
    lam: &[f64],
    closure: bool,
    ev: Eval,
    it: usize,
    res: f64,
) -> Converged {
    let (lv, lg, lj) = split(basis, lam, closure);
    Converged {
        a,
        lambda_v: lv,
        lambda_g: lg,
        lambda_j: lj,
        eval: ev,
        iterations: it,
        residual: res,
    }
}

/// Newton from `a0` to the stationary point of `e` at `v = v0` (and `G = 0` if `closure`).
/// `None` if the iteration leaves the admissible shapes, meets a singular system or does not
/// converge in `max_iter` steps.
pub(crate) fn newton(
    basis: &Basis,
    a0: &[f64],
    v0: f64,
    closure: bool,
    set: &NewtonSettings,
) -> Option<Converged> {
    let n = a0.len();
    let mut a = a0.to_vec();
    let mut ev = basis.eval(&a)?;
    // Initial multipliers: least squares ∇e + Σ λ_i ∇c_i ≈ 0.
    let mut lam = initial_multipliers(basis, &ev, closure);
    let mut first = None;
    let mut hess: Option<Vec<f64>> = None;
    let mut last_residual = f64::INFINITY;
    for iter in 0..=set.max_iter {
        let grad = lagrangian_grad(basis, &ev, &lam, closure);
        let cons = constraints(basis, &ev, v0, closure);
        let mut rhs: Vec<f64> = grad.iter().map(|g| -g).collect();
        rhs.extend(cons.iter().map(|(c, _)| -c));
        let residual = rhs.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        if !residual.is_finite() || residual > DIVERGED * first.unwrap_or(residual) {
            return None;
        }
        first.get_or_insert(residual);
        if residual < set.tol {
            return Some(converged(basis, a, &lam, closure, ev, iter, residual));
        }
        if iter == set.max_iter {
            return None;
        }
        // KKT matrix with the finite-difference Hessian of ℒ, rebuilt only when the last step
        // reduced the residual by less than REBUILD (a chord method otherwise).
        if hess.is_none() || residual > REBUILD * last_residual {
            hess = Some(fd_hessian(basis, &a, &lam, closure)?);
        }
        last_residual = residual;
        let h = hess.as_ref().expect("built above");
        let rows: Vec<&[f64]> = cons.iter().map(|(_, g)| *g).collect();
        let dim = n + rows.len();
        let mut kkt = kkt_matrix(h, &rows, n, 0.0);
        let mut dx = lu_solve(&mut kkt, &mut rhs.clone(), dim)?;
        let big = dx[..n].iter().fold(0.0f64, |m, d| m.max(d.abs()));
        if big > set.max_step {
            let f = set.max_step / big;
            dx.iter_mut().for_each(|d| *d *= f);
        }
        // Halve the step while it leaves the admissible shapes.
        let mut scale = 1.0;
        let next = loop {
            let trial: Vec<f64> = a.iter().zip(&dx).map(|(a, d)| a + scale * d).collect();
            if let Some(e) = basis.eval(&trial) {
                break Some((trial, e));
            }
            scale *= 0.5;
            if scale < 1e-3 {
                break None;
            }
        };
        let (trial, e) = next?;
        a = trial;
        ev = e;
        for (l, d) in lam.iter_mut().zip(&dx[n..]) {
            *l += scale * d;
        }
    }
    None
}

/// Least-squares multipliers for `∇e + Σ λ_i ∇c_i ≈ 0` over the [`constraints`] (zero where
/// the normal equations are singular, as at the sphere where `∇v = 0`).
pub(crate) fn initial_multipliers(basis: &Basis, ev: &Eval, closure: bool) -> Vec<f64> {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let rows: Vec<&[f64]> = constraints(basis, ev, 0.0, closure)
        .iter()
        .map(|(_, g)| *g)
        .collect();
    let nc = rows.len();
    let mut m: Vec<f64> = (0..nc * nc)
        .map(|ij| dot(rows[ij / nc], rows[ij % nc]))
        .collect();
    let mut r: Vec<f64> = rows.iter().map(|g| -dot(&ev.grad_e, g)).collect();
    if nc == 1 {
        return vec![if m[0] > 1e-300 { r[0] / m[0] } else { 0.0 }];
    }
    lu_solve(&mut m, &mut r, nc).unwrap_or_else(|| vec![0.0; nc])
}

/// Solve `A x = b` (row-major `dim × dim`) by Gaussian elimination with partial pivoting;
/// `A` and `b` are overwritten. `None` if `A` is singular to working precision.
pub(crate) fn lu_solve(a: &mut [f64], b: &mut [f64], dim: usize) -> Option<Vec<f64>> {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for col in 0..dim {
        let piv = (col..dim)
            .max_by(|&i, &j| a[i * dim + col].abs().total_cmp(&a[j * dim + col].abs()))?;
        if a[piv * dim + col].abs() <= 1e-14 * scale {
            return None;
        }
        if piv != col {
            for k in 0..dim {
                a.swap(piv * dim + k, col * dim + k);
            }
            b.swap(piv, col);
        }
        let p = a[col * dim + col];
        for i in col + 1..dim {
            let f = a[i * dim + col] / p;
            if f != 0.0 {
                for k in col..dim {
                    a[i * dim + k] -= f * a[col * dim + k];
                }
                b[i] -= f * b[col];
            }
        }
    }
    let mut x = vec![0.0; dim];
    for i in (0..dim).rev() {
        let s: f64 = (i + 1..dim).map(|k| a[i * dim + k] * x[k]).sum();
        x[i] = (b[i] - s) / a[i * dim + i];
    }
    Some(x)
}

/// Move `a` onto the constraints `v = v0` (and `G = 0` if `closure`) by Gauss–Newton
/// minimum-norm corrections `δa = −Jᵀ (J Jᵀ)⁻¹ c`. `None` if it leaves the admissible shapes
/// or does not reach `|c| < 1e-13` in 30 corrections.
fn project(basis: &Basis, a: &[f64], v0: f64, closure: bool) -> Option<(Vec<f64>, Eval)> {
    let mut a = a.to_vec();
    for _ in 0..30 {
        let ev = basis.eval(&a)?;
        let cons = constraints(basis, &ev, v0, closure);
        if cons.iter().all(|(c, _)| c.abs() < 1e-13) {
            return Some((a, ev));
        }
        let nc = cons.len();
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let mut m: Vec<f64> = (0..nc * nc)
            .map(|ij| dot(cons[ij / nc].1, cons[ij % nc].1))
            .collect();
        let mut rhs: Vec<f64> = cons.iter().map(|(c, _)| -c).collect();
        let y = lu_solve(&mut m, &mut rhs, nc)?;
        for (i, ai) in a.iter_mut().enumerate() {
            *ai += (0..nc).map(|r| y[r] * cons[r].1[i]).sum::<f64>();
        }
    }
    None
}

/// Descend to a constrained local minimum of `e` from a rough start `a0`, then finish with
/// [`newton`]: a Levenberg–Marquardt iteration on the constraint surface. Each step solves
///
/// ```text
/// [ ∇²ℒ + μI   Jᵀ ] [ δa ]   [ −∇ℒ ]
/// [ J          0  ] [ y  ] = [  0  ]      (J = ∇ of the constraints, λ least squares)
/// ```
///
/// projects `a + δa` back onto the constraints and accepts it if `e` fell (then `μ ← μ/3`),
/// else retries with `μ ← 4μ`. It hands over to Newton once `max |∇ℒ| < 1e-6`.
/// `None` if `μ` exceeds `1e8` or 300 steps do not get there.
pub(crate) fn minimise(
    basis: &Basis,
    a0: &[f64],
    v0: f64,
    closure: bool,
    set: &NewtonSettings,
) -> Option<Converged> {
    let n = a0.len();
    let (mut a, mut ev) = project(basis, a0, v0, closure)?;
    let mut mu = 1.0;
    for _ in 0..300 {
        let lam = initial_multipliers(basis, &ev, closure);
        let grad = lagrangian_grad(basis, &ev, &lam, closure);
        if grad.iter().all(|g| g.abs() < 1e-6) {
            return newton(basis, &a, v0, closure, set);
        }
        let hess = fd_hessian(basis, &a, &lam, closure)?;
        loop {
            let cons = constraints(basis, &ev, v0, closure);
            let rows: Vec<&[f64]> = cons.iter().map(|(_, g)| *g).collect();
            let dim = n + rows.len();
            let mut kkt = kkt_matrix(&hess, &rows, n, mu);
            let mut rhs: Vec<f64> = grad.iter().map(|g| -g).collect();
            rhs.resize(dim, 0.0);
            let step = lu_solve(&mut kkt, &mut rhs, dim).map(|mut d| {
                d.truncate(n);
                let big = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                if big > set.max_step {
                    d.iter_mut().for_each(|x| *x *= set.max_step / big);
                }
                d
            });
            let trial = step.and_then(|d| {
                let t: Vec<f64> = a.iter().zip(&d).map(|(a, d)| a + d).collect();
                project(basis, &t, v0, closure)
            });
            match trial {
                Some((t, te)) if te.e < ev.e => {
                    a = t;
                    ev = te;
                    mu = (mu / 3.0).max(1e-10);
                    break;
                }
                _ => {
                    mu *= 4.0;
                    if mu > 1e8 {
                        return None;
                    }
                }
            }
        }
    }
    None
}
