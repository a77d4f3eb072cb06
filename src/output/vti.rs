//! VTK XML ImageData (`.vti`) files for ParaView: one Float64 point-data array stored as raw
//! appended little-endian binary with a UInt64 byte-count header.
//!
//! The field's last internal axis is the fastest in memory and VTK wants x fastest, so the
//! internal axes `(a0, a1, a2)` map to VTK `(z, y, x)` and the data is written in memory order.
//! In 3D, VTK x/y/z are thus the scene's z/y/x; in 2D (`[1, nx, ny]`) VTK x/y are the scene's
//! y/x and the image has a single z layer. Points sit at `(i + 1/2 − N/2) h`, so the box is
//! centred on the origin exactly as in [`crate::problem::grid::Grid::coords`].

use super::{check_field, create_file, OutputError};
use ndarray::Array3;
use std::io::Write;
use std::path::Path;

/// Write `field` (full box, `dim`-dimensional scene, spacing `h`) as a `.vti` file holding one
/// Float64 point-data array called `name`.
pub fn write_vti(
    path: &Path,
    field: &Array3<f64>,
    dim: usize,
    h: f64,
    name: &str,
) -> Result<(), OutputError> {
    check_field(path, field, dim)?;
    if !(h.is_finite() && h > 0.0) {
        return Err(OutputError::format(
            path,
            format!("grid spacing must be positive, got {h}"),
        ));
    }
    let shape = [field.shape()[0], field.shape()[1], field.shape()[2]];
    let mut file = create_file(path)?;
    write_all(&mut file, &xml_header(shape, h, name), field)
        .and_then(|()| file.flush())
        .map_err(|e| OutputError::io(path, e))
}

/// Write the XML header, the appended binary block and the closing tags.
fn write_all(out: &mut impl Write, header: &str, field: &Array3<f64>) -> std::io::Result<()> {
    out.write_all(header.as_bytes())?;
    let nbytes = (field.len() * std::mem::size_of::<f64>()) as u64;
    out.write_all(&nbytes.to_le_bytes())?;
    for v in field.iter() {
        out.write_all(&v.to_le_bytes())?;
    }
    out.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
}

/// Everything up to and including the `_` that starts the appended data.
fn xml_header(shape: [usize; 3], h: f64, name: &str) -> String {
    let [n0, n1, n2] = shape;
    let extent = format!("0 {} 0 {} 0 {}", n2 - 1, n1 - 1, n0 - 1);
    let origin = format!("{} {} {}", origin(n2, h), origin(n1, h), origin(n0, h));
    let name = xml_escape(name);
    let version = env!("CARGO_PKG_VERSION");
    format!(
        r#"<?xml version="1.0"?>
<!-- written by vesicle {version}; the run's resolved scene is in summary.json beside it -->
<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <ImageData WholeExtent="{extent}" Origin="{origin}" Spacing="{h} {h} {h}">
    <Piece Extent="{extent}">
      <PointData Scalars="{name}">
        <DataArray type="Float64" Name="{name}" NumberOfComponents="1" format="appended" offset="0"/>
      </PointData>
    </Piece>
  </ImageData>
  <AppendedData encoding="raw">
   _"#
    )
}

/// Coordinate of the first point of an axis of `n` cell-centred points centred on 0.
fn origin(n: usize, h: f64) -> f64 {
    (0.5 - n as f64 / 2.0) * h
}

/// Escape the characters that may not appear inside an XML attribute value.
fn xml_escape(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '&' => "&amp;".to_string(),
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '"' => "&quot;".to_string(),
            '\'' => "&apos;".to_string(),
            c => c.to_string(),
        })
        .collect()
}
