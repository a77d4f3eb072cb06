//! Charts as PNG and SVG: line, dashed and marker series on linear or true logarithmic axes.
//!
//! A log axis is plotters' logarithmic coordinate (positions ∝ log10 of the value), its range
//! widened outward to whole decades, with a labelled tick at every decade (`1e-5`) and unlabelled
//! minor ticks between. A [`Figure`] is a title, two [`Axis`] and a list of [`Series`]; each
//! series has a colour, a [`Mark`] and an optional legend entry. [`Figure::write`] draws it to
//! `STEM.png` and `STEM.svg`.
//!
//! A line is broken where a measure does not exist (a non-finite point, or one ≤ 0 on a log
//! axis): the gap shows, no straight segment is drawn across it. [`style`] hands out the
//! `(colour, mark)` pairs of a chart's series so that no two look alike, and [`slope_guide`]
//! draws the reference slope of an order on a log-log convergence chart.

use super::{ensure_font, write_rgb_png, OutputError, FONT_FAMILY};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Chart size in pixels.
const SIZE: (u32, u32) = (900, 600);
/// Relative padding added to the data range on a linear axis.
const PAD: f64 = 0.05;

/// How an axis maps values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Linear.
    Linear,
    /// Logarithmic (base 10, decade ticks); values ≤ 0 are not drawn.
    Log,
}

/// An axis: its label (with units) and scale.
#[derive(Clone, Debug)]
pub struct Axis {
    /// Axis title, with units.
    pub label: String,
    /// Linear or logarithmic.
    pub scale: Scale,
}

impl Axis {
    /// A linear axis.
    pub fn linear(label: impl Into<String>) -> Self {
        Axis {
            label: label.into(),
            scale: Scale::Linear,
        }
    }

    /// A logarithmic axis.
    pub fn log(label: impl Into<String>) -> Self {
        Axis {
            label: label.into(),
            scale: Scale::Log,
        }
    }
}

/// Marker shape of a point series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle.
    Triangle,
    /// Cross (×).
    Cross,
    /// Filled diamond.
    Diamond,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A solid line through the points.
    Line,
    /// A dashed line (fitted laws, bounds).
    Dashed,
    /// A dotted line (slope guides).
    Dotted,
    /// Markers only.
    Points(Shape),
    /// A solid line with markers.
    LinePoints(Shape),
    /// A dashed line with markers.
    DashedPoints(Shape),
}

/// One series: points, colour, how it is drawn, legend text (`None`: not in the legend).
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry.
    pub name: Option<String>,
    /// The `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// RGB colour.
    pub colour: [u8; 3],
    /// Line, dashes or markers.
    pub mark: Mark,
}

impl Series {
    /// A series named `name` (in the legend), colour `colour`, drawn as `mark`.
    pub fn new(
        name: impl Into<String>,
        points: Vec<(f64, f64)>,
        colour: [u8; 3],
        mark: Mark,
    ) -> Self {
        Series {
            name: Some(name.into()),
            points,
            colour,
            mark,
        }
    }

    /// The same series without a legend entry.
    pub fn unlisted(mut self) -> Self {
        self.name = None;
        self
    }
}

/// The `i`-th colour of a palette of well separated colours (cycling).
pub fn colour(i: usize) -> [u8; 3] {
    const P: [[u8; 3]; 8] = [
        [31, 119, 180],
        [214, 39, 40],
        [44, 160, 44],
        [255, 127, 14],
        [148, 103, 189],
        [140, 86, 75],
        [227, 119, 194],
        [23, 190, 207],
    ];
    P[i % P.len()]
}

/// The `i`-th line style of a chart with many line series: the palette's colours as solid
/// lines, then as dashed lines, then as dotted lines; no two of the first 24 alike.
pub fn style(i: usize) -> ([u8; 3], Mark) {
    const MARKS: [Mark; 3] = [Mark::Line, Mark::Dashed, Mark::Dotted];
    (colour(i), MARKS[(i / 8) % MARKS.len()])
}

