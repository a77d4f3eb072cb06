//! Tests of the pictures of `vesicle render`: the φ = 0 mesh of a sphere against the exact
//! area and volume, closed and outward, the PLY round trip, shaded frames that show the shape
//! and tell shapes apart, animated GIFs, and the command end to end on a tiny run.

use ndarray::Array3;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;
use tempfile::TempDir;
use vesicle::analysis::surface::{extract, Mesh};
use vesicle::output::animation::write_gif;
use vesicle::output::ply::{read_ply, write_ply};
use vesicle::output::shade::{render, Bounds, View, BACKGROUND};
use vesicle::output::RgbImage;

/// The tanh profile of an ellipsoid with semi-axes `r` (physical units, spacing `h`) centred
/// in an `n` box: φ = tanh((1 − ρ) R̄ / √2), ρ the ellipsoidal radius, R̄ the mean semi-axis.
fn ellipsoid(n: [usize; 3], h: f64, r: [f64; 3]) -> Array3<f64> {
    let mean = (r[0] + r[1] + r[2]) / 3.0;
    Array3::from_shape_fn(n, |(i, j, k)| {
        let x = [i, j, k];
        let rho = (0..3)
            .map(|d| ((x[d] as f64 - (n[d] - 1) as f64 / 2.0) * h / r[d]).powi(2))
            .sum::<f64>()
            .sqrt();
        ((1.0 - rho) * mean / std::f64::consts::SQRT_2).tanh()
    })
}

