//! `vesicle measure DIR [--axis z]`: the radius profile of a finished 3D run along an axis, and
//! what it says about necks (budding), pearls (a tube's dominant wavelength) and pears
//! (up–down asymmetry), for every saved state.
//!
//! The states are the full-box fields of [`crate::commands::run_folder`] (snapshots and the final
//! field), so a reduced (mirrored) box needs no special care here: its slices were unfolded
//! to whole discs before they were written. Per slice j normal to the axis (coordinate
//! z_j = j h):
//!
//! ```text
//! S_j   = area of {φ > 0} in the slice       (sub-cell: marching squares, [`inside_area`])
//! r_j   = √(S_j / π)                        (radius of the disc of that area)
//! ```
//!
//! From the profile r_j (see each function): the largest radius, the neck (the narrowest
//! slice between the two largest maxima), on the profile's body (the slices with r ≥ r_max/2:
//! the whole axis for a tube through a periodic box, the part between the tips of a capsule)
//! the dominant Fourier mode of r − r̄ with its wavelength λ = M h/k (M body slices) and the
//! equivalent tube radius R_tube = √(mean r²), the ratio λ/(2π R_tube) (the Rayleigh–Plateau
//! threshold of a cylinder is λ = 2πR) and the skewness of the volume along the axis (0 for a
//! shape with a mirror plane normal to the axis, nonzero for a pear). Per state also the area,
//! volume and reduced volume of the φ = 0 surface, with their drift over the run
//! ([`surface_drift`]), and the number of connected pieces of {φ > 0} (a chain or separate
//! spheres). Results go to `DIR/measure.csv` and the chart `DIR/neck.png` (neck and largest
//! radius against t).

use crate::analysis::components;
use crate::analysis::levelset::{self, LevelSet};
use crate::commands::run_folder::{self, RunInfo};
use crate::error::{Error, Result};
use crate::output::chart;
use ndarray::{Array3, ArrayView2, Axis};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A neck must be at least this fraction of the largest radius narrower than both maxima
/// around it, so that round-off ripples on a cylinder or a plateau do not count as necks.
pub const NECK_DEPTH: f64 = 0.02;

/// The measures of one state.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeMeasure {
    /// Step of the state.
    pub step: usize,
    /// Time of the state.
    pub t: f64,
    /// Largest slice radius max_j r_j.
    pub r_max: f64,
    /// Neck radius and its coordinate (see [`neck`]); `None` when there is no neck.
    pub neck: Option<(f64, f64)>,
    /// The dominant mode (see [`dominant_mode`]).
    pub mode: Mode,
    /// Equivalent tube radius of the profile's body (see [`measure_field`]).
    pub r_tube: f64,
    /// Volume skewness along the axis (see [`skewness`]).
    pub skewness: f64,
    /// Area, enclosed volume and reduced volume of the φ = 0 surface
    /// ([`levelset::measure_refined`]).
    pub surface: LevelSet,
    /// Connected pieces of {φ > 0} ([`components::count`]): 1 for a connected chain or a bud on
    /// its neck, more once pieces have separated at the grid's resolution.
    pub pieces: usize,
    /// Δa = ∮2H dA / (8πR0) of the φ = 0 surface ([`levelset::measure_surface`]): the area
    /// difference of ADE; NaN for an open surface.
    pub surface_da: f64,
}

/// The dominant Fourier mode of a radius profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mode {
    /// Mode number k ≥ 1 (0 for a constant profile).
    pub k: usize,
    /// Wavelength L/k (infinite for k = 0).
    pub wavelength: f64,
    /// Amplitude of r's k-th cosine/sine component, (2/n)|Σ_j (r_j − r̄) e^{−2πi jk/n}|.
    pub amplitude: f64,
}

/// The slice radii along internal axis `axis` of a full-box 3D field: r_j = √(S_j/π), S_j
/// the area of {φ > 0} in slice j (see [`inside_area`]).
pub fn radius_profile(phi: &Array3<f64>, axis: usize, h: f64) -> Vec<f64> {
    phi.axis_iter(Axis(axis))
        .map(|slice| (inside_area(slice, h) / PI).sqrt())
        .collect()
}