/// Grey of the slope guides.
pub const GUIDE: [u8; 3] = [120, 120, 120];

/// The guide of slope `p` on a log-log chart: the line y = y0 (x/x0)^p over `[lo, hi]`
/// through `(x0, y0)`, dotted grey, named `slope p`.
pub fn slope_guide(p: f64, (x0, y0): (f64, f64), lo: f64, hi: f64, colour: [u8; 3]) -> Series {
    let line = [lo, hi]
        .iter()
        .map(|&x| (x, y0 * (x / x0).powf(p)))
        .collect();
    Series::new(format!("slope {p}"), line, colour, Mark::Dotted)
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corner {
    /// Upper left.
    UpperLeft,
    /// Upper right.
    UpperRight,
    /// Lower left.
    LowerLeft,
    /// Lower right.
    LowerRight,
}

/// A chart: title, axes, series.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Legend position (upper left by default).
    pub legend: Corner,
    /// Title drawn above the plot.
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// What is drawn, in order (later series on top).
    pub series: Vec<Series>,
}

impl Figure {
    /// An empty figure.
    pub fn new(title: impl Into<String>, x: Axis, y: Axis) -> Self {
        Figure {
            legend: Corner::UpperLeft,
            title: title.into(),
            x,
            y,
            series: Vec::new(),
        }
    }

    /// Add a series.
    pub fn push(&mut self, s: Series) -> &mut Self {
        self.series.push(s);
        self
    }

    /// Write `stem.png` and `stem.svg` (the stem's extension, if any, is replaced); the paths
    /// written.
    ///
    /// # Errors
    /// [`OutputError`] if a file cannot be written or the chart cannot be drawn.
    pub fn write(&self, stem: &Path) -> Result<[PathBuf; 2], OutputError> {
        let png = stem.with_extension("png");
        let svg = stem.with_extension("svg");
        self.write_png(&png)?;
        self.write_svg(&svg)?;
        Ok([png, svg])
    }

