//! The reductions of the spectral sweeps and of the relaxation, over a piece of a spectrum held
//! as interleaved (re, im) reals (or a run of real-space values): a plain sum, a stored L-BFGS
//! pair's six inner products and the sums of the real-space pass. Each keeps [`LANES`] partial
//! sums (the last two fuse each multiply-add, `mul_add`), so that the AVX2/FMA build, taken when
//! the CPU has those instructions, gives the portable build's results bit for bit. `wide_fn`
//! (from `vesicle-transforms`) compiles a sweep's element-wise loops for the same instructions.

/// Partial sums per reduction: one AVX2 register of f64.
pub const LANES: usize = 4;

pub(crate) use vesicle_transforms::wide_fn;

/// Σ_j v_j in [`LANES`] partial sums (a loop the wide build vectorises; the same order, so the
/// same value, in every build).
#[inline(always)]
pub fn sum(v: &[f64]) -> f64 {
    let mut acc = [0.0; LANES];
    let blocks = v.chunks_exact(LANES);
    let rest = blocks.remainder();
    for b in blocks {
        acc.iter_mut().zip(b).for_each(|(a, v)| *a += v);
    }
    acc.iter_mut().zip(rest).for_each(|(a, v)| *a += v);
    fold(acc)
}

/// With v = [w M r, w M q, w M s_new, w M y_new] over the piece, a stored pair's
/// [Σ s v₀, Σ y v₀, Σ y v₁, Σ y v₂, Σ s v₃, Σ y v₃]: its ⟨s, r⟩, ⟨y, r⟩, ⟨y, q⟩,
/// ⟨y, s_new⟩, ⟨s, y_new⟩, ⟨y, y_new⟩ in the M metric. The pair is stored in single
/// precision; each value is widened exactly to f64 before it is used.
pub fn pair_sums(s: &[f32], y: &[f32], v: [&[f64]; 4]) -> [f64; 6] {
    let n = s.len();
    assert!(y.len() == n && v.iter().all(|v| v.len() == n));
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked above); the lengths are equal (asserted).
        return unsafe { avx2::pair_sums(s, y, v) };
    }
    let mut acc = [[0.0; LANES]; 6];
    for j in 0..n {
        pair_terms(&mut acc, j, s, y, v);
    }
    acc.map(fold)
}

/// Value `j`'s terms of [`pair_sums`] into its lane, j mod [`LANES`] (the pair widened).
#[inline(always)]
fn pair_terms(acc: &mut [[f64; LANES]; 6], j: usize, s: &[f32], y: &[f32], v: [&[f64]; 4]) {
    let (l, s, y) = (j % LANES, f64::from(s[j]), f64::from(y[j]));
    let [wr, wq, ws, wy] = v.map(|v| v[j]);
    acc[0][l] = s.mul_add(wr, acc[0][l]);
    acc[1][l] = y.mul_add(wr, acc[1][l]);
    acc[2][l] = y.mul_add(wq, acc[2][l]);
    acc[3][l] = y.mul_add(ws, acc[3][l]);
    acc[4][l] = s.mul_add(wy, acc[4][l]);
    acc[5][l] = y.mul_add(wy, acc[5][l]);
}

/// The real-space pass's sums over a run of values: [Σ Φ², Σ φ, max|φ|, max|φ − φ_old|]. A max
/// keeps its lane's value unless the new one is larger (NaN never enters it; a NaN φ makes Σ Φ²
/// NaN, which the divergence check sees).
pub fn pointwise_sums(phi: &[f64], old: &[f64], big: &[f64]) -> [f64; 4] {
    let n = phi.len();
    assert!(old.len() == n && big.len() == n);
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked above); the lengths are equal (asserted).
        return unsafe { avx2::pointwise_sums(phi, old, big) };
    }
    let mut acc = [[0.0; LANES]; 4];
    for j in 0..n {
        pointwise_terms(&mut acc, j % LANES, phi[j], old[j], big[j]);
    }
    fold_pointwise(acc)
}

/// One value's terms of [`pointwise_sums`] into lane `l`.
#[inline(always)]
fn pointwise_terms(acc: &mut [[f64; LANES]; 4], l: usize, p: f64, o: f64, big: f64) {
    acc[0][l] = big.mul_add(big, acc[0][l]);
    acc[1][l] += p;
    acc[2][l] = larger(acc[2][l], p.abs());
    acc[3][l] = larger(acc[3][l], (p - o).abs());
}

