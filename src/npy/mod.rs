//! NumPy `.npy` files: float64, C order, shape `[nx, ny]` (2D) or `[n0, n1, n2]` (3D). The
//! format is read here ([`read_npy`]: the scene's `initial.file` and `c0.file`, the fields
//! the commands read back) and written by [`write()`] (the output writer of a field calls it).
//! A leaf of the crate: it uses none of its layers.
//!
//! The format (NumPy's `numpy.lib.format`): the magic `\x93NUMPY`, the version's major and
//! minor bytes, the header's length (`u16` little-endian in version 1.0, `u32` in 2.0 and 3.0),
//! the header, then the values as raw little-endian float64 in C order. The header is a Python
//! dict literal, `{'descr': '<f8', 'fortran_order': False, 'shape': (96, 96), }`, padded with
//! spaces and ended by a newline so that the values start at a multiple of 64 bytes.

mod header;

use crate::error::OutputError;
use header::{Header, HeaderError};
use ndarray::Array3;
use std::fs::File;
use std::io::{BufReader, ErrorKind, Read, Write};
use std::path::Path;

/// The type descriptor of little-endian float64.
const F64_DESCR: &str = "<f8";

/// The header of a float64 C-order array of `shape`, then `values` (its values in C order), to
/// `file`, flushed.
///
/// # Errors
/// The I/O error of a write.
pub fn write<'a>(
    file: &mut impl Write,
    shape: &[usize],
    values: impl IntoIterator<Item = &'a f64>,
) -> std::io::Result<()> {
    file.write_all(&header::to_bytes(F64_DESCR, shape))?;
    for v in values {
        file.write_all(&v.to_le_bytes())?;
    }
    file.flush()
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
    let data = read_values(&mut reader, len).map_err(|e| data_error(path, len, e))?;
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
    if header.descr != F64_DESCR {
        return Err(OutputError::format(
            path,
            format!(
                "expected dtype '{F64_DESCR}' (float64), found '{}'",
                header.descr
            ),
        ));
    }
    if header.fortran_order {
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

/// Exactly `len` little-endian float64 values, then the end of the file.
fn read_values(reader: &mut impl Read, len: usize) -> std::io::Result<Vec<f64>> {
    let mut values = vec![0.0f64; len];
    reader.read_exact(bytemuck::cast_slice_mut(&mut values))?;
    if reader.read(&mut [0u8])? != 0 {
        return Err(std::io::Error::new(
            ErrorKind::InvalidData,
            "the file goes on after its values",
        ));
    }
    // The bytes were read in the file's (little-endian) order: a no-op on little-endian hosts.
    for v in &mut values {
        *v = f64::from_le_bytes(v.to_ne_bytes());
    }
    Ok(values)
}

/// Map a header error, keeping I/O errors as such.
fn header_error(path: &Path, err: HeaderError) -> OutputError {
    match err {
        HeaderError::Io(io) if io.kind() == ErrorKind::UnexpectedEof => OutputError::format(
            path,
            "invalid npy header: the file ends before its header does (empty or cut short)",
        ),
        HeaderError::Io(io) => OutputError::io(path, io),
        HeaderError::Invalid(message) => {
            OutputError::format(path, format!("invalid npy header: {message}"))
        }
    }
}

/// Map an error reading the `len` values, keeping I/O errors other than a short or long file.
fn data_error(path: &Path, len: usize, err: std::io::Error) -> OutputError {
    match err.kind() {
        ErrorKind::UnexpectedEof => OutputError::format(
            path,
            format!("invalid npy data: the file ends before its {len} values do"),
        ),
        ErrorKind::InvalidData => OutputError::format(path, format!("invalid npy data: {err}")),
        _ => OutputError::io(path, err),
    }
}
