//! Connected pieces of the inside {φ > 0}: tells a chain of pearls joined by necks from
//! separate spheres, and a bud still attached from one pinched off.
//!
//! Two grid points belong to the same piece when a path of face-neighbours (6-connectivity in
//! 3D, 4 in 2D) joins them with φ > 0 all along. The box is taken periodic along every axis:
//! that is the full periodic box, and also the unfolded full box of a mirror-reduced run (its
//! even extension is periodic). A neck thinner than about one grid spacing no longer joins
//! its two sides at the grid points, so a count of 2 means "pinched off at the resolution of
//! the grid", which for a phase field is the interface width, not a molecular fission.

use ndarray::Array3;

/// The number of connected pieces of {φ > 0} on the periodic grid of `phi` (any shape
/// `[n0, n1, n2]`; axes of length 1 carry no neighbours).
pub fn count(phi: &Array3<f64>) -> usize {
    let dims = phi.dim();
    let n = [dims.0, dims.1, dims.2];
    let len = n[0] * n[1] * n[2];
    let inside: Vec<bool> = phi.iter().map(|&p| p > 0.0).collect();
    let mut seen = vec![false; len];
    let mut stack = Vec::new();
    let mut pieces = 0;
    for start in 0..len {
        if !inside[start] || seen[start] {
            continue;
        }
        pieces += 1;
        seen[start] = true;
        stack.push(start);
        while let Some(at) = stack.pop() {
            for next in neighbours(at, n) {
                if inside[next] && !seen[next] {
                    seen[next] = true;
                    stack.push(next);
                }
            }
        }
    }
    pieces
}

/// The periodic face-neighbours of the C-order index `at` on a grid of shape `n` (none along
/// an axis of length 1; one, not two, along an axis of length 2).
fn neighbours(at: usize, n: [usize; 3]) -> impl Iterator<Item = usize> {
    let idx = [at / (n[1] * n[2]), (at / n[2]) % n[1], at % n[2]];
    let stride = [n[1] * n[2], n[2], 1];
    (0..3).flat_map(move |axis| {
        let len = n[axis];
        // Steps forward (+1) and backward (len − 1, mod len); one neighbour when len = 2.
        let steps = match len {
            1 => 0,
            2 => 1,
            _ => 2,
        };
        [1, len.saturating_sub(1)]
            .into_iter()
            .take(steps)
            .map(move |s| {
                let moved = (idx[axis] + s) % len;
                at + moved * stride[axis] - idx[axis] * stride[axis]
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn balls(n: usize, centres: &[[f64; 3]], r: f64) -> Array3<f64> {
        Array3::from_shape_fn((n, n, n), |(i, j, k)| {
            let p = [i as f64, j as f64, k as f64];
            let inside = centres
                .iter()
                .any(|c| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>() < r * r);
            if inside {
                1.0
            } else {
                -1.0
            }
        })
    }

    #[test]
    fn two_separate_balls_are_two_pieces_and_a_bridge_joins_them() {
        let mut phi = balls(24, &[[6.0, 12.0, 12.0], [17.0, 12.0, 12.0]], 4.0);
        assert_eq!(count(&phi), 2);
        for i in 6..=17 {
            phi[[i, 12, 12]] = 0.5;
        }
        assert_eq!(count(&phi), 1);
    }

    #[test]
    fn a_ball_cut_by_the_periodic_boundary_is_one_piece() {
        let phi = balls(20, &[[0.0, 10.0, 10.0], [20.0, 10.0, 10.0]], 4.0);
        assert_eq!(count(&phi), 1);
    }

    #[test]
    fn an_empty_field_has_no_piece_and_a_2d_field_counts_discs() {
        assert_eq!(count(&Array3::from_elem((8, 8, 8), -1.0)), 0);
        let discs = Array3::from_shape_fn((1, 30, 30), |(_, j, k)| {
            let d = |c: f64| ((j as f64 - c).powi(2) + (k as f64 - 15.0).powi(2)).sqrt();
            if d(7.0) < 4.0 || d(22.0) < 4.0 {
                1.0
            } else {
                -1.0
            }
        });
        assert_eq!(count(&discs), 2);
    }
}
