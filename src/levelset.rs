//! Geometry of the φ = 0 level set (DESIGN.md §1: the diffuse ∫(1+φ)/2 and ∫a carry
//! O(ε²/R²) errors; shape diagrams need the sharp surface). φ is interpolated linearly on a
//! simplex split of the grid (two triangles per cell in 2D, six tetrahedra around the main
//! diagonal per cube in 3D, which match across faces), the zero set is triangulated, and
//!
//! ```text
//! 3D: A₀ = Σ |triangles|,   V₀ = Σ (1/6) p₁·(p₂ × p₃)   (outward orientation, divergence theorem)
//! 2D: L₀ = Σ |segments|,    V₀ = Σ over triangles of the exact area where φ > 0
//! ```
//!
//! For a closed surface inside the box (the full box, after unfolding a reduced one).

use crate::model::Measures;
use ndarray::Array3;
use serde::Serialize;

/// Area (perimeter in 2D) and enclosed volume (area in 2D) of the φ = 0 surface.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LevelSet {
    /// A₀ (3D) or L₀ (2D).
    pub area: f64,
    /// V₀ (3D) or the enclosed area (2D).
    pub volume: f64,
    /// v of §1 from A₀ and V₀.
    pub reduced_volume: f64,
}

impl LevelSet {
    fn new(area: f64, volume: f64, dim: usize) -> Self {
        let m = Measures {
            energy: 0.0,
            area,
            volume,
        };
        LevelSet {
            area,
            volume,
            reduced_volume: m.reduced(dim, 1.0).volume,
        }
    }
}

/// The φ = 0 surface of `phi` (the full box in internal layout, [1, nx, ny] in 2D; spacing
/// `h`).
pub fn measure(phi: &Array3<f64>, dim: usize, h: f64) -> LevelSet {
    if dim == 2 {
        measure_2d(phi, h)
    } else {
        measure_3d(phi, h)
    }
}

type P3 = [f64; 3];

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The zero of the linear interpolant on the edge p → q.
fn crossing(p: P3, vp: f64, q: P3, vq: f64) -> P3 {
    let t = vp / (vp - vq);
    [
        p[0] + t * (q[0] - p[0]),
        p[1] + t * (q[1] - p[1]),
        p[2] + t * (q[2] - p[2]),
    ]
}

/// Six tetrahedra of the unit cube around the diagonal 0–7 (corner index x + 2y + 4z).
const TETS: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

