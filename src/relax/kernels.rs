//! The relaxation's reductions over a piece of a spectrum held as interleaved (re, im) reals:
//! Σ a b c, the six weighted quadratic sums of two vectors, and a stored pair's six inner
//! products. Both keep [`LANES`] partial sums and fuse
//! each multiply-add (`mul_add`), so that the AVX2/FMA build, taken when the CPU has those
//! instructions, gives the portable build's results bit for bit.

/// Partial sums per reduction: one AVX2 register of f64.
pub const LANES: usize = 4;

/// Σ_j a_j b_j c_j over equal-length slices.
pub fn dot3(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    assert!(a.len() == b.len() && a.len() == c.len());
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked above); the lengths are equal (asserted).
        return unsafe { avx2::dot3(a, b, c) };
    }
    let mut acc = [0.0; LANES];
    for (j, ((a, b), c)) in a.iter().zip(b).zip(c).enumerate() {
        acc[j % LANES] = (a * b).mul_add(*c, acc[j % LANES]);
    }
    fold(acc)
}

/// [Σ a x², Σ b x², Σ c x², Σ a x d, Σ b x d, Σ a d²] over equal-length slices.
pub fn quadratic_sums(a: &[f64], b: &[f64], c: &[f64], x: &[f64], d: &[f64]) -> [f64; 6] {
    let n = x.len();
    assert!([a, b, c, d].iter().all(|v| v.len() == n));
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked above); the lengths are equal (asserted).
        return unsafe { avx2::quadratic_sums(a, b, c, x, d) };
    }
    let mut acc = [[0.0; LANES]; 6];
    for j in 0..n {
        quadratic_terms(&mut acc, j % LANES, [a[j], b[j], c[j]], x[j], d[j]);
    }
    acc.map(fold)
}

/// One value's terms of [`quadratic_sums`] into lane `l`.
#[inline(always)]
fn quadratic_terms(acc: &mut [[f64; LANES]; 6], l: usize, [a, b, c]: [f64; 3], x: f64, d: f64) {
    let (xx, xd, dd) = (x * x, x * d, d * d);
    acc[0][l] = a.mul_add(xx, acc[0][l]);
    acc[1][l] = b.mul_add(xx, acc[1][l]);
    acc[2][l] = c.mul_add(xx, acc[2][l]);
    acc[3][l] = a.mul_add(xd, acc[3][l]);
    acc[4][l] = b.mul_add(xd, acc[4][l]);
    acc[5][l] = a.mul_add(dd, acc[5][l]);
}

/// With v = [w M r, w M q, w M s_new, w M y_new] over the piece, a stored pair's
/// [Σ s v₀, Σ y v₀, Σ y v₁, Σ y v₂, Σ s v₃, Σ y v₃]: its ⟨s, r⟩, ⟨y, r⟩, ⟨y, q⟩,
/// ⟨y, s_new⟩, ⟨s, y_new⟩, ⟨y, y_new⟩ in the M metric.
pub fn pair_sums(s: &[f64], y: &[f64], v: [&[f64]; 4]) -> [f64; 6] {
    let n = s.len();
    assert!(y.len() == n && v.iter().all(|v| v.len() == n));
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked above); the lengths are equal (asserted).
        return unsafe { avx2::pair_sums(s, y, v) };
    }
    let mut acc = [[0.0; LANES]; 6];
    for j in 0..n {
        pair_terms(
            &mut acc,
            j % LANES,
            s[j],
            y[j],
            [v[0][j], v[1][j], v[2][j], v[3][j]],
        );
    }
    acc.map(fold)
}