/// The area of {φ > 0} in a 2D slice of spacing h, to sub-cell accuracy: in each cell (four
/// neighbouring nodes) the region is the polygon through the corners with φ > 0 and the
/// points where φ crosses 0 on the edges (linear interpolation, as marching squares), and
///
/// ```text
/// S = Σ_cells ½ |Σ_v (x_v y_{v+1} − x_{v+1} y_v)|        (shoelace formula, in units of h²)
/// ```
///
/// The error is O(h²) in the curvature of the contour. Cells across the slice's outer edges
/// are not counted (a shape keeps outside bulk there).
pub fn inside_area(slice: ArrayView2<f64>, h: f64) -> f64 {
    cells(slice)
        .map(|corners| cell_inside_area(&corners))
        .sum::<f64>()
        * h
        * h
}

/// The cells of a 2D slice (four neighbouring nodes each), as their corners in order around
/// the cell with φ: (position in the unit cell, φ). Cells across the slice's outer edges are
/// left out.
fn cells(slice: ArrayView2<'_, f64>) -> impl Iterator<Item = [([f64; 2], f64); 4]> + '_ {
    let (n0, n1) = slice.dim();
    (0..n0.saturating_sub(1)).flat_map(move |i| {
        (0..n1.saturating_sub(1)).map(move |j| {
            [
                ([0.0, 0.0], slice[[i, j]]),
                ([1.0, 0.0], slice[[i + 1, j]]),
                ([1.0, 1.0], slice[[i + 1, j + 1]]),
                ([0.0, 1.0], slice[[i, j + 1]]),
            ]
        })
    })
}

/// The area (unit cell) of the polygon of a cell's corners with φ > 0 and its edges' zero
/// crossings, corners given in order around the cell as (position, φ).
fn cell_inside_area(corners: &[([f64; 2], f64); 4]) -> f64 {
    if corners.iter().all(|c| c.1 > 0.0) {
        return 1.0;
    }
    if corners.iter().all(|c| c.1 <= 0.0) {
        return 0.0;
    }
    let mut poly: Vec<[f64; 2]> = Vec::with_capacity(8);
    for (k, &(p, a)) in corners.iter().enumerate() {
        let (q, b) = corners[(k + 1) % 4];
        if a > 0.0 {
            poly.push(p);
        }
        if (a > 0.0) != (b > 0.0) {
            let s = a / (a - b);
            poly.push([p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])]);
        }
    }
    let twice: f64 = (0..poly.len())
        .map(|k| {
            let (u, v) = (poly[k], poly[(k + 1) % poly.len()]);
            u[0] * v[1] - v[0] * u[1]
        })
        .sum();
    twice.abs() / 2.0
}

/// The length of the φ = 0 contour in a 2D slice of spacing h: in each cell the segments
/// between its edges' zero crossings (linear interpolation, as [`inside_area`]; a cell with
/// four crossings joins them in order around the cell), summed. Its error is O(h²) in the
/// contour's curvature; cells across the slice's outer edges are not counted.
pub fn contour_length(slice: ArrayView2<f64>, h: f64) -> f64 {
    let length: f64 = cells(slice)
        .map(|corners| {
            let mut crossings: Vec<[f64; 2]> = Vec::with_capacity(4);
            for (k, &(p, a)) in corners.iter().enumerate() {
                let (q, b) = corners[(k + 1) % 4];
                if (a > 0.0) != (b > 0.0) {
                    let s = a / (a - b);
                    crossings.push([p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])]);
                }
            }
            crossings
                .chunks_exact(2)
                .map(|c| (c[0][0] - c[1][0]).hypot(c[0][1] - c[1][1]))
                .sum::<f64>()
        })
        .sum();
    length * h
}

/// Indices of the local maxima of `r` taken as a periodic sequence: r_i > r_{i−1} and
/// r_i ≥ r_{i+1} (a flat top counts once, at its first point), in index order.
pub fn local_maxima(r: &[f64]) -> Vec<usize> {
    let n = r.len();
    (0..n)
        .filter(|&i| {
            let (prev, next) = (r[(i + n - 1) % n], r[(i + 1) % n]);
            r[i] > prev && r[i] >= next
        })
        .collect()
}

/// The neck: with i < j the indices of the two largest local maxima of the profile, the
/// smallest r_m over i ≤ m ≤ j (the stretch between them that does not cross the box's end,
/// so for a closed vesicle the stretch inside it), returned as (r_m, m h). `None` when there
/// are fewer than two maxima or when r_m is not below both maxima by [`NECK_DEPTH`] · max r.
pub fn neck(r: &[f64], h: f64) -> Option<(f64, f64)> {
    let mut maxima = local_maxima(r);
    maxima.sort_by(|&a, &b| r[b].total_cmp(&r[a]));
    let (&a, &b) = (maxima.first()?, maxima.get(1)?);
    let (i, j) = (a.min(b), a.max(b));
    let m = (i..=j).min_by(|&p, &q| r[p].total_cmp(&r[q]))?;
    let r_max = r.iter().cloned().fold(0.0, f64::max);
    (r[m] < r[i].min(r[j]) - NECK_DEPTH * r_max).then_some((r[m], m as f64 * h))
}

