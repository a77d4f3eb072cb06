//! Signed distance to a surface of revolution given by its generating curve (the `axisym`
//! initial shape, docs/src/reference/scene-file.md, docs/src/theory/relaxation.md).
//!
//! The surface is described in the meridian half-plane: `ρ ≥ 0` the distance from the axis,
//! `ζ` the coordinate along it. The generating curve runs from the axis back to the axis
//! (`ρ = 0` at both ends); with its mirror image `ρ → −ρ` it is a closed polygon, and the 3D
//! signed distance of a point is the 2D signed distance of its `(ρ, ζ)` to that polygon
//! (positive inside). For `ρ ≥ 0` the mirror half is never closer than the curve itself
//! (`(ρ + a)² ≥ (ρ − a)²` for `a ≥ 0`), and a ray from `(ρ, ζ)` towards `+ρ` never meets it, so
//! both the distance and the even–odd inside test use the curve alone; points on the axis need
//! no special case.
//!
//! The curve's samples (the solver's Chebyshev–Lobatto nodes, or a CSV) are resampled by cubic
//! Hermite interpolation in chord length (tangents from the three-point formula, at the poles
//! from the mirrored neighbour, so the tangent there is normal to the axis) to at most
//! `spacing` between points, and the distance is exact to that polyline: the polyline's sag is
//! `spacing² κ / 8`, below 1e-3 ε at `spacing = 0.05 ε` and curvature radii ≥ ε. The segments are
//! grouped in chunks of [`CHUNK`] with bounding boxes; a query computes the exact distance only
//! to the chunks whose box is nearer than the best distance found so far (branch and bound from
//! the nearest box), and counts ray crossings only in chunks whose box the ray meets.

use std::path::Path;

/// Segments per bounding box.
pub const CHUNK: usize = 16;

/// Most polyline points after resampling (a huge `r0/ε` would otherwise ask for billions).
pub const MAX_POINTS: usize = 400_000;

/// A closed generating curve ready for distance queries.
#[derive(Clone, Debug)]
pub struct Meridian {
    /// Resampled polyline `(ρ, ζ)`, scaled, `ζ` measured from the centre.
    pts: Vec<[f64; 2]>,
    /// Chunks of consecutive segments `[start, end)` with the bounding box of their points.
    chunks: Vec<Chunk>,
    /// Whether the curve is even about `ζ = 0` (then queries use `|ζ|`, so the field is exactly
    /// even under the mirror normal to the axis).
    symmetric: bool,
}

#[derive(Clone, Copy, Debug)]
struct Chunk {
    start: usize,
    end: usize,
    lo: [f64; 2],
    hi: [f64; 2],
}

impl Meridian {
    /// The curve through `(r_i, z_i)` (both ends on the axis, `r ≥ 0`), scaled by `scale` and
    /// resampled to at most `spacing` (after scaling) between points.
    ///
    /// Centre: a curve that is even about its middle height (the samples pair up as
    /// `r_i = r_{n−1−i}`, `z_i + z_{n−1−i} = z_0 + z_{n−1}` to 1e-9 of its size, as on the prolate
    /// and oblate branches) is centred on that height and evaluated at `|ζ|`; any other curve is
    /// centred on the middle of its extent along the axis.
    ///
    /// # Panics
    /// If fewer than 2 samples, or `r` and `z` differ in length.
    pub fn new(r: &[f64], z: &[f64], scale: f64, spacing: f64) -> Self {
        assert!(
            r.len() >= 2 && r.len() == z.len(),
            "a curve needs 2 or more samples"
        );
        let n = r.len();
        let (zmin, zmax) = z
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let rmax = r.iter().cloned().fold(0.0, f64::max);
        let size = (zmax - zmin).max(rmax);
        let tol = 1e-9 * size;
        let symmetric = (0..n).all(|i| {
            let j = n - 1 - i;
            (r[i] - r[j]).abs() <= tol && (z[i] + z[j] - z[0] - z[n - 1]).abs() <= tol
        });
        let centre = if symmetric {
            0.5 * (z[0] + z[n - 1])
        } else {
            0.5 * (zmin + zmax)
        };
        let p: Vec<[f64; 2]> = (0..n)
            .map(|i| [r[i].max(0.0) * scale, (z[i] - centre) * scale])
            .collect();
        let pts = resample(&p, spacing);
        let chunks = (0..pts.len() - 1)
            .step_by(CHUNK)
            .map(|start| {
                let end = (start + CHUNK).min(pts.len() - 1);
                let mut lo = [f64::INFINITY; 2];
                let mut hi = [f64::NEG_INFINITY; 2];
                for q in &pts[start..=end] {
                    for k in 0..2 {
                        lo[k] = lo[k].min(q[k]);
                        hi[k] = hi[k].max(q[k]);
                    }
                }
                Chunk { start, end, lo, hi }
            })
            .collect();
        Meridian {
            pts,
            chunks,
            symmetric,
        }
    }

