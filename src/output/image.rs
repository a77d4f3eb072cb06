//! PNG pictures of the phase field φ: a diverging colormap (blue φ = −1 outside, white φ = 0,
//! red φ = +1 inside) with the φ = 0 contour drawn in black, one panel for a 2D scene and the
//! three mid-plane slices side by side for a 3D scene.
//!
//! Each grid cell covers `s × s` pixels (the panel's longer side is about 600
//! pixels); colours are bilinearly interpolated between grid points and the contour comes from
//! marching squares with linear interpolation, drawn as anti-aliased segments.

use super::{check_field, ensure_font, fit_line, OutputError, RgbImage, FONT_FAMILY};
use ndarray::{Array2, Array3, ArrayView2, Axis};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Approximate length in pixels of the longer side of a panel.
const TARGET_SIDE: usize = 600;
/// Smallest number of pixels per grid cell.
const MIN_SCALE: usize = 2;
/// Blank border around and between panels, in pixels.
const MARGIN: usize = 20;
/// Height of the title band, in pixels.
const TITLE_HEIGHT: usize = 44;
/// Height of the band holding the panel labels, in pixels.
const LABEL_HEIGHT: usize = 30;
/// Height of the caption band under the panels, in pixels.
const CAPTION_HEIGHT: usize = 34;
/// Top pixel row of the panels.
const PANEL_TOP: usize = TITLE_HEIGHT + LABEL_HEIGHT;
/// Smallest canvas width, in pixels, so that the caption fits.
const MIN_WIDTH: usize = 640;
/// Width of the contour line, in pixels.
const LINE_WIDTH: f64 = 2.5;
/// Colour of φ = −1 (outside).
const BLUE: [f64; 3] = [33.0, 102.0, 172.0];
/// Colour of φ = +1 (inside).
const RED: [f64; 3] = [178.0, 24.0, 43.0];
/// Colour of φ = 0.
const WHITE: [f64; 3] = [255.0, 255.0, 255.0];

/// A 2D slice to draw: `values[[u, v]]` with `u` to the right and `v` upwards.
struct Panel {
    label: String,
    values: Array2<f64>,
}

/// An 8-bit RGB image, row-major, row 0 at the top.
struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

/// A line segment in pixel coordinates (pixel centres at half-integers).
type Segment = [(f64, f64); 2];

/// Write a PNG showing φ of a full-box `field` of a `dim`-dimensional scene: the whole field
/// in 2D, the three mid-plane slices (planes through the box centre normal to each axis) in
/// 3D, each labelled, under the heading `title`.
pub fn write_slices_png(
    path: &Path,
    field: &Array3<f64>,
    dim: usize,
    title: &str,
) -> Result<(), OutputError> {
    slices_image(path, field, dim, title)?.write_png(path)
}

/// The picture of [`write_slices_png`] as an RGB buffer; `path` names it in error messages.
/// Its size depends only on the shape of `field`, so the frames of one run match.
pub fn slices_image(
    path: &Path,
    field: &Array3<f64>,
    dim: usize,
    title: &str,
) -> Result<RgbImage, OutputError> {
    check_field(path, field, dim)?;
    ensure_font(path)?;
    let panels = panels(field, dim);
    let scale = scale_for(&panels);
    let lefts = panel_lefts(&panels, scale);
    let mut canvas = layout_canvas(&panels, scale);
    for (panel, &x0) in panels.iter().zip(&lefts) {
        canvas.blit(&render_panel(&panel.values, scale), x0, PANEL_TOP);
    }
    let labels = panels.iter().zip(&lefts).map(|(panel, &x0)| {
        let centre = x0 + panel.values.shape()[0] * scale / 2;
        (panel.label.as_str(), centre)
    });
    draw_texts(path, &mut canvas, title, labels, &caption(field))?;
    Ok(RgbImage {
        width: canvas.width,
        height: canvas.height,
        rgb: canvas.rgb,
    })
}