/// The dominant nonzero mode of r − r̄ over n slices taken as periodic, L = n h:
/// R_k = Σ_j (r_j − r̄) e^{−2πi jk/n} for 1 ≤ k ≤ n/2 (direct sum), k* = argmax |R_k|,
/// λ = L/k*, amplitude (2/n)|R_k*| (halved at the Nyquist mode k = n/2, whose e^{iπj} is real).
/// A constant profile gives k = 0, λ = ∞, amplitude 0.
pub fn dominant_mode(r: &[f64], h: f64) -> Mode {
    let n = r.len();
    let mean = r.iter().sum::<f64>() / n as f64;
    let best = (1..=n / 2)
        .map(|k| {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, &rj) in r.iter().enumerate() {
                let angle = 2.0 * PI * ((j * k) % n) as f64 / n as f64;
                re += (rj - mean) * angle.cos();
                im -= (rj - mean) * angle.sin();
            }
            let scale = if 2 * k == n { 1.0 } else { 2.0 } / n as f64;
            (k, scale * re.hypot(im))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1));
    match best {
        Some((k, amplitude)) if amplitude > 1e-12 * mean.abs().max(1.0) => Mode {
            k,
            wavelength: n as f64 * h / k as f64,
            amplitude,
        },
        _ => Mode {
            k: 0,
            wavelength: f64::INFINITY,
            amplitude: 0.0,
        },
    }
}

/// The skewness of the volume distribution S_j = π r_j² along the axis:
/// z̄ = Σ S_j z_j / Σ S_j, s² = Σ S_j (z_j − z̄)² / Σ S_j, skewness = Σ S_j (z_j − z̄)³ / (s³ Σ S_j).
/// Zero for a profile with a mirror plane; positive when the wider part sits at lower z (the
/// tail points to +z), negative the other way. Meant for a closed shape inside the box.
pub fn skewness(r: &[f64], h: f64) -> f64 {
    let w: Vec<f64> = r.iter().map(|x| PI * x * x).collect();
    let total: f64 = w.iter().sum();
    let z = |j: usize| j as f64 * h;
    let mean = w.iter().enumerate().map(|(j, s)| s * z(j)).sum::<f64>() / total;
    let moment = |p: i32| {
        w.iter()
            .enumerate()
            .map(|(j, s)| s * (z(j) - mean).powi(p))
            .sum::<f64>()
            / total
    };
    moment(3) / moment(2).powf(1.5)
}

/// The body of a profile: the stretch of slices from the first to the last with
/// r_j ≥ r_max/2 (the whole axis for a tube running through a periodic box; between the
/// tips for a closed shape such as a capsule), as a range of indices.
pub fn body(r: &[f64]) -> std::ops::Range<usize> {
    let r_max = r.iter().cloned().fold(0.0, f64::max);
    let wide = |x: &f64| *x >= r_max / 2.0;
    match (r.iter().position(wide), r.iter().rposition(wide)) {
        (Some(a), Some(b)) => a..b + 1,
        _ => 0..0,
    }
}

/// All measures of one full-box field: the profile along internal axis `axis`, then
/// [`neck`] and [`skewness`] of the whole profile, and on its [`body`] (M slices) the
/// [`dominant_mode`] and the equivalent tube radius R_tube = √(Σ_body r_j² / M) (the radius
/// of the cylinder with the body's volume and length; √(V/(πL)) for a tube through the box).
pub fn measure_field(phi: &Array3<f64>, axis: usize, h: f64, step: usize, t: f64) -> ShapeMeasure {
    let r = radius_profile(phi, axis, h);
    let body = &r[body(&r)];
    let r_tube = (body.iter().map(|x| x * x).sum::<f64>() / body.len().max(1) as f64).sqrt();
    let surface = levelset::measure_surface(phi, h);
    ShapeMeasure {
        step,
        t,
        r_max: r.iter().cloned().fold(0.0, f64::max),
        neck: neck(&r, h),
        mode: dominant_mode(body, h),
        r_tube,
        skewness: skewness(&r, h),
        surface: surface.level,
        pieces: components::count(phi),
        surface_da: surface.area_difference,
    }
}

