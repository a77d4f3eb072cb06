//! Tests of the output writers: npy round trips and headers, byte-level VTI checks, and
//! decoded PNG pictures and charts.

use ndarray::Array3;
use std::path::{Path, PathBuf};
use tempfile::TempDir;
use vesicle::npy::read_npy;
use vesicle::output::chart::write_timeseries_png;
use vesicle::output::image::write_slices_png;
use vesicle::output::npy::write_npy;
use vesicle::output::vti::write_vti;
use vesicle::output::OutputError;

/// A field whose values are all distinct and not exactly representable in decimal.
fn distinct_field(shape: [usize; 3]) -> Array3<f64> {
    Array3::from_shape_fn(shape, |(i, j, k)| {
        (i as f64 * 100.0 + j as f64 * 10.0 + k as f64) / 7.0 - 3.3
    })
}

fn temp_file(dir: &TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

/// Bitwise comparison, so that e.g. -0.0 and 0.0 would be told apart.
fn assert_bitwise_eq(a: &Array3<f64>, b: &Array3<f64>) {
    assert_eq!(a.shape(), b.shape());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.to_bits(), y.to_bits());
    }
}

#[test]
fn npy_round_trip_2d() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "phi2.npy");
    let mut field = distinct_field([1, 5, 7]);
    field[[0, 0, 1]] = -0.0;
    field[[0, 4, 6]] = 1e-300;
    write_npy(&path, &field, 2).unwrap();
    let back = read_npy(&path, &[5, 7]).unwrap();
    assert_bitwise_eq(&field, &back);
}

#[test]
fn npy_round_trip_3d() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "phi3.npy");
    let field = distinct_field([3, 4, 5]);
    write_npy(&path, &field, 3).unwrap();
    let back = read_npy(&path, &[3, 4, 5]).unwrap();
    assert_bitwise_eq(&field, &back);
}

/// Split an npy v1.0 file into its header text and its data bytes.
fn npy_parts(bytes: &[u8]) -> (String, &[u8]) {
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    assert_eq!(&bytes[6..8], &[1, 0], "npy format version 1.0");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + len) % 64, 0, "header padded to a multiple of 64");
    let header = String::from_utf8(bytes[10..10 + len].to_vec()).unwrap();
    (header, &bytes[10 + len..])
}

#[test]
fn npy_header_is_c_order_float64_with_scene_shape() {
    let dir = TempDir::new().unwrap();
    for (shape, dim, text) in [([1, 5, 7], 2, "(5, 7)"), ([3, 4, 5], 3, "(3, 4, 5)")] {
        let path = temp_file(&dir, "h.npy");
        let field = distinct_field(shape);
        write_npy(&path, &field, dim).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let (header, data) = npy_parts(&bytes);
        let expected = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {text}");
        let rest = header.strip_prefix(&expected).expect(&header);
        let rest = rest.trim_end_matches([' ', '\n']);
        assert!(rest == "}" || rest == ", }", "header {header:?}");
        assert!(header.ends_with('\n'));
        assert_eq!(data.len(), field.len() * 8);
        let first = f64::from_le_bytes(data[..8].try_into().unwrap());
        let last = f64::from_le_bytes(data[data.len() - 8..].try_into().unwrap());
        assert_eq!(first, field[[0, 0, 0]]);
        assert_eq!(last, field[[shape[0] - 1, shape[1] - 1, shape[2] - 1]]);
    }
}

#[test]
fn read_npy_wrong_shape_names_both_shapes_and_file() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "shape.npy");
    write_npy(&path, &distinct_field([1, 5, 7]), 2).unwrap();
    let err = read_npy(&path, &[7, 5]).unwrap_err();
    assert!(matches!(err, OutputError::Shape { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("[7, 5]") && msg.contains("[5, 7]"), "{msg}");
    assert!(msg.contains("shape.npy"), "{msg}");
    let err = read_npy(&path, &[1, 5, 7]).unwrap_err();
    assert!(err.to_string().contains("[1, 5, 7]"), "{err}");
}

/// An npy version 1.0 file of `descr`, order and shape, its values all zero bytes, as NumPy
/// writes it: the header padded with spaces to 64 bytes and ended by a newline.
fn zero_npy(descr: &str, fortran: &str, shape: &str, data_len: usize) -> Vec<u8> {
    let mut dict =
        format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}");
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((dict.len() as u16).to_le_bytes());
    bytes.extend(dict.as_bytes());
    bytes.resize(bytes.len() + data_len, 0);
    bytes
}

