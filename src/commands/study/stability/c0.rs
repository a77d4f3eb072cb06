//! The stability map's spontaneous-curvature axis: at h = ε, from the field prepared there, the
//! fixed-Δt sweep of each spectral scheme with its default stabiliser at each εc0 (c0 uniform),
//! classified as the rest of the map. The bulk term's linearisation f'(±1) = 2 ± 2εC0 (C0 =
//! c0/√2) grows with c0 while the default S does not, so the frontier falls as c0 grows (not
//! necessarily monotonically from one εc0 to the next).
//!
//! Writes `stability_c0.csv` (every run), the frontier table (largest stable Δt per scheme and
//! εc0) and the chart `stability_c0` (PNG and SVG).

use super::measure::{at_spacing, dt_sweep, prepared, METHODS};
use super::report::{class_colour, Edge, FRONTIER};
use super::spec::{C0Sweep, Spec};
use crate::commands::study::classify::Class;
use crate::commands::study::harness::Report;
use crate::commands::study::table::{self, Column, Format, Row};
use crate::error::{Error, Result};
use crate::output::chart::{Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::{C0Spec, Scene, Scheme};
use crate::problem::model::C0;

/// One classified run of the c0 sweep; a row of `stability_c0.csv`.
#[derive(Clone, Debug)]
pub struct C0Run {
    /// `sbdf1` or `sbdf2` (default stabiliser).
    pub scheme: &'static str,
    /// εc0.
    pub eps_c0: f64,
    /// Δt.
    pub dt: f64,
    /// The class.
    pub class: Class,
    /// Accepted steps.
    pub steps: usize,
    /// Largest max|φ| seen.
    pub max_abs_phi: f64,
    /// Largest |A − A0|/A0 seen.
    pub max_area_error: f64,
}

impl Row for C0Run {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("scheme", |r| r.scheme.into()),
            Column::csv("eps_c0", |r| r.eps_c0.into()),
            Column::csv("dt", |r| r.dt.into()),
            Column::csv("class", |r| r.class.as_str().into()),
            Column::csv("steps", |r| r.steps.into()),
            Column::csv("max_abs_phi", |r| r.max_abs_phi.into()),
            Column::csv("max_area_error", |r| r.max_area_error.into()),
        ]
    }
}

/// Add the c0 axis of `runs` to `report`: the frontier table, `stability_c0.csv` and the chart
/// `stability_c0`.
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub(super) fn report(report: &mut Report, runs: &[C0Run], c0: &C0Sweep) -> Result<()> {
    let edges = c0_frontier(runs, c0);
    report
        .text
        .push_str("\nspontaneous curvature at h = eps, default S, c0 uniform:\n");
    report.text.push_str(&table::text(&edges));
    report.table("stability_c0.csv", runs)?;
    report.chart("stability_c0", c0_chart(runs, &edges, c0));
    Ok(())
}

/// Name of `scheme` in the file and the CSV.
fn scheme_name(scheme: Scheme) -> &'static str {
    match scheme {
        Scheme::Sbdf1 => "sbdf1",
        Scheme::Sbdf2 => "sbdf2",
    }
}

/// Every run of the c0 sweep `c0`, at h = ε from the field prepared there.
///
/// # Errors
/// `Error::Config` (field `c0.…`) for an empty or non-finite axis.
pub(super) fn c0_sweep(spec: &Spec, c0: &C0Sweep, base: &Scene) -> Result<Vec<C0Run>> {
    if c0.eps_c0.is_empty() || c0.eps_c0.iter().any(|x| !x.is_finite()) {
        return Err(Error::config("c0.eps_c0", "need at least one finite value"));
    }
    if c0.schemes.is_empty() {
        return Err(Error::config("c0.schemes", "need at least one scheme"));
    }
    let problem = prepared(base, 1.0)?;
    let mut runs = Vec::new();
    for &scheme in &c0.schemes {
        let method = METHODS
            .iter()
            .find(|m| m.scheme == Some(scheme) && !m.no_stabiliser)
            .expect("every scheme has a default-stabiliser method");
        for &eps_c0 in &c0.eps_c0 {
            // The run takes c0 from the problem: the prepared field with this c0.
            let uniform = C0Spec::Uniform(eps_c0 / base.eps);
            let mut at_c0 = problem.clone();
            at_c0.c0 = C0::new(&uniform, &at_c0.grid, base.eps)?;
            let edit = |s: &mut Scene| {
                at_spacing(s, base, 1.0);
                method.apply(s);
                s.c0 = uniform.clone();
            };
            for (dt, r) in dt_sweep(spec, base, &at_c0, &edit)? {
                runs.push(C0Run {
                    scheme: scheme_name(scheme),
                    eps_c0,
                    dt,
                    class: r.0,
                    steps: r.1,
                    max_abs_phi: r.2,
                    max_area_error: r.3,
                });
            }
        }
    }
    Ok(runs)
}

