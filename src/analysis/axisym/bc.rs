//! The bilayer-couple (BC) model: stationary shapes at fixed reduced volume `v` and area
//! difference `Δa` ([`super::Model::Bc`], the constraint `J = Δa` in the Newton system), each
//! branch followed at fixed `v` with `Δa` free ([`bc_curve`]).
//!
//! * Prolate, oblate, stomatocyte: the branch's SC shape at `v` (at `c̄0`, or for a stomatocyte
//!   that does not reach `v` there at `c̄0` lowered in steps of 1, or for one that reaches it
//!   at none of them the BC shape continued in `v` from a smaller `v`, [`start_below`]) is the
//!   BC shape at its own `Δa`; a second one is the SC shape at `c̄0,eff ± 0.1`. From these
//!   two the branch is followed both ways by pseudo-arclength in the coefficients (the BC
//!   Newton system with the row of `Δa` replaced by the arclength condition): near `v = 1`
//!   the branches are so stiff in `Δa` (at `v = 0.9` the SC prolate's `Δa` moves by 2e-5
//!   between `c̄0 = −1` and 2) that neither `Δa` nor `c̄0` is a usable parameter. The
//!   stomatocyte's modes are stretched at its neck once it is below 0.1 R0, as the pear's
//!   ([`super::map`]), so its path closes the neck towards `L_sto`.
//! * Pear: the up–down test function of the prolate ([`super::prolate_updown`]'s `μ`, the
//!   smallest eigenvalue of the odd Hessian block of the BC Lagrangian, which is that of the
//!   SC Lagrangian at `c̄0,eff`) is evaluated along the prolate's path towards larger `Δa`; its
//!   first sign change is refined by the secant method in `Δa`. The prolates past it (μ < 0),
//!   kicked along the unstable eigenvector, descend (the solver's constrained minimisation,
//!   every mode, closure held) to the pear, which is followed both ways by arclength.
//!
//! The BC energy is `e` (at [`super::Options::c0`], usually 0: at fixed `Δa`, `c̄0` only adds
//! the constant `−c̄0 Δa + c̄0²/4`).

use super::branches::secant_in_v;
use super::functional::Basis;
use super::limits::inner_spheres_da;
use super::map::{moved_map, new_map, reproject};
use super::pear::{full_basis, odd_stability};
use super::solver::{
    constraints, fd_hessian, kkt_matrix, lagrangian_grad, lu_solve, minimise, newton, Converged,
    NewtonSettings,
};
use super::{solution, solve, Branch, Model, Options, Solution};
use crate::error::{Error, Result};

/// [`bc_solution`] starts Newton from the curve's shape nearest in `Δa` if it is this close.
const NEAR: f64 = 0.02;

/// Most Newton solves [`Walker::approach`] takes on its way to a `Δa`.
const APPROACH_SOLVES: usize = 40;

/// Step in `Δa` below which [`Walker::approach`] gives up.
const APPROACH_MIN_STEP: f64 = 1e-7;

/// Narrowest neck (`R0`) at which [`updown_changes`] evaluates `μ`. Below it the zeros at 241
/// nodes are not those at 481: along the chart's v grid (0.60–0.98) 241 nodes put extra pairs of
/// zeros at necks of 0.005–0.012 R0 (v = 0.60, 0.62, 0.64, 0.86) that 481 nodes do not have,
/// while every zero at a neck of 0.02 R0 or wider agrees to 1e-5 in `Δa`.
const UPDOWN_NECK_MIN: f64 = 0.015;

/// Amplitudes of the unstable eigenvector added to the prolate to start the pear, in order.
const PEAR_KICKS: [f64; 3] = [0.05, 0.2, 0.5];

/// A branch of the BC model followed in `Δa` at fixed `v`.
#[derive(Clone, Debug)]
pub struct BcCurve {
    /// The branch.
    pub branch: Branch,
    /// The reduced volume.
    pub v: f64,
    /// The shapes in the order of the continuation path ([`Solution::model`] is
    /// [`Model::Bc`]); `Δa` need not be monotone along it (the path may fold).
    pub shapes: Vec<Solution>,
    /// For the pear: the prolate where the pear leaves it (the prolate's up–down test
    /// function vanishes there); `None` otherwise or if not found.
    pub bifurcation: Option<Solution>,
}

/// A branch being followed in `Δa`: the basis (whose model carries the current target) and the
/// last (at most two) solutions.
struct Walker {
    branch: Branch,
    basis: Basis,
    closure: bool,
    set: NewtonSettings,
    v: f64,
    last: Vec<Converged>,
    /// The neck the basis's map was made for (`None`: the identity map).
    mapped: Option<f64>,
}

impl Walker {
    fn new(branch: Branch, v: f64, basis: Basis, closure: bool, opts: &Options) -> Self {
        Walker {
            branch,
            basis,
            closure,
            set: NewtonSettings {
                tol: opts.tol,
                max_iter: opts.max_iter,
                max_step: 0.5,
            },
            v,
            last: Vec::new(),
            mapped: None,
        }
    }

    fn current(&self) -> &Converged {
        self.last.last().expect("walker started")
    }

    fn push(&mut self, c: Converged) {
        if self.last.len() == 2 {
            self.last.remove(0);
        }
        self.last.push(c);
    }

