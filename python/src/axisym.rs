//! The axisymmetric sharp-interface reference (the shape diagram, at any reduced spontaneous
//! curvature c̄0) as NumPy arrays.

use crate::errors::check;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vesicle::analysis::axisym::{self, map::NeckMap, Branch, Options, Solution};
use vesicle::error::Error;

fn branch(py: Python<'_>, name: &str) -> PyResult<Branch> {
    Branch::ALL
        .into_iter()
        .find(|b| b.name() == name)
        .ok_or_else(|| {
            let e = Error::config(
                "branch",
                format!("unknown branch {name:?}: expected prolate, oblate or stomatocyte"),
            );
            crate::errors::to_py(py, e, None)
        })
}

/// A branch of the ADE and BC models (the pear included).
fn branch_with_pear(py: Python<'_>, name: &str) -> PyResult<Branch> {
    Branch::WITH_PEAR
        .into_iter()
        .find(|b| b.name() == name)
        .ok_or_else(|| {
            let e = Error::config(
                "branch",
                format!("unknown branch {name:?}: expected prolate, oblate, stomatocyte or pear"),
            );
            crate::errors::to_py(py, e, None)
        })
}

/// A solution as a dict: scalars and the contour as arrays.
fn solution<'py>(py: Python<'py>, s: &Solution) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("branch", s.branch.name())?;
    d.set_item("v", s.v)?;
    d.set_item("c0", s.c0)?;
    d.set_item("e", s.e)?;
    d.set_item("mean_curvature", s.mean_curvature)?;
    d.set_item("da", s.da())?;
    d.set_item("model", s.model.name())?;
    d.set_item("w", s.w)?;
    d.set_item("c0_eff", s.c0_eff)?;
    d.set_item("sigma", s.sigma)?;
    d.set_item("pressure", s.pressure)?;
    d.set_item("length", s.length())?;
    d.set_item("self_intersecting", s.self_intersecting())?;
    d.set_item("residual", s.residual)?;
    d.set_item("s", PyArray1::from_slice(py, &s.s))?;
    d.set_item("r", PyArray1::from_slice(py, &s.r))?;
    d.set_item("z", PyArray1::from_slice(py, &s.z))?;
    d.set_item("psi", PyArray1::from_slice(py, &s.psi))?;
    let modes: Vec<i64> = s.modes.iter().map(|&k| k as i64).collect();
    d.set_item("modes", PyArray1::from_vec(py, modes))?;
    d.set_item("coefficients", PyArray1::from_slice(py, &s.coefficients))?;
    d.set_item("neck_map", neck_map(py, &s.map)?)?;
    Ok(d)
}

/// The stretching of the contour parameter the coefficients are in: `None` for the identity
/// (`τ = s/L`), else a dict `centre` (the neck's arclength fraction `t_n`), `half_width` (the
/// kernel's, in `t`), `background` (`α`, the uniform share of the node density) and
/// `mirrored` (kernels at `1 − t_n` too).
fn neck_map<'py>(py: Python<'py>, m: &NeckMap) -> PyResult<Option<Bound<'py, PyDict>>> {
    if m.is_identity() {
        return Ok(None);
    }
    let d = PyDict::new(py);
    d.set_item("centre", m.centre)?;
    d.set_item("half_width", m.half_width())?;
    d.set_item("background", m.alpha)?;
    d.set_item("mirrored", m.mirrored)?;
    Ok(Some(d))
}

/// The options of `nodes` nodes (at least 9) at the reduced spontaneous curvature `c0`
/// (finite).
fn options(py: Python<'_>, nodes: usize, c0: f64) -> PyResult<Options> {
    if nodes < 9 {
        let e = Error::config("nodes", format!("need at least 9 nodes, got {nodes}"));
        return Err(crate::errors::to_py(py, e, None));
    }
    if !c0.is_finite() {
        let e = Error::config("c0", format!("must be a finite number, got {c0}"));
        return Err(crate::errors::to_py(py, e, None));
    }
    Ok(Options::with_nodes(nodes).with_c0(c0))
}

