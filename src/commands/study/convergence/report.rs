//! The convergence study's report: the printed tables (a table per series, its floor and fits,
//! the extrapolated limits), `convergence.csv`, `fits.csv`, and the charts `convergence_time`,
//! `convergence_space`, `convergence_space_semilog`, `convergence_eps`, `convergence_sphere`.

use super::fits::{floor_line, resolved, series_of, Quoted};
use super::measure::Row;
use crate::commands::study::fit;
use crate::commands::study::harness::Report;
use crate::commands::study::table::{self, Column, Format};
use crate::error::Result;
use crate::output::chart::{colour, slope_guide, Axis, Corner, Figure, Mark, Series, Shape, GUIDE};
use std::fmt::Write as _;

/// The report of `rows` with their fitted laws `fits`.
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn report(rows: &[Row], fits: &[Quoted]) -> Result<Report> {
    let mut report = Report {
        text: text(rows, fits),
        ..Report::default()
    };
    report.table("convergence.csv", rows)?;
    report.table("fits.csv", fits)?;
    charts(&mut report, rows);
    Ok(report)
}

impl table::Row for Row {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("part", |r| r.part.into()),
            Column::csv("series", |r| r.series.as_str().into()),
            Column::both("x", "x", Format::Sci(4), |r| r.x.into()),
            Column::both("error", "error", Format::Sci(4), |r| r.error.into()),
            Column::both("e", "e", Format::Fixed(7), |r| r.e.into()),
            Column::both("v_levelset", "v (phi=0)", Format::Fixed(5), |r| r.v.into()),
            Column::both("e_ref", "e_ref", Format::Fixed(7), |r| r.e_ref.into()),
            Column::both("residual", "residual", Format::Sci(1), |r| {
                r.residual.into()
            }),
            Column::both("steps", "steps", Format::Plain, |r| r.steps.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(2), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

impl table::Row for Quoted {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("part", |r| r.part.into()),
            Column::csv("series", |r| r.series.as_str().into()),
            Column::csv("law", |r| r.law.into()),
            Column::csv("value", |r| r.value.into()),
            Column::csv("spread", |r| r.spread.into()),
            Column::csv("text", |r| r.text.as_str().into()),
        ]
    }
}

/// The printed report: per part and series its rows, its floor and its fits; then the ε/R0
/// limits against the sharp-interface e at the extrapolated v.
fn text(rows: &[Row], fits: &[Quoted]) -> String {
    let mut s = String::new();
    let heads = [
        ("time", "dt", "max|phi - phi_ref| at t"),
        ("space", "h/eps", "|e(h) - e_ref|"),
        ("eps", "eps/R0", "e - e_ref(v)"),
    ];
    for (part, x, error) in heads {
        let _ = writeln!(s, "== {part}: x = {x}, error = {error} ==");
        for (name, rs) in series_of(rows, part) {
            let _ = writeln!(s, "{name}");
            s.push_str(&table::text(rs.iter().copied()));
            if let Some(line) = floor_line(&rs, |r| r.error.abs()) {
                let _ = writeln!(s, "{line}");
            }
            for f in fits.iter().filter(|f| f.part == part && f.series == name) {
                let _ = writeln!(s, "  fit: {}", f.text);
            }
        }
    }
    for (name, _) in series_of(rows, "eps") {
        let get = |law| fits.iter().find(|f| f.series == name && f.law == law);
        if let (Some(e0), Some(v0)) = (get("limit e"), get("limit v")) {
            let branch = if name.starts_with("prolate") {
                Some(crate::analysis::axisym::Branch::Prolate)
            } else if name.starts_with("oblate") {
                Some(crate::analysis::axisym::Branch::Oblate)
            } else {
                None
            };
            let reference = branch
                .and_then(|b| {
                    crate::analysis::axisym::solve(
                        b,
                        v0.value,
                        &crate::analysis::axisym::Options::default(),
                    )
                    .ok()
                })
                .map_or(f64::NAN, |sol| sol.e);
            let _ = writeln!(
                s,
                "{name}: extrapolated to eps/R0 -> 0: v = {:.5}, e = {:.5}; sharp-interface e at that v = {reference:.5} (difference {:.2e})",
                v0.value,
                e0.value,
                e0.value - reference
            );
        }
    }
    s
}

/// A fitted law's legend text and its function.
type Law = Option<(String, Box<dyn Fn(f64) -> f64>)>;

/// The marker shape of the `i`-th series.
fn shape(i: usize) -> Shape {
    [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ][i % 4]
}

/// Markers for `pts` and the fitted law drawn dashed in the same colour over `fitted` (the x
/// range of the points above the floor: the law is not drawn through the floor).
fn with_fit(
    fig: &mut Figure,
    i: usize,
    name: &str,
    pts: Vec<(f64, f64)>,
    fitted: &[f64],
    law: Law,
) {
    if let Some((label, f)) = law {
        let (lo, hi) = fitted
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(*x), b.max(*x))
            });
        let line = (0..=20)
            .map(|k| lo * (hi / lo).powf(k as f64 / 20.0))
            .map(|x| (x, f(x)))
            .collect();
        fig.push(Series::new(label, line, colour(i), Mark::Dashed));
    }
    fig.push(Series::new(name, pts, colour(i), Mark::Points(shape(i))));
}