    /// Whether the curve is even about its centre (see [`Meridian::new`]).
    pub fn symmetric(&self) -> bool {
        self.symmetric
    }

    /// Number of polyline points after resampling.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    /// Always false (a curve has at least 2 points).
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty()
    }

    /// Signed distance from `(ρ, ζ)` (`ρ ≥ 0`) to the closed curve, positive inside.
    pub fn signed_distance(&self, rho: f64, zeta: f64) -> f64 {
        let zeta = if self.symmetric { zeta.abs() } else { zeta };
        let q = [rho, zeta];
        // Branch and bound: the nearest box first, then every box nearer than the best.
        let (mut first, mut lb_first) = (0, f64::INFINITY);
        for (k, c) in self.chunks.iter().enumerate() {
            let lb = box_dist2(q, c);
            if lb < lb_first {
                lb_first = lb;
                first = k;
            }
        }
        let mut best = self.chunk_dist2(q, &self.chunks[first]);
        for (k, c) in self.chunks.iter().enumerate() {
            if k != first && box_dist2(q, c) < best {
                best = best.min(self.chunk_dist2(q, c));
            }
        }
        let d = best.sqrt();
        if self.inside(q) {
            d
        } else {
            -d
        }
    }

    fn chunk_dist2(&self, q: [f64; 2], c: &Chunk) -> f64 {
        (c.start..c.end).fold(f64::INFINITY, |m, i| {
            m.min(seg_dist2(q, self.pts[i], self.pts[i + 1]))
        })
    }

    /// Even–odd test: crossings of the ray from `q` towards `+ρ` with the curve.
    fn inside(&self, q: [f64; 2]) -> bool {
        let mut odd = false;
        for c in &self.chunks {
            if q[1] < c.lo[1] || q[1] > c.hi[1] || c.hi[0] <= q[0] {
                continue;
            }
            for i in c.start..c.end {
                let (a, b) = (self.pts[i], self.pts[i + 1]);
                if (a[1] > q[1]) != (b[1] > q[1]) {
                    let x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
                    if x > q[0] {
                        odd = !odd;
                    }
                }
            }
        }
        odd
    }
}

/// Squared distance from `q` to the box of `c` (0 inside).
fn box_dist2(q: [f64; 2], c: &Chunk) -> f64 {
    let dx = (c.lo[0] - q[0]).max(q[0] - c.hi[0]).max(0.0);
    let dy = (c.lo[1] - q[1]).max(q[1] - c.hi[1]).max(0.0);
    dx * dx + dy * dy
}

/// Squared distance from `q` to the segment `ab`.
fn seg_dist2(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let (px, py) = (q[0] - a[0], q[1] - a[1]);
    let len2 = ex * ex + ey * ey;
    let t = if len2 > 0.0 {
        ((px * ex + py * ey) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (dx, dy) = (px - t * ex, py - t * ey);
    dx * dx + dy * dy
}

/// Cubic Hermite resampling in chord length to at most `spacing` between points (at most
/// [`MAX_POINTS`] points in all; the spacing grows if needed). The pole tangents come from the
/// mirrored neighbour (`(−ρ_1, ζ_1)`), i.e. normal to the axis.
fn resample(p: &[[f64; 2]], spacing: f64) -> Vec<[f64; 2]> {
    let n = p.len();
    let chord =
        |i: usize| ((p[i + 1][0] - p[i][0]).powi(2) + (p[i + 1][1] - p[i][1]).powi(2)).sqrt();
    let h: Vec<f64> = (0..n - 1).map(chord).collect();
    let total: f64 = h.iter().sum();
    let spacing = spacing.max(total / MAX_POINTS as f64);
    // Tangents dP/du at the samples (three-point formula on non-uniform spacing).
    let three = |pm: [f64; 2], p0: [f64; 2], pp: [f64; 2], hm: f64, hp: f64| -> [f64; 2] {
        if hm <= 0.0 || hp <= 0.0 {
            return [0.0, 0.0];
        }
        let mut m = [0.0; 2];
        for k in 0..2 {
            m[k] =
                hm / (hp * (hm + hp)) * (pp[k] - p0[k]) + hp / (hm * (hm + hp)) * (p0[k] - pm[k]);
        }
        m
    };
    let mirror = |q: [f64; 2]| [-q[0], q[1]];
    let m: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            if n == 2 {
                let d = h[0].max(f64::MIN_POSITIVE);
                [(p[1][0] - p[0][0]) / d, (p[1][1] - p[0][1]) / d]
            } else if i == 0 {
                three(mirror(p[1]), p[0], p[1], h[0], h[0])
            } else if i == n - 1 {
                three(p[n - 2], p[n - 1], mirror(p[n - 2]), h[n - 2], h[n - 2])
            } else {
                three(p[i - 1], p[i], p[i + 1], h[i - 1], h[i])
            }
        })
        .collect();
    let mut out = Vec::with_capacity((total / spacing) as usize + n + 1);
    out.push(p[0]);
    for i in 0..n - 1 {
        let pieces = ((h[i] / spacing).ceil() as usize).max(1);
        for k in 1..=pieces {
            if k == pieces {
                out.push(p[i + 1]);
                continue;
            }
            let t = k as f64 / pieces as f64;
            let (t2, t3) = (t * t, t * t * t);
            let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
            let h10 = t3 - 2.0 * t2 + t;
            let h01 = -2.0 * t3 + 3.0 * t2;
            let h11 = t3 - t2;
            let mut q = [0.0; 2];
            for (kk, qk) in q.iter_mut().enumerate() {
                *qk = h00 * p[i][kk]
                    + h10 * h[i] * m[i][kk]
                    + h01 * p[i + 1][kk]
                    + h11 * h[i] * m[i + 1][kk];
            }
            q[0] = q[0].max(0.0);
            out.push(q);
        }
    }
    out
}