    /// Newton at `Δa = da` from `a0` (the basis's model becomes `Bc { da }`).
    fn solve_at(&mut self, da: f64, a0: &[f64]) -> Option<Converged> {
        self.basis.model = Model::Bc { da };
        newton(&self.basis, a0, self.v, self.closure, &self.set)
    }

    /// The state at `Δa = da` from the converged `start` (at its own `Δa`), by Newton at
    /// fixed `Δa` in steps that grow by 1.5 after a success and halve after a failure; `None`
    /// after [`APPROACH_SOLVES`] solves or once the step falls below [`APPROACH_MIN_STEP`].
    /// One Newton from `start` is not enough near a closing neck: at v = 0.88 and 241 nodes,
    /// 1.5e-4 in `Δa` from a stomatocyte whose neck is 0.0063 R0, the first step's quadratic
    /// error raises the residual 115-fold and Newton gives up, where a quarter of that
    /// distance converges in four iterations.
    fn approach(&mut self, start: Converged, da: f64) -> Option<Converged> {
        let (mut cur, mut at) = (start, None::<f64>);
        let mut step = da - cur.eval.j;
        for _ in 0..APPROACH_SOLVES {
            let from = at.unwrap_or(cur.eval.j);
            let left = da - from;
            let target = if left.abs() <= step.abs() {
                da
            } else {
                from + step
            };
            match self.solve_at(target, &cur.a) {
                Some(c) if target == da => return Some(c),
                Some(c) => {
                    (cur, at) = (c, Some(target));
                    step *= 1.5;
                }
                None => {
                    step *= 0.5;
                    if step.abs() < APPROACH_MIN_STEP {
                        return None;
                    }
                }
            }
        }
        None
    }

    fn solution(&self) -> Solution {
        solution(self.branch, &self.basis, self.current())
    }

    /// Once the neck of `s` (the state `cur`) calls for a new map ([`new_map`]: below 0.1 R0,
    /// or narrowed or moved since the last one; or, on a stretched basis, moved at any width,
    /// [`moved_map`]; mirrored on the up–down symmetric branches): the basis stretched at the
    /// neck, `prev` and `cur` re-projected onto it ([`reproject`]) and each
    /// solved again at its own `Δa` (`prev` kept re-projected if its solve fails), so that
    /// the secant `cur − prev` that sets the next step runs along the path and not along the
    /// change of resolution. (The stomatocyte's start at v = 0.88, neck 0.058 R0, gains 0.007
    /// in `e` from the map; with `prev` only re-projected and the start unstretched, that
    /// difference turned the walk back on its first step.) Returns the pair in the new
    /// coordinates, or `None` (basis unchanged) if no map is due or the solve of `cur` fails.
    fn remap(
        &mut self,
        s: &Solution,
        prev: &Converged,
        cur: &Converged,
    ) -> Option<(Converged, Converged)> {
        let (map, neck) =
            new_map(s, &self.basis.map, self.mapped).or_else(|| moved_map(s, &self.basis.map))?;
        let old = self.basis.map;
        let modes = self.basis.modes.clone();
        let nb = self.basis.clone().with_map(map);
        let a_cur = reproject(&cur.a, &old, &map, &modes);
        let saved = std::mem::replace(&mut self.basis, nb);
        let Some(c) = self.solve_at(cur.eval.j, &a_cur) else {
            self.basis = saved;
            return None;
        };
        self.mapped = (!map.is_identity()).then_some(neck);
        let a_prev = reproject(&prev.a, &old, &map, &modes);
        let p = self.solve_at(prev.eval.j, &a_prev).unwrap_or_else(|| {
            let mut p = prev.clone();
            p.a = a_prev;
            p
        });
        Some((p, c))
    }
}

/// The modes of `branch` (even only for the up–down symmetric branches).
pub(super) fn basis_of(branch: Branch, opts: &Options) -> Basis {
    if branch.up_down_symmetric() {
        Basis::new(opts.nodes - 1, (2..=opts.modes).step_by(2).collect())
            .with_c0(opts.c0)
            .with_model(opts.model)
    } else {
        full_basis(opts)
    }
}

/// The SC shape of `branch` at `v` that starts the BC curve: at `opts.c0`, or for a
/// stomatocyte (oblate) that does not reach `v` there, at `c̄0` lowered (raised) in steps.
fn sc_start(branch: Branch, v: f64, opts: &Options) -> Option<Solution> {
    let sc = opts.with_model(Model::Sc);
    let shifts: &[f64] = match branch {
        Branch::Stomatocyte => &[0.0, -1.0, -2.0, -3.0, -4.0],
        Branch::Oblate => &[0.0, -1.0, 1.0],
        _ => &[0.0],
    };
    shifts
        .iter()
        .find_map(|d| solve(branch, v, &sc.with_c0(opts.c0 + d)).ok())
        .filter(|s| branch.up_down_symmetric() || s.asymmetry() > super::phase::ASYMMETRIC)
}

/// A walker of `branch` (not the pear) started at its SC shape at `v` ([`start_sc`]); for a
/// stomatocyte whose SC branch reaches `v` at none of the `c̄0` of [`sc_start`], from a
/// smaller `v` ([`start_below`]).
fn start(branch: Branch, v: f64, opts: &Options) -> Option<Walker> {
    start_sc(branch, v, opts).or_else(|| {
        (branch == Branch::Stomatocyte)
            .then(|| start_below(v, opts))
            .flatten()
    })
}

