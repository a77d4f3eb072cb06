//! Eigenvalues and eigenvectors of a small symmetric matrix by cyclic Jacobi rotations.
//!
//! Each rotation `A ← Jᵀ A J` zeroes one off-diagonal pair; sweeps over all pairs repeat until
//! the off-diagonal norm falls below `1e-14` of the Frobenius norm (quadratic convergence once
//! the eigenvalues separate). The accumulated rotations are the eigenvectors.

/// Eigenvalues (ascending) and unit eigenvectors (`vectors[i]` belongs to `values[i]`) of the
/// symmetric row-major `n × n` matrix `a`.
pub(crate) fn symmetric_eigen(a: &[f64], n: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut m = a.to_vec();
    let mut q = vec![0.0; n * n];
    for i in 0..n {
        q[i * n + i] = 1.0;
    }
    let frob: f64 = m.iter().map(|x| x * x).sum::<f64>().sqrt();
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |j| *j != i).map(move |j| (i, j)))
            .map(|(i, j)| m[i * n + j] * m[i * n + j])
            .sum::<f64>()
            .sqrt();
        if off <= 1e-14 * frob || frob == 0.0 {
            break;
        }
        for p in 0..n {
            for r in p + 1..n {
                let apr = m[p * n + r];
                if apr == 0.0 {
                    continue;
                }
                // Rotation angle: tan 2θ = 2 a_pr / (a_rr − a_pp).
                let theta = 0.5 * (m[r * n + r] - m[p * n + p]) / apr;
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (mkp, mkr) = (m[k * n + p], m[k * n + r]);
                    m[k * n + p] = c * mkp - s * mkr;
                    m[k * n + r] = s * mkp + c * mkr;
                }
                for k in 0..n {
                    let (mpk, mrk) = (m[p * n + k], m[r * n + k]);
                    m[p * n + k] = c * mpk - s * mrk;
                    m[r * n + k] = s * mpk + c * mrk;
                }
                for k in 0..n {
                    let (qkp, qkr) = (q[k * n + p], q[k * n + r]);
                    q[k * n + p] = c * qkp - s * qkr;
                    q[k * n + r] = s * qkp + c * qkr;
                }
            }
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| m[i * n + i].total_cmp(&m[j * n + j]));
    let values = order.iter().map(|&i| m[i * n + i]).collect();
    let vectors = order
        .iter()
        .map(|&i| (0..n).map(|k| q[k * n + i]).collect())
        .collect();
    (values, vectors)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 3 matrix with known spectrum: `[[2, 1, 0], [1, 2, 0], [0, 0, 5]]` has eigenvalues
    /// 1, 3, 5; each returned pair satisfies `A x = λ x` to round-off.
    #[test]
    fn known_spectrum() {
        let a = [2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 5.0];
        let (vals, vecs) = symmetric_eigen(&a, 3);
        for (v, want) in vals.iter().zip([1.0, 3.0, 5.0]) {
            assert!((v - want).abs() < 1e-14, "{v} vs {want}");
        }
        for (l, x) in vals.iter().zip(&vecs) {
            for i in 0..3 {
                let ax: f64 = (0..3).map(|k| a[i * 3 + k] * x[k]).sum();
                assert!((ax - l * x[i]).abs() < 1e-14);
            }
        }
    }
}
