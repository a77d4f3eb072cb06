//! Initial shapes as signed distances (positive inside) and the tanh profile
//! φ = tanh(d / (√2 ε)) built from them (docs/src/reference/scene-file.md).
//!
//! [`prepare`] does the once-per-field work (spheroids to ellipsoids, `axisym` shapes solved or
//! read and resampled, [`crate::problem::revolution`]); [`Prepared::signed_distance`] is then evaluated at
//! every grid point.

use crate::analysis::axisym::{self, Branch};
use crate::error::{Error, Result};
use crate::problem::config::{
    axis_index, Axisym, AxisymBranch, Difference, Ellipsoid, Harmonic, Shape, SpheroidKind, Star,
    Union,
};
use crate::problem::revolution::{self, Meridian};
use std::f64::consts::PI;

/// Largest resampling step of an `axisym` contour, in units of ε: the polyline's sag
/// `spacing² κ/8` stays below 1e-3 ε where the curvature radius is ≥ ε.
pub const AXISYM_SPACING: f64 = 0.05;

/// A shape ready for evaluation at many points.
#[derive(Clone, Debug)]
pub enum Prepared {
    /// A shape evaluated by [`signed_distance`] (spheroids already resolved).
    Plain(Shape),
    /// A surface of revolution.
    Revolution(Revolution),
    /// d = max d_i.
    Union(Vec<Prepared>),
    /// d = min(d_base, −d_minus).
    Difference(Box<Prepared>, Box<Prepared>),
}

/// A surface of revolution placed in the box: the generating curve, the symmetry axis
/// (scene axis) and the centre offset.
#[derive(Clone, Debug)]
pub struct Revolution {
    /// The generating curve, scaled and centred.
    pub meridian: Meridian,
    /// Scene axis of symmetry.
    pub axis: usize,
    /// Offset of the centre from the box centre (3 entries).
    pub center: [f64; 3],
}

impl Prepared {
    /// Signed distance of `p` (scene coordinates, 3 entries) to the surface, positive inside.
    pub fn signed_distance(&self, p: [f64; 3], dim: usize) -> f64 {
        match self {
            Prepared::Plain(s) => signed_distance(s, p, dim),
            Prepared::Revolution(r) => {
                let q = sub(p, Some(&r.center));
                let (a, b) = match r.axis {
                    0 => (1, 2),
                    1 => (0, 2),
                    _ => (0, 1),
                };
                let rho = (q[a] * q[a] + q[b] * q[b]).sqrt();
                r.meridian.signed_distance(rho, q[r.axis])
            }
            Prepared::Union(u) => u
                .iter()
                .map(|s| s.signed_distance(p, dim))
                .fold(f64::NEG_INFINITY, f64::max),
            Prepared::Difference(b, m) => b.signed_distance(p, dim).min(-m.signed_distance(p, dim)),
        }
    }
}

/// Prepare `shape` (a validated scene's, at key `at`, e.g. `initial`) for evaluation with
/// interface width `eps`: spheroids become ellipsoids; an `axisym` shape is solved with the
/// reference solver (default options) or read from its contour, scaled to `r0` and resampled
/// to [`AXISYM_SPACING`] ε.
///
/// # Errors
/// `Error::Config` naming `<at>.reduced_volume` if the solver does not reach the requested v
/// on the branch or the shape there intersects itself, `<at>.contour` if the file is
/// unreadable or not a closed curve.
pub fn prepare(shape: &Shape, at: &str, dim: usize, eps: f64) -> Result<Prepared> {
    Ok(match shape {
        Shape::Axisym(a) => Prepared::Revolution(revolution_of(a, at, dim, eps)?),
        Shape::Union(u) => Prepared::Union(
            u.of.iter()
                .enumerate()
                .map(|(i, s)| prepare(s, &format!("{at}.of[{i}]"), dim, eps))
                .collect::<Result<_>>()?,
        ),
        Shape::Difference(d) => Prepared::Difference(
            Box::new(prepare(&d.base, &format!("{at}.base"), dim, eps)?),
            Box::new(prepare(&d.minus, &format!("{at}.minus"), dim, eps)?),
        ),
        other => Prepared::Plain(resolve(other, dim)),
    })
}