    /// Write the chart as a PNG file.
    ///
    /// # Errors
    /// As [`Figure::write`].
    pub fn write_png(&self, path: &Path) -> Result<(), OutputError> {
        ensure_font(path)?;
        let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
            self.draw_on(&root)
                .and_then(|()| root.present())
                .map_err(|e| OutputError::format(path, format!("cannot draw chart: {e}")))?;
        }
        write_rgb_png(path, SIZE.0, SIZE.1, &rgb)
    }

    /// Write the chart as an SVG file.
    ///
    /// # Errors
    /// As [`Figure::write`].
    pub fn write_svg(&self, path: &Path) -> Result<(), OutputError> {
        ensure_font(path)?;
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, SIZE).into_drawing_area();
            self.draw_on(&root)
                .and_then(|()| root.present())
                .map_err(|e| OutputError::format(path, format!("cannot draw chart: {e}")))?;
        }
        std::fs::write(path, text).map_err(|e| OutputError::io(path, e))
    }

    /// The drawable runs of every series: its points split where one is not drawable
    /// (non-finite; ≤ 0 on a log axis), so that a line shows the gap.
    fn drawable(&self) -> Vec<Vec<Vec<(f64, f64)>>> {
        let ok = |v: f64, s: Scale| v.is_finite() && (s == Scale::Linear || v > 0.0);
        self.series
            .iter()
            .map(|s| {
                runs(&s.points, |&(x, y)| {
                    ok(x, self.x.scale) && ok(y, self.y.scale)
                })
            })
            .collect()
    }

    fn draw_on<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let data = self.drawable();
        let xr = axis_range(data.iter().flatten().flatten().map(|p| p.0), self.x.scale);
        let yr = axis_range(data.iter().flatten().flatten().map(|p| p.1), self.y.scale);
        let spans = (xr.end - xr.start, yr.end - yr.start);
        match (self.x.scale, self.y.scale) {
            (Scale::Linear, Scale::Linear) => self.draw(root, &data, spans, xr, yr),
            (Scale::Linear, Scale::Log) => self.draw(root, &data, spans, xr, yr.log_scale()),
            (Scale::Log, Scale::Linear) => self.draw(root, &data, spans, xr.log_scale(), yr),
            (Scale::Log, Scale::Log) => {
                self.draw(root, &data, spans, xr.log_scale(), yr.log_scale())
            }
        }
    }

    /// Draw on `root` the drawable runs `data` on the axes `xs`, `ys`, whose ranges are
    /// `spans` = (x, y) long.
    fn draw<DB, X, Y>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
        data: &[Vec<Vec<(f64, f64)>>],
        spans: (f64, f64),
        xs: X,
        ys: Y,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
    where
        DB: DrawingBackend,
        X: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, (FONT_FAMILY, 20))
            .margin(20)
            .x_label_area_size(55)
            .y_label_area_size(95)
            .build_cartesian_2d(xs, ys)?;
        let xf = tick_label(self.x.scale, spans.0);
        let yf = tick_label(self.y.scale, spans.1);
        chart
            .configure_mesh()
            .x_desc(self.x.label.as_str())
            .y_desc(self.y.label.as_str())
            .axis_desc_style((FONT_FAMILY, 18))
            .label_style((FONT_FAMILY, 14))
            .x_labels(labels(self.x.scale))
            .y_labels(labels(self.y.scale))
            .max_light_lines(0)
            .x_label_formatter(&xf)
            .y_label_formatter(&yf)
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(200, 200, 200))
            .draw()?;
        let mut listed = false;
        for (s, segments) in self.series.iter().zip(data) {
            let c = RGBColor(s.colour[0], s.colour[1], s.colour[2]);
            let line = c.stroke_width(2);
            let dashes = match s.mark {
                Mark::Line | Mark::LinePoints(_) => Some((0, 0)),
                Mark::Dashed | Mark::DashedPoints(_) => Some((8, 5)),
                Mark::Dotted => Some((2, 4)),
                Mark::Points(_) => None,
            };
            if let Some((on, off)) = dashes {
                // One drawing per run; the legend entry hangs on the first (an empty run when
                // the series has nothing to draw).
                let empty = vec![Vec::new()];
                let runs = if segments.is_empty() {
                    &empty
                } else {
                    segments
                };
                for (k, pts) in runs.iter().enumerate() {
                    let anno = if on == 0 {
                        chart.draw_series(LineSeries::new(pts.iter().copied(), line))?
                    } else {
                        chart.draw_series(DashedLineSeries::new(
                            pts.iter().copied(),
                            on,
                            off,
                            line,
                        ))?
                    };
                    if let (0, Some(name)) = (k, &s.name) {
                        listed = true;
                        let seg = legend_dashes(on, off);
                        anno.label(name.as_str()).legend(move |(x, y)| {
                            let part =
                                |(a, b): (i32, i32)| PathElement::new(vec![(a, 0), (b, 0)], line);
                            EmptyElement::at((x, y))
                                + part(seg[0])
                                + part(seg[1])
                                + part(seg[2])
                                + part(seg[3])
                        });
                    }
                }
            }
            let shape = match s.mark {
                Mark::Points(shape) => shape,
                Mark::LinePoints(shape) | Mark::DashedPoints(shape) => shape,
                Mark::Line | Mark::Dashed | Mark::Dotted => continue,
            };
            // A line-and-marker series is listed once, by its line.
            let name = match s.mark {
                Mark::Points(_) => s.name.as_deref(),
                _ => None,
            };
            listed |= name.is_some();
            let pts: Vec<(f64, f64)> = segments.iter().flatten().copied().collect();
            markers(&mut chart, &pts, shape, c, name)?;
        }
        if listed {
            chart
                .configure_series_labels()
                .position(match self.legend {
                    Corner::UpperLeft => SeriesLabelPosition::UpperLeft,
                    Corner::UpperRight => SeriesLabelPosition::UpperRight,
                    Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
                    Corner::LowerRight => SeriesLabelPosition::LowerRight,
                })
                .label_font((FONT_FAMILY, 14))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()?;
        }
        Ok(())
    }
}