#[test]
fn read_npy_rejects_other_dtype_and_fortran_order() {
    let dir = TempDir::new().unwrap();
    let f32_path = temp_file(&dir, "f32.npy");
    std::fs::write(&f32_path, zero_npy("<f4", "False", "(2, 3)", 24)).unwrap();
    let msg = read_npy(&f32_path, &[2, 3]).unwrap_err().to_string();
    assert!(msg.contains("<f4") && msg.contains("f32.npy"), "{msg}");

    let fortran_path = temp_file(&dir, "fortran.npy");
    std::fs::write(&fortran_path, zero_npy("<f8", "True", "(2, 3)", 48)).unwrap();
    let msg = read_npy(&fortran_path, &[2, 3]).unwrap_err().to_string();
    assert!(msg.contains("Fortran"), "{msg}");

    let good_path = temp_file(&dir, "good.npy");
    std::fs::write(&good_path, zero_npy("<f8", "False", "(2, 3)", 48)).unwrap();
    assert_eq!(read_npy(&good_path, &[2, 3]).unwrap().shape(), [1, 2, 3]);
}

/// The bytes NumPy 2.4 writes for `np.save(f, np.arange(6.0).reshape(2, 3))`: its header
/// (with the padding NumPy leaves for the first axis to grow) and the values 0 to 5.
#[test]
fn read_npy_reads_what_numpy_writes() {
    let mut bytes =
        b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"
            .to_vec();
    bytes.resize(127, b' ');
    bytes.push(b'\n');
    bytes.extend((0..6).flat_map(|i| f64::from(i).to_le_bytes()));
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "numpy.npy");
    std::fs::write(&path, &bytes).unwrap();
    let field = read_npy(&path, &[2, 3]).unwrap();
    assert_eq!(field, ndarray::array![[[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]]]);
}

#[test]
fn read_npy_missing_file_is_io_error_naming_it() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "absent.npy");
    let err = read_npy(&path, &[2, 2]).unwrap_err();
    assert!(matches!(err, OutputError::Io { .. }));
    assert!(err.to_string().contains("absent.npy"));
}

#[test]
fn writers_reject_a_2d_field_without_unit_leading_axis() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "bad.npy");
    let err = write_npy(&path, &distinct_field([2, 3, 3]), 2).unwrap_err();
    assert!(matches!(err, OutputError::Format(_)));
    assert!(err.to_string().contains("bad.npy"));
}

/// The fixed XML text preceding the appended data, and the binary block after `_`.
fn vti_parts(bytes: &[u8]) -> (String, &[u8]) {
    let marker = b"<AppendedData encoding=\"raw\">\n   _";
    let pos = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("appended data marker");
    let xml = String::from_utf8(bytes[..pos + marker.len()].to_vec()).unwrap();
    (xml, &bytes[pos + marker.len()..])
}

/// What follows the binary block.
const VTI_TAIL: &[u8] = b"\n  </AppendedData>\n</VTKFile>\n";

/// Check the binary block: UInt64 byte count, values in memory order, closing tags.
fn check_vti_block(block: &[u8], field: &Array3<f64>) {
    let nbytes = u64::from_le_bytes(block[..8].try_into().unwrap()) as usize;
    assert_eq!(nbytes, field.len() * 8);
    let data = &block[8..8 + nbytes];
    for (chunk, v) in data.chunks_exact(8).zip(field.iter()) {
        assert_eq!(
            f64::from_le_bytes(chunk.try_into().unwrap()).to_bits(),
            v.to_bits()
        );
    }
    assert_eq!(&block[8 + nbytes..], VTI_TAIL);
}