/// The largest relative departure of the φ = 0 area and volume from the first state's over
/// all states, `max_i |X_i − X_0| / X_0` for X = A₀ and V₀: the drift of the constrained
/// quantities as the sharp surface sees them (the diffuse A and V are held to round-off; the
/// φ = 0 ones move when the profile across the interface changes, e.g. when a feature
/// approaches the interface width).
pub fn surface_drift(rows: &[ShapeMeasure]) -> Option<(f64, f64)> {
    let first = rows.first()?.surface;
    let worst = |of: fn(&LevelSet) -> f64| {
        rows.iter()
            .map(|m| ((of(&m.surface) - of(&first)) / of(&first)).abs())
            .fold(0.0, f64::max)
    };
    Some((worst(|s| s.area), worst(|s| s.volume)))
}

/// What `vesicle measure` reads and writes.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasureOptions {
    /// Axis of the profile, by name (`x`, `y` or `z`).
    pub axis: String,
    /// Replace an existing `DIR/measure.csv` and `DIR/neck.png`.
    pub force: bool,
}

/// What was measured and written.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// One row per state, in step order.
    pub rows: Vec<ShapeMeasure>,
    /// The CSV file.
    pub csv: PathBuf,
    /// The chart of neck and largest radius against t.
    pub chart: PathBuf,
}

/// Measure every saved state of the 3D run in `dir` along `opts.axis` and write
/// `DIR/measure.csv` and `DIR/neck.png`.
///
/// # Errors
/// `Error::Config` (exit code 2) naming `DIR` for a missing folder, summary or snapshots, or a
/// 2D run; `--axis` for a name other than x, y, z; `--force` when the outputs exist;
/// `Error::Io`/`Error::Output` when reading or writing fails.
pub fn measure(dir: &Path, opts: &MeasureOptions) -> Result<Measured> {
    run_folder::check_dir(dir)?;
    let axis = crate::commands::render::axis_index(&opts.axis)
        .map_err(|_| Error::config("--axis", format!("expected x, y or z, got `{}`", opts.axis)))?;
    let info = run_folder::run_info(dir)?;
    if info.dim != 3 {
        return Err(Error::config(
            "DIR",
            format!(
                "{} holds a {}D run; `measure` takes slices of 3D runs",
                dir.display(),
                info.dim
            ),
        ));
    }
    let csv = dir.join("measure.csv");
    let chart_path = dir.join("neck.png");
    for path in [&csv, &chart_path] {
        if path.exists() && !opts.force {
            return Err(Error::config(
                "--force",
                format!(
                    "{} already exists; results are never overwritten silently (pass --force \
                     to replace them)",
                    path.display()
                ),
            ));
        }
    }
    let times = step_times(dir)?;
    let states = run_folder::states(dir, &info, 1)?;
    let mut rows = Vec::with_capacity(states.len());
    for state in &states {
        let phi = crate::npy::read_npy(&state.path, &info.n)?;
        let t = time_of(state.step, &times, &info);
        rows.push(measure_field(&phi, axis, info.h, state.step, t));
    }
    write_file(&csv, &csv_text(&rows))?;
    write_chart(&chart_path, &rows)?;
    Ok(Measured {
        rows,
        csv,
        chart: chart_path,
    })
}

