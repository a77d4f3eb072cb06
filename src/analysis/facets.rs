//! Integrals over the region φ > 0 and its boundary, read from the φ = 0 level set of
//! [`super::levelset`] (the same simplex split: two triangles per cell in 2D, the six
//! tetrahedra of [`super::surface`] per cube in 3D, φ linear in each).
//!
//! The zero set in one simplex is a facet: a segment in 2D, a triangle or quadrilateral (two
//! triangles) in 3D. Each corner of a facet is a [`Crossing`], the zero of φ on a grid edge, so
//! any other field is read there by the same linear interpolation. A region integral becomes a
//! facet sum by the divergence theorem, ∫_{φ>0} ∂_a G dV = ∮ G n_a dA, which needs no cell of
//! the inside and ignores φ away from the surface (a bulk that is not exactly ±1 leaves it
//! unchanged, unlike Σ(1 + φ)/2).
//!
//! A facet's `normal` is its outward vector area (length in 2D): it points from φ > 0
//! towards φ ≤ 0, and its size is the facet's length (2D) or area (3D). [`Facet::mean`]
//! averages a function over the facet with a rule exact for cubic polynomials, so that the
//! moments up to second order of the inside are exact for the piecewise-linear surface.
//!
//! Coordinates: grid point `[i, j, k]` is at `(i h, j h, k h)` (internal axes; a 2D field is
//! `[1, nx, ny]`). A surface that meets the box's edge is open, and the sums then miss its
//! cut faces.

use super::surface::{cross, dot, sub, P3, TETS};
use ndarray::Array3;

/// The zero of φ's linear interpolant on the grid edge `a` → `b`: the point a + t(b − a).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// The edge's inside end (φ > 0).
    pub a: [usize; 3],
    /// The edge's outside end (φ ≤ 0).
    pub b: [usize; 3],
    /// The fraction of the way from `a` to `b`.
    pub t: f64,
}

impl Crossing {
    /// The value of `field` here, interpolated linearly along the edge.
    pub fn read(&self, field: &Array3<f64>) -> f64 {
        field[self.a] + self.t * (field[self.b] - field[self.a])
    }

    /// The physical position.
    pub fn position(&self, h: f64) -> P3 {
        std::array::from_fn(|d| {
            h * (self.a[d] as f64 + self.t * (self.b[d] as f64 - self.a[d] as f64))
        })
    }
}

/// One piece of the φ = 0 surface in one simplex (a segment in 2D, a triangle in 3D).
#[derive(Clone, Debug)]
pub struct Facet {
    /// Two corners in 2D, three in 3D.
    pub corners: Vec<Crossing>,
    /// The corners' positions.
    pub positions: Vec<P3>,
    /// The outward vector area (length in 2D).
    pub normal: P3,
}

/// Points and weights (summing to 1) in barycentric coordinates of a segment and a triangle,
/// exact for cubic polynomials: two-point Gauss–Legendre, and Strang–Fix's degree-3 rule.
const SEGMENT_RULE: [([f64; 3], f64); 2] = [
    ([0.788_675_134_594_812_9, 0.211_324_865_405_187_1, 0.0], 0.5),
    ([0.211_324_865_405_187_1, 0.788_675_134_594_812_9, 0.0], 0.5),
];
const TRIANGLE_RULE: [([f64; 3], f64); 4] = [
    ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], -27.0 / 48.0),
    ([0.6, 0.2, 0.2], 25.0 / 48.0),
    ([0.2, 0.6, 0.2], 25.0 / 48.0),
    ([0.2, 0.2, 0.6], 25.0 / 48.0),
];

impl Facet {
    /// The mean of `g(x, λ)` over the facet (x the point, λ its barycentric coordinates, for
    /// [`Facet::read`]), exact for g cubic in x.
    pub fn mean(&self, g: impl Fn(P3, &[f64; 3]) -> f64) -> f64 {
        let rule: &[([f64; 3], f64)] = match self.corners.len() {
            2 => &SEGMENT_RULE,
            _ => &TRIANGLE_RULE,
        };
        rule.iter()
            .map(|(l, w)| {
                let x = std::array::from_fn(|d| {
                    (0..self.positions.len())
                        .map(|c| l[c] * self.positions[c][d])
                        .sum()
                });
                w * g(x, l)
            })
            .sum()
    }

    /// `field` at barycentric coordinates `l`: linear between the corners' values.
    pub fn read(&self, field: &Array3<f64>, l: &[f64; 3]) -> f64 {
        self.corners
            .iter()
            .zip(l)
            .map(|(c, w)| w * c.read(field))
            .sum()
    }
}

/// Calls `visit` on every facet of the φ = 0 surface of `phi` (spacing `h`; 2D when the first
/// axis has length 1). Non-finite values count as outside.
pub fn for_each(phi: &Array3<f64>, h: f64, mut visit: impl FnMut(&Facet)) {
    let [n0, n1, n2] = [phi.shape()[0], phi.shape()[1], phi.shape()[2]];
    let mixed = |corners: &[[usize; 3]]| {
        let inside = corners.iter().filter(|&&p| phi[p] > 0.0).count();
        inside > 0 && inside < corners.len()
    };
    if n0 == 1 {
        for j in 0..n1.saturating_sub(1) {
            for k in 0..n2.saturating_sub(1) {
                let at = |a: usize, b: usize| [0, j + a, k + b];
                for tri in [[(0, 0), (1, 0), (1, 1)], [(0, 0), (1, 1), (0, 1)]] {
                    let p = tri.map(|(a, b)| at(a, b));
                    if mixed(&p) {
                        visit(&simplex_facets(phi, h, &p).remove(0));
                    }
                }
            }
        }
        return;
    }
    for i in 0..n0 - 1 {
        for j in 0..n1.saturating_sub(1) {
            for k in 0..n2.saturating_sub(1) {
                let cube: [[usize; 3]; 8] =
                    std::array::from_fn(|c| [i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)]);
                if !mixed(&cube) {
                    continue;
                }
                for t in TETS {
                    let p = t.map(|c| cube[c]);
                    if mixed(&p) {
                        simplex_facets(phi, h, &p).iter().for_each(&mut visit);
                    }
                }
            }
        }
    }
}

