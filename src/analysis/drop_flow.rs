//! The sharp-interface reference for a 2D vesicle tank-treading in simple shear: the Stokes
//! flow around a fixed closed contour on which the membrane pushes only normally, with equal
//! viscosities inside and out (the drop-like membrane of one global tension,
//! docs/src/theory/flow.md). The shape is steady, so the fluid does not cross it:
//!
//! ```text
//! u(x) = u∞(x) + ∮ G(x − y) F(y) n(y) ds_y,   n·u = 0 on the contour,   ∮ F ds = 0
//! G(d) = (1/4πη)(−log|d| I + d dᵀ/|d|²),      u∞ = γ̇ (y − ȳ, 0)
//! ```
//!
//! (a uniform F drives no flow, hence the last condition). The mean vorticity inside,
//! ∮ u·t ds / A, over the imposed −γ̇ is the tank-treading rate Ω/(γ̇/2): 1 for a circle, where
//! the normal force is F = −3ηγ̇ sin 2θ. It depends on the shape alone, not on η, γ̇ or the size.
//!
//! The contour is r(θ) about its centroid, sampled at N equal angles; r′ is spectral. The
//! single layer is discretised by Kress's product rule: the logarithm's singular part
//! −½ log(4 sin²((θ − θ′)/2)) is integrated exactly against the trigonometric interpolant, the
//! rest by the trapezoidal rule (its limit on the diagonal is −log|x′|, that of d dᵀ/|d|² the
//! tangent's t tᵀ). Both converge spectrally for a smooth contour.

use super::axisym::solver::lu_solve;
use num_complex::Complex64;
use std::f64::consts::PI;
use vesicle_fft_plans::Planner;

/// What the reference gives for one contour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TankTreading {
    /// Ω/(γ̇/2): minus the mean z-vorticity inside over γ̇.
    pub rate: f64,
    /// The normal force's torque ∮ (x × F n)_z ds over ∮ |F||x| ds: a steady shape of the model
    /// has none, so it measures how far the contour is from one.
    pub torque: f64,
}

/// Ω/(γ̇/2) and the torque of the contour r(θ_j) = `radius[j]`, θ_j = 2πj/N about the
/// contour's centroid (N even, at least 16). The flow is u∞ = γ̇(y − ȳ, 0) with η = γ̇ = 1.
pub fn tank_treading(radius: &[f64]) -> TankTreading {
    let c = Contour::new(radius);
    let n = radius.len();
    let centroid_y = c.dtheta / (2.0 * c.area)
        * (0..n)
            .map(|j| c.point[j][1] * c.point[j][1] * c.normal[j][1] * c.speed[j])
            .sum::<f64>();
    let imposed = |p: [f64; 2]| [p[1] - centroid_y, 0.0];
    // n_i·u(x_i) = 0 with ∮ F ds = 0, bordered by a multiplier that absorbs the uniform F.
    let dim = n + 1;
    let mut a = vec![0.0; dim * dim];
    let mut b = vec![0.0; dim];
    for i in 0..n {
        for j in 0..n {
            a[i * dim + j] = dot(c.normal[i], c.response(i, j));
        }
        a[i * dim + n] = 1.0;
        a[n * dim + i] = c.speed[i] * c.dtheta;
        b[i] = -dot(c.normal[i], imposed(c.point[i]));
    }
    let mut force = lu_solve(&mut a, &mut b, dim).unwrap_or_else(|| vec![f64::NAN; dim]);
    force.truncate(n);
    let disturbance = c.single_layer(&force);
    let circulation = c.dtheta
        * (0..n)
            .map(|i| {
                let u = imposed(c.point[i]);
                dot(
                    [u[0] + disturbance[i][0], u[1] + disturbance[i][1]],
                    c.tangent[i],
                )
            })
            .sum::<f64>();
    let (mut torque, mut scale) = (0.0, 0.0);
    for j in 0..n {
        let weight = force[j] * c.speed[j] * c.dtheta;
        torque += cross(c.point[j], c.normal[j]) * weight;
        scale += (weight * radius[j]).abs();
    }
    TankTreading {
        rate: -circulation / c.area,
        torque: torque / scale,
    }
}

/// A contour r(θ) sampled at N equal angles: its points, tangents x′(θ), speeds |x′|, outward
/// normals, area and the discretised single layer of a normal force.
struct Contour {
    dtheta: f64,
    theta: Vec<f64>,
    point: Vec<[f64; 2]>,
    tangent: Vec<[f64; 2]>,
    speed: Vec<f64>,
    normal: Vec<[f64; 2]>,
    area: f64,
}

