//! The sweeps over the spectrum: the direction, the area's quadratic, the trial state and the
//! gradient with the new pair, each one pass over the pieces with its sums.

use super::lbfgs::{flat, AreaSums, Direction, GradientSums, Pair};
use crate::engines::numerics::sum_in_fixed_tree;
use crate::engines::spectral::evaluator::{write_inverse_value, Metric, State, Symbols};
use crate::engines::spectral::kernels::{pair_sums, sum, wide_fn};
use crate::engines::spectral::pieces::{
    for_each_piece, mode, per_width, re_dot, reals, reals_mut, Piece, PIECE,
};
use num_complex::Complex64;
use rayon::prelude::*;
use std::collections::VecDeque;

wide_fn! {
/// One piece of [`super::RelaxEngine::write_direction`]: d' = −c_r r − Σ_j (c_y,j y_j + c_s,j s_j)
/// into `out` over the pairs from `d.off`, from the piece's reals `r` of r and the reals `g` of
/// the pairs.
pub(super) fn direction_piece(
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
pub(super) fn area_values<const W: usize>(
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
    let (xx, xq, qq) = (sum(&txx[..len]), sum(&txq[..len]), sum(&tqq[..len]));
    let (xd, qd, dd) = (sum(&txd[..len]), sum(&tqd[..len]), sum(&tdd[..len]));
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
/// One piece of [`super::RelaxEngine::write_trial`], mode by mode: φ̂ + α d' + β q into `hat`, and
/// the inverse transforms' inputs ([`write_inverse_value`]) into `copy` and `lap`, from the
/// piece's reals of φ̂ and d' (`(x, d)`); returns its area (`terms` scratch).
pub(super) fn trial_values<const W: usize>(
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
    [sum(&trr[..len]), sum(&tres[..len]), sum(&tqr[..len])]
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
pub(super) fn dot_m<A: Copy + Into<f64>, B: Copy + Into<f64>>(
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
pub(super) fn pair_dots(sym: &Symbols, m: Metric, a: &Pair, b: &Pair) -> (f64, f64) {
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
pub(super) fn gradient_sweep(
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
        None => {
            let partials = grad
                .par_chunks_mut(task)
                .enumerate()
                .map(|(t, r)| run(t, r, None));
            sum_in_fixed_tree(partials, GradientSums::zero, GradientSums::add)
        }
        Some((x_old, pair)) => {
            let partials = grad
                .par_chunks_mut(task)
                .zip(pair.s.par_chunks_mut(task))
                .zip(pair.y.par_chunks_mut(task))
                .enumerate()
                .map(|(t, ((r, s), y))| run(t, r, Some((reals(x_old), s, y))));
            sum_in_fixed_tree(partials, GradientSums::zero, GradientSums::add)
        }
    }
}