fn measure_3d(phi: &Array3<f64>, h: f64) -> LevelSet {
    let [n0, n1, n2] = [phi.shape()[0], phi.shape()[1], phi.shape()[2]];
    let coord = |i: usize, n: usize| (i as f64 + 0.5 - n as f64 / 2.0) * h;
    let (mut area, mut volume) = (0.0, 0.0);
    for i in 0..n0 - 1 {
        for j in 0..n1 - 1 {
            for k in 0..n2 - 1 {
                let mut p = [[0.0; 3]; 8];
                let mut v = [0.0; 8];
                for (c, (pc, vc)) in p.iter_mut().zip(v.iter_mut()).enumerate() {
                    let (a, b, d) = (i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                    *pc = [coord(a, n0), coord(b, n1), coord(d, n2)];
                    *vc = phi[[a, b, d]];
                }
                if v.iter().all(|&x| x > 0.0) || v.iter().all(|&x| x <= 0.0) {
                    continue;
                }
                for t in TETS {
                    let (a, vol) = tet_surface(t.map(|c| p[c]), t.map(|c| v[c]));
                    area += a;
                    volume += vol;
                }
            }
        }
    }
    LevelSet::new(area, volume, 3)
}

/// Area of the zero set in one tetrahedron and its divergence-theorem volume term.
fn tet_surface(p: [P3; 4], v: [f64; 4]) -> (f64, f64) {
    let inside: Vec<usize> = (0..4).filter(|&i| v[i] > 0.0).collect();
    let outside: Vec<usize> = (0..4).filter(|&i| v[i] <= 0.0).collect();
    let e = |a: usize, b: usize| crossing(p[a], v[a], p[b], v[b]);
    let polygon: Vec<P3> = match (inside.len(), outside.len()) {
        (1, 3) => outside.iter().map(|&o| e(inside[0], o)).collect(),
        (3, 1) => inside.iter().map(|&i| e(i, outside[0])).collect(),
        (2, 2) => {
            let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
            vec![e(a, c), e(a, d), e(b, d), e(b, c)]
        }
        _ => return (0.0, 0.0),
    };
    // Outward: from the inside vertices towards the outside ones.
    let centroid = |idx: &[usize]| {
        let s = idx.iter().fold([0.0; 3], |s, &i| {
            [s[0] + p[i][0], s[1] + p[i][1], s[2] + p[i][2]]
        });
        [
            s[0] / idx.len() as f64,
            s[1] / idx.len() as f64,
            s[2] / idx.len() as f64,
        ]
    };
    let out_dir = sub(centroid(&outside), centroid(&inside));
    let (mut area, mut volume) = (0.0, 0.0);
    for w in 1..polygon.len() - 1 {
        let (a, mut b, mut c) = (polygon[0], polygon[w], polygon[w + 1]);
        let mut n = cross(sub(b, a), sub(c, a));
        if dot(n, out_dir) < 0.0 {
            std::mem::swap(&mut b, &mut c);
            n = [-n[0], -n[1], -n[2]];
        }
        area += 0.5 * dot(n, n).sqrt();
        volume += dot(a, cross(b, c)) / 6.0;
    }
    (area, volume)
}

fn measure_2d(phi: &Array3<f64>, h: f64) -> LevelSet {
    let (nx, ny) = (phi.shape()[1], phi.shape()[2]);
    let (mut length, mut area) = (0.0, 0.0);
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            let v = |a: usize, b: usize| phi[[0, i + a, j + b]];
            let at = |a: usize, b: usize| [a as f64 * h, b as f64 * h, 0.0];
            // Two triangles: (00, 10, 11) and (00, 11, 01).
            for tri in [[(0, 0), (1, 0), (1, 1)], [(0, 0), (1, 1), (0, 1)]] {
                let p = tri.map(|(a, b)| at(a, b));
                let val = tri.map(|(a, b)| v(a, b));
                let (l, s) = triangle_part(p, val);
                length += l;
                area += s;
            }
        }
    }
    LevelSet::new(length, area, 2)
}

/// Length of the zero set in a triangle and the exact area where the linear φ > 0.
fn triangle_part(p: [P3; 3], v: [f64; 3]) -> (f64, f64) {
    let full = 0.5 * cross(sub(p[1], p[0]), sub(p[2], p[0]))[2].abs();
    let pos: Vec<usize> = (0..3).filter(|&i| v[i] > 0.0).collect();
    let lone = match pos.len() {
        0 => return (0.0, 0.0),
        3 => return (0.0, full),
        1 => pos[0],
        _ => (0..3)
            .find(|i| !pos.contains(i))
            .expect("one vertex is outside"),
    };
    let (o1, o2) = ((lone + 1) % 3, (lone + 2) % 3);
    let (a, b) = (
        crossing(p[lone], v[lone], p[o1], v[o1]),
        crossing(p[lone], v[lone], p[o2], v[o2]),
    );
    let d = sub(b, a);
    let length = dot(d, d).sqrt();
    // The corner triangle at the lone vertex covers t1·t2 of the triangle.
    let t1 = v[lone] / (v[lone] - v[o1]);
    let t2 = v[lone] / (v[lone] - v[o2]);
    let corner = full * t1 * t2;
    (
        length,
        if pos.len() == 1 {
            corner
        } else {
            full - corner
        },
    )
}