/// The stationary shape of `branch` at reduced volume `v` and reduced spontaneous curvature
/// `c0` (see vesicle.axisym.solve): SC, or ADE with `ade = (alpha, da0)`, or the bilayer couple
/// with `bc = da`.
#[pyfunction]
#[pyo3(signature = (branch_name, v, nodes=241, c0=0.0, ade=None, bc=None))]
pub fn axisym_solve<'py>(
    py: Python<'py>,
    branch_name: &str,
    v: f64,
    nodes: usize,
    c0: f64,
    ade: Option<(f64, f64)>,
    bc: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = options(py, nodes, c0)?;
    let s = match (ade, bc) {
        (Some(_), Some(_)) => {
            let e = Error::config("ade", "give ade or bc, not both");
            return Err(crate::errors::to_py(py, e, None));
        }
        (Some((alpha, da0)), None) => {
            let b = branch_with_pear(py, branch_name)?;
            check(
                py,
                py.detach(|| axisym::ade_solution(b, v, alpha, da0, &opts)),
            )?
        }
        (None, Some(da)) => {
            if c0 != 0.0 {
                let e = Error::config("c0", "the bilayer couple takes no c0");
                return Err(crate::errors::to_py(py, e, None));
            }
            let b = branch_with_pear(py, branch_name)?;
            check(py, py.detach(|| axisym::bc_solution(b, v, da, &opts)))?
        }
        (None, None) => {
            let b = branch(py, branch_name)?;
            check(py, py.detach(|| axisym::solve(b, v, &opts)))?
        }
    };
    solution(py, &s)
}

/// A branch followed over reduced volumes `vs` at reduced spontaneous curvature `c0` (see
/// vesicle.axisym.follow).
#[pyfunction]
#[pyo3(signature = (branch_name, vs, nodes=241, c0=0.0))]
pub fn axisym_follow<'py>(
    py: Python<'py>,
    branch_name: &str,
    vs: Vec<f64>,
    nodes: usize,
    c0: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let b = branch(py, branch_name)?;
    let opts = options(py, nodes, c0)?;
    let f = py.detach(|| axisym::follow(b, &vs, &opts));
    let d = PyDict::new(py);
    let col = |g: fn(&Solution) -> f64| f.shapes.iter().map(g).collect::<Vec<f64>>();
    d.set_item("branch", b.name())?;
    d.set_item("c0", c0)?;
    d.set_item("v", PyArray1::from_vec(py, col(|s| s.v)))?;
    d.set_item("e", PyArray1::from_vec(py, col(|s| s.e)))?;
    d.set_item("sigma", PyArray1::from_vec(py, col(|s| s.sigma)))?;
    d.set_item("pressure", PyArray1::from_vec(py, col(|s| s.pressure)))?;
    d.set_item("end", f.end)?;
    let shapes = f
        .shapes
        .iter()
        .map(|s| solution(py, s))
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("shapes", shapes)?;
    Ok(d)
}

/// Where the bilayer-couple prolate at reduced volume `v` loses or regains up–down stability
/// along its path in Δa (see vesicle.axisym.updown).
#[pyfunction]
#[pyo3(signature = (v, nodes=241))]
pub fn axisym_updown<'py>(
    py: Python<'py>,
    v: f64,
    nodes: usize,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    if !(v > 0.0 && v < 1.0) {
        let e = Error::config("v", format!("need 0 < v < 1, got {v}"));
        return Err(crate::errors::to_py(py, e, None));
    }
    let opts = options(py, nodes, 0.0)?;
    let changes = py.detach(|| {
        let curve = axisym::bc_curve(Branch::Prolate, v, axisym::ade::ADE_WINDOW, &opts);
        axisym::updown_changes(&curve, &opts)
    });
    changes
        .iter()
        .map(|c| {
            let d = PyDict::new(py);
            d.set_item("da", c.shape.da())?;
            d.set_item("loses", c.loses)?;
            d.set_item("c0_eff", c.shape.c0_eff)?;
            d.set_item("neck", c.shape.neck())?;
            d.set_item("shape", solution(py, &c.shape)?)?;
            Ok(d)
        })
        .collect()
}
