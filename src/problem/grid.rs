//! The computational grid: a box of `n` points with spacing `h`, periodic or with mirror walls.
//!
//! Every field is stored as a standard-layout `Array3<f64>` of shape `[n0, n1, n2]`. A 2D scene
//! with `n = [nx, ny]` is stored as `[1, nx, ny]`: the leading axis has length 1, so every
//! stencil and transform sees no variation along it and the memory layout equals the C-order
//! `[nx, ny]` array of the contract.
//!
//! A mirrored axis holds the upper half of a periodic full box that is even about its centre.
//! Full-box points sit at `x_i = (i + 1/2 − N/2) h` (cell-centred, symmetric about 0), so the
//! mirror planes fall half-way between grid points: the reduced box keeps `i = N/2 .. N−1`, its
//! ghost values are `φ_{−1} = φ_0` and `φ_m = φ_{m−1}` (Neumann walls), and the matching spectral
//! transform is the DCT-II. Reduced-box sums are multiplied by `2^(mirrored axes)` to report the
//! full-box integrals.
//!
//! A wall axis is transformed like a mirrored axis (the same DCT-II and Neumann ghosts), but its
//! walls bound the domain: they lie half-way outside the box's first and last points, the box is
//! not halved, its sums are not doubled and its fields are not unfolded. The even extension
//! beyond a wall is only the image that makes the wall a Neumann (free-slip) boundary.

use ndarray::Array3;
use std::borrow::Cow;

/// Boundary treatment of one axis (defined beside the transforms, in `vesicle-transforms`).
pub use vesicle_transforms::AxisKind;

/// Grid geometry shared by all engines.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Spatial dimension of the scene (2 or 3).
    pub dim: usize,
    /// Points of the computed (possibly reduced) box, internal 3-axis form.
    pub shape: [usize; 3],
    /// Boundary kind of each internal axis.
    pub kinds: [AxisKind; 3],
    /// Grid spacing.
    pub h: f64,
    /// Internal axes bounded by walls (their kind is `Mirror`; see the module documentation).
    pub walls: [bool; 3],
}

impl Grid {
    /// Grid for a scene with `n` points (2 or 3 entries) and the mirror flags of each scene
    /// axis. A mirrored axis is halved: the computed box holds `n/2` points along it.
    ///
    /// # Panics
    /// If `n` has not 2 or 3 entries or a mirrored axis has an odd length (validated earlier).
    pub fn new(n: &[usize], h: f64, mirror: &[bool]) -> Self {
        assert!(n.len() == 2 || n.len() == 3, "n must have 2 or 3 entries");
        assert_eq!(n.len(), mirror.len());
        let offset = 3 - n.len();
        let mut shape = [1usize; 3];
        let mut kinds = [AxisKind::Periodic; 3];
        for (a, (&len, &m)) in n.iter().zip(mirror).enumerate() {
            if m {
                assert!(len % 2 == 0, "mirrored axis needs an even length");
                shape[a + offset] = len / 2;
                kinds[a + offset] = AxisKind::Mirror;
            } else {
                shape[a + offset] = len;
            }
        }
        Grid {
            dim: n.len(),
            shape,
            kinds,
            h,
            walls: [false; 3],
        }
    }

    /// This grid with walls on the scene axes flagged in `walls` (not mirrored ones): each such
    /// axis keeps its points and becomes a `Mirror` axis of the transforms.
    ///
    /// # Panics
    /// If `walls` has not one flag per scene axis or flags a mirrored axis (validated earlier).
    pub fn with_walls(mut self, walls: &[bool]) -> Self {
        assert_eq!(walls.len(), self.dim);
        let offset = 3 - self.dim;
        for (s, _) in walls.iter().enumerate().filter(|(_, &w)| w) {
            let a = s + offset;
            assert_eq!(
                self.kinds[a],
                AxisKind::Periodic,
                "a wall axis is not mirrored"
            );
            self.kinds[a] = AxisKind::Mirror;
            self.walls[a] = true;
        }
        self
    }

    /// Whether internal axis `a` is a mirror reduction (a `Mirror` axis that is not a wall).
    pub fn mirrored(&self, a: usize) -> bool {
        self.kinds[a] == AxisKind::Mirror && !self.walls[a]
    }

    /// Number of computed points.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// True when the grid has no points (never for a validated scene).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Volume of one cell, `h^dim`.
    pub fn cell_volume(&self) -> f64 {
        self.h.powi(self.dim as i32)
    }

    /// Factor from reduced-box sums to full-box integrals: `2^(number of mirrored axes)` (walls
    /// not counted).
    pub fn mirror_factor(&self) -> f64 {
        let m = (0..3).filter(|&a| self.mirrored(a)).count();
        (1u32 << m) as f64
    }

    /// Volume (area in 2D) of the full box: computed points × h^d × 2^(mirrored axes).
    pub fn full_volume(&self) -> f64 {
        self.len() as f64 * self.cell_volume() * self.mirror_factor()
    }

    /// Points of the full (unreduced) box along each internal axis.
    pub fn full_shape(&self) -> [usize; 3] {
        let mut s = self.shape;
        for (a, len) in s.iter_mut().enumerate() {
            if self.mirrored(a) {
                *len *= 2;
            }
        }
        s
    }

