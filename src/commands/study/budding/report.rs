//! The budding study's report: the printed table (from the rows of `budding.csv`), the
//! reference's pear paths, `budding.csv` and the charts `budding_neck_eps`, `budding_neck_r0`
//! and `budding_skewness`.

use super::reference::PearPath;
use super::{Row, Spec};
use crate::commands::study::harness::Report;
use crate::commands::study::table::{self, Column, Format};
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use std::fmt::Write as _;

impl table::Row for Row {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("c0", "c0R0", Format::Fixed(2), |r| r.c0.into()),
            Column::both("eps_c0", "eps*c0", Format::Fixed(3), |r| r.eps_c0.into()),
            Column::both("iterations", "iters", Format::Plain, |r| {
                r.iterations.into()
            }),
            Column::both("stopped", "stopped", Format::Plain, |r| {
                r.stopped.as_str().into()
            }),
            Column::csv("residual", |r| r.residual.into()),
            Column::both("e", "e", Format::Fixed(4), |r| r.e.into()),
            Column::both("v", "v", Format::Fixed(4), |r| r.v.into()),
            Column::csv("r0_surface", |r| r.r0_surface.into()),
            Column::both("neck", "neck/eps", Format::Fixed(3), |r| r.neck.into()),
            Column::both("neck_r0", "neck/R0", Format::Fixed(4), |r| r.neck_r0.into()),
            Column::csv("r_max", |r| r.r_max.into()),
            Column::both("skewness", "skew", Format::Fixed(4), |r| r.skewness.into()),
            Column::both("pieces", "pieces", Format::Plain, |r| r.pieces.into()),
            Column::both("e_prolate_ref", "e_prol", Format::Fixed(4), |r| {
                r.e_prolate_ref.into()
            }),
            Column::both("neck_prolate_ref", "waist", Format::Fixed(4), |r| {
                r.neck_prolate_ref.into()
            }),
            Column::both("v_bifurcation_ref", "v_bif", Format::Fixed(4), |r| {
                r.v_bifurcation_ref.into()
            }),
            Column::both("v_fold_ref", "v_fold", Format::Fixed(4), |r| {
                r.v_fold_ref.into()
            }),
            Column::csv("v_limit_ref", |r| r.v_limit_ref.into()),
            Column::both("neck_pear_ref", "neck_ref", Format::Fixed(4), |r| {
                r.neck_pear_ref.into()
            }),
            Column::both("e_pear_ref", "e_pear", Format::Fixed(4), |r| {
                r.e_pear_ref.into()
            }),
            Column::both("neck_unstable_ref", "neck_uns", Format::Fixed(4), |r| {
                r.neck_unstable_ref.into()
            }),
            Column::csv("e_unstable_ref", |r| r.e_unstable_ref.into()),
            Column::both("state", "state", Format::Plain, |r| r.state.as_str().into()),
            Column::csv("wall_seconds", |r| r.wall_seconds.into()),
        ]
    }
}

/// The report of the continuation `rows` of `spec`, with the reference's pear `paths`.
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn report(spec: &Spec, rows: &[Row], paths: &[PearPath]) -> Result<Report> {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "budding continuation: v = {} (start), R0 = {} eps, seed {}; L-BFGS through stationary \
         states (no time: the path is not a transient)",
        spec.v, spec.r0, spec.seed
    );
    text.push_str(&table::text(rows));
    let _ = writeln!(
        text,
        "reference: the axisymmetric prolate (e_prol, its waist) and pear branch at each row's \
         phi = 0 v; neck_ref the stable pear's (after the fold), neck_uns the unstable one's (before it), in R0; - \
         where the stretch does not reach v"
    );
    for p in paths {
        let _ = writeln!(
            text,
            "  c0R0 = {}: pear bifurcation v = {:.5}, {} path states{}",
            p.c0,
            p.v_bifurcation,
            p.states.len(),
            if p.reached_limit {
                " (ends at the neck threshold)"
            } else {
                ""
            }
        );
    }
    let mut report = Report {
        text,
        ..Report::default()
    };
    report.table("budding.csv", rows)?;
    let r0 = rows.first().map_or(spec.r0, |r| r.r0_surface);
    report.chart(
        "budding_neck_eps",
        neck_chart(rows, r0, "neck radius / eps"),
    );
    report.chart("budding_neck_r0", neck_chart(rows, 1.0, "neck radius / R0"));
    report.chart("budding_skewness", skewness_chart(rows));
    Ok(report)
}

/// Neck against c̄0: the phase field's (in ε, or in R0 when `scale` = 1) beside the reference
/// pear's stable and unstable necks (in R0, times `scale`).
/// The phase field's points are joined in path order (up and down a hysteresis loop).
fn neck_chart(rows: &[Row], scale: f64, label: &str) -> Figure {
    let per_r0 = scale == 1.0;
    let pts = |f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
        rows.iter()
            .map(|r| (r.c0, f(r)))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let mut fig = Figure::new(
        "Quasi-static budding: neck radius against c0 R0 at fixed v",
        Axis::linear("c0 R0"),
        Axis::linear(label),
    );
    fig.legend = Corner::UpperRight;
    fig.push(Series::new(
        "phase field (L-BFGS)",
        pts(&|r| if per_r0 { r.neck_r0 } else { r.neck }),
        colour(0),
        Mark::LinePoints(Shape::Circle),
    ));
    fig.push(Series::new(
        "reference: prolate's waist",
        pts(&|r| r.neck_prolate_ref * scale),
        colour(3),
        Mark::Dashed,
    ));
    fig.push(Series::new(
        "reference: stable pear",
        pts(&|r| r.neck_pear_ref * scale),
        colour(1),
        Mark::LinePoints(Shape::Square),
    ));
    fig.push(Series::new(
        "reference: unstable pear",
        pts(&|r| r.neck_unstable_ref * scale),
        colour(2),
        Mark::DashedPoints(Shape::Triangle),
    ));
    fig
}

/// Skewness of the volume along z against c̄0.
fn skewness_chart(rows: &[Row]) -> Figure {
    let mut fig = Figure::new(
        "Quasi-static budding: up-down asymmetry",
        Axis::linear("c0 R0"),
        Axis::linear("skewness of the volume along z"),
    );
    fig.push(Series::new(
        "phase field (L-BFGS)",
        rows.iter().map(|r| (r.c0, r.skewness)).collect(),
        colour(0),
        Mark::LinePoints(Shape::Circle),
    ));
    fig
}