fn sphere(n: usize, h: f64, r: f64) -> Array3<f64> {
    ellipsoid([n; 3], h, [r; 3])
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn sphere_mesh_area_volume_closed_outward() {
    let (h, r) = (1.0, 12.0);
    let mesh = extract(&sphere(40, h, r), h);
    let (area, volume) = (mesh.area(), mesh.enclosed_volume());
    let (ea, ev) = (
        rel(area, 4.0 * PI * r * r),
        rel(volume, 4.0 * PI * r.powi(3) / 3.0),
    );
    println!(
        "sphere R = 12h on 40³: {} vertices, {} triangles, area error {ea:.2e}, volume error {ev:.2e}",
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    assert!(ea < 0.01, "area {area} is {ea:.3e} off");
    assert!(ev < 0.01, "volume {volume} is {ev:.3e} off");
    assert!(volume > 0.0, "outward normals give a positive volume");
    // The same split as the sharp measures of `levelset` (written to summary.json).
    let ls = vesicle::analysis::levelset::measure(&sphere(40, h, r), 3, h);
    assert!(rel(area, ls.area) < 1e-12 && rel(volume, ls.volume) < 1e-10);
    assert!(mesh.is_closed());
    // Vertices are shared: a closed triangle mesh of genus 0 has V − E + F = 2, E = 3F/2.
    assert_eq!(
        2 * mesh.vertices.len() as i64 - mesh.triangles.len() as i64,
        4
    );
    // Outward, triangle by triangle: the normal points away from the centre.
    let c = 19.5 * h;
    for t in 0..mesh.triangles.len() {
        let n = mesh.face_normal(t);
        let p = mesh.corners(t)[0];
        let radial: f64 = (0..3).map(|d| n[d] * (p[d] - c)).sum();
        assert!(radial >= 0.0, "triangle {t} points inward");
    }
    // Physical coordinates, x along axis 0: a shifted, scaled sphere moves with them.
    let shifted = extract(
        &ellipsoid([40, 40, 40], 0.5, [6.0, 6.0, 6.0]).map(|v| *v),
        0.5,
    );
    let centre = shifted.centroid();
    for d in 0..3 {
        assert!((centre[d] - 9.75).abs() < 1e-6, "centroid {centre:?}");
    }
}

#[test]
fn open_and_flipped_meshes_are_told_apart() {
    let mesh = extract(&sphere(20, 1.0, 6.0), 1.0);
    assert!(mesh.is_closed());
    let mut open = mesh.clone();
    open.triangles.pop();
    assert!(!open.is_closed());
    let mut flipped = mesh.clone();
    flipped.triangles[0].swap(1, 2);
    assert!(!flipped.is_closed());
    let mut inverted = mesh.clone();
    for t in &mut inverted.triangles {
        t.swap(1, 2);
    }
    assert!(inverted.is_closed());
    assert!(inverted.enclosed_volume() < 0.0);
    // A 2D field (one plane) has no cells; a field without a sign change has no surface.
    assert!(extract(&Array3::zeros((1, 8, 8)), 1.0).triangles.is_empty());
    assert!(extract(&Array3::from_elem((8, 8, 8), -1.0), 1.0)
        .triangles
        .is_empty());
}

#[test]
fn ply_round_trip() {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("s.ply");
    let mesh = extract(&sphere(16, 0.5, 2.5), 0.5);
    write_ply(&path, &mesh, "sphere test").unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let end = b"end_header\n";
    let at = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("header end")
        + end.len();
    let header = std::str::from_utf8(&bytes[..at]).unwrap();
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    assert!(header.contains(&format!("element vertex {}\n", mesh.vertices.len())));
    assert!(header.contains(&format!("element face {}\n", mesh.triangles.len())));
    assert!(header.contains("property list uchar uint vertex_indices\n"));
    assert_eq!(
        bytes.len() - at,
        12 * mesh.vertices.len() + 13 * mesh.triangles.len()
    );
    let back = read_ply(&path).unwrap();
    assert_eq!(back.triangles, mesh.triangles);
    assert_eq!(back.vertices.len(), mesh.vertices.len());
    for (a, b) in back.vertices.iter().zip(&mesh.vertices) {
        for d in 0..3 {
            assert!((a[d] - b[d]).abs() <= 1e-6 * (1.0 + b[d].abs()));
        }
    }
    assert!(back.is_closed());
}

/// Pixels of the drawing area (below the title band) that differ from the background.
fn covered_fraction(image: &RgbImage) -> f64 {
    let top = 40;
    let mut n = 0;
    for y in top..image.height {
        for x in 0..image.width {
            n += usize::from(image.pixel(x, y) != BACKGROUND);
        }
    }
    n as f64 / (image.width * (image.height - top)) as f64
}

#[test]
fn rendered_frames_show_the_shape_and_tell_shapes_apart() {
    let (n, h) = (40, 1.0);
    let bounds = Bounds::of_grid([n; 3], h);
    let view = View::default();
    let sphere_mesh = extract(&sphere(n, h, 12.0), h);
    let t0 = std::time::Instant::now();
    let a = render(&sphere_mesh, &bounds, &view, "sphere").unwrap();
    println!(
        "render of 40³ sphere: {:.1} ms",
        t0.elapsed().as_secs_f64() * 1e3
    );
    assert_eq!((a.width, a.height), (640, 480));
    // The box outline (39 × 1.495 high on the screen at the default view) spans 0.96 × 444
    // pixels, so the sphere of radius 12 is a disc of radius 87.7 pixels: 8.6 % of the
    // drawing area; the box edges add about 1.5 %.
    let covered = covered_fraction(&a);
    assert!(
        (0.08..0.12).contains(&covered),
        "covered fraction {covered}"
    );
    // Shaded: many distinct colours, not a flat silhouette.
    let mut colours: Vec<[u8; 3]> = (0..a.height)
        .flat_map(|y| (0..a.width).map(move |x| (x, y)))
        .map(|(x, y)| a.pixel(x, y))
        .collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 50, "{} colours", colours.len());

    let ellipsoid_mesh = extract(&ellipsoid([n; 3], h, [16.0, 10.0, 9.0]), h);
    let b = render(&ellipsoid_mesh, &bounds, &view, "sphere").unwrap();
    let differing = a
        .rgb
        .chunks(3)
        .zip(b.rgb.chunks(3))
        .filter(|(p, q)| p != q)
        .count();
    assert!(
        differing > a.width * a.height / 50,
        "only {differing} pixels differ"
    );

    // A cut shows the inner side (blue) of the surface.
    let cut = View {
        cut: Some(0),
        ..view
    };
    let c = render(&sphere_mesh, &bounds, &cut, "cut").unwrap();
    let bluish = c
        .rgb
        .chunks(3)
        .filter(|p| p[2] > p[0] + 40 && p[2] > 80)
        .count();
    assert!(bluish > 1000, "{bluish} inner-side pixels");
    assert_ne!(a, c);
}

/// The columns `(first, last)` of the pixels in rows `rows` that differ from `background`.
fn ink_columns(
    image: &RgbImage,
    rows: std::ops::Range<usize>,
    background: [u8; 3],
) -> (usize, usize) {
    let cols: Vec<usize> = (0..image.width)
        .filter(|&x| rows.clone().any(|y| image.pixel(x, y) != background))
        .collect();
    (
        *cols.first().expect("some ink"),
        *cols.last().expect("some ink"),
    )
}

/// A title wider than the picture at its font size (the one of `deflation3d_180000.png`, cut
/// at both edges when drawn as is, and one far longer) stays inside the frame: the ink of the
/// title band keeps clear of both edges and still spans most of the width.
#[test]
fn long_titles_stay_inside_the_frame() {
    let (n, h) = (24, 1.0);
    let bounds = Bounds::of_grid([n; 3], h);
    let mesh = extract(&sphere(n, h, 7.0), h);
    let view = View::default();
    let deflation = "deflation3d   step 180000   A = 5244.77329   V = 25132.09399   v = 0.7037";
    let longer = deflation.repeat(3);
    for title in [deflation, longer.as_str()] {
        let image = render(&mesh, &bounds, &view, title).unwrap();
        let (first, last) = ink_columns(&image, 0..36, BACKGROUND);
        assert!(
            first >= 4 && last + 4 < image.width,
            "title ink in columns {first}..={last} of {}",
            image.width
        );
        assert!(last - first > image.width * 3 / 4, "{first}..={last}");
    }
    // A short title is drawn as asked, centred.
    let image = render(&mesh, &bounds, &view, "sphere").unwrap();
    let (first, last) = ink_columns(&image, 0..36, BACKGROUND);
    assert!(
        (first + last).abs_diff(image.width) <= 4,
        "{first}..={last}"
    );
}

#[test]
fn time_of_a_64_cubed_frame() {
    let (n, h) = (64, 1.0);
    let field = ellipsoid([n; 3], h, [26.0, 18.0, 14.0]);
    let t0 = std::time::Instant::now();
    let mesh = extract(&field, h);
    let t1 = std::time::Instant::now();
    let image = render(&mesh, &Bounds::of_grid([n; 3], h), &View::default(), "64³").unwrap();
    let t2 = std::time::Instant::now();
    println!(
        "64³ ellipsoid: {} triangles, extract {:.1} ms, render {:.1} ms",
        mesh.triangles.len(),
        (t1 - t0).as_secs_f64() * 1e3,
        (t2 - t1).as_secs_f64() * 1e3
    );
    assert!(mesh.is_closed());
    let covered = covered_fraction(&image);
    assert!((0.05..0.3).contains(&covered), "covered fraction {covered}");
}

#[test]
fn gif_has_header_and_frames() {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("m.gif");
    let frames: Vec<RgbImage> = (0..3u8)
        .map(|i| RgbImage::filled(32, 24, [80 * i, 200 - 50 * i, 30]))
        .collect();
    write_gif(&path, &frames, 20).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..6], b"GIF89a");
    assert_eq!(gif_frames(&path), 3);
    let mixed = [frames[0].clone(), RgbImage::filled(10, 10, [0; 3])];
    assert!(write_gif(&path, &mixed, 20).is_err());
    assert!(write_gif(&path, &[], 20).is_err());
}

