use super::*;
use crate::analysis::axisym::eigen::symmetric_eigen;
use crate::problem::config::C0Spec;
use crate::problem::shapes::profile;

/// A prolate blob (semi-axes 2.2, 2.2, 3.2 at ε = 1, h = 1) on the box mirrored across x and
/// y of `n` points, even in z, with c0 = `c0`: not stationary, which the algebra checked here
/// does not need.
fn hessian(n: [usize; 3], c0: f64) -> OddHessian {
    let grid = Grid::new(&n, 1.0, &[true, true, false]);
    let phi = grid.field_from(|[x, y, z]| {
        let r = ((x / 2.2).powi(2) + (y / 2.2).powi(2) + (z / 3.2).powi(2)).sqrt();
        profile(2.5 * (1.0 - r), 1.0)
    });
    let c0 = C0::new(&C0Spec::Uniform(c0), &grid, 1.0).expect("a uniform c0");
    OddHessian::new(grid, (1.0, c0, Laplacian::Spectral), &phi, 1).expect("finite")
}

/// The spectrum of the real field `f(x, y, z)` on the hessian's grid.
fn spectrum_of(h: &mut OddHessian, f: impl Fn([f64; 3]) -> f64) -> Array3<Complex64> {
    let mut field = h.ev.grid.field_from(f);
    let mut out = Array3::zeros(h.hat.raw_dim());
    h.ev.transform.forward(&mut field, &mut out);
    out
}

/// The odd part of a field even in z is 0 and that of a field odd in z is the field itself (to
/// round-off): the phase e^{2πij/N} puts the mirror plane at the box's centre, between the
/// points N/2 − 1 and N/2.
#[test]
fn the_odd_part_splits_even_from_odd() {
    let mut h = hessian([8, 8, 12], 0.0);
    let bump = |[x, y, z]: [f64; 3]| (-(x * x + y * y) / 4.0 - (z - 0.7) * (z - 0.7) / 3.0).exp();
    let even = spectrum_of(&mut h, |p| bump(p) + bump([p[0], p[1], -p[2]]));
    let odd = spectrum_of(&mut h, |p| bump(p) - bump([p[0], p[1], -p[2]]));
    let size = h.dot(&odd, &odd).sqrt();
    let mut e = even.clone();
    h.odd_part(&mut e);
    assert!(h.dot(&e, &e).sqrt() < 1e-14 * size, "even part left");
    let mut o = odd.clone();
    h.odd_part(&mut o);
    o.zip_mut_with(&odd, |a, b| *a -= b);
    assert!(h.dot(&o, &o).sqrt() < 1e-14 * size, "odd part changed");
}

/// B = M⁻¹H is self-adjoint in the M metric: ⟨x, By⟩_M = ⟨Bx, y⟩_M for two odd fields, to
/// the central difference's O(τ²) (τ = 1e-5 relative: ~1e-9) and round-off.
#[test]
fn the_second_variation_is_self_adjoint() {
    let mut h = hessian([12, 12, 16], 0.3);
    let mut x = spectrum_of(&mut h, |[x, y, z]| {
        z * (-(x * x + 2.0 * y * y + z * z) / 9.0).exp()
    });
    let mut y = spectrum_of(&mut h, |[x, _, z]| {
        z.powi(3) * (-(x * x + z * z) / 12.0).exp()
    });
    h.project(&mut x);
    h.project(&mut y);
    let (mut bx, mut by) = (Array3::zeros(x.raw_dim()), Array3::zeros(x.raw_dim()));
    h.apply(&x, &mut bx).expect("finite");
    h.apply(&y, &mut by).expect("finite");
    let (xby, bxy) = (h.dot(&x, &by), h.dot(&bx, &y));
    let scale = (h.dot(&x, &bx) * h.dot(&y, &by)).abs().sqrt();
    assert!((xby - bxy).abs() < 1e-7 * scale, "{xby} against {bxy}");
}

/// LOBPCG finds the lowest eigenvalue of P B P that a dense diagonalisation of the same operator
/// finds on a box small enough to write it out (the odd subspace of an 8 × 8 × 12 box mirrored
/// across x and y: its M-orthonormal basis from the unit coefficients, projected): the two
/// agree to 1e-8 (the residual tolerance 1e-6 bounds the error by 1e-12 over the gap).
#[test]
fn lobpcg_finds_the_dense_lowest_eigenvalue() {
    let mut h = hessian([8, 8, 12], 0.5);
    let shape = h.hat.raw_dim();
    let mut basis: Vec<Array3<Complex64>> = Vec::new();
    for idx in 0..h.hat.len() {
        for unit in [Complex64::new(1.0, 0.0), Complex64::new(0.0, 1.0)] {
            let mut v = Array3::zeros(shape);
            v.as_slice_mut().expect("standard layout")[idx] = unit;
            h.project(&mut v);
            for _ in 0..2 {
                for u in &basis {
                    let c = h.dot(u, &v);
                    v.zip_mut_with(u, |a, b| *a -= c * b);
                }
            }
            let size = h.dot(&v, &v).sqrt();
            if size > 1e-8 {
                basis.push(v.mapv(|z| z / size));
            }
        }
    }
    let n = basis.len();
    assert!(n > 50, "the odd subspace has {n} dimensions");
    let images: Vec<Array3<Complex64>> = basis
        .iter()
        .map(|v| {
            let mut bv = Array3::zeros(shape);
            h.apply(v, &mut bv).expect("finite");
            bv
        })
        .collect();
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            a[i * n + j] = 0.5 * (h.dot(&basis[i], &images[j]) + h.dot(&basis[j], &images[i]));
        }
    }
    let (values, _) = symmetric_eigen(&a, n);
    let found = h.lowest(None, 1e-6, 500).expect("finite");
    assert!(found.residual <= 1e-6, "residual {}", found.residual);
    assert!(
        (found.value - values[0]).abs() < 1e-8,
        "LOBPCG {} against dense {} (next {})",
        found.value,
        values[0],
        values[1]
    );
}
