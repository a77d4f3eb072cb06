//! The lowest eigenpair of the odd second variation by LOBPCG (Knyazev, SIAM J. Sci. Comput.
//! 23, 517 (2001)), in the orthonormalised form of Hetmaniuk & Lehoucq (J. Comput. Phys. 218,
//! 324 (2006)), for one vector.
//!
//! With x M-normalised, θ = ⟨x, Bx⟩_M and the residual r = Bx − θx, the next x minimises the
//! Rayleigh quotient over span{x, r, p} (p the previous step's direction): the three vectors
//! are M-orthonormalised by modified Gram–Schmidt (a vector whose remainder is below
//! [`DROP`] of its size is left out), the 3 × 3 matrix ⟨v_i, Bv_j⟩_M is diagonalised
//! ([`symmetric_eigen`]), x ← Σ c_i v_i with c the lowest eigenvector and p ← its part outside
//! the old x. One product with B per iteration (Bx and Bp follow by linearity). B = M⁻¹H is
//! already preconditioned by the bulk Hessian, so no other preconditioner is applied.
//!
//! The residual bounds the eigenvalue's error: some eigenvalue lies within ‖r‖_M of θ, and
//! within ‖r‖²_M/gap once θ is nearer the lowest than the next. Bx is formed anew before a
//! residual is accepted, so that the reported residual is the true one, not that of the
//! linearly updated images.

use super::OddHessian;
use crate::analysis::axisym::eigen::symmetric_eigen;
use crate::engines::Diverged;
use ndarray::{Array3, Zip};
use num_complex::Complex64;

/// A vector whose remainder after Gram–Schmidt is below this fraction of its norm is dropped
/// from the basis (it adds nothing but round-off).
pub const DROP: f64 = 1e-10;

type Spectrum = Array3<Complex64>;

/// The lowest eigenpair found.
pub struct Lowest {
    /// The eigenvalue θ (the Rayleigh quotient of `vector`).
    pub value: f64,
    /// The eigenvector, M-normalised, odd, orthogonal to the translation.
    pub vector: Spectrum,
    /// Products with B taken (the iterations plus the fresh images).
    pub products: usize,
    /// ‖Bx − θx‖_M of the returned vector (formed anew).
    pub residual: f64,
}

/// LOBPCG on P B P from `x` until ‖Bx − θx‖_M ≤ `tolerance` or `max_iterations` products.
///
/// # Errors
/// [`Diverged`] if a perturbed state is not finite or the start has no odd part.
pub fn lowest(
    h: &mut OddHessian,
    mut x: Spectrum,
    tolerance: f64,
    max_iterations: usize,
) -> Result<Lowest, Diverged> {
    h.project(&mut x);
    let size = h.dot(&x, &x).sqrt();
    if size == 0.0 || !size.is_finite() {
        return Err(Diverged(
            "the start of the eigensolver has no odd part".into(),
        ));
    }
    x.mapv_inplace(|v| v / size);
    let mut bx = Array3::zeros(x.raw_dim());
    h.apply(&x, &mut bx)?;
    let mut products = 1;
    let mut theta = h.dot(&x, &bx);
    let mut previous: Option<(Spectrum, Spectrum)> = None;
    let mut fresh = true;
    loop {
        let mut r = bx.clone();
        Zip::from(&mut r).and(&x).for_each(|r, &v| *r -= theta * v);
        let residual = h.dot(&r, &r).sqrt();
        if residual <= tolerance || products >= max_iterations {
            if fresh {
                return Ok(Lowest {
                    value: theta,
                    vector: x,
                    products,
                    residual,
                });
            }
            // The images were updated by linearity: form Bx anew and test again.
            h.apply(&x, &mut bx)?;
            products += 1;
            theta = h.dot(&x, &bx);
            fresh = true;
            continue;
        }
        let mut br = Array3::zeros(x.raw_dim());
        h.apply(&r, &mut br)?;
        products += 1;
        let mut basis = vec![(x, bx), (r, br)];
        basis.extend(previous.take());
        orthonormalise(h, &mut basis);
        let n = basis.len();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] =
                    0.5 * (h.dot(&basis[i].0, &basis[j].1) + h.dot(&basis[j].0, &basis[i].1));
            }
        }
        let (values, vectors) = symmetric_eigen(&a, n);
        let c = &vectors[0];
        let combine = |from: usize, which: fn(&(Spectrum, Spectrum)) -> &Spectrum| {
            let mut out = Array3::zeros(basis[0].0.raw_dim());
            for (ci, b) in c.iter().zip(&basis).skip(from) {
                Zip::from(&mut out)
                    .and(which(b))
                    .for_each(|o, &v| *o += ci * v);
            }
            out
        };
        let p = (combine(1, |b| &b.0), combine(1, |b| &b.1));
        x = combine(0, |b| &b.0);
        bx = combine(0, |b| &b.1);
        theta = values[0];
        previous = Some(p);
        fresh = false;
    }
}

/// M-orthonormalise the vectors of `basis` in order by modified Gram–Schmidt (two passes), their images
/// following by linearity; a vector whose remainder is below [`DROP`] of its norm is removed.
fn orthonormalise(h: &OddHessian, basis: &mut Vec<(Spectrum, Spectrum)>) {
    let mut done: Vec<(Spectrum, Spectrum)> = Vec::with_capacity(basis.len());
    for (mut v, mut bv) in basis.drain(..) {
        let before = h.dot(&v, &v).sqrt();
        // Twice: one pass leaves a remainder of order ε_mach/DROP along the others.
        for _ in 0..2 {
            for (u, bu) in &done {
                let c = h.dot(u, &v);
                Zip::from(&mut v).and(u).for_each(|v, &u| *v -= c * u);
                Zip::from(&mut bv).and(bu).for_each(|v, &u| *v -= c * u);
            }
        }
        let after = h.dot(&v, &v).sqrt();
        if after > DROP * before && after > 0.0 {
            v.mapv_inplace(|z| z / after);
            bv.mapv_inplace(|z| z / after);
            done.push((v, bv));
        }
    }
    *basis = done;
}