impl Contour {
    fn new(radius: &[f64]) -> Self {
        let n = radius.len();
        let dtheta = 2.0 * PI / n as f64;
        let theta: Vec<f64> = (0..n).map(|j| j as f64 * dtheta).collect();
        let dr = derivative(radius);
        let point: Vec<[f64; 2]> = (0..n)
            .map(|j| [radius[j] * theta[j].cos(), radius[j] * theta[j].sin()])
            .collect();
        let tangent: Vec<[f64; 2]> = (0..n)
            .map(|j| {
                let (c, s) = (theta[j].cos(), theta[j].sin());
                [dr[j] * c - radius[j] * s, dr[j] * s + radius[j] * c]
            })
            .collect();
        let speed: Vec<f64> = tangent.iter().map(|t| t[0].hypot(t[1])).collect();
        let normal = (0..n)
            .map(|j| [tangent[j][1] / speed[j], -tangent[j][0] / speed[j]])
            .collect();
        let area = 0.5 * dtheta * (0..n).map(|j| cross(point[j], tangent[j])).sum::<f64>();
        Contour {
            dtheta,
            theta,
            point,
            tangent,
            speed,
            normal,
            area,
        }
    }

    /// The velocity at x_i of a unit normal force density at x_j, times x_j's quadrature
    /// weight (η = 1).
    fn response(&self, i: usize, j: usize) -> [f64; 2] {
        let (p, t, s) = (&self.point, &self.tangent, &self.speed);
        let kress = kress_weight(p.len(), self.theta[i] - self.theta[j]);
        let (smooth, dyad) = if i == j {
            let u = [t[i][0] / s[i], t[i][1] / s[i]];
            (
                -s[i].ln(),
                [[u[0] * u[0], u[0] * u[1]], [u[1] * u[0], u[1] * u[1]]],
            )
        } else {
            let d = [p[i][0] - p[j][0], p[i][1] - p[j][1]];
            let d2 = d[0] * d[0] + d[1] * d[1];
            let s2 = 4.0 * (0.5 * (self.theta[i] - self.theta[j])).sin().powi(2);
            (
                -0.5 * (d2 / s2).ln(),
                [
                    [d[0] * d[0] / d2, d[0] * d[1] / d2],
                    [d[1] * d[0] / d2, d[1] * d[1] / d2],
                ],
            )
        };
        let log_part = -0.5 * kress + self.dtheta * smooth;
        let w = s[j] / (4.0 * PI);
        let n = self.normal[j];
        std::array::from_fn(|a| {
            w * (log_part * n[a] + self.dtheta * (dyad[a][0] * n[0] + dyad[a][1] * n[1]))
        })
    }

    /// The disturbance velocity on the contour of the normal force density `force`.
    fn single_layer(&self, force: &[f64]) -> Vec<[f64; 2]> {
        (0..force.len())
            .map(|i| {
                (0..force.len()).fold([0.0; 2], |u, j| {
                    let r = self.response(i, j);
                    [u[0] + r[0] * force[j], u[1] + r[1] * force[j]]
                })
            })
            .collect()
    }
}

/// Kress's weight R(t) = −(2π/m) Σ_{k=1}^{m−1} cos(k t)/k − (π/m²) cos(m t), N = 2m: the
/// integral of −log(4 sin²(t′/2))·(the trigonometric interpolant's cardinal function at 0)
/// sampled at t.
fn kress_weight(n: usize, t: f64) -> f64 {
    let m = n / 2;
    let sum: f64 = (1..m).map(|k| (k as f64 * t).cos() / k as f64).sum();
    let mf = m as f64;
    -(2.0 * PI / mf) * sum - PI / (mf * mf) * (mf * t).cos()
}

