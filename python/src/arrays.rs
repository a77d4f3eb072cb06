//! Conversions to Python: a step's record as a dict, the time series as a dict of NumPy
//! arrays, a full-box field as a read-only NumPy array.

use ndarray::{Array3, Ix2};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vesicle::driver::record::Record;

/// A record as a dict keyed by the timeseries.csv column names (`step` and `rejected` ints;
/// with ADE or the bilayer couple also `bending_energy`, `da`, `w`, `c0_eff`, `lambda`).
pub fn record_dict<'py>(py: Python<'py>, r: &Record) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for name in r.names() {
        match name {
            "step" => d.set_item(name, r.step)?,
            "rejected" => d.set_item(name, r.rejected)?,
            _ => d.set_item(name, r.get(name))?,
        }
    }
    Ok(d)
}

/// The time series as a dict of 1-D arrays, one per column of its first row (`step` and
/// `rejected` int64).
pub fn history_dict<'py>(py: Python<'py>, rows: &[Record]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let names = rows
        .first()
        .map_or_else(|| vesicle::driver::record::COLUMNS.to_vec(), Record::names);
    for name in names {
        let col = |r: &Record| r.get(name).unwrap_or(f64::NAN);
        match name {
            "step" | "rejected" => {
                let ints: Vec<i64> = rows.iter().map(|r| col(r) as i64).collect();
                d.set_item(name, PyArray1::from_vec(py, ints))?;
            }
            _ => {
                let values: Vec<f64> = rows.iter().map(col).collect();
                d.set_item(name, PyArray1::from_vec(py, values))?;
            }
        }
    }
    Ok(d)
}

/// A full-box field (internal layout, `[1, nx, ny]` in 2D) as a read-only NumPy array of the
/// scene's shape (`(nx, ny)` in 2D, `(nx, ny, nz)` in 3D), taking the array without a copy.
pub fn field_array<'py>(
    py: Python<'py>,
    field: Array3<f64>,
    dim: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let array = if dim == 2 {
        let (_, nx, ny) = field.dim();
        let flat = field
            .into_shape_with_order((nx, ny))
            .expect("a [1, nx, ny] field reshapes to (nx, ny)")
            .into_dimensionality::<Ix2>()
            .expect("two axes");
        numpy::PyArray2::from_owned_array(py, flat).into_any()
    } else {
        numpy::PyArray3::from_owned_array(py, field).into_any()
    };
    read_only(&array)?;
    Ok(array)
}

/// Mark a NumPy array read-only (`a.flags.writeable = False`).
pub fn read_only(array: &Bound<'_, PyAny>) -> PyResult<()> {
    let kwargs = PyDict::new(array.py());
    kwargs.set_item("write", false)?;
    array.call_method("setflags", (), Some(&kwargs))?;
    Ok(())
}

/// A list of points as an `(n, 3)` float64 array.
pub fn points<'py>(py: Python<'py>, p: &[[f64; 3]]) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = p.iter().flatten().copied().collect();
    PyArray1::from_vec(py, flat)
        .reshape([p.len(), 3])
        .expect("3 values a point")
        .into_any()
}

/// A list of triangles as an `(n, 3)` int64 array.
pub fn triangles<'py>(py: Python<'py>, t: &[[u32; 3]]) -> Bound<'py, PyAny> {
    let flat: Vec<i64> = t.iter().flatten().map(|&v| i64::from(v)).collect();
    PyArray1::from_vec(py, flat)
        .reshape([t.len(), 3])
        .expect("3 vertices a triangle")
        .into_any()
}