/// Read an `r,z` contour (as `vesicle axisym` writes `contours/<branch>_v<v>.csv`): one point a
/// line, an optional header line `r,z`, blank lines ignored.
///
/// # Errors
/// A reason (for `Error::Config`) if the file cannot be read, a line does not hold two finite
/// numbers, or the contour is not a closed generating curve (see [`check_contour`]).
pub fn read_contour(path: &Path) -> Result<(Vec<f64>, Vec<f64>), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let (mut r, mut z) = (Vec::new(), Vec::new());
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || (k == 0 && line.replace(' ', "") == "r,z") {
            continue;
        }
        let bad = || {
            format!(
                "{} line {}: expected two finite numbers `r,z`, got {line:?}",
                path.display(),
                k + 1
            )
        };
        let mut it = line.split(',').map(|s| s.trim().parse::<f64>());
        match (it.next(), it.next(), it.next()) {
            (Some(Ok(a)), Some(Ok(b)), None) if a.is_finite() && b.is_finite() => {
                r.push(a);
                z.push(b);
            }
            _ => return Err(bad()),
        }
    }
    check_contour(&r, &z).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((r, z))
}

/// A closed generating curve at `R0 = 1`: at least 3 points, `r ≥ 0`, both ends on the axis
/// (`r = 0`, to 1e-6 of its size), and `R0 = √(A/4π)` of the polyline's surface of revolution
/// within 1% of 1 (contours are read at `R0 = 1`, as `vesicle axisym` writes them).
///
/// # Errors
/// The reason, when the curve is not such a curve.
pub fn check_contour(r: &[f64], z: &[f64]) -> Result<(), String> {
    let n = r.len();
    if n < 3 {
        return Err(format!("a contour needs at least 3 points, got {n}"));
    }
    let size = r
        .iter()
        .chain(z)
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    if let Some(i) = r.iter().position(|x| *x < -1e-9 * size) {
        return Err(format!(
            "r must be ≥ 0 (distance from the axis), got r = {} at point {}",
            r[i],
            i + 1
        ));
    }
    if r[0].abs() > 1e-6 * size || r[n - 1].abs() > 1e-6 * size {
        return Err(format!(
            "the contour is not closed: both ends must lie on the axis (r = 0), got r = {} and {}",
            r[0],
            r[n - 1]
        ));
    }
    let area: f64 = (0..n - 1)
        .map(|i| {
            let ds = (r[i + 1] - r[i]).hypot(z[i + 1] - z[i]);
            std::f64::consts::PI * (r[i].max(0.0) + r[i + 1].max(0.0)) * ds
        })
        .sum();
    let r0 = (area / (4.0 * std::f64::consts::PI)).sqrt();
    if (r0 - 1.0).abs() > 0.01 || r0.is_nan() {
        return Err(format!(
            "the contour's R0 = √(A/4π) is {r0:.6}, expected 1 (contours are read at R0 = 1, as \
             `vesicle axisym` writes them; r0 sets the size)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A unit half circle from pole to pole: the distance is `1 − |p|` to the polyline's sag.
    #[test]
    fn sphere_distance() {
        let n = 41;
        let t: Vec<f64> = (0..n).map(|i| PI * i as f64 / (n - 1) as f64).collect();
        let r: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        let z: Vec<f64> = t.iter().map(|t| 1.0 - t.cos()).collect();
        let m = Meridian::new(&r, &z, 10.0, 0.02);
        assert!(m.symmetric());
        for (rho, zeta) in [
            (0.0f64, 0.0f64),
            (0.0, 9.5),
            (0.0, -12.0),
            (3.0, 4.0),
            (9.9, 0.1),
            (20.0, -3.0),
        ] {
            let exact = 10.0 - (rho * rho + zeta * zeta).sqrt();
            let d = m.signed_distance(rho, zeta);
            assert!((d - exact).abs() < 1e-4, "({rho}, {zeta}): {d} vs {exact}");
        }
    }
}