/// The derivative of the trigonometric interpolant of `f` (N equal samples over 2π) at the
/// samples: f̂_k times i k by a complex FFT, the Nyquist mode dropped.
fn derivative(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let mut planner = Planner::new();
    let mut spectrum: Vec<Complex64> = f.iter().map(|&v| Complex64::new(v, 0.0)).collect();
    planner.forward(n).process(&mut spectrum);
    for (k, c) in spectrum.iter_mut().enumerate() {
        let wave = match 2 * k {
            m if m < n => k as f64,
            m if m == n => 0.0,
            _ => k as f64 - n as f64,
        };
        *c *= Complex64::new(0.0, wave / n as f64);
    }
    planner.inverse(n).process(&mut spectrum);
    spectrum.iter().map(|c| c.re).collect()
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circle turns at exactly the imposed rate, Ω/(γ̇/2) = 1, with no torque: the normal
    /// force −3ηγ̇ sin 2θ that stops the strain's normal velocity drives no mean vorticity
    /// inside (docs/src/theory/flow.md).
    #[test]
    fn a_circle_turns_with_the_shear() {
        let t = tank_treading(&[1.0; 64]);
        assert!((t.rate - 1.0).abs() < 1e-10, "{t:?}");
        assert!(t.torque.abs() < 1e-10, "{t:?}");
    }

    /// A normal force cos nθ on the unit circle moves it at the drop's mobility (the rate
    /// n(n² − 3/2 + σ̄)/4 over the stiffness, docs/src/theory/flow.md): u_r = n/(4(n² − 1))
    /// cos nθ, and u_θ = −(u_r's amplitude/n) sin nθ (the drop's surface flow has no surface
    /// divergence). To 1e-10 at N = 64: the quadrature is spectral.
    #[test]
    fn a_normal_force_on_a_circle_moves_it_at_the_drops_mobility() {
        let c = Contour::new(&[1.0; 64]);
        for n in [2, 3, 5] {
            let force: Vec<f64> = c.theta.iter().map(|t| (n as f64 * t).cos()).collect();
            let amplitude = n as f64 / (4.0 * (n * n - 1) as f64);
            for (i, u) in c.single_layer(&force).iter().enumerate() {
                let t = c.theta[i];
                let (ur, ut) = (dot(*u, c.normal[i]), dot(*u, [-t.sin(), t.cos()]));
                assert!(
                    (ur - amplitude * (n as f64 * t).cos()).abs() < 1e-10,
                    "n {n}: {ur}"
                );
                let expected = -amplitude / n as f64 * (n as f64 * t).sin();
                assert!((ut - expected).abs() < 1e-10, "n {n}: {ut}");
            }
        }
    }

    /// On the linear theory's shapes r = 1 + b cos 2(θ − ψ), cos 2ψ = 2b, the rate departs from
    /// 1 at fourth order in b: 1 − Ω grows 15.2-fold from b = 0.05 to 0.1 (b⁴: 16). These
    /// shapes are nearly torque-free (2.9e-5 and 4.1e-4), as a steady shape must be, while the
    /// same shapes at ψ = 45° carry a torque of order b² (7.7e-3, 2.9e-2): the reference and
    /// the linear theory pick the same angle.
    #[test]
    fn the_linear_theorys_shapes_turn_nearly_with_the_shear() {
        let shape = |b: f64, psi: f64| {
            (0..128)
                .map(|j| 1.0 + b * (2.0 * (2.0 * PI * j as f64 / 128.0 - psi)).cos())
                .collect::<Vec<f64>>()
        };
        let linear = |b: f64| tank_treading(&shape(b, 0.5 * (2.0 * b).acos()));
        let (small, large) = (linear(0.05), linear(0.1));
        let growth = (1.0 - large.rate) / (1.0 - small.rate);
        assert!(
            growth > 14.0 && growth < 17.0,
            "{growth}: {small:?} {large:?}"
        );
        for (b, steady) in [(0.05, small), (0.1, large)] {
            let tilted = tank_treading(&shape(b, PI / 4.0));
            assert!(steady.torque.abs() < 1e-3, "{steady:?}");
            assert!(tilted.torque.abs() > 5e-3, "{tilted:?}");
        }
    }

    /// The derivative of the interpolant is exact for a trigonometric polynomial.
    #[test]
    fn the_spectral_derivative_is_exact_for_modes_below_nyquist() {
        let n = 32;
        let f: Vec<f64> = (0..n)
            .map(|j| {
                let t = 2.0 * PI * j as f64 / n as f64;
                1.0 + 0.3 * (2.0 * t).cos() + 0.1 * (5.0 * t).sin()
            })
            .collect();
        for (j, d) in derivative(&f).iter().enumerate() {
            let t = 2.0 * PI * j as f64 / n as f64;
            let exact = -0.6 * (2.0 * t).sin() + 0.5 * (5.0 * t).cos();
            assert!((d - exact).abs() < 1e-12, "{d} against {exact}");
        }
    }
}
