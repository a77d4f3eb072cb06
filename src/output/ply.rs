//! Stanford PLY files of a [`Mesh`]: `binary_little_endian 1.0`, vertices as `float x y z`,
//! faces as `list uchar uint vertex_indices` (three per face). ParaView, MeshLab and Blender
//! open them. [`read_ply`] reads back exactly this layout (it is not a general PLY reader).

use super::{create_file, OutputError};
use crate::analysis::surface::Mesh;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

/// Write `mesh` to `path` as binary little-endian PLY, coordinates rounded to `f32`, with
/// `comment` (one line, no newline) in the header.
pub fn write_ply(path: &Path, mesh: &Mesh, comment: &str) -> Result<(), OutputError> {
    let mut file = create_file(path)?;
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment {}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nelement face {}\n\
         property list uchar uint vertex_indices\nend_header\n",
        comment.replace(['\n', '\r'], " "),
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    let mut bytes = Vec::with_capacity(12 * mesh.vertices.len() + 13 * mesh.triangles.len());
    for p in &mesh.vertices {
        for x in p {
            bytes.extend_from_slice(&(*x as f32).to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        bytes.push(3);
        for v in t {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    let io = |e| OutputError::io(path, e);
    file.write_all(header.as_bytes()).map_err(io)?;
    file.write_all(&bytes).map_err(io)?;
    file.flush().map_err(io)
}

/// Read a PLY file in the layout [`write_ply`] writes (vertex coordinates widened to `f64`).
///
/// # Errors
/// `OutputError::Format` naming what differs from that layout, or a truncated file.
pub fn read_ply(path: &Path) -> Result<Mesh, OutputError> {
    let file = std::fs::File::open(path).map_err(|e| OutputError::io(path, e))?;
    let mut reader = BufReader::new(file);
    let bad = |m: &str| OutputError::format(path, format!("not a PLY file of this layout: {m}"));
    let mut lines = Vec::new();
    loop {
        let mut line = String::new();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| OutputError::io(path, e))?;
        if n == 0 {
            return Err(bad("no end_header"));
        }
        let line = line.trim_end().to_string();
        if line == "end_header" {
            break;
        }
        lines.push(line);
    }
    let expected_fixed = [
        "ply",
        "format binary_little_endian 1.0",
        "property float x",
        "property float y",
        "property float z",
        "property list uchar uint vertex_indices",
    ];
    let body: Vec<&str> = lines
        .iter()
        .map(String::as_str)
        .filter(|l| !l.starts_with("comment"))
        .collect();
    let count = |prefix: &str| -> Result<usize, OutputError> {
        body.iter()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|n| n.trim().parse().ok())
            .ok_or_else(|| bad(&format!("no `{prefix}N` line")))
    };
    let (nv, nf) = (count("element vertex ")?, count("element face ")?);
    if body.len() != expected_fixed.len() + 2 || !expected_fixed.iter().all(|l| body.contains(l)) {
        return Err(bad(&format!("unexpected header {body:?}")));
    }
    let mut data = Vec::new();
    reader
        .read_to_end(&mut data)
        .map_err(|e| OutputError::io(path, e))?;
    if data.len() != 12 * nv + 13 * nf {
        return Err(bad(&format!(
            "expected {} data bytes for {nv} vertices and {nf} faces, found {}",
            12 * nv + 13 * nf,
            data.len()
        )));
    }
    let word = |at: usize| [data[at], data[at + 1], data[at + 2], data[at + 3]];
    let vertices = (0..nv)
        .map(|v| [0, 1, 2].map(|d| f64::from(f32::from_le_bytes(word(12 * v + 4 * d)))))
        .collect();
    let base = 12 * nv;
    let mut triangles = Vec::with_capacity(nf);
    for f in 0..nf {
        let at = base + 13 * f;
        if data[at] != 3 {
            return Err(bad(&format!("face {f} has {} corners, not 3", data[at])));
        }
        let tri = [0, 1, 2].map(|d| u32::from_le_bytes(word(at + 1 + 4 * d)));
        if tri.iter().any(|&v| v as usize >= nv) {
            return Err(bad(&format!("face {f} refers to a vertex beyond {nv}")));
        }
        triangles.push(tri);
    }
    Ok(Mesh {
        vertices,
        triangles,
    })
}