/// One value's terms of [`pair_sums`] into lane `l`.
#[inline(always)]
fn pair_terms(acc: &mut [[f64; LANES]; 6], l: usize, s: f64, y: f64, [wr, wq, ws, wy]: [f64; 4]) {
    acc[0][l] = s.mul_add(wr, acc[0][l]);
    acc[1][l] = y.mul_add(wr, acc[1][l]);
    acc[2][l] = y.mul_add(wq, acc[2][l]);
    acc[3][l] = y.mul_add(ws, acc[3][l]);
    acc[4][l] = s.mul_add(wy, acc[4][l]);
    acc[5][l] = y.mul_add(wy, acc[5][l]);
}

/// The lanes' total, in a fixed order.
#[inline(always)]
fn fold(a: [f64; LANES]) -> f64 {
    (a[0] + a[1]) + (a[2] + a[3])
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{fold, pair_terms, quadratic_terms, LANES};
    use std::arch::x86_64::*;

    /// [`super::dot3`] with AVX2/FMA: lane l sums the values j ≡ l (mod 4), as there.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn dot3(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
        let n = a.len();
        let full = n - n % LANES;
        let mut acc = _mm256_setzero_pd();
        for j in (0..full).step_by(LANES) {
            let ab = _mm256_mul_pd(
                _mm256_loadu_pd(a.as_ptr().add(j)),
                _mm256_loadu_pd(b.as_ptr().add(j)),
            );
            acc = _mm256_fmadd_pd(ab, _mm256_loadu_pd(c.as_ptr().add(j)), acc);
        }
        let mut lanes = [0.0; LANES];
        _mm256_storeu_pd(lanes.as_mut_ptr(), acc);
        for j in full..n {
            lanes[j % LANES] = (a[j] * b[j]).mul_add(c[j], lanes[j % LANES]);
        }
        fold(lanes)
    }

    /// [`super::quadratic_sums`] with AVX2/FMA: lane l sums the values j ≡ l (mod 4), as there.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn quadratic_sums(
        a: &[f64],
        b: &[f64],
        c: &[f64],
        x: &[f64],
        d: &[f64],
    ) -> [f64; 6] {
        let n = x.len();
        let full = n - n % LANES;
        let mut acc = [_mm256_setzero_pd(); 6];
        for j in (0..full).step_by(LANES) {
            let [av, bv, cv, xv, dv] = [a, b, c, x, d].map(|v| _mm256_loadu_pd(v.as_ptr().add(j)));
            let (xx, xd, dd) = (
                _mm256_mul_pd(xv, xv),
                _mm256_mul_pd(xv, dv),
                _mm256_mul_pd(dv, dv),
            );
            acc[0] = _mm256_fmadd_pd(av, xx, acc[0]);
            acc[1] = _mm256_fmadd_pd(bv, xx, acc[1]);
            acc[2] = _mm256_fmadd_pd(cv, xx, acc[2]);
            acc[3] = _mm256_fmadd_pd(av, xd, acc[3]);
            acc[4] = _mm256_fmadd_pd(bv, xd, acc[4]);
            acc[5] = _mm256_fmadd_pd(av, dd, acc[5]);
        }
        let mut lanes = [[0.0; LANES]; 6];
        for (l, a) in lanes.iter_mut().zip(acc) {
            _mm256_storeu_pd(l.as_mut_ptr(), a);
        }
        for j in full..n {
            quadratic_terms(&mut lanes, j % LANES, [a[j], b[j], c[j]], x[j], d[j]);
        }
        lanes.map(fold)
    }

    /// [`super::pair_sums`] with AVX2/FMA: lane l sums the values j ≡ l (mod 4), as there.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn pair_sums(s: &[f64], y: &[f64], v: [&[f64]; 4]) -> [f64; 6] {
        let n = s.len();
        let full = n - n % LANES;
        let mut acc = [_mm256_setzero_pd(); 6];
        for j in (0..full).step_by(LANES) {
            let sv = _mm256_loadu_pd(s.as_ptr().add(j));
            let yv = _mm256_loadu_pd(y.as_ptr().add(j));
            let w = v.map(|v| _mm256_loadu_pd(v.as_ptr().add(j)));
            acc[0] = _mm256_fmadd_pd(sv, w[0], acc[0]);
            acc[1] = _mm256_fmadd_pd(yv, w[0], acc[1]);
            acc[2] = _mm256_fmadd_pd(yv, w[1], acc[2]);
            acc[3] = _mm256_fmadd_pd(yv, w[2], acc[3]);
            acc[4] = _mm256_fmadd_pd(sv, w[3], acc[4]);
            acc[5] = _mm256_fmadd_pd(yv, w[3], acc[5]);
        }
        let mut lanes = [[0.0; LANES]; 6];
        for (l, a) in lanes.iter_mut().zip(acc) {
            _mm256_storeu_pd(l.as_mut_ptr(), a);
        }
        for j in full..n {
            pair_terms(
                &mut lanes,
                j % LANES,
                s[j],
                y[j],
                [v[0][j], v[1][j], v[2][j], v[3][j]],
            );
        }
        lanes.map(fold)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values with no exact cancellations, length 2·25 + 2 (not a multiple of LANES).
    fn values(n: usize, seed: f64) -> Vec<f64> {
        (0..n).map(|j| ((j as f64 + seed) * 0.713).sin()).collect()
    }

    /// The sums equal plain sequential sums to round-off (1e-14 relative: 52 terms of size 1).
    #[test]
    fn reductions_equal_plain_sums() {
        let n = 52;
        let [a, b, c, d, e, f] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0].map(|s| values(n, s));
        let plain: f64 = (0..n).map(|j| a[j] * b[j] * c[j]).sum();
        assert!((dot3(&a, &b, &c) - plain).abs() < 1e-14 * n as f64);
        let got = pair_sums(&a, &b, [&c, &d, &e, &f]);
        let dot = |u: &[f64], v: &[f64]| (0..n).map(|j| u[j] * v[j]).sum::<f64>();
        let want = [
            dot(&a, &c),
            dot(&b, &c),
            dot(&b, &d),
            dot(&b, &e),
            dot(&a, &f),
            dot(&b, &f),
        ];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-14 * n as f64, "{g} against {w}");
        }
        let got = quadratic_sums(&a, &b, &c, &d, &e);
        let sum = |f: &dyn Fn(usize) -> f64| (0..n).map(f).sum::<f64>();
        let want = [
            sum(&|j| a[j] * d[j] * d[j]),
            sum(&|j| b[j] * d[j] * d[j]),
            sum(&|j| c[j] * d[j] * d[j]),
            sum(&|j| a[j] * d[j] * e[j]),
            sum(&|j| b[j] * d[j] * e[j]),
            sum(&|j| a[j] * e[j] * e[j]),
        ];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-14 * n as f64, "{g} against {w}");
        }
    }

    /// The portable build's lanes give the dispatched build's sums bit for bit.
    #[test]
    fn portable_build_matches_bit_for_bit() {
        let n = 50;
        let [a, b, c, d, e, f] = [0.5, 1.5, 2.5, 3.5, 4.5, 5.5].map(|s| values(n, s));
        let mut acc = [[0.0; LANES]; 6];
        let mut one = [0.0; LANES];
        for j in 0..n {
            pair_terms(&mut acc, j % LANES, a[j], b[j], [c[j], d[j], e[j], f[j]]);
            one[j % LANES] = (a[j] * b[j]).mul_add(c[j], one[j % LANES]);
        }
        assert_eq!(pair_sums(&a, &b, [&c, &d, &e, &f]), acc.map(fold));
        assert_eq!(dot3(&a, &b, &c), fold(one));
        let mut quad = [[0.0; LANES]; 6];
        for j in 0..n {
            quadratic_terms(&mut quad, j % LANES, [a[j], b[j], c[j]], d[j], e[j]);
        }
        assert_eq!(quadratic_sums(&a, &b, &c, &d, &e), quad.map(fold));
    }
}