/// Number of frames in a GIF file.
fn gif_frames(path: &Path) -> usize {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::fs::File::open(path).unwrap())
        .unwrap();
    let mut n = 0;
    while decoder.read_next_frame().unwrap().is_some() {
        n += 1;
    }
    n
}

fn vesicle(args: &[&str], cwd: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("vesicle runs")
}

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn files_in(dir: &Path, ext: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(ext))
        .collect();
    names.sort();
    names
}

#[test]
fn render_command_end_to_end() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("T");
    let out_s = out.to_str().unwrap();
    // Refused before anything exists.
    let missing = vesicle(&["render", out_s], &crate_dir());
    assert_eq!(missing.status.code(), Some(2), "{missing:?}");
    let run = vesicle(
        &[
            "run",
            "runs/sphere3d.json",
            "--out",
            out_s,
            "--set",
            "max_steps=4",
            "--set",
            "output.snapshot_every=2",
            "--set",
            "output.png=false",
            "--set",
            "output.vti=false",
        ],
        &crate_dir(),
    );
    assert!(run.status.success(), "{run:?}");
    let render = vesicle(&["render", out_s, "--gif", "--cut", "y"], &crate_dir());
    assert!(render.status.success(), "{render:?}");
    let frames = out.join("frames");
    // Snapshots of the initial state (step 0) and at steps 2 and 4; the final state is step 4
    // too.
    assert_eq!(
        files_in(&frames, ".png"),
        [
            "frame_00000000.png",
            "frame_00000002.png",
            "frame_00000004.png"
        ]
    );
    assert_eq!(
        files_in(&frames, ".ply"),
        [
            "surface_00000000.ply",
            "surface_00000002.ply",
            "surface_00000004.ply"
        ]
    );
    // The initial sphere of radius 10 as well.
    let first: Mesh = read_ply(&frames.join("surface_00000000.ply")).unwrap();
    assert!(rel(first.area(), 4.0 * PI * 100.0) < 0.02);
    let mesh: Mesh = read_ply(&frames.join("surface_00000004.ply")).unwrap();
    assert!(mesh.is_closed() && mesh.enclosed_volume() > 0.0);
    // The sphere of radius 10 (h = 1), from the mesh of the written field.
    assert!(rel(mesh.area(), 4.0 * PI * 100.0) < 0.02);
    let gif = std::fs::read(out.join("movie.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    assert_eq!(gif_frames(&out.join("movie.gif")), 3);
    // An existing frames/ is kept without --force, replaced with it.
    let again = vesicle(&["render", out_s], &crate_dir());
    assert_eq!(again.status.code(), Some(2), "{again:?}");
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    let forced = vesicle(&["render", out_s, "--force", "--every", "2"], &crate_dir());
    assert!(forced.status.success(), "{forced:?}");
    // Every 2nd snapshot (steps 0 and 4; the final state is step 4).
    assert_eq!(
        files_in(&frames, ".png"),
        ["frame_00000000.png", "frame_00000004.png"]
    );
    // A folder without snapshots is refused.
    std::fs::remove_dir_all(out.join("snapshots")).unwrap();
    std::fs::create_dir(out.join("snapshots")).unwrap();
    let none = vesicle(&["render", out_s, "--force"], &crate_dir());
    assert_eq!(none.status.code(), Some(2), "{none:?}");
}

#[test]
fn render_command_2d_gif() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("E");
    let out_s = out.to_str().unwrap();
    let run = vesicle(
        &[
            "run",
            "runs/ellipse2d.json",
            "--out",
            out_s,
            "--set",
            "max_steps=6",
            "--set",
            "output.snapshot_every=2",
            "--set",
            "output.png=false",
            "--set",
            "output.vti=false",
        ],
        &crate_dir(),
    );
    assert!(run.status.success(), "{run:?}");
    let render = vesicle(&["render", out_s, "--gif"], &crate_dir());
    assert!(render.status.success(), "{render:?}");
    let frames = out.join("frames");
    // Steps 0, 2, 4 and 6: the movie starts at the initial state.
    assert_eq!(files_in(&frames, ".png").len(), 4);
    assert!(files_in(&frames, ".ply").is_empty());
    assert_eq!(gif_frames(&out.join("movie.gif")), 4);
}

