//! A field as a NumPy `.npy` file (the format: [`crate::npy`]).

use super::{check_field, create_file, OutputError};
use ndarray::Array3;
use std::path::Path;

/// Write a full-box `field` of a `dim`-dimensional scene as a float64 C-order `.npy` file of
/// shape `[nx, ny]` (dim 2, the leading length-1 axis dropped) or `[n0, n1, n2]` (dim 3).
pub fn write_npy(path: &Path, field: &Array3<f64>, dim: usize) -> Result<(), OutputError> {
    check_field(path, field, dim)?;
    let shape = if dim == 2 {
        &field.shape()[1..]
    } else {
        field.shape()
    };
    let mut file = create_file(path)?;
    crate::npy::write(&mut file, shape, field).map_err(|e| OutputError::io(path, e))
}
