//! Chebyshev–Lobatto nodes on `[0, 1]` and the spectral operators built on them: the
//! indefinite-integral matrix, Clenshaw–Curtis weights and the differentiation matrix.
//!
//! Nodes `t_j = (1 − cos(jπ/m))/2`, `j = 0..=m` (so `t_0 = 0`, `t_m = 1`). A function sampled
//! there is the degree-`m` polynomial `p(t) = Σ_k c_k T_k(x)`, `x = 1 − 2t`, with
//! `c_k = (2/m) γ_k Σ''_j f_j cos(jkπ/m)` (`γ_0 = γ_m = 1/2`, else 1; `Σ''` halves the end terms).
//! All three operators act exactly on such polynomials, so for smooth (analytic) functions they
//! converge exponentially in `m`.

use std::f64::consts::PI;

/// The `m + 1` Chebyshev–Lobatto nodes on `[0, 1]`, increasing, with `t_0 = 0`, `t_m = 1`.
///
/// # Panics
/// If `m == 0`.
pub fn nodes(m: usize) -> Vec<f64> {
    assert!(m > 0, "need at least two nodes");
    (0..=m)
        .map(|j| 0.5 * (1.0 - (PI * j as f64 / m as f64).cos()))
        .collect()
}

/// The indefinite-integral matrix `Q` (row-major, `(m+1)²`): `(Q f)_i = ∫_0^{t_i} p(t) dt`
/// for the interpolant `p` of the samples `f`.
///
/// With `x = 1 − 2t`, `∫_0^t p = (F(1) − F(x))/2`, `F` the antiderivative in `x` from
/// `∫T_0 = T_1`, `∫T_1 = T_2/4`, `∫T_k = T_{k+1}/(2(k+1)) − T_{k−1}/(2(k−1))` (`k ≥ 2`).
/// Row 0 is zero; row `m` holds the Clenshaw–Curtis weights.
///
/// # Panics
/// If `m == 0`.
pub fn integration_matrix(m: usize) -> Vec<f64> {
    assert!(m > 0, "need at least two nodes");
    let n = m + 1;
    // cos(qπ/m) for q in 0..2m: T_k(x_i) = cos(k i π/m) = table[(k i) mod 2m].
    let table: Vec<f64> = (0..2 * m)
        .map(|q| (PI * q as f64 / m as f64).cos())
        .collect();
    let t = |k: usize, i: usize| table[(k * i) % (2 * m)];
    // Antiderivative of T_k evaluated at x_i (a node) and at x = 1.
    let anti = |k: usize, i: usize| -> f64 {
        match k {
            0 => t(1, i),
            1 => t(2, i) / 4.0,
            _ => t(k + 1, i) / (2.0 * (k + 1) as f64) - t(k - 1, i) / (2.0 * (k - 1) as f64),
        }
    };
    let anti_one = |k: usize| -> f64 {
        match k {
            0 => 1.0,
            1 => 0.25,
            _ => 1.0 / (2.0 * (k + 1) as f64) - 1.0 / (2.0 * (k - 1) as f64),
        }
    };
    // G[k][i] = (F_k(1) − F_k(x_i))/2, the t-integral of T_k from 0 to t_i.
    let g: Vec<Vec<f64>> = (0..n)
        .map(|k| (0..n).map(|i| 0.5 * (anti_one(k) - anti(k, i))).collect())
        .collect();
    let end = |j: usize| if j == 0 || j == m { 0.5 } else { 1.0 };
    let mut q = vec![0.0; n * n];
    for j in 0..n {
        // Chebyshev coefficients of the j-th cardinal function.
        let coef: Vec<f64> = (0..n)
            .map(|k| 2.0 / m as f64 * end(k) * end(j) * t(k, j))
            .collect();
        for i in 1..n {
            q[i * n + j] = (0..n).map(|k| coef[k] * g[k][i]).sum();
        }
    }
    q
}

/// Clenshaw–Curtis weights on `[0, 1]`: `Σ_j w_j f(t_j) = ∫_0^1 p(t) dt` (the last row of
/// [`integration_matrix`]).
pub fn weights(m: usize) -> Vec<f64> {
    let n = m + 1;
    integration_matrix(m)[m * n..].to_vec()
}

/// The Chebyshev differentiation matrix on `[0, 1]` (row-major, `(m+1)²`): `(D f)_i = p'(t_i)`.
///
/// The classical matrix on `x_j = cos(jπ/m)` (off-diagonal `c_i (−1)^{i+j} / (c_j (x_i − x_j))`,
/// `c_0 = c_m = 2`, else 1; diagonal the negative row sum) times `dx/dt = −2`.
///
/// # Panics
/// If `m == 0`.
pub fn diff_matrix(m: usize) -> Vec<f64> {
    assert!(m > 0, "need at least two nodes");
    let n = m + 1;
    let x: Vec<f64> = (0..n).map(|j| (PI * j as f64 / m as f64).cos()).collect();
    let c = |j: usize| if j == 0 || j == m { 2.0 } else { 1.0 };
    let mut d = vec![0.0; n * n];
    for i in 0..n {
        let mut row = 0.0;
        for j in 0..n {
            if i != j {
                let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
                let v = c(i) * sign / (c(j) * (x[i] - x[j]));
                d[i * n + j] = -2.0 * v;
                row += v;
            }
        }
        d[i * n + i] = 2.0 * row;
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Polynomials of degree ≤ m are integrated and differentiated exactly (to round-off).
    #[test]
    fn exact_on_polynomials() {
        let m = 12;
        let t = nodes(m);
        let q = integration_matrix(m);
        let d = diff_matrix(m);
        let n = m + 1;
        let f: Vec<f64> = t.iter().map(|t| 3.0 * t.powi(7) - t * t + 0.5).collect();
        for i in 0..n {
            let int: f64 = (0..n).map(|j| q[i * n + j] * f[j]).sum();
            let exact = 3.0 / 8.0 * t[i].powi(8) - t[i].powi(3) / 3.0 + 0.5 * t[i];
            assert!((int - exact).abs() < 1e-14, "integral at {i}");
            let der: f64 = (0..n).map(|j| d[i * n + j] * f[j]).sum();
            let exact = 21.0 * t[i].powi(6) - 2.0 * t[i];
            assert!((der - exact).abs() < 1e-12, "derivative at {i}");
        }
        let w = weights(m);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }
}
