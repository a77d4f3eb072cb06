use super::*;
use crate::analysis::axisym::eigen::symmetric_eigen;
use crate::problem::config::C0Spec;
use crate::problem::shapes::profile;

/// A prolate blob (semi-axes 2.2, 2.2, 3.2 at ε = 1, h = 1) on the box mirrored across x and
/// y of `n` points, even in z, with c0 = `c0`: not stationary, which the algebra checked here
/// does not need.
fn hessian(n: [usize; 3], c0: f64) -> OddHessian {
    with_area_difference(n, c0, None)
}

/// [`hessian`] with the area-difference term `term`.
fn with_area_difference(n: [usize; 3], c0: f64, term: Option<AreaDifference>) -> OddHessian {
    let grid = Grid::new(&n, 1.0, &[true, true, false]);
    let phi = blob(&grid);
    let c0 = C0::new(&C0Spec::Uniform(c0), &grid, 1.0).expect("a uniform c0");
    OddHessian::new(grid, (1.0, c0, Laplacian::Spectral), term, &phi, 1).expect("finite")
}

/// The prolate blob of [`hessian`] on `grid`.
fn blob(grid: &Grid) -> Array3<f64> {
    grid.field_from(|[x, y, z]| {
        let r = ((x / 2.2).powi(2) + (y / 2.2).powi(2) + (z / 3.2).powi(2)).sqrt();
        profile(2.5 * (1.0 - r), 1.0)
    })
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

/// On odd fields the bilayer couple's second variation (multipliers σ*, λ* by least squares)
/// is the ADE one at the same state and the same λ (module documentation): with Δa0 chosen
/// so that κ_λ(M* − M0) = λ*, the two give one B x to the central difference's O(τ²) (~1e-9),
/// and one σ*. The couple's λ* is not small here (the blob is not stationary), so a product
/// that left out its term λ* ∇²M x would differ from the ADE one at order 1e-2.
#[test]
fn the_couples_second_variation_is_the_ade_one_at_its_multiplier() {
    let (n, area0) = ([12, 12, 16], 4.0 * std::f64::consts::PI * 9.0);
    let couple = AreaDifference::new(Law::Couple { da: 1.1 }, 1.0, area0);
    let mut bc = with_area_difference(n, 0.3, Some(couple));
    let lambda = bc.couple_multiplier();
    let grid = Grid::new(&n, 1.0, &[true, true, false]);
    let m = bc
        .ev
        .state_of(&blob(&grid), 0.0)
        .expect("finite")
        .measures
        .curvature;
    let unit = AreaDifference::new(
        Law::Elastic {
            alpha: 1.0,
            da0: 0.0,
            lagged: false,
        },
        1.0,
        area0,
    );
    let da0 = (m - lambda / unit.stiffness()) / unit.m_unit;
    let law = Law::Elastic {
        alpha: 1.0,
        da0,
        lagged: false,
    };
    let mut ade = with_area_difference(n, 0.3, Some(AreaDifference { law, ..unit }));
    assert!(lambda.abs() > 1e-3, "λ* = {lambda}");
    assert!(
        (bc.sigma() - ade.sigma()).abs() < 1e-10 * bc.sigma().abs(),
        "σ* {} against {}",
        bc.sigma(),
        ade.sigma()
    );
    let mut x = spectrum_of(&mut bc, |[x, y, z]| {
        z * (-(x * x + 2.0 * y * y + z * z) / 9.0).exp()
    });
    bc.project(&mut x);
    let (mut from_bc, mut from_ade, mut from_sc) = (
        Array3::zeros(x.raw_dim()),
        Array3::zeros(x.raw_dim()),
        Array3::zeros(x.raw_dim()),
    );
    bc.apply(&x, &mut from_bc).expect("finite");
    ade.apply(&x, &mut from_ade).expect("finite");
    hessian(n, 0.3).apply(&x, &mut from_sc).expect("finite");
    let size = bc.dot(&from_bc, &from_bc).sqrt();
    let gap = |u: &Array3<Complex64>| {
        let d = &from_bc - u;
        bc.dot(&d, &d).sqrt() / size
    };
    assert!(
        gap(&from_ade) < 1e-7,
        "BC against ADE: {:e}",
        gap(&from_ade)
    );
    assert!(
        gap(&from_sc) > 1e-2,
        "BC against no term: {:e}",
        gap(&from_sc)
    );
}