/// The refined φ = 0 measure (area on the band-limited interpolant at h/2, volume Richardson-
/// extrapolated from h and h/2) on the tanh profile of spheres (ε = h): the plain mesh's
/// reduced volume is 2.5e-3 – 3e-3 low at every R (volume deficit O((h/R)²) plus an area
/// excess that does not fall with R); the refined one is within 5e-4 at R = 12h and falls
/// at least 4× by R = 24h.
#[test]
fn refined_level_set_measures_spheres_accurately() {
    let mut errors = Vec::new();
    for r in [12.0, 18.0, 24.0] {
        let phi = sphere((2.0 * r + 16.0) as usize, 1.0, r);
        let plain = vesicle::analysis::levelset::measure(&phi, 3, 1.0);
        let refined = vesicle::analysis::levelset::measure_refined(&phi, 3, 1.0);
        let ev = (refined.reduced_volume - 1.0).abs();
        println!(
            "sphere R = {r}h: v − 1 plain {:.2e}, refined {:.2e}; refined area {:.2e}, volume {:.2e}",
            plain.reduced_volume - 1.0,
            refined.reduced_volume - 1.0,
            rel(refined.area, 4.0 * PI * r * r),
            rel(refined.volume, 4.0 * PI * r.powi(3) / 3.0)
        );
        assert!(1.0 - plain.reduced_volume > 2e-3, "the plain mesh's bias");
        errors.push(ev);
    }
    assert!(errors[0] < 5e-4, "R = 12h: {:.2e}", errors[0]);
    assert!(errors[2] < errors[0] / 4.0, "R = 24h: {:.2e}", errors[2]);
}