/// Slope guides of the orders `ps` on a log-log figure: through a point a factor 3 below the
/// lowest error at the coarsest x of the fitted series (those drawn as markers only; not a
/// control at its floor), spanning the figure's x range; each its own grey.
fn guides(fig: &mut Figure, ps: &[f64]) {
    let pts: Vec<(f64, f64)> = fig
        .series
        .iter()
        .filter(|s| matches!(s.mark, Mark::Points(_)))
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .collect();
    let (lo, hi) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let y = pts
        .iter()
        .filter(|p| p.0 >= hi * (1.0 - 1e-9))
        .fold(f64::INFINITY, |m, p| m.min(p.1));
    if !(lo < hi && y.is_finite()) {
        return;
    }
    let greys = [GUIDE, [40, 40, 40], [170, 170, 170]];
    for (k, &p) in ps.iter().enumerate() {
        fig.push(slope_guide(
            p,
            (hi, y / 3.0),
            lo,
            hi,
            greys[k % greys.len()],
        ));
    }
}

/// The power law through `(x, e)` with its legend (its fitted slope).
fn power_law(x: &[f64], e: &[f64]) -> Law {
    fit::power(x, e).map(|f| {
        (
            format!("fit: slope {:.2}", f.order()),
            Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
        )
    })
}

/// The charts: error against Δt, h (log-log and semi-log) and ε/R0 (the sphere apart), each
/// series with its fitted law and slope guides.
fn charts(report: &mut Report, rows: &[Row]) {
    let mut time = Figure::new(
        "Temporal convergence: error at fixed t against dt",
        Axis::log("dt [time units]"),
        Axis::log("max |phi - phi_ref|"),
    );
    time.legend = Corner::LowerRight;
    for (i, (name, rs)) in series_of(rows, "time").into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = rs.iter().map(|r| (r.x, r.error)).collect();
        let (x, e) = resolved(&rs, |r| r.error);
        with_fit(&mut time, i, name, pts, &x, power_law(&x, &e));
    }
    guides(&mut time, &[1.0, 2.0]);
    report.chart("convergence_time", time);

    let mut space = Figure::new(
        "Spatial convergence at fixed eps: stationary e",
        Axis::log("h / eps"),
        Axis::log("|e(h) - e_ref|"),
    );
    space.legend = Corner::LowerRight;
    let mut semilog = Figure::new(
        "Spatial convergence, semi-log: spectral is a straight line",
        Axis::linear("eps / h"),
        Axis::log("|e(h) - e_ref|"),
    );
    semilog.legend = Corner::UpperRight;
    for (i, (name, rs)) in series_of(rows, "space").into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = rs.iter().map(|r| (r.x, r.error)).collect();
        let semi: Vec<(f64, f64)> = pts.iter().map(|&(h, e)| (1.0 / h, e)).collect();
        let (x, e) = resolved(&rs, |r| r.error);
        let inv: Vec<f64> = x.iter().map(|h| 1.0 / h).collect();
        if name.starts_with("FD") {
            with_fit(&mut space, i, name, pts, &x, power_law(&x, &e));
            semilog.push(Series::new(
                name,
                semi,
                colour(i),
                Mark::LinePoints(shape(i)),
            ));
        } else {
            let law = fit::exponential(&inv, &e).map(|f| {
                (
                    format!("fit: exp({:.2} eps/h)", f.line.slope),
                    Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
                )
            });
            with_fit(&mut semilog, i, name, semi, &inv, law);
            space.push(Series::new(
                name,
                pts,
                colour(i),
                Mark::LinePoints(shape(i)),
            ));
        }
    }
    guides(&mut space, &[2.0]);
    report.chart("convergence_space", space);
    report.chart("convergence_space_semilog", semilog);

    let mut eps = Figure::new(
        "Phase-field error against eps/R0 (v on the phi = 0 surface)",
        Axis::log("eps / R0"),
        Axis::log("|e - e_ref(v)|"),
    );
    eps.legend = Corner::LowerRight;
    let mut sphere = Figure::new(
        "Control: sphere, c0 = 0 (|e - 1| at the stop tolerance's floor: no law fitted)",
        Axis::linear("R0 / eps"),
        Axis::log("|e - 1|"),
    );
    sphere.legend = Corner::UpperRight;
    for (i, (name, rs)) in series_of(rows, "eps").into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = rs.iter().map(|r| (r.x, r.error.abs())).collect();
        let (x, e) = resolved(&rs, |r| r.error.abs());
        let enough = x.len() >= 3;
        if name == "sphere" {
            let inv: Vec<f64> = x.iter().map(|v| 1.0 / v).collect();
            let semi = pts.iter().map(|&(x, e)| (1.0 / x, e)).collect();
            let law = fit::exponential(&inv, &e).filter(|_| enough).map(|f| {
                (
                    format!("fit: exp({:.2} R0/eps)", f.line.slope),
                    Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
                )
            });
            if law.is_some() {
                sphere.title = "Control: sphere, c0 = 0".into();
            }
            with_fit(&mut sphere, i, name, semi, &inv, law);
            eps.push(Series::new(
                name,
                pts,
                colour(i),
                Mark::LinePoints(Shape::Cross),
            ));
        } else {
            let law = if enough { power_law(&x, &e) } else { None };
            with_fit(&mut eps, i, name, pts, &x, law);
        }
    }
    guides(&mut eps, &[1.0, 2.0]);
    report.chart("convergence_eps", eps);
    report.chart("convergence_sphere", sphere);
}