/// Four pieces of a 24-pixel legend line: contiguous for a solid line (`on` = 0), else dashes
/// `on` long with gaps `off`.
fn legend_dashes(on: u32, off: u32) -> [(i32, i32); 4] {
    let (on, off) = (on as i32, off as i32);
    if on == 0 {
        return [(0, 6), (6, 12), (12, 18), (18, 24)];
    }
    let mut seg = [(24, 24); 4];
    for (k, s) in seg.iter_mut().enumerate() {
        let a = k as i32 * (on + off);
        if a < 24 {
            *s = (a, (a + on).min(24));
        }
    }
    seg
}

/// The maximal runs of consecutive points of `pts` that are `ok`, in order (the points that are
/// not split them and are dropped).
fn runs(pts: &[(f64, f64)], ok: impl Fn(&(f64, f64)) -> bool) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for p in pts {
        if ok(p) {
            if !open {
                out.push(Vec::new());
                open = true;
            }
            out.last_mut().expect("opened").push(*p);
        } else {
            open = false;
        }
    }
    out
}

/// Markers of `shape` and colour `c` at `pts`, listed in the legend as `name` if given.
fn markers<DB: DrawingBackend, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    shape: Shape,
    c: RGBColor,
    name: Option<&str>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let fill = c.filled();
    let at = pts.iter().copied();
    let anno =
        match shape {
            Shape::Circle => chart.draw_series(at.map(|p| Circle::new(p, 5, fill)))?,
            Shape::Square => chart.draw_series(
                at.map(|p| EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], fill)),
            )?,
            Shape::Triangle => chart.draw_series(at.map(|p| {
                EmptyElement::at(p) + Polygon::new(vec![(0, -6), (-5, 4), (5, 4)], fill)
            }))?,
            Shape::Cross => chart.draw_series(at.map(|p| Cross::new(p, 5, c.stroke_width(2))))?,
            Shape::Diamond => chart.draw_series(at.map(|p| {
                EmptyElement::at(p) + Polygon::new(vec![(0, -6), (-5, 0), (0, 6), (5, 0)], fill)
            }))?,
        };
    if let Some(name) = name {
        let anno = anno.label(name);
        match shape {
            Shape::Circle => anno.legend(move |(x, y)| Circle::new((x + 12, y), 5, fill)),
            Shape::Square => {
                anno.legend(move |(x, y)| Rectangle::new([(x + 8, y - 4), (x + 16, y + 4)], fill))
            }
            Shape::Triangle => anno.legend(move |(x, y)| {
                Polygon::new(vec![(x + 12, y - 6), (x + 7, y + 4), (x + 17, y + 4)], fill)
            }),
            Shape::Cross => {
                anno.legend(move |(x, y)| Cross::new((x + 12, y), 5, c.stroke_width(2)))
            }
            Shape::Diamond => anno.legend(move |(x, y)| {
                Polygon::new(
                    vec![(x + 12, y - 6), (x + 7, y), (x + 12, y + 6), (x + 17, y)],
                    fill,
                )
            }),
        };
    }
    Ok(())
}

/// How many ticks to ask for: enough on a log axis for the minor ticks 2…9 of each decade, a
/// readable number on a linear one.
fn labels(scale: Scale) -> usize {
    match scale {
        Scale::Log => 40,
        Scale::Linear => 10,
    }
}

/// Tick labels: on a log axis `1e-5` at decades and nothing between (the minor ticks); on a
/// linear axis whose range is `span` long the shortest of fixed and exponent notation, and `0`
/// for a tick within round-off of zero (the axis' ticks are sums of steps, so the one at zero
/// can come out as ±1e-16 times the span).
fn tick_label(scale: Scale, span: f64) -> impl Fn(&f64) -> String {
    move |v: &f64| match scale {
        Scale::Log => {
            let e = v.log10();
            if (e - e.round()).abs() < 1e-6 {
                format!("1e{}", e.round() as i32)
            } else {
                String::new()
            }
        }
        Scale::Linear => {
            let a = v.abs();
            if a <= 1e-9 * span {
                "0".to_string()
            } else if (1e-3..1e4).contains(&a) {
                let s = format!("{v:.4}");
                s.trim_end_matches('0').trim_end_matches('.').to_string()
            } else {
                format!("{v:.1e}")
            }
        }
    }
}

