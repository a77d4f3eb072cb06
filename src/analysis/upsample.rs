//! Band-limited (Fourier) interpolation of a periodic field onto a grid twice as fine.
//!
//! Along each refined axis of length `n`, with `X_k` the DFT of the samples, the refined
//! samples are the trigonometric interpolant at the old points and the midpoints:
//!
//! ```text
//! y_j = (1/n) Σ_k Y_k e^{2πi jk/(2n)},   Y_k = X_k (|k| < n/2),   Y_{±n/2} = X_{n/2}/2 (n even)
//! ```
//!
//! so `y_{2i} = x_i` exactly and a smooth field (the tanh profile resolved at h ≤ ε) is
//! interpolated to spectral accuracy.

use ndarray::{Array3, Axis};
use num_complex::Complex64;
use vesicle_fft_plans::Planner;

/// The field `phi` (a full periodic box, `[1, nx, ny]` in 2D) on the grid of spacing h/2:
/// every axis of length > 1 doubled by [band-limited interpolation](self).
pub fn double(phi: &Array3<f64>) -> Array3<f64> {
    let mut out = phi.clone();
    for axis in 0..3 {
        if out.shape()[axis] > 1 {
            out = double_axis(&out, axis);
        }
    }
    out
}

/// Double `field` along `axis` (see the module docs).
fn double_axis(field: &Array3<f64>, axis: usize) -> Array3<f64> {
    let n = field.shape()[axis];
    let mut shape = [field.shape()[0], field.shape()[1], field.shape()[2]];
    shape[axis] = 2 * n;
    let mut out = Array3::zeros(shape);
    let mut planner = Planner::new();
    let forward = planner.forward(n);
    let inverse = planner.inverse(2 * n);
    let mut x = vec![Complex64::default(); n];
    let mut y = vec![Complex64::default(); 2 * n];
    let half = n / 2;
    for (lane, mut target) in field
        .lanes(Axis(axis))
        .into_iter()
        .zip(out.lanes_mut(Axis(axis)))
    {
        for (xi, v) in x.iter_mut().zip(lane.iter()) {
            *xi = Complex64::new(*v, 0.0);
        }
        forward.process(&mut x);
        y.fill(Complex64::default());
        // Non-negative frequencies 0..⌈n/2⌉, negative ones −⌊n/2⌋+1..−1 (or to −n/2 if odd).
        let positive = n.div_ceil(2);
        y[..positive].copy_from_slice(&x[..positive]);
        y[n + positive..].copy_from_slice(&x[positive..]);
        if n.is_multiple_of(2) {
            let nyquist = x[half] * 0.5;
            y[half] = nyquist;
            y[n + half] = nyquist;
        }
        inverse.process(&mut y);
        for (t, v) in target.iter_mut().zip(&y) {
            *t = v.re / n as f64;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trigonometric polynomial below the Nyquist frequency is interpolated exactly.
    #[test]
    fn doubling_is_exact_for_band_limited_fields() {
        let (nx, ny, nz) = (6usize, 8usize, 10usize);
        let f = |x: f64, y: f64, z: f64| {
            use std::f64::consts::TAU;
            (TAU * x).cos() * (2.0 * TAU * y).sin() + (3.0 * TAU * z + 0.3).cos() + 0.5
        };
        let phi = Array3::from_shape_fn((nx, ny, nz), |(i, j, k)| {
            f(
                i as f64 / nx as f64,
                j as f64 / ny as f64,
                k as f64 / nz as f64,
            )
        });
        let fine = double(&phi);
        assert_eq!(fine.shape(), &[12, 16, 20]);
        for ((i, j, k), v) in fine.indexed_iter() {
            let exact = f(i as f64 / 12.0, j as f64 / 16.0, k as f64 / 20.0);
            assert!((v - exact).abs() < 1e-12, "{v} vs {exact} at {i},{j},{k}");
        }
    }
}