/// A walker of `branch` (not the pear) started at its SC shape at `v` ([`sc_start`]).
fn start_sc(branch: Branch, v: f64, opts: &Options) -> Option<Walker> {
    let s = sc_start(branch, v, opts)?;
    let mut w = Walker::new(
        branch,
        v,
        basis_of(branch, opts),
        !branch.up_down_symmetric(),
        opts,
    );
    // The SC shape at another c̄0 is the BC shape at its Δa (the multiplier absorbs the
    // difference); the basis keeps opts.c0.
    let c = w.solve_at(s.da(), &s.coefficients)?;
    w.push(c);
    Some(w)
}

/// [`start_below`] looks for an SC start at `v − k DV_BELOW`, `k = 1 … K_BELOW`.
const DV_BELOW: f64 = 0.01;
/// See [`DV_BELOW`].
const K_BELOW: usize = 10;

/// A stomatocyte walker at `v` from the nearest smaller `v' = v − k DV_BELOW` where its SC
/// start exists (as at v = 0.98, which the SC stomatocyte reaches at none of `c̄0` = 0 … −4:
/// it turns back in `v` at 0.661, 0.868, 0.936, 0.962, 0.975 at 121 nodes), followed in `v`
/// at fixed height above `L_sto`: the BC shape at
///
/// ```text
/// Δa(u) = Δa' + Δa_Lsto(u) − Δa_Lsto(v'),    u from v' to v
/// ```
///
/// (`Δa'` the start's), by Newton at each `u` from the secant predictor, steps of at most
/// 0.005 in `u` halved on failure down to 1e-4. Holding the distance to `L_sto` keeps the
/// neck from closing as `u` grows (at fixed `Δa` the path would run into `L_sto`, whose `Δa`
/// rises with `v`).
fn start_below(v: f64, opts: &Options) -> Option<Walker> {
    let (mut w, v0) = (1..=K_BELOW).find_map(|k| {
        let v0 = v - k as f64 * DV_BELOW;
        start_sc(Branch::Stomatocyte, v0, opts).map(|w| (w, v0))
    })?;
    let l0 = inner_spheres_da(v0, 1)?;
    let da0 = w.current().eval.j;
    let da_at = |u: f64| inner_spheres_da(u, 1).map(|l| da0 + l - l0);
    let mut step = 0.0025;
    while w.v < v {
        let u = (w.v + step).min(v);
        let a0 = secant_in_v(&w.last, u);
        let v_last = w.v;
        w.v = u;
        match w.solve_at(da_at(u)?, &a0) {
            Some(c) => {
                w.push(c);
                step = (2.0 * step).min(0.005);
            }
            None => {
                w.v = v_last;
                step *= 0.5;
                if step < 1e-4 {
                    return None;
                }
            }
        }
    }
    Some(w)
}

/// First arclength step (Euclidean norm of the coefficient change).
const H0: f64 = 0.01;
/// Largest arclength step.
const H_MAX: f64 = 0.05;
/// Arclength step below which the continuation counts as ended.
const H_MIN: f64 = 1e-4;
/// Most arclength steps in one direction.
const MAX_STEPS: usize = 200;
/// The continuation stops where `|c̄0,eff|` exceeds this (the shape is then close to a limit
/// shape or a sphere-like end the modes do not resolve).
const C_MAX: f64 = 150.0;

