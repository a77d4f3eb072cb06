//! Shaded pictures of a [`Mesh`]: an orthographic view from a fixed direction, Lambert
//! shading under one directional light plus ambient, hidden surfaces removed with a z-buffer,
//! and an optional cut-away half.
//!
//! The camera looks at the centre of a fixed box ([`Bounds`], normally the simulation box)
//! from azimuth α (about the z axis, from x towards y) and elevation β, i.e. from the
//! direction `t = (cos β cos α, cos β sin α, sin β)`; z points up in the picture. The scale
//! makes the sphere around the box fill the drawing area, so it depends on the box and the
//! picture size only: frames of one run drawn with the same box are directly comparable
//! (the shape is never re-centred or re-scaled).
//!
//! Triangles are rasterised with edge functions at `supersample²` samples per pixel, depths
//! and normals interpolated barycentrically (exact for an orthographic view), then averaged
//! down. Front faces (outer side of the membrane) are drawn in [`OUTER`], faces seen from
//! behind (the inner side, visible through a cut) in [`INNER`]. The box edges are drawn thin
//! with the depth test, the three from the origin in red (x), green (y) and blue (z).

use super::{OutputError, RgbImage};
use crate::analysis::surface::Mesh;
use std::path::Path;

/// Colour of the outer side of the surface.
pub const OUTER: [f64; 3] = [232.0, 150.0, 72.0];
/// Colour of the inner side of the surface (seen through a cut).
pub const INNER: [f64; 3] = [96.0, 150.0, 210.0];
/// Background colour.
pub const BACKGROUND: [u8; 3] = [255, 255, 255];
/// Ambient share of the brightness (the rest is Lambert).
const AMBIENT: f64 = 0.3;
/// Height of the title band at the top, in pixels.
const TITLE_BAND: usize = 36;
/// Fraction of the drawing area's width or height taken by the box's outline.
const FILL: f64 = 0.96;

/// The region the view is fitted to: the box `[lo, hi]` (physical units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
}

impl Bounds {
    /// The box spanned by the grid points of an `n` grid of spacing `h` in the coordinates of
    /// [`crate::analysis::surface::extract`]: `[0, (n − 1) h]` along each axis.
    pub fn of_grid(n: [usize; 3], h: f64) -> Self {
        Bounds {
            lo: [0.0; 3],
            hi: n.map(|m| m.saturating_sub(1) as f64 * h),
        }
    }

    /// The centre of the box.
    pub fn centre(&self) -> [f64; 3] {
        [0, 1, 2].map(|d| 0.5 * (self.lo[d] + self.hi[d]))
    }
}

/// How to draw: picture size, view direction, cut-away and anti-aliasing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Picture width in pixels (default 640).
    pub width: usize,
    /// Picture height in pixels, title band included (default 480).
    pub height: usize,
    /// Azimuth α in degrees, about z from the x axis towards y (default 35).
    pub azimuth_deg: f64,
    /// Elevation β in degrees above the x–y plane (default 25).
    pub elevation_deg: f64,
    /// Cut away the part of the surface on the viewer's side of the plane through the box
    /// centre normal to this axis (0, 1, 2 for x, y, z), so the inside shows.
    pub cut: Option<usize>,
    /// Samples per pixel along each direction (default 2).
    pub supersample: usize,
}

impl Default for View {
    fn default() -> Self {
        View {
            width: 640,
            height: 480,
            azimuth_deg: 35.0,
            elevation_deg: 25.0,
            cut: None,
            supersample: 2,
        }
    }
}

type P3 = [f64; 3];

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalised(a: P3) -> P3 {
    let n = dot(a, a).sqrt();
    a.map(|x| x / n)
}

/// The orthographic camera: screen axes `right`, `up`, towards the viewer `toward`, and the
/// map from world points to (pixel x, pixel y, depth) in the supersampled picture.
struct Camera {
    right: P3,
    up: P3,
    toward: P3,
    centre: P3,
    scale: f64,
    /// Pixel position of the box centre.
    origin: (f64, f64),
}

impl Camera {
    fn new(bounds: &Bounds, view: &View) -> Self {
        let (a, b) = (
            view.azimuth_deg.to_radians(),
            view.elevation_deg.to_radians(),
        );
        let toward = [b.cos() * a.cos(), b.cos() * a.sin(), b.sin()];
        let right = [-a.sin(), a.cos(), 0.0];
        let up = [-b.sin() * a.cos(), -b.sin() * a.sin(), b.cos()];
        let s = view.supersample.max(1) as f64;
        let (w, h) = (view.width as f64 * s, (view.height - TITLE_BAND) as f64 * s);
        // Extent of the box's outline on the screen axes (symmetric about the centre).
        let outline = |axis: P3| -> f64 {
            (0..3)
                .map(|d| (bounds.hi[d] - bounds.lo[d]) * axis[d].abs())
                .sum::<f64>()
                .max(f64::MIN_POSITIVE)
        };
        let scale = FILL * (w / outline(right)).min(h / outline(up));
        Camera {
            right,
            up,
            toward,
            centre: bounds.centre(),
            scale,
            origin: (0.5 * w, TITLE_BAND as f64 * s + 0.5 * h),
        }
    }

