//! The thinnest part of an axisymmetric shape: how close two sheets of its membrane come,
//! through the body (an oblate's centre, a stomatocyte's wall) or through the outside (a
//! neck, the mouth and the cavity of a stomatocyte). A phase-field profile about 5ε wide
//! cannot resolve a part thinner than that: the two interfaces merge and e jumps instead of
//! converging in ε/R0.
//!
//! The meridian section of the surface is the closed curve made of the contour `(r, z)` and its
//! mirror `(−r, z)`, of length 2L. Two of its points p, q are *across* a part when the way
//! between them along the curve is long against the straight line, `arc(p, q) ≥ 2 |p − q|`
//! (on a circle `arc/chord ≤ π/2`, so no pair of a sphere or of a rounded tip qualifies; across
//! a neck, a wall or a waist the arc goes round the body). The thinnest part is the shortest
//! such chord, or, on a shape without any (sphere-like), the smaller of its width `2 max r` and
//! its height.

use crate::analysis::axisym::Solution;

/// Samples per half of the closed curve (the contour resampled at equal arc length, linearly
/// between its Chebyshev samples: spacing L/400 ≈ 0.015 R0 on the shapes of a diagram).
const SAMPLES: usize = 400;

/// Least ratio arc/chord of two points across a part of the shape.
const ACROSS: f64 = 2.0;

/// The thinnest part of `shape` (R0 = 1), in units of R0.
pub fn thinnest(shape: &Solution) -> f64 {
    let half = resample(&shape.s, &shape.r, &shape.z, SAMPLES);
    let length = shape.length();
    let ds = length / SAMPLES as f64;
    // The closed curve: the contour up, its mirror down; point k at arc length k ds.
    let curve: Vec<(f64, f64)> = half
        .iter()
        .copied()
        .chain(half[1..SAMPLES].iter().rev().map(|&(r, z)| (-r, z)))
        .collect();
    let total = curve.len();
    let mut thinnest = f64::INFINITY;
    for (i, p) in curve.iter().enumerate() {
        for (j, q) in curve.iter().enumerate().skip(i + 1) {
            let steps = (j - i).min(total - (j - i));
            let chord = ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
            if steps as f64 * ds >= ACROSS * chord {
                thinnest = thinnest.min(chord);
            }
        }
    }
    if thinnest.is_finite() {
        return thinnest;
    }
    let width = 2.0 * shape.r.iter().cloned().fold(0.0, f64::max);
    let (lo, hi) = shape
        .z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| {
            (a.min(z), b.max(z))
        });
    width.min(hi - lo)
}

/// `n + 1` points of the curve `(r(s), z(s))` at `s = k L / n`, linear between the samples.
fn resample(s: &[f64], r: &[f64], z: &[f64], n: usize) -> Vec<(f64, f64)> {
    let length = *s.last().expect("contour has samples");
    let mut j = 0;
    (0..=n)
        .map(|k| {
            let t = length * k as f64 / n as f64;
            while j + 2 < s.len() && s[j + 1] < t {
                j += 1;
            }
            let w = ((t - s[j]) / (s[j + 1] - s[j])).clamp(0.0, 1.0);
            (r[j] + w * (r[j + 1] - r[j]), z[j] + w * (z[j + 1] - z[j]))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::axisym::{solve, Branch, Options};

    /// A near-sphere (the prolate at v = 0.999, within about 2% of the unit sphere) has no
    /// two points across a thin part: it is its own thinnest part, about its diameter 2 R0.
    #[test]
    fn a_sphere_is_its_own_thinnest_part() {
        let sphere = solve(Branch::Prolate, 0.999, &Options::default()).unwrap();
        let t = thinnest(&sphere);
        assert!((t - 2.0).abs() < 0.05, "{t}");
    }

    /// An oblate's thinnest part is its centre, the height of the contour on the axis
    /// (`z` of the upper pole minus that of the lower, computed independently here).
    #[test]
    fn an_oblate_is_thinnest_at_its_centre() {
        let oblate = solve(Branch::Oblate, 0.59, &Options::default()).unwrap();
        let centre = oblate.z.last().unwrap() - oblate.z[0];
        let t = thinnest(&oblate);
        assert!(
            (t - centre.abs()).abs() < 0.005,
            "thinnest {t}, centre {centre}"
        );
    }

    /// A necked prolate (c̄0 = 2 at v = 0.65: a waist of radius 0.285 R0 from
    /// `Solution::neck`) is thinnest across its waist, 2 × the neck radius.
    #[test]
    fn a_waist_is_twice_its_neck_radius() {
        let prolate = solve(Branch::Prolate, 0.65, &Options::default().with_c0(2.0)).unwrap();
        let neck = prolate.neck().expect("a waist");
        let t = thinnest(&prolate);
        assert!((t - 2.0 * neck).abs() < 0.005, "thinnest {t}, neck {neck}");
    }
}