/// The generating curve of an `axisym` shape, at `R0 = 1`: `(r, z)`.
///
/// # Errors
/// As [`prepare`].
pub fn axisym_contour(a: &Axisym, at: &str) -> Result<(Vec<f64>, Vec<f64>)> {
    if let Some(path) = &a.contour {
        return revolution::read_contour(path)
            .map_err(|e| Error::config(format!("{at}.contour"), e));
    }
    let field = format!("{at}.reduced_volume");
    let (Some(b), Some(v)) = (a.branch, a.reduced_volume) else {
        return Err(Error::config(
            format!("{at}.branch"),
            "missing: give branch + reduced_volume, or contour",
        ));
    };
    let branch = match b {
        AxisymBranch::Prolate => Branch::Prolate,
        AxisymBranch::Oblate => Branch::Oblate,
        AxisymBranch::Stomatocyte => Branch::Stomatocyte,
    };
    let (lo, hi) = b.range();
    let sol = axisym::solve(branch, v, &axisym::Options::default()).map_err(|e| {
        let reason = match e {
            Error::Config { reason, .. } => reason,
            other => other.to_string(),
        };
        Error::config(
            &field,
            format!("the reference solver gives no {} shape at v = {v} ({reason}); the branch's range is {lo} < v ≤ {hi}", b.name()),
        )
    })?;
    if sol.self_intersecting() {
        return Err(Error::config(
            &field,
            format!(
                "the {} shape at v = {v} intersects itself; choose a larger v (the branch's range is {lo} < v ≤ {hi})",
                b.name()
            ),
        ));
    }
    Ok((sol.r, sol.z))
}

fn revolution_of(a: &Axisym, at: &str, dim: usize, eps: f64) -> Result<Revolution> {
    let (r, z) = axisym_contour(a, at)?;
    let meridian = Meridian::new(&r, &z, a.r0, AXISYM_SPACING * eps);
    let mut center = [0.0; 3];
    if let Some(c) = &a.center {
        for (ci, x) in center.iter_mut().zip(c) {
            *ci = *x;
        }
    }
    Ok(Revolution {
        meridian,
        axis: axis_of(&a.axis, dim),
        center,
    })
}