/// `(step, t)` pairs of `DIR/timeseries.csv`, in file order.
fn step_times(dir: &Path) -> Result<Vec<(usize, f64)>> {
    let (path, text) = run_folder::read_file(dir, "timeseries.csv")?;
    let bad = || Error::config("DIR", format!("{}: no `step,t,…` rows", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or_else(bad)?.split(',').collect();
    if header.first() != Some(&"step") || header.get(1) != Some(&"t") {
        return Err(bad());
    }
    Ok(lines
        .filter_map(|line| {
            let mut cells = line.split(',');
            let step = cells.next()?.parse().ok()?;
            let t = cells.next()?.parse().ok()?;
            Some((step, t))
        })
        .collect())
}

/// The time of `step`: the recorded row's t, else linear interpolation in step between the
/// rows around it (rows are written every `record_every` steps, snapshots every
/// `snapshot_every`), else the summary's final t for the final step; NaN if none applies.
fn time_of(step: usize, rows: &[(usize, f64)], info: &RunInfo) -> f64 {
    if let Some(&(_, t)) = rows.iter().find(|(s, _)| *s == step) {
        return t;
    }
    let before = rows
        .iter()
        .filter(|(s, _)| *s < step)
        .max_by_key(|(s, _)| *s);
    let after = rows
        .iter()
        .filter(|(s, _)| *s > step)
        .min_by_key(|(s, _)| *s);
    match (before, after) {
        (Some(&(s0, t0)), Some(&(s1, t1))) => {
            t0 + (t1 - t0) * (step - s0) as f64 / (s1 - s0) as f64
        }
        _ if info.final_step == Some(step) => info.final_t.unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

/// The CSV header of `measure.csv`.
pub const CSV_HEADER: &str = "step,t,r_max,r_neck,z_neck,mode,wavelength,amplitude,r_tube,\
                              wavelength_over_2pi_r_tube,skewness,surface_area,surface_volume,\
                              surface_reduced_volume,pieces,surface_da";

/// The rows as CSV (an absent neck is written `NaN`).
fn csv_text(rows: &[ShapeMeasure]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    for m in rows {
        let (r_neck, z_neck) = m.neck.unwrap_or((f64::NAN, f64::NAN));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            m.step,
            m.t,
            m.r_max,
            r_neck,
            z_neck,
            m.mode.k,
            m.mode.wavelength,
            m.mode.amplitude,
            m.r_tube,
            m.mode.wavelength / (2.0 * PI * m.r_tube),
            m.skewness,
            m.surface.area,
            m.surface.volume,
            m.surface.reduced_volume,
            m.pieces,
            m.surface_da
        );
    }
    s
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Neck radius and largest radius against t.
fn write_chart(path: &Path, rows: &[ShapeMeasure]) -> Result<()> {
    let neck: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|m| m.neck.map(|(r, _)| (m.t, r)))
        .collect();
    let max: Vec<(f64, f64)> = rows.iter().map(|m| (m.t, m.r_max)).collect();
    chart::write_timeseries_png(
        path,
        &[("neck radius", neck), ("largest radius", max)],
        "t",
        "radius",
        false,
    )?;
    Ok(())
}

/// A short table of the rows for the terminal (at most `limit` rows, evenly spread, the last
/// one always).
pub fn table(rows: &[ShapeMeasure], limit: usize) -> String {
    let mut s = String::from(
        "    step          t    r_max   r_neck   mode  wavelength  λ/2πR_tube  skewness      A(φ=0)      V(φ=0)  v(φ=0)  pieces  Δa(φ=0)\n",
    );
    let stride = rows.len().div_ceil(limit.max(1)).max(1);
    let last = rows.len().saturating_sub(1);
    for (i, m) in rows.iter().enumerate() {
        if i % stride != 0 && i != last {
            continue;
        }
        let neck = m
            .neck
            .map_or("       -".to_string(), |(r, _)| format!("{r:8.3}"));
        let _ = writeln!(
            s,
            "{:8} {:10.4e} {:8.3} {neck} {:6} {:11.3} {:11.3} {:9.4} {:11.2} {:11.2} {:7.4} {:7} {:8.4}",
            m.step,
            m.t,
            m.r_max,
            m.mode.k,
            m.mode.wavelength,
            m.mode.wavelength / (2.0 * PI * m.r_tube),
            m.skewness,
            m.surface.area,
            m.surface.volume,
            m.surface.reduced_volume,
            m.pieces,
            m.surface_da
        );
    }
    if let Some((area, volume)) = surface_drift(rows) {
        let _ = writeln!(
            s,
            "φ = 0 surface over the run: area drift {:.2}%, volume drift {:.2}% (largest \
             departure from the first state)",
            100.0 * area,
            100.0 * volume
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circle of radius 10h sampled as φ = tanh((R − r)/1.5h): the contour's length is 2πR
    /// to 1e-3 and the inside area πR² to 3e-3 (second order in h/R: chords of length s ≈ h
    /// cut the area by about s²/(6R²) = 1.7e-3 of it, the length by a quarter of that), so
    /// 4πS/P² reads 1 to 2e-3. A missing segment or a crossing on the wrong edge is O(h/R).
    #[test]
    fn the_contour_of_a_circle_has_its_length() {
        let (n, h, r) = (40, 1.0, 10.0);
        let slice = ndarray::Array2::from_shape_fn((n, n), |(i, j)| {
            let (x, y) = (i as f64 - 19.3, j as f64 - 20.1);
            ((r - x.hypot(y)) / 1.5).tanh()
        });
        let p = contour_length(slice.view(), h);
        let a = inside_area(slice.view(), h);
        assert!((p / (2.0 * PI * r) - 1.0).abs() < 1e-3, "{p}");
        assert!((a / (PI * r * r) - 1.0).abs() < 3e-3, "{a}");
        assert!((4.0 * PI * a / (p * p) - 1.0).abs() < 2e-3);
    }
}