/// `a` unless `b` is larger (`_mm256_max_pd(a, b)` lane by lane).
#[inline(always)]
fn larger(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// [`pointwise_sums`]'s lanes combined in a fixed order.
#[inline(always)]
fn fold_pointwise(acc: [[f64; LANES]; 4]) -> [f64; 4] {
    let max = |a: [f64; LANES]| larger(larger(a[0], a[1]), larger(a[2], a[3]));
    [fold(acc[0]), fold(acc[1]), max(acc[2]), max(acc[3])]
}

/// The lanes' total, in a fixed order.
#[inline(always)]
fn fold(a: [f64; LANES]) -> f64 {
    (a[0] + a[1]) + (a[2] + a[3])
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{fold, fold_pointwise, pair_terms, pointwise_terms, LANES};
    use std::arch::x86_64::*;

    /// [`super::pointwise_sums`] with AVX2/FMA: lane l takes the values j ≡ l (mod 4), as there.
    ///
    /// # Safety
    /// The CPU has AVX2 and FMA; `old` and `big` hold as many values as `phi`.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn pointwise_sums(phi: &[f64], old: &[f64], big: &[f64]) -> [f64; 4] {
        let n = phi.len();
        let full = n - n % LANES;
        let mut acc = [_mm256_setzero_pd(); 4];
        let abs = _mm256_set1_pd(-0.0);
        for j in (0..full).step_by(LANES) {
            let p = _mm256_loadu_pd(phi.as_ptr().add(j));
            let o = _mm256_loadu_pd(old.as_ptr().add(j));
            let b = _mm256_loadu_pd(big.as_ptr().add(j));
            acc[0] = _mm256_fmadd_pd(b, b, acc[0]);
            acc[1] = _mm256_add_pd(acc[1], p);
            acc[2] = _mm256_max_pd(acc[2], _mm256_andnot_pd(abs, p));
            acc[3] = _mm256_max_pd(acc[3], _mm256_andnot_pd(abs, _mm256_sub_pd(p, o)));
        }
        let mut lanes = [[0.0; LANES]; 4];
        for (l, a) in lanes.iter_mut().zip(acc) {
            _mm256_storeu_pd(l.as_mut_ptr(), a);
        }
        for j in full..n {
            pointwise_terms(&mut lanes, j % LANES, phi[j], old[j], big[j]);
        }
        fold_pointwise(lanes)
    }

    /// [`super::pair_sums`] with AVX2/FMA: lane l sums the values j ≡ l (mod 4), as there.
    ///
    /// # Safety
    /// The CPU has AVX2 and FMA; `y` and every `v` hold as many values as `s`.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn pair_sums(s: &[f32], y: &[f32], v: [&[f64]; 4]) -> [f64; 6] {
        let n = s.len();
        let full = n - n % LANES;
        let mut acc = [_mm256_setzero_pd(); 6];
        for j in (0..full).step_by(LANES) {
            let sv = _mm256_cvtps_pd(_mm_loadu_ps(s.as_ptr().add(j)));
            let yv = _mm256_cvtps_pd(_mm_loadu_ps(y.as_ptr().add(j)));
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
            pair_terms(&mut lanes, j, s, y, v);
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

    /// `v` rounded to single precision (a stored L-BFGS pair), and those values widened back.
    fn single(v: &[f64]) -> (Vec<f32>, Vec<f64>) {
        let s: Vec<f32> = v.iter().map(|&x| x as f32).collect();
        let wide = s.iter().map(|&x| f64::from(x)).collect();
        (s, wide)
    }

    /// The sums equal plain sequential sums to round-off (1e-14 relative: 52 terms of size 1).
    #[test]
    fn reductions_equal_plain_sums() {
        let n = 52;
        let [a, b, c, d, e, f] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0].map(|s| values(n, s));
        let plain: f64 = a.iter().sum();
        assert!((sum(&a) - plain).abs() < 1e-14 * n as f64);
        let ((a32, a), (b32, b)) = (single(&a), single(&b));
        let got = pair_sums(&a32, &b32, [&c, &d, &e, &f]);
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
    }

    /// The portable build's lanes give the dispatched build's sums bit for bit.
    #[test]
    fn portable_build_matches_bit_for_bit() {
        let n = 50;
        let [a, b, c, d, e, f] = [0.5, 1.5, 2.5, 3.5, 4.5, 5.5].map(|s| values(n, s));
        let ((a32, a), (b32, b)) = (single(&a), single(&b));
        let mut acc = [[0.0; LANES]; 6];
        for j in 0..n {
            pair_terms(&mut acc, j, &a32, &b32, [&c, &d, &e, &f]);
        }
        assert_eq!(pair_sums(&a32, &b32, [&c, &d, &e, &f]), acc.map(fold));
        let mut point = [[0.0; LANES]; 4];
        for j in 0..n {
            pointwise_terms(&mut point, j % LANES, a[j], b[j], c[j]);
        }
        assert_eq!(pointwise_sums(&a, &b, &c), fold_pointwise(point));
    }

    /// The real-space pass's sums equal plain sums and maxima (the maxima exactly).
    #[test]
    fn pointwise_sums_equal_plain_sums() {
        let n = 51;
        let [phi, old, big] = [0.5, 1.5, 2.5].map(|s| values(n, s));
        let [sq, sum, max_abs, change] = pointwise_sums(&phi, &old, &big);
        let plain = |f: &dyn Fn(usize) -> f64| (0..n).map(f).sum::<f64>();
        let max = |f: &dyn Fn(usize) -> f64| (0..n).map(f).fold(0.0, f64::max);
        assert!((sq - plain(&|j| big[j] * big[j])).abs() < 1e-14 * n as f64);
        assert!((sum - plain(&|j| phi[j])).abs() < 1e-14 * n as f64);
        assert_eq!(max_abs, max(&|j| phi[j].abs()));
        assert_eq!(change, max(&|j| (phi[j] - old[j]).abs()));
    }
}
