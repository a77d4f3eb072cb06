//! Pictures of a merged diagram: `diagram.png` (e against v: the reference branches as lines,
//! the extrapolated points filled, the finest resolution's raw points hollow, the reference
//! transitions between lowest-energy branches as dashed lines, crossings of metastable branches
//! dotted and lighter) and `thumbnails.png` (the cases' shape pictures side by side).

use super::reference::Reference;
use super::spec::{Couple, SliceAt, BRANCHES};
use crate::error::Result;
use crate::output::{ensure_font, write_rgb_png, OutputError, RgbImage, FONT_FAMILY};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Chart size in pixels.
const SIZE: (u32, u32) = (1000, 680);

/// Colour of each branch of [`BRANCHES`].
const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
];

/// A transition between two branches, as drawn.
#[derive(Clone, Debug)]
pub struct Transition {
    /// `a/b`.
    pub name: String,
    /// The reference volume (a dashed vertical line).
    pub reference: f64,
    /// Where the extrapolated phase-field branches cross, `(v, e)` (a black cross).
    pub crossing: Option<(f64, f64)>,
    /// Between the lowest-energy branches (a transition, dashed) or two metastable ones (a
    /// crossing, dotted and lighter).
    pub ground: bool,
}

/// Write the diagram chart of the slice `at`: `extrapolated` and `finest` are per branch of
/// [`BRANCHES`], `(v, e)` points (w with ADE); `transitions` the reference transitions and the phase-field crossings.
///
/// # Errors
/// `Error::Output` if drawing or writing fails.
pub fn write_chart(
    path: &Path,
    at: SliceAt,
    reference: &Reference,
    extrapolated: &[Vec<(f64, f64)>],
    finest: &[Vec<(f64, f64)>],
    transitions: &[Transition],
) -> Result<()> {
    ensure_font(path)?;
    let all = extrapolated.iter().chain(finest).flatten();
    let (mut v_lo, mut v_hi, mut e_lo, mut e_hi) =
        (1.0f64, 0.0f64, f64::INFINITY, f64::NEG_INFINITY);
    for &(v, e) in all {
        v_lo = v_lo.min(v);
        v_hi = v_hi.max(v);
        e_lo = e_lo.min(e);
        e_hi = e_hi.max(e);
    }
    let (v_lo, v_hi) = (v_lo - 0.02, (v_hi + 0.02).min(1.0));
    // From 0.95 (below the sphere's e = 1 at c0 = 0), lower where a point lies lower.
    let e_lo = 0.95f64.min(0.9 * e_lo);
    let e_range = e_lo..e_hi + 0.1 * (e_hi - e_lo);
    let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(
            &root,
            at,
            (v_lo..v_hi, e_range),
            reference,
            extrapolated,
            finest,
            transitions,
        )
        .and_then(|()| root.present())
        .map_err(|e| OutputError::format(path, format!("cannot draw chart: {e}")))?;
    }
    write_rgb_png(path, SIZE.0, SIZE.1, &rgb)?;
    Ok(())
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult = std::result::Result<
    (),
    DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>,
>;