#[test]
fn vti_3d_header_and_binary_block() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "phi.vti");
    let field = distinct_field([2, 3, 4]);
    write_vti(&path, &field, 3, 0.5, "phi").unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let (xml, block) = vti_parts(&bytes);
    assert!(xml.starts_with("<?xml version=\"1.0\"?>\n<!-- written by vesicle "));
    assert!(
        xml.contains(env!("CARGO_PKG_VERSION")),
        "the program version is recorded"
    );
    assert!(xml.contains("-->\n<VTKFile type=\"ImageData\""));
    for needle in [
        "byte_order=\"LittleEndian\"",
        "header_type=\"UInt64\"",
        "<ImageData WholeExtent=\"0 3 0 2 0 1\" Origin=\"-0.75 -0.5 -0.25\" \
         Spacing=\"0.5 0.5 0.5\">",
        "<Piece Extent=\"0 3 0 2 0 1\">",
        "<PointData Scalars=\"phi\">",
        "<DataArray type=\"Float64\" Name=\"phi\" NumberOfComponents=\"1\" \
         format=\"appended\" offset=\"0\"/>",
    ] {
        assert!(xml.contains(needle), "missing {needle:?} in\n{xml}");
    }
    check_vti_block(block, &field);
    assert_eq!(
        bytes.len(),
        xml.len() + 8 + field.len() * 8 + VTI_TAIL.len()
    );
}

#[test]
fn vti_2d_has_one_z_layer_and_escaped_name() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "phi2.vti");
    let field = distinct_field([1, 4, 6]);
    write_vti(&path, &field, 2, 0.5, "a<b").unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let (xml, block) = vti_parts(&bytes);
    assert!(
        xml.contains("WholeExtent=\"0 5 0 3 0 0\" Origin=\"-1.25 -0.75 0\""),
        "{xml}"
    );
    assert!(xml.contains("Name=\"a&lt;b\""), "{xml}");
    check_vti_block(block, &field);
}

#[test]
fn vti_rejects_bad_spacing() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "h0.vti");
    let err = write_vti(&path, &distinct_field([2, 2, 2]), 3, 0.0, "phi").unwrap_err();
    assert!(err.to_string().contains("h0.vti"));
}

/// Decode an 8-bit RGB PNG into (width, height, pixels).
fn decode_rgb(path: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let px = buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width as usize, info.height as usize, px)
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Class {
    Red,
    Blue,
    Black,
}

/// Strongly red, strongly blue or black pixels; anything else is ignored.
fn classify([r, g, b]: [u8; 3]) -> Option<Class> {
    match (r, g, b) {
        (r, g, b) if r < 40 && g < 40 && b < 40 => Some(Class::Black),
        (r, g, b) if r > 150 && g < 90 && b < 90 => Some(Class::Red),
        (r, g, b) if b > 150 && r < 90 && g < 140 => Some(Class::Blue),
        _ => None,
    }
}

/// Classes met along a line of pixels, consecutive repeats merged.
fn class_runs(pixels: impl Iterator<Item = [u8; 3]>) -> Vec<Class> {
    let mut runs: Vec<Class> = Vec::new();
    for c in pixels.filter_map(classify) {
        if runs.last() != Some(&c) {
            runs.push(c);
        }
    }
    runs
}

/// A smooth vesicle-like field: +1 inside the ellipsoid with semi-axes `semi`, −1 outside.
fn ellipsoid_field(shape: [usize; 3], semi: [f64; 3]) -> Array3<f64> {
    let c = shape.map(|n| n as f64 / 2.0 - 0.5);
    Array3::from_shape_fn(shape, |(i, j, k)| {
        let p = [i as f64 - c[0], j as f64 - c[1], k as f64 - c[2]];
        let r = (0..3).map(|a| (p[a] / semi[a]).powi(2)).sum::<f64>().sqrt();
        ((1.0 - r) * semi[1] / 2.0).tanh()
    })
}