/// The axis range of `values`: padded by [`PAD`] on a linear axis, widened to whole decades
/// on a log axis; a unit range (or the decade 0.1..1) when there are none.
fn axis_range(values: impl Iterator<Item = f64>, scale: Scale) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    match scale {
        Scale::Log if lo > hi => 0.1..1.0,
        Scale::Log => {
            // Rounded so that a value on a decade stays inside, then nudged outward so that the
            // end decades survive the axis' own rounding and get their ticks.
            let a = (lo.log10() + 1e-9).floor();
            let b = (hi.log10() - 1e-9).ceil().max(a + 1.0);
            10f64.powf(a) * (1.0 - 1e-9)..10f64.powf(b) * (1.0 + 1e-9)
        }
        Scale::Linear if lo > hi => 0.0..1.0,
        Scale::Linear if lo == hi => {
            let w = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
            lo - w..hi + w
        }
        Scale::Linear => lo - PAD * (hi - lo)..hi + PAD * (hi - lo),
    }
}

/// Write a line chart of `series` (each a name and its `(x, y)` points) against a linear x axis
/// labelled `x_label`, the y axis labelled `y_label` and logarithmic if `log_y`, as the PNG
/// `path` (the time-series charts of a run).
///
/// # Errors
/// As [`Figure::write`].
pub fn write_timeseries_png(
    path: &Path,
    series: &[(&str, Vec<(f64, f64)>)],
    x_label: &str,
    y_label: &str,
    log_y: bool,
) -> Result<(), OutputError> {
    let y = if log_y {
        Axis::log(y_label)
    } else {
        Axis::linear(y_label)
    };
    let mut fig = Figure::new("", Axis::linear(x_label), y);
    for (i, (name, pts)) in series.iter().enumerate() {
        let mark = if pts.len() < 2 {
            Mark::Points(Shape::Circle)
        } else {
            Mark::Line
        };
        fig.push(Series::new(*name, pts.clone(), colour(i), mark));
    }
    fig.write_png(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A log range is widened to whole decades: [3e-5, 2e-2] → [1e-5, 1e-1]; a single decade
    /// value still spans one decade.
    #[test]
    fn log_ranges_are_whole_decades() {
        let r = axis_range([3e-5, 2e-2].into_iter(), Scale::Log);
        assert!((r.start / 1e-5 - 1.0).abs() < 1e-8 && (r.end / 1e-1 - 1.0).abs() < 1e-8);
        assert!(r.start < 1e-5 && r.end > 1e-1);
        let r = axis_range([1e-3].into_iter(), Scale::Log);
        assert!((r.start / 1e-3 - 1.0).abs() < 1e-8 && (r.end / 1e-2 - 1.0).abs() < 1e-8);
    }

    /// Decades are labelled `1eK`, the minor ticks between them not at all.
    #[test]
    fn log_ticks_label_decades_only() {
        let f = tick_label(Scale::Log, 1.0);
        assert_eq!(f(&1e-5), "1e-5");
        assert_eq!(f(&100.0), "1e2");
        assert_eq!(f(&3e-5), "");
    }

    /// A linear tick at zero reads `0`, also when the axis' sums of steps leave it at ±1e-16
    /// or ±1e-17 times the span (the −1.1e-16 of a ±1 axis); small ticks of a small axis keep
    /// their value, and the rest is the shortest of fixed and exponent notation.
    #[test]
    fn linear_ticks_print_zero_as_zero() {
        let f = tick_label(Scale::Linear, 1.6);
        for zero in [0.0, -0.0, -1.1e-16, 1.4e-17, -0.6 + 0.2 * 3.0] {
            assert_eq!(f(&zero), "0", "{zero:e}");
        }
        assert_eq!(f(&-0.2), "-0.2");
        assert_eq!(f(&0.25), "0.25");
        let f = tick_label(Scale::Linear, 4e-15);
        assert_eq!(f(&-1e-15), "-1.0e-15");
        assert_eq!(f(&-1.4e-30), "0");
        let f = tick_label(Scale::Linear, 3e5);
        assert_eq!(f(&1e5), "1.0e5");
        assert_eq!(f(&2e-11), "0");
    }

    /// A chart whose y axis crosses zero has no tick label in exponent notation: the tick at
    /// zero reads `0` (the SVG holds every label as text).
    #[test]
    fn a_chart_across_zero_labels_zero() {
        let tmp = tempfile::TempDir::new().unwrap();
        let mut fig = Figure::new("t", Axis::linear("x"), Axis::linear("y"));
        fig.push(Series::new(
            "s",
            vec![(-1.0, -0.6), (0.0, 0.3), (1.0, 1.0)],
            colour(0),
            Mark::Line,
        ));
        let [_, svg] = fig.write(&tmp.path().join("c")).unwrap();
        let text = std::fs::read_to_string(svg).unwrap();
        let labels: Vec<&str> = text
            .split("</text>")
            .filter_map(|t| t.rsplit_once('>').map(|(_, l)| l.trim()))
            .collect();
        assert!(labels.contains(&"0"), "a tick labelled 0: {labels:?}");
        assert!(labels.iter().all(|l| !l.contains("e-")), "{labels:?}");
    }

    /// A line is broken at a missing value (NaN) and, on a log axis, at a value ≤ 0: three
    /// runs, none spanning a gap.
    #[test]
    fn lines_break_at_missing_values() {
        let fig = {
            let mut f = Figure::new("t", Axis::linear("x"), Axis::log("y"));
            f.push(Series::new(
                "s",
                vec![
                    (0.0, 1.0),
                    (1.0, 2.0),
                    (2.0, f64::NAN),
                    (3.0, 1.0),
                    (4.0, 0.0),
                    (5.0, 3.0),
                ],
                colour(0),
                Mark::Line,
            ));
            f
        };
        let d = fig.drawable();
        assert_eq!(
            d[0],
            vec![
                vec![(0.0, 1.0), (1.0, 2.0)],
                vec![(3.0, 1.0)],
                vec![(5.0, 3.0)]
            ]
        );
    }

    /// The first 24 styles are pairwise distinct in colour and dash together.
    #[test]
    fn styles_do_not_repeat() {
        let all: Vec<_> = (0..24).map(style).collect();
        for i in 0..all.len() {
            for j in 0..i {
                assert_ne!(all[i], all[j], "styles {i} and {j}");
            }
        }
    }

    /// A slope guide of order 2 through (0.1, 1e-3) passes 1e-5 at 0.01.
    #[test]
    fn slope_guides_have_their_slope() {
        let g = slope_guide(2.0, (0.1, 1e-3), 0.01, 0.1, GUIDE);
        assert_eq!(g.points[1], (0.1, 1e-3));
        assert!((g.points[0].1 / 1e-5 - 1.0).abs() < 1e-12);
        assert_eq!(g.mark, Mark::Dotted);
    }

    /// Both files are written, and the SVG holds the axis label and a legend entry.
    #[test]
    fn figure_writes_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let mut fig = Figure::new("t", Axis::log("dt [time]"), Axis::log("error"));
        fig.push(Series::new(
            "SBDF1",
            vec![(0.1, 1e-2), (0.05, 5e-3), (0.025, 2.5e-3)],
            colour(0),
            Mark::LinePoints(Shape::Circle),
        ));
        fig.push(Series::new(
            "slope 1",
            vec![(0.1, 2e-2), (0.025, 5e-3)],
            colour(1),
            Mark::Dashed,
        ));
        let [png, svg] = fig.write(&dir.path().join("c")).unwrap();
        assert!(std::fs::metadata(png).unwrap().len() > 1000);
        let text = std::fs::read_to_string(svg).unwrap();
        assert!(text.contains("dt [time]") && text.contains("SBDF1") && text.contains("1e-2"));
    }
}
