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
//! The gradients are exact; `∇²ℒ` is the central difference of `∇ℒ` (step `1e-5`: truncation
//! `≈ 1e-10`, round-off `≈ 1e-11` relative), which leaves Newton's convergence quadratic down to
//! that level and linear with a factor `≈ 1e-10` below it.

use super::functional::{Basis, Eval};

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

/// Central-difference Hessian of `ℒ` at `a` (row-major `n × n`, symmetrised); `None` if a
/// perturbed shape is not admissible.
fn fd_hessian(basis: &Basis, a: &[f64], lv: f64, lg: f64, closure: bool) -> Option<Vec<f64>> {
    let n = a.len();
    let mut hess = vec![0.0; n * n];
    let mut ap = a.to_vec();
    for k in 0..n {
        ap[k] = a[k] + FD_STEP;
        let gp = lagrangian_grad(&basis.eval(&ap)?, lv, lg, closure);
        ap[k] = a[k] - FD_STEP;
        let gm = lagrangian_grad(&basis.eval(&ap)?, lv, lg, closure);
        ap[k] = a[k];
        for i in 0..n {
            let h = 0.25 * (gp[i] - gm[i]) / FD_STEP;
            hess[i * n + k] += h;
            hess[k * n + i] += h;
        }
    }
    Some(hess)
}

/// `∇ℒ = ∇e + λ_v ∇v + λ_G ∇G`.
fn lagrangian_grad(ev: &Eval, lv: f64, lg: f64, closure: bool) -> Vec<f64> {
    (0..ev.grad_e.len())
        .map(|k| {
            let mut g = ev.grad_e[k] + lv * ev.grad_v[k];
            if closure {
                g += lg * ev.grad_g[k];
            }
            g
        })
        .collect()
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
    let nc = if closure { 2 } else { 1 };
    let mut a = a0.to_vec();
    let mut ev = basis.eval(&a)?;
    // Initial multipliers: least squares ∇e + λ_v ∇v + λ_G ∇G ≈ 0.
    let (mut lv, mut lg) = initial_multipliers(&ev, closure);
    let mut first = None;
    let mut hess: Option<Vec<f64>> = None;
    let mut last_residual = f64::INFINITY;
    for iter in 0..=set.max_iter {
        let grad = lagrangian_grad(&ev, lv, lg, closure);
        let mut rhs: Vec<f64> = grad.iter().map(|g| -g).collect();
        rhs.push(-(ev.v - v0));
        if closure {
            rhs.push(-ev.g);
        }
        let residual = rhs.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        if !residual.is_finite() || residual > DIVERGED * first.unwrap_or(residual) {
            return None;
        }
        first.get_or_insert(residual);
        if residual < set.tol {
            return Some(Converged {
                a,
                lambda_v: lv,
                lambda_g: if closure { lg } else { 0.0 },
                eval: ev,
                iterations: iter,
                residual,
            });
        }
        if iter == set.max_iter {
            return None;
        }
        // KKT matrix with the finite-difference Hessian of ℒ, rebuilt only when the last step
        // reduced the residual by less than REBUILD (a chord method otherwise).
        if hess.is_none() || residual > REBUILD * last_residual {
            hess = Some(fd_hessian(basis, &a, lv, lg, closure)?);
        }
        last_residual = residual;
        let h = hess.as_ref().expect("built above");
        let dim = n + nc;
        let mut kkt = vec![0.0; dim * dim];
        for i in 0..n {
            kkt[i * dim..i * dim + n].copy_from_slice(&h[i * n..(i + 1) * n]);
        }
        for i in 0..n {
            kkt[i * dim + n] = ev.grad_v[i];
            kkt[n * dim + i] = ev.grad_v[i];
            if closure {
                kkt[i * dim + n + 1] = ev.grad_g[i];
                kkt[(n + 1) * dim + i] = ev.grad_g[i];
            }
        }
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
        lv += scale * dx[n];
        if closure {
            lg += scale * dx[n + 1];
        }
    }
    None
}

/// Least-squares multipliers for `∇e + λ_v ∇v + λ_G ∇G ≈ 0` (zero where the constraint
/// gradients vanish, as at the sphere).
fn initial_multipliers(ev: &Eval, closure: bool) -> (f64, f64) {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let (gv, gg, ge) = (&ev.grad_v, &ev.grad_g, &ev.grad_e);
    if !closure {
        let d = dot(gv, gv);
        return if d > 1e-300 {
            (-dot(ge, gv) / d, 0.0)
        } else {
            (0.0, 0.0)
        };
    }
    let mut m = [dot(gv, gv), dot(gv, gg), dot(gg, gv), dot(gg, gg)];
    let mut r = [-dot(ge, gv), -dot(ge, gg)];
    lu_solve(&mut m, &mut r, 2).map_or((0.0, 0.0), |x| (x[0], x[1]))
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
        let mut rows = vec![ev.grad_v.clone()];
        let mut c = vec![ev.v - v0];
        if closure {
            rows.push(ev.grad_g.clone());
            c.push(ev.g);
        }
        if c.iter().all(|c| c.abs() < 1e-13) {
            return Some((a, ev));
        }
        let nc = rows.len();
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let mut m: Vec<f64> = (0..nc * nc)
            .map(|ij| dot(&rows[ij / nc], &rows[ij % nc]))
            .collect();
        let mut rhs: Vec<f64> = c.iter().map(|c| -c).collect();
        let y = lu_solve(&mut m, &mut rhs, nc)?;
        for (i, ai) in a.iter_mut().enumerate() {
            *ai += (0..nc).map(|r| y[r] * rows[r][i]).sum::<f64>();
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
    let nc = if closure { 2 } else { 1 };
    let (mut a, mut ev) = project(basis, a0, v0, closure)?;
    let mut mu = 1.0;
    for _ in 0..300 {
        let (lv, lg) = initial_multipliers(&ev, closure);
        let grad = lagrangian_grad(&ev, lv, lg, closure);
        if grad.iter().all(|g| g.abs() < 1e-6) {
            return newton(basis, &a, v0, closure, set);
        }
        let hess = fd_hessian(basis, &a, lv, lg, closure)?;
        loop {
            let dim = n + nc;
            let mut kkt = vec![0.0; dim * dim];
            for i in 0..n {
                for k in 0..n {
                    kkt[i * dim + k] = hess[i * n + k];
                }
                kkt[i * dim + i] += mu;
                kkt[i * dim + n] = ev.grad_v[i];
                kkt[n * dim + i] = ev.grad_v[i];
                if closure {
                    kkt[i * dim + n + 1] = ev.grad_g[i];
                    kkt[(n + 1) * dim + i] = ev.grad_g[i];
                }
            }
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