const PATTERN: [Class; 5] = [
    Class::Blue,
    Class::Black,
    Class::Red,
    Class::Black,
    Class::Blue,
];

#[test]
fn png_2d_circle_has_contour_red_inside_blue_outside() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "circle.png");
    let field = ellipsoid_field([1, 64, 64], [1.0, 20.0, 20.0]);
    write_slices_png(&path, &field, 2, "circle t = 0").unwrap();
    let (w, h, px) = decode_rgb(&path);
    assert!(w >= 400 && h >= 400, "{w}x{h}");
    // The single panel is centred horizontally: the middle column crosses the circle centre.
    let runs = class_runs((0..h).map(|y| px[y * w + w / 2]));
    assert!(runs.windows(5).any(|r| r == PATTERN), "{runs:?}");
    assert!(px.iter().any(|&p| classify(p) == Some(Class::Red)));
    assert!(px.iter().any(|&p| classify(p) == Some(Class::Blue)));
}

#[test]
fn png_3d_shows_three_labelled_mid_plane_slices() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "prolate.png");
    let field = ellipsoid_field([40, 40, 40], [15.0, 9.0, 9.0]);
    write_slices_png(&path, &field, 3, "prolate").unwrap();
    let (w, h, px) = decode_rgb(&path);
    assert!(w > 2 * h, "three panels side by side: {w}x{h}");
    // Some row crosses all three panels through their middles (white gaps are ignored, so
    // the blue outside of neighbouring panels merges).
    let expected = [&PATTERN[..4], &PATTERN[..4], &PATTERN[..]].concat();
    let hit = (0..h).any(|y| {
        let runs = class_runs((0..w).map(|x| px[y * w + x]));
        runs.windows(expected.len()).any(|r| r == expected)
    });
    assert!(hit, "no row crosses three red-inside/blue-outside slices");
}

/// A title too wide for the picture (a 2D frame's canvas is 640 pixels wide) is drawn smaller
/// or shortened: the ink of the title band (44 rows) keeps clear of both edges.
#[test]
fn png_title_too_wide_stays_inside_the_frame() {
    let dir = TempDir::new().unwrap();
    let path = temp_file(&dir, "long.png");
    let field = ellipsoid_field([1, 40, 40], [1.0, 12.0, 9.0]);
    let title = "ellipse2d   step 1000000   L = 123.4567   v = 0.9876   ".repeat(3);
    write_slices_png(&path, &field, 2, &title).unwrap();
    let (w, _, px) = decode_rgb(&path);
    let ink: Vec<usize> = (0..w)
        .filter(|&x| (0..44).any(|y| px[y * w + x] != [255, 255, 255]))
        .collect();
    let (first, last) = (ink[0], ink[ink.len() - 1]);
    assert!(
        first >= 4 && last + 4 < w,
        "title ink in {first}..={last} of {w}"
    );
    assert!(last - first > w * 3 / 4, "{first}..={last}");
}

#[test]
fn charts_decode_and_tolerate_bad_points() {
    let dir = TempDir::new().unwrap();
    let energy: Vec<(f64, f64)> = (0..50)
        .map(|i| (i as f64 * 0.1, 10.0 - i as f64 * 0.05))
        .collect();
    let residual: Vec<(f64, f64)> = (0..50)
        .map(|i| (i as f64 * 0.1, 10f64.powi(-i / 5)))
        .chain([
            (5.0, f64::NAN),
            (5.1, 0.0),
            (5.2, -1.0),
            (f64::INFINITY, 1.0),
        ])
        .collect();
    for (name, series, log_y) in [
        ("energy.png", vec![("E/E0", energy)], false),
        (
            "residual.png",
            vec![("residual", residual), ("empty", vec![])],
            true,
        ),
    ] {
        let path = temp_file(&dir, name);
        write_timeseries_png(&path, &series, "t", "value", log_y).unwrap();
        let (w, h, px) = decode_rgb(&path);
        assert!(w > 0 && h > 0);
        assert!(px.iter().any(|p| p != &[255, 255, 255]));
    }
}