/// The panels of a 2D (one) or 3D (three mid-plane slices) scene.
fn panels(field: &Array3<f64>, dim: usize) -> Vec<Panel> {
    if dim == 2 {
        return vec![Panel {
            label: "x-y".to_string(),
            values: field.index_axis(Axis(0), 0).to_owned(),
        }];
    }
    [(2, "x-y (z=mid)"), (1, "x-z (y=mid)"), (0, "y-z (x=mid)")]
        .into_iter()
        .map(|(axis, label)| Panel {
            label: label.to_string(),
            values: mid_plane(field, axis),
        })
        .collect()
}

/// The slice through the box centre normal to `axis`: the middle plane for an odd length, the
/// mean of the two middle planes (the centre lies half-way between them) for an even length.
fn mid_plane(field: &Array3<f64>, axis: usize) -> Array2<f64> {
    let n = field.shape()[axis];
    let upper = field.index_axis(Axis(axis), n / 2);
    if n % 2 == 1 {
        return upper.to_owned();
    }
    let lower = field.index_axis(Axis(axis), n / 2 - 1);
    (&upper + &lower) * 0.5
}

/// Pixels per grid cell so that the longest panel side is about [`TARGET_SIDE`].
fn scale_for(panels: &[Panel]) -> usize {
    let longest = panels
        .iter()
        .flat_map(|p| p.values.shape().to_vec())
        .max()
        .unwrap_or(1);
    (TARGET_SIDE / longest).max(MIN_SCALE)
}

/// Total width of the panels side by side with [`MARGIN`] between them.
fn panels_width(panels: &[Panel], scale: usize) -> usize {
    let widths: usize = panels.iter().map(|p| p.values.shape()[0] * scale).sum();
    widths + MARGIN * panels.len().saturating_sub(1)
}

/// Canvas width: the panels with margins, at least [`MIN_WIDTH`] so the caption fits.
fn canvas_width(panels: &[Panel], scale: usize) -> usize {
    (panels_width(panels, scale) + 2 * MARGIN).max(MIN_WIDTH)
}

/// A white canvas large enough for the title, labels, panels side by side and caption.
fn layout_canvas(panels: &[Panel], scale: usize) -> Canvas {
    let width = canvas_width(panels, scale);
    let tallest = panels
        .iter()
        .map(|p| p.values.shape()[1])
        .max()
        .unwrap_or(1);
    Canvas::white(width, PANEL_TOP + tallest * scale + CAPTION_HEIGHT)
}

/// Left pixel column of each panel, the row of panels centred on the canvas.
fn panel_lefts(panels: &[Panel], scale: usize) -> Vec<usize> {
    let width = canvas_width(panels, scale);
    let mut x0 = (width - panels_width(panels, scale)) / 2;
    panels
        .iter()
        .map(|p| {
            let left = x0;
            x0 += p.values.shape()[0] * scale + MARGIN;
            left
        })
        .collect()
}

/// The coloured panel with its φ = 0 contour, `scale` pixels per cell.
fn render_panel(values: &Array2<f64>, scale: usize) -> Canvas {
    let (nu, nv) = (values.shape()[0], values.shape()[1]);
    let mut canvas = Canvas::white(nu * scale, nv * scale);
    let s = scale as f64;
    for py in 0..canvas.height {
        let v = (canvas.height as f64 - py as f64 - 0.5) / s - 0.5;
        for px in 0..canvas.width {
            let u = (px as f64 + 0.5) / s - 0.5;
            canvas.set(px, py, colormap(bilinear(values.view(), u, v)));
        }
    }
    let segments = contour_segments(values.view(), |(u, v)| {
        ((u + 0.5) * s, canvas.height as f64 - (v + 0.5) * s)
    });
    canvas.darken(&line_coverage(&segments, canvas.width, canvas.height));
    canvas
}

/// Bilinear interpolation of `values` at fractional indices `(u, v)`, clamped to the grid.
pub(crate) fn bilinear(values: ArrayView2<f64>, u: f64, v: f64) -> f64 {
    let (nu, nv) = (values.shape()[0], values.shape()[1]);
    let (i, fu) = split_index(u, nu);
    let (j, fv) = split_index(v, nv);
    let (i1, j1) = ((i + 1).min(nu - 1), (j + 1).min(nv - 1));
    let bottom = values[[i, j]] * (1.0 - fu) + values[[i1, j]] * fu;
    let top = values[[i, j1]] * (1.0 - fu) + values[[i1, j1]] * fu;
    bottom * (1.0 - fv) + top * fv
}

