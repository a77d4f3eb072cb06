//! Second-order finite-difference operators on the grid, periodic or with mirror (Neumann)
//! walls: the (2d+1)-point Laplacian and the forward-difference area of docs/src/theory/fd.md.

use crate::engines::numerics::{sum_in_fixed_tree, PAR_CHUNK};
use crate::problem::grid::{AxisKind, Grid};
use crate::problem::model::AREA_PREFACTOR;
use ndarray::Array3;
use rayon::prelude::*;

/// Index of the neighbour below `i` on an axis of length `n`: periodic wrap, or the mirror
/// ghost φ_{−1} = φ_0.
#[inline]
pub(crate) fn below(i: usize, n: usize, kind: AxisKind) -> usize {
    match (i, kind) {
        (0, AxisKind::Periodic) => n - 1,
        (0, AxisKind::Mirror) => 0,
        _ => i - 1,
    }
}

/// Index of the neighbour above `i`: periodic wrap, or the mirror ghost φ_m = φ_{m−1}.
#[inline]
pub(crate) fn above(i: usize, n: usize, kind: AxisKind) -> usize {
    match (i + 1 == n, kind) {
        (true, AxisKind::Periodic) => 0,
        (true, AxisKind::Mirror) => n - 1,
        _ => i + 1,
    }
}

/// `out = ∇²_h u`: Σ_axes (u_{i+e} − 2u_i + u_{i−e}) / h², axes of length 1 skipped.
pub fn laplacian(grid: &Grid, u: &Array3<f64>, out: &mut Array3<f64>) {
    let [n0, n1, n2] = grid.shape;
    let kinds = grid.kinds;
    let inv_h2 = 1.0 / (grid.h * grid.h);
    let u = u.as_slice().expect("standard layout");
    let out = out.as_slice_mut().expect("standard layout");
    out.par_chunks_mut(n2)
        .with_min_len(8)
        .enumerate()
        .for_each(|(row, o)| {
            let (i, j) = (row / n1, row % n1);
            let at = |i: usize, j: usize| &u[(i * n1 + j) * n2..(i * n1 + j + 1) * n2];
            let c = at(i, j);
            let mut rows: [&[f64]; 4] = [c; 4];
            let mut m = 0;
            if n0 > 1 {
                rows[0] = at(below(i, n0, kinds[0]), j);
                rows[1] = at(above(i, n0, kinds[0]), j);
                m = 2;
            }
            if n1 > 1 {
                rows[m] = at(i, below(j, n1, kinds[1]));
                rows[m + 1] = at(i, above(j, n1, kinds[1]));
                m += 2;
            }
            transverse_sum(&rows[..m], c, o);
            if n2 > 1 {
                add_along_row(c, kinds[2], o);
            }
            for v in o.iter_mut() {
                *v *= inv_h2;
            }
        });
}

/// `o = Σ_r r − m c` over the `m` transverse neighbour rows.
fn transverse_sum(rows: &[&[f64]], c: &[f64], o: &mut [f64]) {
    let n = o.len();
    let c = &c[..n];
    match rows {
        [a, b, d, e] => {
            let (a, b, d, e) = (&a[..n], &b[..n], &d[..n], &e[..n]);
            for k in 0..n {
                o[k] = (a[k] + b[k]) + (d[k] + e[k]) - 4.0 * c[k];
            }
        }
        [a, b] => {
            let (a, b) = (&a[..n], &b[..n]);
            for k in 0..n {
                o[k] = a[k] + b[k] - 2.0 * c[k];
            }
        }
        _ => o.fill(0.0),
    }
}

/// `o += c_{k−1} − 2c_k + c_{k+1}` along the contiguous axis, with its walls.
fn add_along_row(c: &[f64], kind: AxisKind, o: &mut [f64]) {
    let n = c.len();
    for k in 1..n - 1 {
        o[k] += c[k - 1] + c[k + 1] - 2.0 * c[k];
    }
    o[0] += c[below(0, n, kind)] + c[1] - 2.0 * c[0];
    o[n - 1] += c[n - 2] + c[above(n - 1, n, kind)] - 2.0 * c[n - 1];
}

/// A_h = (3/(2√2)) ε Σ_i Σ_axes ((u_{i+e} − u_i)/h)² h^d, full-box value (× mirror factor).
/// Its exact variation is −(3/√2) ε ∇²_h u (with the same walls).
pub fn area(grid: &Grid, eps: f64, u: &Array3<f64>) -> f64 {
    area_form(grid, eps, u, u)
}

/// The symmetric bilinear form of A_h: (3/(2√2)) ε Σ_i Σ_axes (u_{i+e} − u_i)(v_{i+e} − v_i)
/// h^{d−2} (× mirror factor), so that A_h(u + σv) = B(u,u) + 2σ B(u,v) + σ² B(v,v).
pub fn area_form(grid: &Grid, eps: f64, u: &Array3<f64>, v: &Array3<f64>) -> f64 {
    let [n0, n1, n2] = grid.shape;
    let kinds = grid.kinds;
    let us = u.as_slice().expect("standard layout");
    let vs = v.as_slice().expect("standard layout");
    let row_sum = |row: usize| {
        let (i, j) = (row / n1, row % n1);
        let line = |i: usize, j: usize| (i * n1 + j) * n2..(i * n1 + j + 1) * n2;
        let (cu, cv) = (&us[line(i, j)], &vs[line(i, j)]);
        let mut s = 0.0;
        if n0 > 1 {
            let r = line(above(i, n0, kinds[0]), j);
            s += difference_product(cu, &us[r.clone()], cv, &vs[r]);
        }
        if n1 > 1 {
            let r = line(i, above(j, n1, kinds[1]));
            s += difference_product(cu, &us[r.clone()], cv, &vs[r]);
        }
        if n2 > 1 {
            for k in 0..n2 {
                let up = above(k, n2, kinds[2]);
                s += (cu[up] - cu[k]) * (cv[up] - cv[k]);
            }
        }
        s
    };
    // Rows in groups of about PAR_CHUNK points, each group added in sequence, the groups
    // over a fixed tree (both fixed by the box, not by the thread count).
    let (rows, per) = (n0 * n1, (PAR_CHUNK / n2).max(1));
    let pieces = (0..rows.div_ceil(per))
        .into_par_iter()
        .map(|g| (g * per..((g + 1) * per).min(rows)).fold(0.0, |s, r| s + row_sum(r)));
    let sum = sum_in_fixed_tree(pieces, || 0.0, |a, b| a + b);
    AREA_PREFACTOR * eps * sum * grid.h.powi(grid.dim as i32 - 2) * grid.mirror_factor()
}

/// Σ_k (nu_k − cu_k)(nv_k − cv_k).
fn difference_product(cu: &[f64], nu: &[f64], cv: &[f64], nv: &[f64]) -> f64 {
    cu.iter()
        .zip(nu)
        .zip(cv.iter().zip(nv))
        .map(|((a, b), (c, d))| (b - a) * (d - c))
        .sum()
}

/// Largest eigenvalue of −∇²_h used in the stability bound: λ_max = 4d/h².
pub fn lambda_max(grid: &Grid) -> f64 {
    4.0 * grid.dim as f64 / (grid.h * grid.h)
}
