//! NumPy `.npy` files: float64, C order, shape `[nx, ny]` (2D) or `[n0, n1, n2]` (3D).

use super::{check_field, create_file, OutputError};
use ndarray::{Array3, Axis};
use ndarray_npy::npy::header::{Header, Layout, ReadHeaderError};
use ndarray_npy::{ReadDataError, ReadableElement, WriteNpyError, WriteNpyExt};
use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;

/// The type descriptor of little-endian float64 as it appears in an npy header.
const F64_DESCR: &str = "'<f8'";

/// Write a full-box `field` of a `dim`-dimensional scene as a float64 C-order `.npy` file of
/// shape `[nx, ny]` (dim 2, the leading length-1 axis dropped) or `[n0, n1, n2]` (dim 3).
pub fn write_npy(path: &Path, field: &Array3<f64>, dim: usize) -> Result<(), OutputError> {
    check_field(path, field, dim)?;
    let mut file = create_file(path)?;
    let result = if dim == 2 {
        field.index_axis(Axis(0), 0).write_npy(&mut file)
    } else {
        field.write_npy(&mut file)
    };
    result.map_err(|e| write_error(path, e))?;
    file.flush().map_err(|e| OutputError::io(path, e))
}

/// Read a float64 C-order `.npy` file of shape `expected_shape` (`[nx, ny]` or
/// `[n0, n1, n2]`) into the internal layout (`[1, nx, ny]` or `[n0, n1, n2]`).
///
/// Errors name the expected and found shapes, or the offending dtype / memory order.
pub fn read_npy(path: &Path, expected_shape: &[usize]) -> Result<Array3<f64>, OutputError> {
    let internal = internal_shape(path, expected_shape)?;
    let file = File::open(path).map_err(|e| OutputError::io(path, e))?;
    let mut reader = BufReader::new(file);
    let header = Header::from_reader(&mut reader).map_err(|e| header_error(path, e))?;
    check_header(path, &header, expected_shape)?;
    let len = internal.iter().product();
    let data = f64::read_to_end_exact_vec(&mut reader, &header.type_descriptor, len)
        .map_err(|e| data_error(path, e))?;
    Array3::from_shape_vec(internal, data).map_err(|e| OutputError::format(path, e))
}

/// The internal 3-axis shape for a scene shape of 2 or 3 entries.
fn internal_shape(path: &Path, shape: &[usize]) -> Result<[usize; 3], OutputError> {
    match *shape {
        [nx, ny] => Ok([1, nx, ny]),
        [n0, n1, n2] => Ok([n0, n1, n2]),
        _ => Err(OutputError::format(
            path,
            format!("expected shape must have 2 or 3 entries, got {shape:?}"),
        )),
    }
}

/// Accept only little-endian float64 in C order with exactly the expected shape.
fn check_header(path: &Path, header: &Header, expected: &[usize]) -> Result<(), OutputError> {
    let descr = header.type_descriptor.to_string();
    if descr != F64_DESCR {
        return Err(OutputError::format(
            path,
            format!("expected dtype {F64_DESCR} (float64), found {descr}"),
        ));
    }
    if header.layout == Layout::Fortran {
        return Err(OutputError::format(
            path,
            "expected C order (fortran_order: False), found Fortran order",
        ));
    }
    if header.shape != expected {
        return Err(OutputError::Shape {
            path: path.to_path_buf(),
            expected: expected.to_vec(),
            found: header.shape.clone(),
        });
    }
    Ok(())
}

/// Map an ndarray-npy write error, keeping I/O errors as such.
fn write_error(path: &Path, err: WriteNpyError) -> OutputError {
    match err {
        WriteNpyError::Io(io) => OutputError::io(path, io),
        other => OutputError::format(path, format!("cannot write npy: {other}")),
    }
}

/// Map an ndarray-npy header error, keeping I/O errors as such.
fn header_error(path: &Path, err: ReadHeaderError) -> OutputError {
    match err {
        ReadHeaderError::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            OutputError::format(
                path,
                "invalid npy header: the file ends before its header does (empty or cut short)",
            )
        }
        ReadHeaderError::Io(io) => OutputError::io(path, io),
        other => OutputError::format(path, format!("invalid npy header: {other}")),
    }
}

/// Map an ndarray-npy data error, keeping I/O errors as such.
fn data_error(path: &Path, err: ReadDataError) -> OutputError {
    match err {
        ReadDataError::Io(io) => OutputError::io(path, io),
        other => OutputError::format(path, format!("invalid npy data: {other}")),
    }
}