/// Integer part and fraction of a coordinate clamped to `[0, n − 1]`.
fn split_index(x: f64, n: usize) -> (usize, f64) {
    let x = x.clamp(0.0, (n - 1) as f64);
    let i = (x.floor() as usize).min(n.saturating_sub(2));
    (i, x - i as f64)
}

/// Diverging colour of φ: blue at −1, white at 0, red at +1 (clamped); grey if not finite.
fn colormap(phi: f64) -> [u8; 3] {
    if !phi.is_finite() {
        return [128, 128, 128];
    }
    let t = phi.clamp(-1.0, 1.0);
    let end = if t < 0.0 { BLUE } else { RED };
    let w = t.abs();
    [0, 1, 2].map(|c| (WHITE[c] * (1.0 - w) + end[c] * w).round() as u8)
}

/// Segments of the φ = 0 contour by marching squares with linear interpolation along cell
/// edges, mapped from index coordinates `(u, v)` to pixels by `to_pixel`. Saddle cells are
/// resolved with the mean of the four corners.
fn contour_segments(
    values: ArrayView2<f64>,
    to_pixel: impl Fn((f64, f64)) -> (f64, f64),
) -> Vec<Segment> {
    let (nu, nv) = (values.shape()[0], values.shape()[1]);
    let mut segments = Vec::new();
    for i in 0..nu.saturating_sub(1) {
        for j in 0..nv.saturating_sub(1) {
            let corners = [
                values[[i, j]],
                values[[i + 1, j]],
                values[[i + 1, j + 1]],
                values[[i, j + 1]],
            ];
            for [p, q] in cell_segments(corners) {
                let offset = |(a, b): (f64, f64)| to_pixel((i as f64 + a, j as f64 + b));
                segments.push([offset(p), offset(q)]);
            }
        }
    }
    segments
}

/// Contour segments inside one cell, in cell-local coordinates `[0, 1]²`. Corners are ordered
/// counter-clockwise from `(0, 0)`: `(0,0), (1,0), (1,1), (0,1)`.
fn cell_segments(f: [f64; 4]) -> Vec<Segment> {
    if f.iter().any(|v| !v.is_finite()) {
        return Vec::new();
    }
    const CORNERS: [(f64, f64); 4] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    // Crossing on edge k (from corner k to corner k+1), if the sign changes along it.
    let crossing = |k: usize| {
        let (a, b) = (f[k], f[(k + 1) % 4]);
        ((a > 0.0) != (b > 0.0)).then(|| {
            let t = a / (a - b);
            let (p, q) = (CORNERS[k], CORNERS[(k + 1) % 4]);
            (p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1))
        })
    };
    let edges: Vec<(usize, (f64, f64))> =
        (0..4).filter_map(|k| crossing(k).map(|p| (k, p))).collect();
    match edges.as_slice() {
        [(_, p), (_, q)] => vec![[*p, *q]],
        [e0, e1, e2, e3] => {
            let centre_like_first = (f.iter().sum::<f64>() > 0.0) == (f[0] > 0.0);
            if centre_like_first {
                // Corners 0 and 2 connect through the centre: cut off corners 1 and 3.
                vec![[e0.1, e1.1], [e2.1, e3.1]]
            } else {
                // Cut off corners 0 and 2.
                vec![[e3.1, e0.1], [e1.1, e2.1]]
            }
        }
        _ => Vec::new(),
    }
}

/// Anti-aliased coverage in `[0, 1]` of `width x height` pixels by the segments drawn
/// [`LINE_WIDTH`] pixels wide (maximum over segments, so joints are not darkened twice).
fn line_coverage(segments: &[Segment], width: usize, height: usize) -> Vec<f64> {
    let mut coverage = vec![0.0_f64; width * height];
    let reach = LINE_WIDTH / 2.0 + 1.0;
    for seg in segments {
        let [(x0, y0), (x1, y1)] = *seg;
        let px_range = pixel_range(x0.min(x1) - reach, x0.max(x1) + reach, width);
        let py_range = pixel_range(y0.min(y1) - reach, y0.max(y1) + reach, height);
        for py in py_range {
            for px in px_range.clone() {
                let d = distance_to_segment((px as f64 + 0.5, py as f64 + 0.5), seg);
                let c = (LINE_WIDTH / 2.0 + 0.5 - d).clamp(0.0, 1.0);
                let cell = &mut coverage[py * width + px];
                *cell = cell.max(c);
            }
        }
    }
    coverage
}