    /// Supersampled pixel coordinates (x right, y down) and depth (larger is nearer).
    fn project(&self, p: P3) -> [f64; 3] {
        let q = [0, 1, 2].map(|d| p[d] - self.centre[d]);
        [
            self.origin.0 + self.scale * dot(q, self.right),
            self.origin.1 - self.scale * dot(q, self.up),
            dot(q, self.toward),
        ]
    }
}

/// The supersampled colour and depth buffers.
struct Target {
    width: usize,
    height: usize,
    depth: Vec<f64>,
    colour: Vec<[f64; 3]>,
}

/// Draw `mesh` as seen by `view`, fitted to `bounds`, with `title` centred in the band at the
/// top (smaller, or shortened, where it would not fit the width).
///
/// # Errors
/// `OutputError::Format` if the view is unusable (a zero size, a picture not taller than the
/// title band) or the title cannot be drawn.
pub fn render(
    mesh: &Mesh,
    bounds: &Bounds,
    view: &View,
    title: &str,
) -> Result<RgbImage, OutputError> {
    let name = Path::new("shaded picture");
    if view.width == 0 || view.height <= TITLE_BAND || view.supersample == 0 {
        return Err(OutputError::format(
            name,
            format!(
                "need width ≥ 1, height > {TITLE_BAND} and supersample ≥ 1, got {}x{} and {}",
                view.width, view.height, view.supersample
            ),
        ));
    }
    let camera = Camera::new(bounds, view);
    let s = view.supersample;
    let mut target = Target {
        width: view.width * s,
        height: view.height * s,
        depth: vec![f64::NEG_INFINITY; view.width * view.height * s * s],
        colour: vec![BACKGROUND.map(f64::from); view.width * view.height * s * s],
    };
    let light = normalised(
        [0, 1, 2].map(|d| -0.4 * camera.right[d] + 0.6 * camera.up[d] + 0.7 * camera.toward[d]),
    );
    let normals = mesh.vertex_normals();
    let projected: Vec<[f64; 3]> = mesh.vertices.iter().map(|&p| camera.project(p)).collect();
    let cut = view.cut.map(|a| Cut::new(a, bounds, camera.toward));
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let removed = cut.map(|c| tri.map(|v| c.removed_by(mesh.vertices[v as usize])));
        if removed.is_some_and(|k| k.iter().all(|&d| d > 0.0)) {
            continue;
        }
        let front = dot(mesh.face_normal(t), camera.toward) >= 0.0;
        let corners = tri.map(|v| projected[v as usize]);
        let corner_normals = tri.map(|v| normals[v as usize]);
        let visible =
            |b: [f64; 3]| removed.is_none_or(|k| b[0] * k[0] + b[1] * k[1] + b[2] * k[2] <= 0.0);
        raster_triangle(&mut target, corners, visible, |b| {
            let mut n = [0, 1, 2].map(|d| (0..3).map(|k| b[k] * corner_normals[k][d]).sum());
            let (base, sign) = if front { (OUTER, 1.0) } else { (INNER, -1.0) };
            n = n.map(|x: f64| sign * x);
            let len = dot(n, n).sqrt();
            let lambert = if len > 0.0 {
                (dot(n, light) / len).max(0.0)
            } else {
                0.0
            };
            base.map(|c| c * (AMBIENT + (1.0 - AMBIENT) * lambert))
        });
    }
    draw_box(&mut target, &camera, bounds, s);
    let mut image = downsample(&target, s);
    image.draw_heading(name, title, 20, [0, 0, 0], TITLE_BAND / 2)?;
    Ok(image)
}

/// The cut-away: the plane through the box centre normal to `axis`; the half on the viewer's
/// side of it is not drawn.
#[derive(Clone, Copy, Debug)]
struct Cut {
    axis: usize,
    centre: f64,
    /// +1 if the viewer is on the upper side of the plane, −1 otherwise.
    side: f64,
}

impl Cut {
    fn new(axis: usize, bounds: &Bounds, toward: P3) -> Self {
        Cut {
            axis,
            centre: bounds.centre()[axis],
            side: if toward[axis] >= 0.0 { 1.0 } else { -1.0 },
        }
    }

    /// Signed distance of `p` from the plane, positive on the removed (viewer's) side; it is
    /// linear, so its barycentric interpolation decides each sample exactly.
    fn removed_by(&self, p: P3) -> f64 {
        (p[self.axis] - self.centre) * self.side
    }
}

/// Edge function: twice the signed area of (a, b, p) in the picture plane.
fn edge(a: [f64; 3], b: [f64; 3], p: (f64, f64)) -> f64 {
    (b[0] - a[0]) * (p.1 - a[1]) - (b[1] - a[1]) * (p.0 - a[0])
}