/// The edge of one scheme at one εc0 (printed only).
struct C0Edge {
    scheme: &'static str,
    eps_c0: f64,
    edge: Edge,
}

impl Row for C0Edge {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::text("scheme", Format::Plain, |r| r.scheme.into()),
            Column::text("eps*c0", Format::Fixed(3), |r| r.eps_c0.into()),
            Column::text("largest stable dt", Format::Sci(3), |r: &Self| {
                r.edge.largest_dt().into()
            })
            .or("none"),
            Column::text("first failure dt", Format::Sci(3), |r: &Self| {
                r.edge.failure_dt().into()
            })
            .or("none"),
            Column::text("its class", Format::Plain, |r| {
                r.edge.failure_class().into()
            }),
        ]
    }
}

/// The edge of each scheme at each εc0 of the c0 runs, in the order of the file.
fn c0_frontier(runs: &[C0Run], c0: &C0Sweep) -> Vec<C0Edge> {
    let mut f = Vec::new();
    for &scheme in &c0.schemes {
        let name = scheme_name(scheme);
        for &eps_c0 in &c0.eps_c0 {
            let rs = runs
                .iter()
                .filter(|r| r.scheme == name && r.eps_c0 == eps_c0)
                .map(|r| (r.dt, r.class));
            f.push(C0Edge {
                scheme: name,
                eps_c0,
                edge: Edge::of(rs),
            });
        }
    }
    f
}

/// The chart: Δt (log) against εc0, a marker per scheme coloured by class, the measured
/// frontier of each scheme.
fn c0_chart(runs: &[C0Run], f: &[C0Edge], c0: &C0Sweep) -> Figure {
    let mut fig = Figure::new(
        "Stability against c0 at h = eps, default S (markers by scheme, colour by class)",
        Axis::log("dt [time units]"),
        Axis::linear("eps * c0 (schemes offset vertically)"),
    );
    fig.legend = Corner::LowerLeft;
    let (lo, hi) = c0
        .eps_c0
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let step = if hi > lo { 0.015 * (hi - lo) } else { 0.01 };
    let shapes = [Shape::Triangle, Shape::Diamond];
    for (i, &scheme) in c0.schemes.iter().enumerate() {
        let name = scheme_name(scheme);
        let dy = step * (i as f64 - (c0.schemes.len() as f64 - 1.0) / 2.0);
        let shape = shapes[i % shapes.len()];
        for class in Class::ALL {
            let pts: Vec<(f64, f64)> = runs
                .iter()
                .filter(|r| r.scheme == name && r.class == class)
                .map(|r| (r.dt, r.eps_c0 + dy))
                .collect();
            fig.push(Series::new("", pts, class_colour(class), Mark::Points(shape)).unlisted());
        }
        fig.push(Series::new(
            format!("{}, default S", name.to_uppercase()),
            Vec::new(),
            [90, 90, 90],
            Mark::Points(shape),
        ));
        let frontier: Vec<(f64, f64)> = f
            .iter()
            .filter(|x| x.scheme == name)
            .filter_map(|x| x.edge.largest_stable.map(|d| (d, x.eps_c0 + dy)))
            .collect();
        fig.push(Series::new(
            format!("measured frontier, {}", name.to_uppercase()),
            frontier,
            FRONTIER[i % FRONTIER.len()],
            Mark::Line,
        ));
    }
    for class in Class::ALL {
        fig.push(Series::new(
            class.as_str(),
            Vec::new(),
            class_colour(class),
            Mark::Line,
        ));
    }
    fig
}