/// Newton for a BC shape with `Δa` free on the hyperplane `d·(a − p) = 0`: the BC KKT system
/// with the row of `J − Δa` replaced by the arclength condition (the column of `∇J`, and so
/// `λ_J = c̄0 − c̄0,eff`, stays). `lam` starts the multipliers (`λ_v`, `λ_G`, `λ_J`).
fn newton_arc(
    basis: &Basis,
    p: &[f64],
    d: &[f64],
    v0: f64,
    closure: bool,
    lam: &[f64],
    set: &NewtonSettings,
) -> Option<Converged> {
    let n = p.len();
    let mut a = p.to_vec();
    let mut lam = lam.to_vec();
    for iter in 0..=set.max_iter {
        let ev = basis.eval(&a)?;
        let grad = lagrangian_grad(basis, &ev, &lam, closure);
        let cons = constraints(basis, &ev, v0, closure);
        let nc = cons.len();
        let mut rhs: Vec<f64> = grad.iter().map(|g| -g).collect();
        rhs.extend(cons.iter().map(|(c, _)| -c));
        let arc: f64 = d
            .iter()
            .zip(a.iter().zip(p))
            .map(|(d, (x, y))| d * (x - y))
            .sum();
        rhs[n + nc - 1] = -arc;
        let residual = rhs.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        if !residual.is_finite() {
            return None;
        }
        if residual < set.tol {
            let lg = if closure { lam[1] } else { 0.0 };
            return Some(Converged {
                a,
                lambda_v: lam[0],
                lambda_g: lg,
                lambda_j: lam[nc - 1],
                eval: ev,
                iterations: iter,
                residual,
            });
        }
        if iter == set.max_iter {
            return None;
        }
        let h = fd_hessian(basis, &a, &lam, closure)?;
        let rows: Vec<&[f64]> = cons.iter().map(|(_, g)| *g).collect();
        let dim = n + nc;
        let mut kkt = kkt_matrix(&h, &rows, n, 0.0);
        let last = n + nc - 1;
        kkt[last * dim..(last + 1) * dim].fill(0.0);
        kkt[last * dim..last * dim + n].copy_from_slice(d);
        let dx = lu_solve(&mut kkt, &mut rhs, dim)?;
        let big = dx[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let f = if big > set.max_step {
            set.max_step / big
        } else {
            1.0
        };
        for (x, dxi) in a.iter_mut().zip(&dx) {
            *x += f * dxi;
        }
        for (l, dl) in lam.iter_mut().zip(&dx[n..]) {
            *l += f * dl;
        }
    }
    None
}

/// The multipliers of a converged state in [`constraints`] order.
fn multipliers(c: &Converged, closure: bool) -> Vec<f64> {
    let mut l = vec![c.lambda_v];
    if closure {
        l.push(c.lambda_g);
    }
    l.push(c.lambda_j);
    l
}

/// Pseudo-arclength continuation in the coefficients from `prev` to `cur` onwards (the
/// direction of `cur − prev`), at fixed `v`, with `Δa` free: the predictor `p = a + h d`
/// (`d` the unit secant), the corrector [`newton_arc`]. Steps grow by 1.5 after a success (at
/// most `H_MAX`) and halve after a failure. Returns the shapes after `cur`, in path order,
/// until `stop` holds (that shape included), `|c̄0,eff| > C_MAX`, the step falls below
/// `H_MIN` or `MAX_STEPS` are taken. On the pear and the stomatocyte the modes cluster at a
/// neck below 0.1 R0 ([`Walker::remap`]), so the path reaches [`Options::neck_min`] (the
/// stomatocyte within 0.003 of `L_sto`'s `Δa`); each shape carries its map (where the map
/// changes, the shape is the one solved again in the new basis).
fn arc_follow(
    w: &mut Walker,
    mut prev: Converged,
    mut cur: Converged,
    mut stop: impl FnMut(&Solution) -> bool,
) -> Vec<Solution> {
    let mut out = Vec::new();
    let mut h = H0;
    let closure = w.closure;
    for _ in 0..MAX_STEPS {
        let diff: Vec<f64> = cur.a.iter().zip(&prev.a).map(|(x, y)| x - y).collect();
        let norm = diff.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm == 0.0 {
            break;
        }
        let d: Vec<f64> = diff.iter().map(|x| x / norm).collect();
        let next = loop {
            let p: Vec<f64> = cur.a.iter().zip(&d).map(|(x, d)| x + h * d).collect();
            let f = h / norm;
            let lam: Vec<f64> = multipliers(&cur, closure)
                .iter()
                .zip(multipliers(&prev, closure))
                .map(|(c, q)| c + f * (c - q))
                .collect();
            let solved = newton_arc(&w.basis, &p, &d, w.v, closure, &lam, &w.set).filter(|c| {
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
            break;
        };
        w.basis.model = Model::Bc { da: next.eval.j };
        let s = solution(w.branch, &w.basis, &next);
        let done = stop(&s) || s.c0_eff.abs() > C_MAX;
        let remapped = if done { None } else { w.remap(&s, &cur, &next) };
        // The shape as solved again in the new basis, where it has one.
        out.push(match &remapped {
            Some((_, c)) => {
                w.basis.model = Model::Bc { da: c.eval.j };
                solution(w.branch, &w.basis, c)
            }
            None => s,
        });
        if done {
            break;
        }
        (prev, cur) = remapped.unwrap_or((cur, next));
    }
    out
}

/// The branch at `v` from the BC shape `first` both ways along the path (towards larger and
/// smaller `Δa` at the start, judged by `second`, which lies on one side), as one list in
/// path order, `first` included; `stop(shape, up)` ends the walk in the direction of increasing
/// (`up`) or decreasing `Δa` after `shape`.
fn both_ways(
    w: &mut Walker,
    first: Converged,
    second: Converged,
    mut stop: impl FnMut(&Solution, bool) -> bool,
) -> Vec<Solution> {
    w.basis.model = Model::Bc { da: first.eval.j };
    let s0 = solution(w.branch, &w.basis, &first);
    let fwd_up = second.eval.j >= first.eval.j;
    let (basis, mapped) = (w.basis.clone(), w.mapped);
    let ahead = arc_follow(w, first.clone(), second.clone(), |s| stop(s, fwd_up));
    // Backwards: from `second` through `first` and on, in their own coordinates.
    (w.basis, w.mapped) = (basis, mapped);
    let behind = arc_follow(w, second, first, |s| stop(s, !fwd_up));
    let mut all: Vec<Solution> = behind.into_iter().rev().collect();
    all.push(s0);
    all.extend(ahead);
    all
}

/// Follow `branch` at reduced volume `v` by pseudo-arclength in the coefficients with `Δa`
/// free, from its SC shape at `v` both ways (the pear from its bifurcation off the prolate),
/// keeping the shapes with `Δa` in `[lo, hi]`, in path order. A walk ends outside `[lo, hi]`
/// (widened by 0.05) on the side it set out towards (a start below the window, as the
/// stomatocyte's at v ≤ 0.78 for
/// `[0.70, 1.40]`, walks up into it), where the oblate first touches itself, where the
/// stomatocyte passes its limit shape `L_sto` or the oblate invaginated at both poles its own
/// (`past_limit`), at a neck below [`Options::neck_min`], or where `|c̄0,eff| > 150`. A branch
/// without a start shape gives an empty curve.
pub fn bc_curve(branch: Branch, v: f64, (lo, hi): (f64, f64), opts: &Options) -> BcCurve {
    let neck_min = opts.neck_min;
    let mut ends = move |s: &Solution, up: bool| {
        (!up && s.da() < lo - 0.05)
            || (up && s.da() > hi + 0.05)
            || s.neck().is_some_and(|r| r < neck_min)
            || (s.branch == Branch::Oblate && s.self_intersecting())
            || (s.branch == Branch::Pear && s.asymmetry() < 1e-4)
            || past_limit(s)
    };
    let (shapes, bifurcation) = if branch == Branch::Pear {
        pear_path(v, opts, &mut ends)
    } else {
        let shapes = match start_pair(branch, v, opts) {
            Some((mut w, first, second)) => both_ways(&mut w, first, second, &mut ends),
            None => Vec::new(),
        };
        (shapes, None)
    };
    let shapes: Vec<Solution> = shapes
        .into_iter()
        .filter(|s| s.da() >= lo && s.da() <= hi)
        .filter(|s| !(s.branch == Branch::Oblate && s.self_intersecting()))
        .filter(|s| !past_limit(s))
        .collect();
    BcCurve {
        branch,
        v,
        shapes,
        bifurcation,
    }
}

/// Whether `s` lies past the limit shape its path ends at: a stomatocyte with `Δa` below that
/// of `L_sto` at its `v` (a sphere inside a sphere, [`inner_spheres_da`] with one), an oblate
/// invaginated at both poles below that of a sphere with two inside. There the necks close.
/// Past them the unmapped modes hold the neck at a width they can resolve (the stomatocyte at
/// v = 0.92: 0.02–0.03 R0 at K = 40, 0.015–0.02 at K = 80) and the path runs on to smaller
/// `Δa` with `e` above the limit's (2, 3) and `c̄0,eff` far beyond its neck condition: no
/// stationary shape of the branch.
fn past_limit(s: &Solution) -> bool {
    let inner = match s.branch {
        Branch::Stomatocyte => 1,
        Branch::Oblate => 2,
        _ => return false,
    };
    inner_spheres_da(s.v, inner).is_some_and(|da| s.da() < da)
}

/// The walker of `branch` at `v`, its SC shape as a BC state, and a second BC state: the SC
/// shape at `c̄0,eff + 0.1`, or at `c̄0,eff − 0.1` where that does not converge, solved from
/// the first, or failing both the BC shape at `Δa ± 0.005`. (The stomatocyte's SC start at
/// v = 0.64, 0.66 and 0.86 lies within 0.021 of the SC branch's turning point in `v`, 0.661
/// at `c̄0` = 0 and 0.868 at −1, which raising `c̄0` moves below `v`: there only the lowered
/// `c̄0` has a shape. At v = 0.96, 0.002 below the turning point at `c̄0` = −3, neither has
/// one once the start is solved in the stretched basis.)
fn start_pair(branch: Branch, v: f64, opts: &Options) -> Option<(Walker, Converged, Converged)> {
    let mut w = start(branch, v, opts)?;
    let mut first = w.current().clone();
    // A start whose neck is already narrow is solved in the stretched basis from the outset
    // ([`Walker::remap`]): at 241 nodes and v = 0.88 (neck 0.04 R0) the walk from the
    // unstretched start failed to remap at its next shape and ran unstretched for three more.
    let s = w.solution();
    if let Some((_, c)) = w.remap(&s, &first, &first) {
        first = c;
    }
    for d in [0.1, -0.1] {
        let c1 = opts.c0 - first.lambda_j + d;
        let sc = w.basis.clone().with_model(Model::Sc).with_c0(c1);
        let Some(a2) = newton(&sc, &first.a, v, w.closure, &w.set) else {
            continue;
        };
        let second = w.basis.eval(&a2.a).and_then(|ev| w.solve_at(ev.j, &a2.a));
        if let Some(second) = second {
            return Some((w, first, second));
        }
    }
    let second = [0.005, -0.005]
        .iter()
        .find_map(|d| w.solve_at(first.eval.j + d, &first.a))?;
    Some((w, first, second))
}

/// The up–down test function `μ` of a prolate BC shape (see [`super::prolate_updown`]) and its
/// eigenvector (full basis): the odd block of the Hessian of the BC Lagrangian is that of the
/// SC Lagrangian at `c̄0,eff`.
fn updown(s: &Solution, opts: &Options) -> Option<(f64, Vec<f64>)> {
    let full = full_basis(&opts.with_model(Model::Sc).with_c0(s.c0_eff)).with_map(s.map);
    odd_stability(&full, &to_full(s, full.modes.len()), s.lambda_v)
}

/// The coefficients of `s` in the full basis of `len` modes.
fn to_full(s: &Solution, len: usize) -> Vec<f64> {
    let mut a = vec![0.0; len];
    for (k, ak) in s.modes.iter().zip(&s.coefficients) {
        a[k - 1] = *ak;
    }
    a
}

/// Where the BC prolate at `v` loses up–down stability as `Δa` grows: its path scanned from
/// its SC shape towards larger `Δa` for the first sign change of `μ`, refined by the secant
/// method in `Δa` (BC solves). Along the BC path c̄0,eff need not grow monotonically (at
/// v = 0.70 it peaks near 2.13, where the SC prolate of fixed c̄0 folds), so this walk finds
/// bifurcations that a search at fixed c̄0 cannot. Returns the bifurcation and the prolates
/// met on its unstable side (μ < 0, nearest it last); `None` if the path meets no sign change
/// before its neck falls below `opts.neck_min`.
fn prolate_bifurcation(v: f64, opts: &Options) -> Option<(Solution, Vec<Solution>)> {
    let (mut w, first, second) = start_pair(Branch::Prolate, v, opts)?;
    w.basis.model = Model::Bc { da: first.eval.j };
    let s0 = solution(Branch::Prolate, &w.basis, &first);
    let (mu0, _) = updown(&s0, opts)?;
    // Walk the prolate towards larger Δa until μ changes sign.
    let mut bracket: Option<(Solution, f64, Solution, f64)> = None;
    let mut last = (s0, mu0);
    let (p, q) = if second.eval.j >= first.eval.j {
        (first, second)
    } else {
        (second, first)
    };
    let mut pending = None;
    arc_follow(&mut w, p, q, |s| {
        if pending.is_some() {
            return true;
        }
        match updown(s, opts) {
            Some((mu, _)) if (mu > 0.0) != (last.1 > 0.0) => {
                pending = Some((last.clone(), (s.clone(), mu)));
                true
            }
            Some((mu, _)) => {
                last = (s.clone(), mu);
                s.neck().is_some_and(|r| r < opts.neck_min)
            }
            None => true,
        }
    });
    if let Some(((sa, ma), (sb, mb))) = pending {
        bracket = Some((sa, ma, sb, mb));
    }
    let (sa, fa, sb, fb) = bracket?;
    Some(refine_updown(&mut w, (&sa, fa), (&sb, fb), opts))
}

/// The zero of `μ` between two prolates `sa` and `sb` of one BC path where `μ` has the
/// opposite signs `fa` and `fb`: the secant method (Illinois) on `μ(Δa)`, each BC solve started
/// from the bracket's coefficients interpolated (in the walker's map; the path may have
/// stretched its modes between them). Returns the last shape solved (`sb` if none) and the
/// prolates met with `μ < 0`, in the order met.
fn refine_updown(
    w: &mut Walker,
    (sa, mut fa): (&Solution, f64),
    (sb, mut fb): (&Solution, f64),
    opts: &Options,
) -> (Solution, Vec<Solution>) {
    // Stretched at `sb`'s neck where it calls for a map: a walk stopped by its bracket has not
    // remapped at its last shape (at v = 0.68, neck 0.082 R0, uniform modes put the zero 1.1e-4
    // high at 241 nodes).
    if let Some((map, neck)) = new_map(sb, &w.basis.map, w.mapped) {
        w.basis = w.basis.clone().with_map(map);
        w.mapped = Some(neck);
    }
    let (mut xa, mut xb) = (sa.da(), sb.da());
    let to_walker = |s: &Solution| reproject(&s.coefficients, &s.map, &w.basis.map, &s.modes);
    let (mut ca, mut cb) = (to_walker(sa), to_walker(sb));
    let mut unstable: Vec<Solution> = [(sa, fa), (sb, fb)]
        .iter()
        .filter(|(_, f)| *f < 0.0)
        .map(|(s, _)| (*s).clone())
        .collect();
    let mut side = 0i8;
    let mut best = sb.clone();
    for _ in 0..40 {
        if (xb - xa).abs() < 1e-10 {
            break;
        }
        let x = xb - fb * (xb - xa) / (fb - fa);
        let t = (x - xa) / (xb - xa);
        let a0: Vec<f64> = ca.iter().zip(&cb).map(|(a, b)| a + t * (b - a)).collect();
        let Some(c) = w.solve_at(x, &a0) else {
            break;
        };
        let s = solution(Branch::Prolate, &w.basis, &c);
        let Some((f, _)) = updown(&s, opts) else {
            break;
        };
        if f < 0.0 {
            unstable.push(s.clone());
        }
        if (f > 0.0) == (fb > 0.0) {
            fa = if side == 1 { 0.5 * fa } else { fa };
            side = 1;
        } else {
            xa = xb;
            fa = fb;
            ca = cb.clone();
            side = -1;
        }
        xb = x;
        fb = f;
        cb = s.coefficients.clone();
        best = s;
    }
    (best, unstable)
}

/// Where the prolate's up–down stability changes along its BC path: a zero of its test
/// function `μ`.
#[derive(Clone, Debug)]
pub struct UpdownChange {
    /// The prolate at the zero.
    pub shape: Solution,
    /// Whether the prolate loses its stability there (`μ` falls through zero walking the path
    /// from its end of smaller `Δa`); `false` where it regains it.
    pub loses: bool,
}

/// Every zero of the up–down test function `μ` along a prolate BC curve, walked from its end
/// of smaller `Δa` while its neck is wider than [`UPDOWN_NECK_MIN`], each refined by the secant
/// method in `Δa` ([`refine_updown`]). The first loss is where the pear leaves the prolate
/// ([`bc_bifurcation`]); after it the prolate, budding at both poles, can regain its stability
/// before its necks close (v = 0.86: Δa = 1.3619) and near v = 0.70 lose it again (1.4077).
/// Empty for another branch. A sign change across a shape where `μ` cannot be evaluated is
/// skipped.
pub fn updown_changes(curve: &BcCurve, opts: &Options) -> Vec<UpdownChange> {
    if curve.branch != Branch::Prolate || curve.shapes.is_empty() {
        return Vec::new();
    }
    let mut path: Vec<&Solution> = curve.shapes.iter().collect();
    if path[0].da() > path[path.len() - 1].da() {
        path.reverse();
    }
    let mut changes = Vec::new();
    let mut last: Option<(&Solution, f64)> = None;
    for s in path {
        if s.neck().is_some_and(|r| r < UPDOWN_NECK_MIN) {
            break;
        }
        let Some((mu, _)) = updown(s, opts) else {
            last = None;
            continue;
        };
        if let Some((sa, fa)) = last.filter(|(_, fa)| (*fa > 0.0) != (mu > 0.0)) {
            let basis = basis_of(Branch::Prolate, opts).with_map(s.map);
            let mut w = Walker::new(Branch::Prolate, curve.v, basis, false, opts);
            let (shape, _) = refine_updown(&mut w, (sa, fa), (s, mu), opts);
            changes.push(UpdownChange {
                shape,
                loses: fa > 0.0,
            });
        }
        last = Some((s, mu));
    }
    changes
}

/// Where the BC prolate at reduced volume `v` loses up–down stability (the BC pear's
/// bifurcation), `None` if it does not ([`prolate_bifurcation`]).
pub fn bc_bifurcation(v: f64, opts: &Options) -> Option<Solution> {
    prolate_bifurcation(v, opts).map(|(b, _)| b)
}

/// The pear at `v`: from the prolate's bifurcation ([`prolate_bifurcation`]), the prolate just
/// past it kicked along the unstable eigenvector and descended to the pear, which is followed
/// both ways. Returns the path and the bifurcation.
fn pear_path(
    v: f64,
    opts: &Options,
    ends: &mut impl FnMut(&Solution, bool) -> bool,
) -> (Vec<Solution>, Option<Solution>) {
    let Some((best, unstable)) = prolate_bifurcation(v, opts) else {
        return (Vec::new(), None);
    };
    let da_b = best.da();
    let bif = Some(best.clone());
    // Prolates past the bifurcation on the unstable side (μ < 0), kicked along φ and
    // descended at their Δa.
    let mut found = None;
    'tries: for prol in unstable.iter().rev() {
        let Some((_, phi)) = updown(prol, opts) else {
            continue;
        };
        let full = full_basis(&opts.with_model(Model::Bc { da: prol.da() })).with_map(prol.map);
        let a0 = to_full(prol, full.modes.len());
        let pw = Walker::new(Branch::Pear, v, full, true, opts);
        for kick in PEAR_KICKS {
            let a: Vec<f64> = a0.iter().zip(&phi).map(|(a, p)| a + kick * p).collect();
            let asym = |c: &Converged| c.a.iter().step_by(2).map(|x| x * x).sum::<f64>().sqrt();
            if let Some(c) = minimise(&pw.basis, &a, v, true, &pw.set).filter(|c| asym(c) > 1e-3) {
                found = Some((pw, c));
                break 'tries;
            }
        }
    }
    let Some((mut pw, c1)) = found else {
        return (Vec::new(), bif);
    };
    // A second pear state a little further from the bifurcation (half its distance again: near
    // v = 1 the branch is so stiff in Δa that a fixed step would leave Newton's basin).
    let da1 = c1.eval.j;
    let step = 0.5 * (da1 - da_b);
    let Some(c2) = pw.solve_at(da1 + step, &c1.a) else {
        return (Vec::new(), bif);
    };
    (both_ways(&mut pw, c1, c2, |s, up| ends(s, up)), bif)
}

/// The BC shape of `branch` at reduced volume `v` and area difference `da`, followed in `Δa`
/// from the branch's SC shape at `v` (the pear from its bifurcation off the prolate): Newton
/// at `da` from the path's shape nearest in `Δa` (within [`NEAR`]), or, where that fails,
/// [`Walker::approach`] from it.
///
/// # Errors
/// `Error::Config` (field `v`) if `v ∉ (0, 1)`; (field `da`) if the branch does not reach `da`
/// at this `v` (beyond a limit point or a closing neck, or no start shape).
pub fn bc_solution(branch: Branch, v: f64, da: f64, opts: &Options) -> Result<Solution> {
    if !(v > 0.0 && v < 1.0) {
        return Err(Error::config("v", format!("need 0 < v < 1, got {v}")));
    }
    if !da.is_finite() {
        return Err(Error::config("da", format!("must be finite, got {da}")));
    }
    let curve = bc_curve(branch, v, (da - 0.5, da + 0.5), opts);
    let near = curve
        .shapes
        .iter()
        .min_by(|a, b| (a.da() - da).abs().total_cmp(&(b.da() - da).abs()))
        .filter(|s| (s.da() - da).abs() <= NEAR)
        .ok_or_else(|| {
            Error::config(
                "da",
                format!(
                    "the {} branch at v = {v} does not reach Δa = {da}",
                    branch.name()
                ),
            )
        })?;
    let basis = basis_of(branch, opts).with_map(near.map);
    let mut w = Walker::new(branch, v, basis, !branch.up_down_symmetric(), opts);
    // Straight to Δa first; where Newton leaves its basin, in steps from the shape itself.
    let c = w
        .solve_at(da, &near.coefficients)
        .or_else(|| {
            let start = w.solve_at(near.da(), &near.coefficients)?;
            w.approach(start, da)
        })
        .ok_or_else(|| Error::config("da", format!("Newton failed at Δa = {da}, v = {v}")))?;
    w.push(c);
    Ok(w.solution())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sign changes of the prolate's up–down test function `μ` along its BC path at `v`
    /// towards larger `Δa`, while the neck is wider than `neck_min` (`R0`): `(Δa, loses)`, `Δa`
    /// linear in `μ` between the path's shapes (about 0.012 apart here).
    fn updown_zeros(v: f64, nodes: usize, neck_min: f64) -> Vec<(f64, bool)> {
        let opts = Options::with_nodes(nodes);
        let path = bc_curve(Branch::Prolate, v, (1.15, 1.45), &opts);
        let mut zeros = Vec::new();
        let mut last: Option<(f64, f64)> = None;
        for s in &path.shapes {
            if s.neck().is_some_and(|r| r < neck_min) {
                break;
            }
            let (mu, _) = updown(s, &opts).expect("μ of a prolate");
            if let Some((da, m)) = last.filter(|(_, m)| (*m > 0.0) != (mu > 0.0)) {
                zeros.push((da + (s.da() - da) * m / (m - mu), m > 0.0));
            }
            last = Some((s.da(), mu));
        }
        zeros
    }

    /// Near v = 0.70 the BC prolate's pear instability is a window in Δa. At v = 0.70 `μ`
    /// falls through 0 at Δa = 1.2999 (the pear's bifurcation) and rises through it again at
    /// 1.3623 (refined by the secant: 1.29987 and 1.36232 at 241 and 481 nodes alike, 1.36107
    /// at 121), where the neck is 0.24 and 0.11 R0. The window closes between v = 0.697 and
    /// 0.698 (Δa 1.332–1.338 at 0.698): at v = 0.697 `μ` stays positive while the neck is
    /// wider than 0.1 R0. The interpolation between the path's shapes is good to about 7e-4.
    #[test]
    fn the_bc_prolate_regains_updown_stability_near_v_070() {
        let zeros = updown_zeros(0.70, 241, 0.1);
        println!("v = 0.70: {zeros:?}");
        assert_eq!(zeros.len(), 2, "{zeros:?}");
        let [(lost, loses), (regained, regains)] = [zeros[0], zeros[1]];
        assert!(loses && !regains, "{zeros:?}");
        assert!((lost - 1.2999).abs() < 2e-3, "lost at {lost}");
        assert!((regained - 1.3623).abs() < 2e-3, "regained at {regained}");
        let below = updown_zeros(0.697, 241, 0.1);
        assert!(below.is_empty(), "v = 0.697: {below:?}");
    }

    /// At v = 0.68 the prolate loses up–down stability near its waist, at a neck of 0.082 R0
    /// (below 0.1 R0, where the modes are stretched): the pear's walk and the prolate's curve
    /// both put the zero at Δa = 1.4035337 at 241 nodes, as 481 nodes do in either basis (the
    /// walk's unstretched modes put it at 1.4036463 at 241 nodes). 1e-6 is a hundredth of that
    /// error.
    #[test]
    fn the_bifurcation_near_a_narrow_waist_is_solved_in_the_stretched_basis() {
        let opts = Options::with_nodes(241);
        let b = bc_bifurcation(0.68, &opts).expect("the pear bifurcation");
        assert!((b.da() - 1.4035337).abs() < 1e-6, "{}", b.da());
        assert!(!b.map.is_identity());
    }

    /// With its modes stretched at both necks (the mirrored map) the prolate's `μ` is resolved
    /// where the prolate buds at both poles. At v = 0.86 [`updown_changes`] finds two zeros:
    /// the loss at Δa = 1.077385, which is the pear's bifurcation ([`bc_bifurcation`], the same
    /// secant), and the regain at 1.361915 (241 nodes) and 1.361916 (481), where the necks are
    /// about 0.055 R0: the prolate regains up–down stability before its necks close. (241
    /// nodes also put a loss at 1.41495, at a neck of 0.0056 R0, that 481 do not: below
    /// [`UPDOWN_NECK_MIN`].) 1e-4 allows ten times the change from 241 to 481 nodes. (With
    /// uniform modes the regain moved with the nodes: 1.326, 1.350, 1.362 at 121, 241, 481.)
    #[test]
    fn the_budding_prolate_regains_updown_stability_at_v_086() {
        let opts = Options::with_nodes(241);
        let curve = bc_curve(Branch::Prolate, 0.86, (1.0, 1.45), &opts);
        let changes: Vec<(f64, bool)> = updown_changes(&curve, &opts)
            .iter()
            .map(|c| (c.shape.da(), c.loses))
            .collect();
        println!("v = 0.86: {changes:?}");
        assert_eq!(changes.len(), 2, "{changes:?}");
        let [(lost, loses), (regained, regains)] = [changes[0], changes[1]];
        let bifurcation = bc_bifurcation(0.86, &opts)
            .expect("the pear bifurcation")
            .da();
        assert!(
            loses && (lost - bifurcation).abs() < 1e-8,
            "{lost} against {bifurcation}"
        );
        assert!(
            !regains && (regained - 1.361916).abs() < 1e-4,
            "{changes:?}"
        );
    }
}