fn draw(
    root: &Area,
    at: SliceAt,
    (vs, es): (std::ops::Range<f64>, std::ops::Range<f64>),
    reference: &Reference,
    extrapolated: &[Vec<(f64, f64)>],
    finest: &[Vec<(f64, f64)>],
    transitions: &[Transition],
) -> DrawResult {
    root.fill(&WHITE)?;
    let (caption, energy) = match at.couple {
        Some(Couple::Ade { .. }) => (
            format!(
                "ADE diagram at {}: phase field (L-BFGS) against the axisymmetric reference",
                at.describe()
            ),
            "reduced energy w = e + πα(Δa − Δa0)²",
        ),
        Some(Couple::Bc { .. }) => (
            format!(
                "Bilayer-couple diagram at {}: phase field (L-BFGS) against the axisymmetric \
                 reference",
                at.describe()
            ),
            "reduced bending energy e = ∮(2H − c0)² dA / 16π",
        ),
        None if at.c0 == 0.0 => (
            "Shape diagram at c0 = 0: phase field (L-BFGS) against the axisymmetric reference"
                .to_string(),
            "reduced bending energy e = ∮(2H)² dA / 16π",
        ),
        None => (
            format!(
                "Shape diagram at c0 R0 = {}: phase field (L-BFGS) against the axisymmetric \
                 reference",
                at.c0
            ),
            "reduced bending energy e = ∮(2H − c0)² dA / 16π",
        ),
    };
    let mut chart = ChartBuilder::on(root)
        .margin(20)
        .caption(caption, (FONT_FAMILY, 20))
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(vs.clone(), es.clone())?;
    chart
        .configure_mesh()
        .x_desc("reduced volume v")
        .y_desc(energy)
        .axis_desc_style((FONT_FAMILY, 18))
        .label_style((FONT_FAMILY, 14))
        .draw()?;
    for (i, b) in BRANCHES.iter().enumerate() {
        // A branch that does not exist at this c0 and has no points is left out of the legend.
        if reference.curve(*b).is_empty() && extrapolated[i].is_empty() {
            continue;
        }
        let colour = COLOURS[i];
        let line: Vec<(f64, f64)> = reference
            .curve(*b)
            .iter()
            .copied()
            .filter(|(v, _)| vs.contains(v))
            .collect();
        chart
            .draw_series(LineSeries::new(line, colour.stroke_width(2)))?
            .label(format!("{} (axisymmetric reference)", b.name()))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(
                extrapolated[i]
                    .iter()
                    .map(|&p| Circle::new(p, 5, colour.filled())),
            )?
            .label(format!("{}: phase field, extrapolated ε/R0 → 0", b.name()))
            .legend(move |(x, y)| Circle::new((x + 12, y), 5, colour.filled()));
        chart
            .draw_series(
                finest[i]
                    .iter()
                    .map(|&p| Circle::new(p, 7, colour.stroke_width(1))),
            )?
            .label(format!("{}: phase field, finest ε/R0 (raw)", b.name()))
            .legend(move |(x, y)| Circle::new((x + 12, y), 7, colour.stroke_width(1)));
    }
    for (k, t) in transitions.iter().enumerate() {
        let v = t.reference;
        if !v.is_finite() || !vs.contains(&v) {
            continue;
        }
        // A transition dashed in dark grey; a crossing of metastable branches dotted, lighter.
        let (grey, pieces, what) = if t.ground {
            (RGBColor(110, 110, 110), 40, "transition")
        } else {
            (RGBColor(165, 165, 165), 120, "metastable crossing")
        };
        let (lo, hi) = (es.start, es.end);
        let dashes: Vec<PathElement<(f64, f64)>> = (0..pieces)
            .filter(|i| i % 2 == 0)
            .map(|i| {
                let a = lo + (hi - lo) * i as f64 / pieces as f64;
                let b = lo + (hi - lo) * (i + 1) as f64 / pieces as f64;
                PathElement::new(vec![(v, a), (v, b)], grey.stroke_width(1))
            })
            .collect();
        chart.draw_series(dashes)?;
        let y = hi - (hi - lo) * (0.04 + 0.05 * k as f64);
        let found = t
            .crossing
            .map_or(String::new(), |(x, _)| format!(", phase field {x:.4}"));
        chart.draw_series(std::iter::once(Text::new(
            format!(" {} {what}: reference v = {v:.4}{found}", t.name),
            (v, y),
            (FONT_FAMILY, 14).into_font().color(&grey),
        )))?;
    }
    let crossings: Vec<(f64, f64)> = transitions.iter().filter_map(|t| t.crossing).collect();
    chart
        .draw_series(
            crossings
                .iter()
                .map(|&p| Cross::new(p, 7, BLACK.stroke_width(2))),
        )?
        .label("phase-field crossings of the extrapolated branches")
        .legend(|(x, y)| Cross::new((x + 12, y), 6, BLACK.stroke_width(2)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .label_font((FONT_FAMILY, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
}

/// Put the pictures `files` (PNG, RGB, equal sizes) side by side, `columns` per row, into
/// `path`.
///
/// # Errors
/// `Error::Output` if a picture cannot be read or the montage cannot be written.
pub fn write_montage(path: &Path, files: &[PathBuf], columns: usize) -> Result<()> {
    let pictures: Vec<RgbImage> = files
        .iter()
        .map(|f| read_png(f))
        .collect::<std::result::Result<_, _>>()?;
    let Some(first) = pictures.first() else {
        return Ok(());
    };
    let (w, h) = (first.width, first.height);
    let rows = pictures.len().div_ceil(columns);
    let cols = columns.min(pictures.len());
    let mut out = RgbImage::filled(cols * w, rows * h, [255, 255, 255]);
    for (k, p) in pictures.iter().enumerate() {
        let (x0, y0) = ((k % columns) * w, (k / columns) * h);
        for y in 0..h.min(p.height) {
            for x in 0..w.min(p.width) {
                let src = 3 * (y * p.width + x);
                let dst = 3 * ((y0 + y) * out.width + x0 + x);
                out.rgb[dst..dst + 3].copy_from_slice(&p.rgb[src..src + 3]);
            }
        }
    }
    out.write_png(path)?;
    Ok(())
}

/// Read an 8-bit RGB PNG.
fn read_png(path: &Path) -> std::result::Result<RgbImage, OutputError> {
    let bad = |m: String| OutputError::format(path, m);
    let file = std::fs::File::open(path).map_err(|e| OutputError::io(path, e))?;
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| bad(format!("cannot read PNG: {e}")))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| bad(format!("cannot read PNG: {e}")))?;
    if info.color_type != png::ColorType::Rgb || info.bit_depth != png::BitDepth::Eight {
        return Err(bad("expected an 8-bit RGB PNG".into()));
    }
    buf.truncate(info.buffer_size());
    Ok(RgbImage {
        width: info.width as usize,
        height: info.height as usize,
        rgb: buf,
    })
}