/// Pixel indices whose centres may lie in `[lo, hi]`, clipped to `0..n`.
fn pixel_range(lo: f64, hi: f64, n: usize) -> std::ops::Range<usize> {
    let start = lo.floor().max(0.0) as usize;
    let end = (hi.ceil().max(0.0) as usize).min(n);
    start.min(end)..end
}

/// Euclidean distance from point `p` to segment `seg`.
fn distance_to_segment(p: (f64, f64), seg: &Segment) -> f64 {
    let [(x0, y0), (x1, y1)] = *seg;
    let (dx, dy) = (x1 - x0, y1 - y0);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - x0) * dx + (p.1 - y0) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.0 - (x0 + t * dx)).hypot(p.1 - (y0 + t * dy))
}

/// Draw the title, the panel labels (text and centre column) and the caption; the title and
/// the caption are fitted to the width ([`fit_line`]).
fn draw_texts<'a>(
    path: &Path,
    canvas: &mut Canvas,
    title: &str,
    labels: impl Iterator<Item = (&'a str, usize)>,
    caption: &str,
) -> Result<(), OutputError> {
    let (width, height) = (canvas.width, canvas.height);
    let root = BitMapBackend::with_buffer(&mut canvas.rgb, (width as u32, height as u32))
        .into_drawing_area();
    let text_err = |e| OutputError::format(path, format!("cannot draw text: {e}"));
    let style = |size: u32| {
        TextStyle::from((FONT_FAMILY, size).into_font()).pos(Pos::new(HPos::Center, VPos::Center))
    };
    let at = |x: usize, y: usize| (x as i32, y as i32);
    let (title, size) = fit_line(path, title, 24, width)?;
    root.draw_text(&title, &style(size), at(width / 2, TITLE_HEIGHT / 2))
        .map_err(text_err)?;
    for (label, centre) in labels {
        let y = TITLE_HEIGHT + LABEL_HEIGHT / 2;
        root.draw_text(label, &style(18), at(centre, y))
            .map_err(text_err)?;
    }
    let y = height - CAPTION_HEIGHT / 2;
    let (caption, size) = fit_line(path, caption, 15, width)?;
    root.draw_text(&caption, &style(size), at(width / 2, y))
        .map_err(text_err)?;
    root.present().map_err(text_err)
}

/// The legend line: colour meaning, contour, and the range of φ.
fn caption(field: &Array3<f64>) -> String {
    let (lo, hi) = field
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    format!("blue: φ = −1 (outside)   red: φ = +1 (inside)   black: φ = 0   φ ∈ [{lo:.3}, {hi:.3}]")
}

impl Canvas {
    /// An all-white canvas.
    fn white(width: usize, height: usize) -> Self {
        Canvas {
            width,
            height,
            rgb: vec![255; width * height * 3],
        }
    }

    /// Set pixel `(x, y)` to `rgb`.
    fn set(&mut self, x: usize, y: usize, rgb: [u8; 3]) {
        let k = 3 * (y * self.width + x);
        self.rgb[k..k + 3].copy_from_slice(&rgb);
    }

    /// Blend every pixel towards black by its coverage.
    fn darken(&mut self, coverage: &[f64]) {
        for (px, &c) in self.rgb.chunks_exact_mut(3).zip(coverage) {
            for ch in px {
                *ch = (f64::from(*ch) * (1.0 - c)).round() as u8;
            }
        }
    }

    /// Copy `other` into this canvas with its top-left corner at `(x0, y0)`.
    fn blit(&mut self, other: &Canvas, x0: usize, y0: usize) {
        for y in 0..other.height {
            let src = &other.rgb[3 * y * other.width..3 * (y + 1) * other.width];
            let k = 3 * ((y0 + y) * self.width + x0);
            self.rgb[k..k + src.len()].copy_from_slice(src);
        }
    }
}