/// Signed distance of `p` (scene coordinates, 3 entries, z = 0 in 2D) to the shape's surface,
/// positive inside. Exact for spheres, capsules and their set operations up to the usual
/// min/max approximation; first-order (d ≈ (1 − F)/|∇F|) for ellipsoids. An `axisym` shape is
/// prepared on every call (solved or read: slow) with ε = r0/100, and reads NaN if that fails;
/// build fields with [`prepare`].
pub fn signed_distance(shape: &Shape, p: [f64; 3], dim: usize) -> f64 {
    match shape {
        Shape::Sphere(s) => s.radius - norm(sub(p, s.center.as_deref())),
        Shape::Ellipsoid(s) => {
            let mut a = [1.0; 3];
            a[..dim].copy_from_slice(&s.axes);
            ellipsoid_distance(sub(p, s.center.as_deref()), a, dim)
        }
        Shape::Spheroid(_) => signed_distance(&resolve(shape, dim), p, dim),
        Shape::Cup(s) => {
            let q = sub(p, s.center.as_deref());
            let mut inner_center = [0.0; 3];
            inner_center[axis_of(&s.axis, dim)] = s.offset;
            let outer = s.radius - norm(q);
            let inner = s.inner_radius - norm(sub(q, Some(&inner_center)));
            outer.min(-inner)
        }
        Shape::Capsule(s) => {
            let q = sub(p, s.center.as_deref());
            let ax = axis_of(&s.axis, dim);
            let mut r = q;
            r[ax] = (q[ax].abs() - s.length / 2.0).max(0.0);
            s.radius - norm(r)
        }
        Shape::Star(s) => {
            let q = sub(p, s.center.as_deref());
            let ax = axis_of(&s.axis, dim);
            let (a, b) = match ax {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            star_distance(q[a], q[b], q[ax], s)
        }
        Shape::Union(u) => {
            u.of.iter()
                .map(|s| signed_distance(s, p, dim))
                .fold(f64::NEG_INFINITY, f64::max)
        }
        Shape::Difference(d) => {
            signed_distance(&d.base, p, dim).min(-signed_distance(&d.minus, p, dim))
        }
        Shape::Axisym(a) => prepare(shape, "initial", dim, a.r0 / 100.0)
            .map_or(f64::NAN, |s| s.signed_distance(p, dim)),
        Shape::Harmonic(h) => harmonic_distance(h, sub(p, h.center.as_deref()), dim),
        Shape::Slab(s) => {
            let normal = axis_of(&s.axis, dim);
            let along = (0..dim).find(|&a| a != normal);
            let x = along.map_or(0.0, |a| p[a]);
            let wave = s.amplitude * (2.0 * PI * x / s.wavelength).cos();
            s.thickness / 2.0 - (p[normal] - wave).abs()
        }
    }
}

/// The radial distance R(1 + aY) − r of the quasi-sphere `h` at `q` (from its centre): Y =
/// P_l(cos θ) about its axis (3D) or cos(lθ) from the x axis (2D).
fn harmonic_distance(h: &Harmonic, q: [f64; 3], dim: usize) -> f64 {
    let r = norm(q);
    let y = if r == 0.0 {
        0.0
    } else if dim == 2 {
        (h.mode as f64 * q[1].atan2(q[0])).cos()
    } else {
        legendre(h.mode, q[axis_of(&h.axis, dim)] / r)
    };
    h.radius * (1.0 + h.amplitude * y) - r
}

/// The Legendre polynomial P_l(x) by the recurrence (j + 1)P_{j+1} = (2j + 1)x P_j − j P_{j−1}.
pub fn legendre(l: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    if l == 0 {
        return p0;
    }
    for j in 1..l {
        let j = j as f64;
        (p0, p1) = (p1, ((2.0 * j + 1.0) * x * p1 - j * p0) / (j + 1.0));
    }
    p1
}

/// The shape with every spheroid given by (v, R0) replaced by its ellipsoid (solve once, then
/// evaluate the distance at every grid point).
pub fn resolve(shape: &Shape, dim: usize) -> Shape {
    match shape {
        Shape::Spheroid(s) => {
            let (equatorial, polar) = spheroid_axes(s.reduced_volume, s.r0, s.kind, dim);
            let mut axes = vec![equatorial; dim];
            axes[axis_of(&s.axis, dim)] = polar;
            Shape::Ellipsoid(Ellipsoid {
                axes,
                center: s.center.clone(),
            })
        }
        Shape::Union(u) => Shape::Union(Union {
            of: u.of.iter().map(|s| resolve(s, dim)).collect(),
        }),
        Shape::Difference(d) => Shape::Difference(Difference {
            base: Box::new(resolve(&d.base, dim)),
            minus: Box::new(resolve(&d.minus, dim)),
        }),
        other => other.clone(),
    }
}

/// The tanh profile φ = tanh(d/(√2 ε)).
pub fn profile(d: f64, eps: f64) -> f64 {
    (d / (std::f64::consts::SQRT_2 * eps)).tanh()
}

/// `p − c` (c absent: the box centre, 0).
fn sub(p: [f64; 3], c: Option<&[f64]>) -> [f64; 3] {
    let mut q = p;
    for (qi, ci) in q.iter_mut().zip(c.unwrap_or(&[])) {
        *qi -= ci;
    }
    q
}

fn norm(q: [f64; 3]) -> f64 {
    (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt()
}

fn axis_of(axis: &Option<String>, dim: usize) -> usize {
    axis.as_deref()
        .and_then(|a| axis_index(a, dim))
        .unwrap_or(dim - 1)
}

/// d ≈ (1 − F)/|∇F| with F = √(Σ (x_i/a_i)²).
fn ellipsoid_distance(q: [f64; 3], a: [f64; 3], dim: usize) -> f64 {
    let f = (0..dim).map(|i| (q[i] / a[i]).powi(2)).sum::<f64>().sqrt();
    let g = (0..dim)
        .map(|i| q[i] * q[i] / a[i].powi(4))
        .sum::<f64>()
        .sqrt();
    if g < 1e-300 {
        a[..dim].iter().cloned().fold(f64::INFINITY, f64::min)
    } else {
        (1.0 - f) * f / g
    }
}

/// First-order signed distance to the star F = (ρ/R(θ))² + (ζ/t)² = 1,
/// R(θ) = R̄(1 + a cos mθ), at in-plane coordinates (`u`, `w`) (ρ, θ) and `zeta` along its
/// axis, as for the ellipsoid: d ≈ (1 − f) f/g with f = √F and g = |∇F|/2 =
/// √((ρ/R²)² + (ρR′/R³)² + (ζ/t²)²), R′ = −R̄am sin mθ (the in-plane gradient has the radial
/// part ρ/R² and the angular part (1/ρ)∂θ(F/2) = −ρR′/R³). At ρ = ζ = 0: min(R̄(1 − a), t).
fn star_distance(u: f64, w: f64, zeta: f64, s: &Star) -> f64 {
    let rho = u.hypot(w);
    let theta = w.atan2(u);
    let m = f64::from(s.arms);
    let r = s.radius * (1.0 + s.amplitude * (m * theta).cos());
    let dr = -s.radius * s.amplitude * m * (m * theta).sin();
    let t = s.thickness;
    let f = ((rho / r).powi(2) + (zeta / t).powi(2)).sqrt();
    let g = ((rho / (r * r)).powi(2) + (rho * dr / r.powi(3)).powi(2) + (zeta / (t * t)).powi(2))
        .sqrt();
    if g < 1e-300 {
        (s.radius * (1.0 - s.amplitude)).min(t)
    } else {
        (1.0 - f) * f / g
    }
}

/// Semi-axes (equatorial, polar) of the spheroid (3D) or ellipse (2D) with reduced volume `v`
/// and size `r0`. 3D: v = V/((4π/3) R0³) with A = 4π R0²; 2D: v = 4πV/L² with L = 2π R0.
/// The aspect ratio q = polar/equatorial is found by bisection (v is monotone in q on each
/// branch: q > 1 prolate, q < 1 oblate), then the size is scaled to R0.
pub fn spheroid_axes(v: f64, r0: f64, kind: SpheroidKind, dim: usize) -> (f64, f64) {
    let (mut lo, mut hi): (f64, f64) = match kind {
        SpheroidKind::Prolate => (1.0, 1e3),
        SpheroidKind::Oblate => (1e-3, 1.0),
    };
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        let too_round = reduced_volume_of(1.0, mid, dim) > v;
        // On the prolate branch v falls as q grows; on the oblate branch it rises.
        if too_round == (kind == SpheroidKind::Prolate) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let q = (lo * hi).sqrt();
    let size = size_of(1.0, q, dim);
    (r0 / size, q * r0 / size)
}

/// Reduced volume of the spheroid/ellipse with equatorial semi-axis `a` and polar `c`.
fn reduced_volume_of(a: f64, c: f64, dim: usize) -> f64 {
    if dim == 3 {
        let r0 = size_of(a, c, 3);
        4.0 / 3.0 * PI * a * a * c / (4.0 / 3.0 * PI * r0.powi(3))
    } else {
        let l = ellipse_perimeter(a, c);
        4.0 * PI * PI * a * c / (l * l)
    }
}

/// R0 of the spheroid (√(A/4π)) or ellipse (L/2π).
fn size_of(a: f64, c: f64, dim: usize) -> f64 {
    if dim == 3 {
        (spheroid_area(a, c) / (4.0 * PI)).sqrt()
    } else {
        ellipse_perimeter(a, c) / (2.0 * PI)
    }
}

/// Area of the spheroid with semi-axes (a, a, c).
pub fn spheroid_area(a: f64, c: f64) -> f64 {
    if (c - a).abs() < 1e-12 * a {
        4.0 * PI * a * a
    } else if c > a {
        let e = (1.0 - a * a / (c * c)).sqrt();
        2.0 * PI * a * a * (1.0 + c / (a * e) * e.asin())
    } else {
        let e = (1.0 - c * c / (a * a)).sqrt();
        2.0 * PI * a * a * (1.0 + (1.0 - e * e) / e * e.atanh())
    }
}

/// Perimeter of the ellipse with semi-axes a, c (trapezoid rule on the periodic integrand,
/// spectrally accurate).
pub fn ellipse_perimeter(a: f64, c: f64) -> f64 {
    let m = 4096;
    let s: f64 = (0..m)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / m as f64;
            (a * a * t.sin().powi(2) + c * c * t.cos().powi(2)).sqrt()
        })
        .sum();
    s * 2.0 * PI / m as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::config::Star;

    fn star(arms: u32, amplitude: f64) -> Shape {
        Shape::Star(Star {
            radius: 20.0,
            thickness: 6.0,
            arms,
            amplitude,
            axis: None,
            center: None,
        })
    }

    /// The star's surface lies at R̄(1 + a) on an arm (θ = 0, along x for axis z), at
    /// R̄(1 − a) between two arms (θ = π/m) and at ±t on the axis; unmodulated it is the oblate
    /// ellipsoid (R̄, R̄, t) with the ellipsoid's distance. Odd m keeps the mirror y → −y and
    /// breaks x → −x.
    #[test]
    fn star_surface_and_symmetries() {
        let s = star(3, 0.4);
        let d = |p: [f64; 3]| signed_distance(&s, p, 3);
        assert!(d([28.0, 0.0, 0.0]).abs() < 1e-12);
        let between = std::f64::consts::PI / 3.0;
        assert!(d([12.0 * between.cos(), 12.0 * between.sin(), 0.0]).abs() < 1e-12);
        assert!(d([0.0, 0.0, 6.0]).abs() < 1e-12 && d([0.0, 0.0, 0.0]) > 0.0);
        let p = [9.0, 7.0, 2.0];
        assert!((d(p) - d([9.0, -7.0, 2.0])).abs() < 1e-12);
        assert!((d(p) - d([-9.0, 7.0, 2.0])).abs() > 1.0);
        let plain = signed_distance(&star(4, 0.0), p, 3);
        let ellipsoid = Shape::Ellipsoid(Ellipsoid {
            axes: vec![20.0, 20.0, 6.0],
            center: None,
        });
        assert!((plain - signed_distance(&ellipsoid, p, 3)).abs() < 1e-12);
    }
}
