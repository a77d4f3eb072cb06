//! Line charts of time series (e.g. reduced energy or residual against time) as PNG files.

use super::{ensure_font, write_rgb_png, OutputError, FONT_FAMILY};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;

/// Chart size in pixels.
const SIZE: (u32, u32) = (900, 560);
/// Relative padding added to the data range on a linear axis.
const PAD: f64 = 0.05;

/// A named series of `(x, y)` points.
type Series<'a> = (&'a str, Vec<(f64, f64)>);

/// Write a line chart of `series` (each a name and its `(x, y)` points) with axis labels
/// `x_label` / `y_label`, the y axis logarithmic if `log_y`.
///
/// Points with a non-finite coordinate, and on a log axis points with `y <= 0`, are skipped;
/// with no points left an empty chart with a unit range is drawn.
pub fn write_timeseries_png(
    path: &Path,
    series: &[(&str, Vec<(f64, f64)>)],
    x_label: &str,
    y_label: &str,
    log_y: bool,
) -> Result<(), OutputError> {
    ensure_font(path)?;
    let data: Vec<Series> = series
        .iter()
        .map(|(name, pts)| (*name, plottable(pts, log_y)))
        .collect();
    let xs = padded(data_range(&data, |p| p.0), false);
    let ys = padded(data_range(&data, |p| p.1), log_y);
    let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        let labels = (x_label, y_label);
        let drawn = if log_y {
            draw(&root, &data, xs, ys.log_scale(), labels, Some(&log_label))
        } else {
            draw(&root, &data, xs, ys, labels, None)
        };
        drawn
            .and_then(|()| root.present())
            .map_err(|e| OutputError::format(path, format!("cannot draw chart: {e}")))?;
    }
    write_rgb_png(path, SIZE.0, SIZE.1, &rgb)
}

/// The points of `pts` that can be drawn: finite, and with `y > 0` on a log axis.
fn plottable(pts: &[(f64, f64)], log_y: bool) -> Vec<(f64, f64)> {
    pts.iter()
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite() && (!log_y || *y > 0.0))
        .collect()
}

/// Smallest and largest value of `coord` over all points, if any.
fn data_range(data: &[Series], coord: impl Fn(&(f64, f64)) -> f64) -> Option<(f64, f64)> {
    data.iter()
        .flat_map(|(_, pts)| pts.iter().map(&coord))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// An axis range around `range` with some padding (multiplicative on a log axis); a unit
/// range when there is no data, and a widened one when all values are equal.
fn padded(range: Option<(f64, f64)>, log: bool) -> Range<f64> {
    match (range, log) {
        (None, false) => 0.0..1.0,
        (None, true) => 0.1..1.0,
        (Some((lo, hi)), true) if lo == hi => lo / 10.0..hi * 10.0,
        (Some((lo, hi)), true) => lo / (hi / lo).powf(PAD)..hi * (hi / lo).powf(PAD),
        (Some((lo, hi)), false) if lo == hi => {
            let w = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
            lo - w..hi + w
        }
        (Some((lo, hi)), false) => lo - PAD * (hi - lo)..hi + PAD * (hi - lo),
    }
}

/// Tick label of a log axis, e.g. `1e-5` (the default would print `9.999999e-5`).
fn log_label(v: &f64) -> String {
    format!("{v:.0e}")
}

/// Draw axes, mesh, the series and a legend on `root`.
fn draw<DB, Y>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    data: &[Series],
    xs: Range<f64>,
    ys: Y,
    (x_label, y_label): (&str, &str),
    y_format: Option<&dyn Fn(&f64) -> String>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(xs, ys)?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_label)
        .y_desc(y_label)
        .axis_desc_style((FONT_FAMILY, 18))
        .label_style((FONT_FAMILY, 14));
    if let Some(f) = y_format {
        mesh.y_label_formatter(f);
    }
    mesh.draw()?;
    for (i, (name, pts)) in data.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let marker = if pts.len() < 2 { 3 } else { 0 };
        chart
            .draw_series(
                LineSeries::new(pts.iter().copied(), color.stroke_width(2)).point_size(marker),
            )?
            .label(*name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .label_font((FONT_FAMILY, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
}
