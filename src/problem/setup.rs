//! From a validated scene to the computed problem: the (possibly reduced) grid, the initial
//! field on it and the c0 field. Checks what needs the field: the shape fits its box, and the
//! declared mirror planes are symmetries of φ and c0.

use crate::error::{Error, Result};
use crate::problem::config::{axis_index, Initial, Scene, Shape, Symmetry};
use crate::problem::grid::Grid;
use crate::problem::model::{SpontaneousCurvature, C0};
use crate::problem::shapes;
use ndarray::{Array3, Axis};

/// Largest φ allowed on the outer faces of the box: the shape must keep about 2ε of bulk
/// (φ = tanh(−1.47) ≈ −0.9) between its surface and the walls.
pub const FACE_PHI_MAX: f64 = -0.9;

/// Largest |φ(x) − φ(mirror x)| for a plane to count as a symmetry.
pub const SYMMETRY_TOL: f64 = 1e-12;

/// The problem a run computes.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The computed grid (reduced when mirror planes are used).
    pub grid: Grid,
    /// Initial φ on the computed grid (before preparation steps).
    pub phi: Array3<f64>,
    /// εC0 on the computed grid.
    pub c0: C0,
    /// Scene axes run as mirror planes.
    pub mirror: Vec<bool>,
}

/// Build the problem of `scene`.
///
/// # Errors
/// `Error::Config` if the initial file is unreadable or has the wrong shape, an `axisym` shape
/// has no solution at its reduced volume (or its contour is unreadable), the shape does not fit
/// its box, a c0 file is unreadable, or a declared mirror plane is not a symmetry of φ or c0.
pub fn build(scene: &Scene) -> Result<Problem> {
    let full_grid = Grid::new(&scene.n, scene.h, &vec![false; scene.dim]);
    let full_phi = initial_field(scene, &full_grid)?;
    check_fits(&full_grid, &full_phi, runs_through(scene))?;
    let full_c0 = C0::new(&scene.c0, &full_grid, scene.eps)?;
    let mirror = mirror_axes(scene, &full_grid, &full_phi, &full_c0)?;
    let grid = Grid::new(&scene.n, scene.h, &mirror).with_walls(&scene.wall_flags());
    let phi = grid.restrict(&full_phi);
    let c0 = C0::new(&scene.c0, &grid, scene.eps)?;
    Ok(Problem {
        grid,
        phi,
        c0,
        mirror,
    })
}

/// The problem of a resolved scene without its initial field (φ = 0; a resumed run restores φ
/// from its checkpoint): the grid of the scene's explicit mirror axes and the c0 field.
///
/// # Errors
/// `Error::Config` on field `symmetry` if the scene does not name its mirror axes, or on
/// `c0.file` if a c0 file cannot be read.
pub fn frame(scene: &Scene) -> Result<Problem> {
    let Symmetry::Axes(axes) = &scene.symmetry else {
        return Err(Error::config(
            "symmetry",
            "a resumed scene names its mirror axes (it was resolved when the run started)",
        ));
    };
    let mirror: Vec<bool> = (0..scene.dim)
        .map(|a| axes.iter().any(|n| axis_index(n, scene.dim) == Some(a)))
        .collect();
    let grid = Grid::new(&scene.n, scene.h, &mirror).with_walls(&scene.wall_flags());
    let c0 = C0::new(&scene.c0, &grid, scene.eps)?;
    Ok(Problem {
        phi: grid.zeros(),
        grid,
        c0,
        mirror,
    })
}

fn initial_field(scene: &Scene, grid: &Grid) -> Result<Array3<f64>> {
    match &scene.initial {
        Initial::Shape(shape) => {
            let shape = shapes::prepare(shape, "initial", scene.dim, scene.eps)?;
            Ok(grid.par_field_from(|p| {
                shapes::profile(shape.signed_distance(p, scene.dim), scene.eps)
            }))
        }
        Initial::File { file } => {
            let phi = crate::npy::read_npy(file, &scene.n)
                .map_err(|e| Error::config("initial.file", e.to_string()))?;
            if let Some(bad) = phi.iter().find(|p| !p.is_finite()) {
                return Err(Error::config(
                    "initial.file",
                    format!("{} holds a non-finite value ({bad})", file.display()),
                ));
            }
            Ok(phi)
        }
    }
}