/// Fill the samples covered by the triangle with corners `c` (pixel x, y, depth) where
/// `visible(barycentric weights)` and it is nearer than what is there, colouring each with
/// `shade(barycentric weights)`.
fn raster_triangle(
    target: &mut Target,
    c: [[f64; 3]; 3],
    visible: impl Fn([f64; 3]) -> bool,
    shade: impl Fn([f64; 3]) -> [f64; 3],
) {
    let area = edge(c[0], c[1], (c[2][0], c[2][1]));
    if area.abs() < 1e-12 {
        return;
    }
    let (w, h) = (target.width as f64, target.height as f64);
    let lo = |d: usize, max: f64| {
        c.iter()
            .map(|p| p[d])
            .fold(f64::INFINITY, f64::min)
            .clamp(0.0, max)
    };
    let hi = |d: usize, max: f64| {
        c.iter()
            .map(|p| p[d])
            .fold(f64::NEG_INFINITY, f64::max)
            .clamp(0.0, max)
    };
    let (x0, x1) = (
        lo(0, w).floor() as usize,
        (hi(0, w).ceil() as usize).min(target.width),
    );
    let (y0, y1) = (
        lo(1, h).floor() as usize,
        (hi(1, h).ceil() as usize).min(target.height),
    );
    for py in y0..y1 {
        for px in x0..x1 {
            let p = (px as f64 + 0.5, py as f64 + 0.5);
            let b = [
                edge(c[1], c[2], p) / area,
                edge(c[2], c[0], p) / area,
                edge(c[0], c[1], p) / area,
            ];
            if b.iter().any(|&x| x < 0.0) || !visible(b) {
                continue;
            }
            let z = b[0] * c[0][2] + b[1] * c[1][2] + b[2] * c[2][2];
            let k = py * target.width + px;
            if z > target.depth[k] {
                target.depth[k] = z;
                target.colour[k] = shade(b);
            }
        }
    }
}

/// The twelve edges of the box, `thickness` samples wide, hidden where the surface is nearer;
/// the edges from the lower corner along x, y, z in red, green, blue, the others grey.
fn draw_box(target: &mut Target, camera: &Camera, bounds: &Bounds, thickness: usize) {
    let corner = |c: usize| {
        [0, 1, 2].map(|d| {
            if c >> d & 1 == 1 {
                bounds.hi[d]
            } else {
                bounds.lo[d]
            }
        })
    };
    for a in 0..8usize {
        for d in 0..3 {
            if a >> d & 1 == 1 {
                continue;
            }
            let colour = match (a, d) {
                (0, 0) => [200.0, 30.0, 30.0],
                (0, 1) => [30.0, 150.0, 30.0],
                (0, 2) => [30.0, 60.0, 200.0],
                _ => [150.0; 3],
            };
            let (p, q) = (
                camera.project(corner(a)),
                camera.project(corner(a | 1 << d)),
            );
            let steps = (q[0] - p[0]).abs().max((q[1] - p[1]).abs()).ceil().max(1.0) as usize;
            for i in 0..=steps {
                let f = i as f64 / steps as f64;
                let r = [0, 1, 2].map(|e| p[e] + f * (q[e] - p[e]));
                plot_square(target, r, thickness, colour);
            }
        }
    }
}

/// Colour a `size × size` square of samples centred on `r` (x, y, depth) where `r` is not
/// behind the surface.
fn plot_square(target: &mut Target, r: [f64; 3], size: usize, colour: [f64; 3]) {
    let half = size as f64 / 2.0;
    let (x0, y0) = ((r[0] - half).round(), (r[1] - half).round());
    for dy in 0..size {
        for dx in 0..size {
            let (x, y) = (x0 + dx as f64, y0 + dy as f64);
            if x < 0.0 || y < 0.0 || x >= target.width as f64 || y >= target.height as f64 {
                continue;
            }
            let k = y as usize * target.width + x as usize;
            // A small allowance so that edges lying on the surface stay visible.
            if r[2] >= target.depth[k] - 1e-9 * (1.0 + r[2].abs()) {
                target.colour[k] = colour;
            }
        }
    }
}

/// Average each `s × s` block of samples into one pixel.
fn downsample(target: &Target, s: usize) -> RgbImage {
    let (width, height) = (target.width / s, target.height / s);
    let mut image = RgbImage::filled(width, height, BACKGROUND);
    let norm = (s * s) as f64;
    for y in 0..height {
        for x in 0..width {
            let mut sum = [0.0; 3];
            for dy in 0..s {
                for dx in 0..s {
                    let c = target.colour[(y * s + dy) * target.width + x * s + dx];
                    sum = [sum[0] + c[0], sum[1] + c[1], sum[2] + c[2]];
                }
            }
            let k = 3 * (y * width + x);
            for (out, total) in image.rgb[k..k + 3].iter_mut().zip(sum) {
                *out = (total / norm).round().clamp(0.0, 255.0) as u8;
            }
        }
    }
    image
}