    /// Coordinates of the computed points along internal axis `a`, centred on the full box:
    /// `x_i = (i + 1/2 − N/2) h` with `N` the full-box length (the reduced box keeps `x > 0`).
    pub fn coords(&self, a: usize) -> Vec<f64> {
        let full = self.full_shape()[a] as f64;
        let start = self.full_shape()[a] - self.shape[a];
        (start..self.full_shape()[a])
            .map(|i| (i as f64 + 0.5 - full / 2.0) * self.h)
            .collect()
    }

    /// A zero field of the computed shape.
    pub fn zeros(&self) -> Array3<f64> {
        Array3::zeros(self.shape)
    }

    /// Evaluate `f(p)` at every computed point, `p` the point in scene coordinates
    /// (`[x, y, 0]` in 2D, `[x, y, z]` in 3D), centred on the full box.
    pub fn field_from(&self, f: impl Fn([f64; 3]) -> f64) -> Array3<f64> {
        let c = [self.coords(0), self.coords(1), self.coords(2)];
        let dim = self.dim;
        Array3::from_shape_fn(self.shape, |(i, j, k)| {
            if dim == 2 {
                f([c[1][j], c[2][k], 0.0])
            } else {
                f([c[0][i], c[1][j], c[2][k]])
            }
        })
    }

    /// [`Grid::field_from`] evaluated in parallel (rayon, in the current pool): the same
    /// values.
    pub fn par_field_from(&self, f: impl Fn([f64; 3]) -> f64 + Sync) -> Array3<f64> {
        let c = [self.coords(0), self.coords(1), self.coords(2)];
        let dim = self.dim;
        let mut out = self.zeros();
        ndarray::Zip::indexed(&mut out).par_for_each(|(i, j, k), v| {
            *v = if dim == 2 {
                f([c[1][j], c[2][k], 0.0])
            } else {
                f([c[0][i], c[1][j], c[2][k]])
            };
        });
        out
    }

    /// The full-box field of a computed field: `field` itself (borrowed, no copy) when no axis
    /// is mirrored, else its even extension across every mirrored axis, built in one pass into
    /// one new array: full-box index i of a mirrored axis of computed length n reads computed
    /// index n − 1 − i below the mirror plane (i < n) and i − n above it.
    pub fn unfold<'a>(&self, field: &'a Array3<f64>) -> Cow<'a, Array3<f64>> {
        if !(0..3).any(|a| self.mirrored(a)) {
            return Cow::Borrowed(field);
        }
        let full = self.full_shape();
        // The computed index each full-box index reads, per axis.
        let [s0, s1, s2]: [Vec<usize>; 3] = std::array::from_fn(|a| {
            let n = self.shape[a];
            (0..full[a])
                .map(|i| match self.mirrored(a) {
                    true if i < n => n - 1 - i,
                    true => i - n,
                    false => i,
                })
                .collect()
        });
        Cow::Owned(Array3::from_shape_fn(full, |(i, j, k)| {
            field[[s0[i], s1[j], s2[k]]]
        }))
    }

    /// Restrict a full-box field to the computed (upper) part of each mirrored axis.
    pub fn restrict(&self, full: &Array3<f64>) -> Array3<f64> {
        let fs = self.full_shape();
        let s = full.slice(ndarray::s![
            fs[0] - self.shape[0]..,
            fs[1] - self.shape[1]..,
            fs[2] - self.shape[2]..
        ]);
        s.as_standard_layout().to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unfolded field is the even extension about every mirror plane (full-box index i and
    /// N − 1 − i hold the same value), its upper part is the computed field (restrict undoes
    /// unfold exactly), and a box without mirrored axes is returned as itself, not copied. A
    /// wrong index map (the lower half not reversed, an axis left out) breaks the symmetry or the
    /// round trip.
    #[test]
    fn unfold_is_the_even_extension_and_borrows_a_full_box() {
        for mirror in [
            [true, false, true],
            [false, true, false],
            [true, true, true],
        ] {
            let grid = Grid::new(&[6, 8, 4], 1.0, &mirror);
            let field =
                Array3::from_shape_fn(grid.shape, |(i, j, k)| (100 * i + 10 * j + k) as f64 + 0.5);
            let full = grid.unfold(&field);
            assert!(matches!(full, Cow::Owned(_)));
            assert_eq!(full.shape(), &grid.full_shape());
            assert_eq!(grid.restrict(&full), field);
            let n = grid.full_shape();
            for a in (0..3).filter(|&a| mirror[a]) {
                for ((i, j, k), v) in full.indexed_iter() {
                    let mut image = [i, j, k];
                    image[a] = n[a] - 1 - image[a];
                    assert_eq!(*v, full[image], "{mirror:?}, axis {a}, ({i}, {j}, {k})");
                }
            }
        }
        let grid = Grid::new(&[6, 8, 4], 1.0, &[false; 3]);
        let field = grid.zeros();
        assert!(matches!(grid.unfold(&field), Cow::Borrowed(f) if std::ptr::eq(f, &field)));
    }
}