/// The internal axes a `slab` initial shape runs through (every axis but its normal): it
/// crosses the periodic faces across them by construction.
fn runs_through(scene: &Scene) -> Vec<usize> {
    match &scene.initial {
        Initial::Shape(Shape::Slab(s)) => {
            let normal = s.axis.as_deref().and_then(|a| axis_index(a, scene.dim));
            let normal = normal.unwrap_or(scene.dim - 1);
            (0..scene.dim)
                .filter(|&a| a != normal)
                .map(|a| a + 3 - scene.dim)
                .collect()
        }
        _ => Vec::new(),
    }
}

/// The outer faces of the box must be bulk outside (φ ≤ FACE_PHI_MAX), except along an axis
/// the field does not depend on (a periodic tube or slab running through the box) or one of
/// `through`, which the shape crosses periodically (a wavy slab).
fn check_fits(grid: &Grid, phi: &Array3<f64>, through: Vec<usize>) -> Result<()> {
    for a in 0..3 {
        if grid.shape[a] == 1 || invariant_along(phi, a) || through.contains(&a) {
            continue;
        }
        for idx in [0, grid.shape[a] - 1] {
            let face_max = phi
                .index_axis(Axis(a), idx)
                .iter()
                .cloned()
                .fold(f64::NEG_INFINITY, f64::max);
            if face_max > FACE_PHI_MAX {
                return Err(Error::config(
                    "initial",
                    format!(
                        "the shape does not fit its box: φ reaches {face_max:.3} on a face normal \
                         to axis {} (must stay ≤ {FACE_PHI_MAX}, about 2ε of outside bulk); \
                         enlarge n or shrink the shape",
                        ["x", "y", "z"][a + grid.dim - 3]
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// True when φ does not change along internal axis `a` (to 1e-12).
fn invariant_along(phi: &Array3<f64>, a: usize) -> bool {
    let first = phi.index_axis(Axis(a), 0);
    phi.axis_iter(Axis(a)).all(|plane| {
        plane
            .iter()
            .zip(first.iter())
            .all(|(x, y)| (x - y).abs() <= 1e-12)
    })
}

/// Largest |u(x) − u(mirror_a x)| over the box, mirror about the centre of internal axis `a`.
fn asymmetry(u: &Array3<f64>, a: usize) -> f64 {
    let mut flipped = u.view();
    flipped.invert_axis(Axis(a));
    crate::problem::model::max_abs_diff(u, flipped)
}

fn c0_asymmetry(c0: &C0, a: usize) -> f64 {
    match &c0.shape {
        SpontaneousCurvature::Field(f) => asymmetry(f, a),
        _ => 0.0,
    }
}

/// Mirror flags per scene axis: declared (and checked) or detected.
fn mirror_axes(scene: &Scene, grid: &Grid, phi: &Array3<f64>, c0: &C0) -> Result<Vec<bool>> {
    let internal = |scene_axis: usize| scene_axis + 3 - scene.dim;
    let mut mirror = vec![false; scene.dim];
    match &scene.symmetry {
        Symmetry::Auto(_) => {
            let walls = scene.wall_flags();
            // An imposed shear along x varying along y is even about neither plane.
            let sheared = scene.stokes_flow().is_some_and(|f| f.shear_rate.is_some());
            // Unequal viscosities and the inextensible membrane run on the periodic box.
            let periodic = scene
                .stokes_flow()
                .is_some_and(|f| f.contrast().is_some() || f.inextensible);
            for (s, m) in mirror.iter_mut().enumerate() {
                let a = internal(s);
                let kept_by_flow = !(sheared && s < 2);
                *m = !walls[s]
                    && !periodic
                    && kept_by_flow
                    && grid.shape[a].is_multiple_of(2)
                    && asymmetry(phi, a) <= SYMMETRY_TOL
                    && c0_asymmetry(c0, a) <= SYMMETRY_TOL;
            }
        }
        Symmetry::Axes(names) => {
            for name in names {
                let s = axis_index(name, scene.dim).expect("validated");
                let a = internal(s);
                let dphi = asymmetry(phi, a);
                if dphi > SYMMETRY_TOL {
                    return Err(Error::config(
                        "symmetry",
                        format!(
                            "the initial φ is not even about the plane {name} = 0 through the box \
                             centre (max |φ − mirror φ| = {dphi:.2e}); centre the shape or drop {name:?}"
                        ),
                    ));
                }
                let dc0 = c0_asymmetry(c0, a);
                if dc0 > SYMMETRY_TOL {
                    return Err(Error::config(
                        "symmetry",
                        format!("the c0 field is not even about the plane {name} = 0 (max difference {dc0:.2e})"),
                    ));
                }
                mirror[s] = true;
            }
        }
    }
    Ok(mirror)
}