/// The facets of the zero set in the simplex with grid-point corners `p` (3 in 2D, 4 in 3D),
/// which has corners on both sides.
fn simplex_facets(phi: &Array3<f64>, h: f64, p: &[[usize; 3]]) -> Vec<Facet> {
    let (ins, out): (Vec<[usize; 3]>, Vec<[usize; 3]>) = p.iter().partition(|&&q| phi[q] > 0.0);
    let crossing = |a: [usize; 3], b: [usize; 3]| Crossing {
        a,
        b,
        t: phi[a] / (phi[a] - phi[b]),
    };
    // The corners in cyclic order around the polygon (a segment in 2D).
    let polygon: Vec<Crossing> = match (ins.len(), out.len()) {
        (1, _) => out.iter().map(|&o| crossing(ins[0], o)).collect(),
        (_, 1) => ins.iter().map(|&i| crossing(i, out[0])).collect(),
        _ => vec![
            crossing(ins[0], out[0]),
            crossing(ins[0], out[1]),
            crossing(ins[1], out[1]),
            crossing(ins[1], out[0]),
        ],
    };
    // Outward is from the inside corners towards the outside ones (the direction of −∇φ).
    let centre = |q: &[[usize; 3]]| -> P3 {
        std::array::from_fn(|d| h * q.iter().map(|c| c[d] as f64).sum::<f64>() / q.len() as f64)
    };
    let (c_in, c_out) = (centre(&ins), centre(&out));
    let outward: P3 = std::array::from_fn(|d| c_out[d] - c_in[d]);
    let facet = |corners: Vec<Crossing>| {
        let positions: Vec<P3> = corners.iter().map(|c| c.position(h)).collect();
        let e1 = sub(positions[1], positions[0]);
        let mut normal = if corners.len() == 2 {
            // The segment turned by a right angle in the (axis 1, axis 2) plane.
            [0.0, e1[2], -e1[1]]
        } else {
            let n = cross(e1, sub(positions[2], positions[0]));
            n.map(|x| 0.5 * x)
        };
        if dot(normal, outward) < 0.0 {
            normal = normal.map(|x| -x);
        }
        Facet {
            corners,
            positions,
            normal,
        }
    };
    if polygon.len() == 2 {
        return vec![facet(polygon)];
    }
    (1..polygon.len() - 1)
        .map(|w| facet(vec![polygon[0], polygon[w], polygon[w + 1]]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The enclosed volume ∮ x n_x dA and the second moment ∮ (x³/3) n_x dA of a sphere of
    /// radius 1 (h = 0.05): 4π/3 and 4π/15, to the O(h²) of the flat facets.
    #[test]
    fn a_sphere_encloses_its_volume_and_moment() {
        let (n, h) = (60, 0.05);
        let c = (n - 1) as f64 * h / 2.0;
        let phi = Array3::from_shape_fn((n, n, n), |(i, j, k)| {
            let r = [i, j, k].map(|q| q as f64 * h - c);
            1.0 - (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
        });
        let (mut volume, mut second) = (0.0, 0.0);
        for_each(&phi, h, |f| {
            volume += f.normal[0] * f.mean(|x, _| x[0] - c);
            second += f.normal[0] * f.mean(|x, _| (x[0] - c).powi(3) / 3.0);
        });
        assert!((volume / (4.0 * PI / 3.0) - 1.0).abs() < 3e-3, "{volume}");
        assert!((second / (4.0 * PI / 15.0) - 1.0).abs() < 5e-3, "{second}");
    }

    /// In 2D, a circle of radius 1 (h = 0.02) encloses π by ∮ x n_x ds, and a rigid rotation
    /// u = (−y, x) (linear, so read exactly) has circulation ∮ u·t ds = ∮ (n_x u_y − n_y u_x) ds
    /// equal to twice the enclosed area, to round-off: the polygon is what both integrals see.
    #[test]
    fn a_circle_encloses_its_area_and_a_rotation_its_vorticity() {
        let (n, h) = (120, 0.02);
        let c = (n - 1) as f64 * h / 2.0;
        let at = |j: usize, k: usize| (j as f64 * h - c, k as f64 * h - c);
        let phi = Array3::from_shape_fn((1, n, n), |(_, j, k)| {
            let (x, y) = at(j, k);
            1.0 - (x * x + y * y).sqrt()
        });
        let ux = Array3::from_shape_fn((1, n, n), |(_, j, k)| -at(j, k).1);
        let uy = Array3::from_shape_fn((1, n, n), |(_, j, k)| at(j, k).0);
        let (mut area, mut circulation) = (0.0, 0.0);
        for_each(&phi, h, |f| {
            area += f.normal[1] * f.mean(|x, _| x[1] - c);
            circulation +=
                f.mean(|_, l| f.normal[1] * f.read(&uy, l) - f.normal[2] * f.read(&ux, l));
        });
        assert!((area / PI - 1.0).abs() < 1e-3, "{area}");
        assert!(
            (circulation / (2.0 * area) - 1.0).abs() < 1e-12,
            "{circulation}"
        );
    }
}
