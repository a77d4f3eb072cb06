//! The stationary study's report: the printed tables and `stationary.csv` (each spectral route
//! at each `stop_residual`), `traces.csv` (every route's error against wall time, thinned),
//! `levels.csv` (the fastest spectral and FD route to each error level), and the charts
//! `convergence`, `residual` and `stationary_pareto`.

use super::measure::{Family, Measurement, Point, Route};
use super::spec::Plan;
use crate::commands::study::harness::Report;
use crate::commands::study::levels::{pareto, Level};
use crate::commands::study::table::{self, Column, Format, Row};
use crate::error::Result;
use crate::output::chart::{style, Axis, Corner, Figure, Mark, Series};
use crate::problem::config::Scene;
use std::fmt::Write as _;

/// The tolerance the guide recommends for stationary shapes (energy within 1e-6).
const RECOMMENDED: f64 = 1e-6;
/// The relative energy error of the speed target (the conserved flow's stationary energy to
/// 1e-6).
const ENERGY_TARGET: f64 = 1e-6;

/// The report of `study`, measured on `scene` by `plan`.
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn report(study: &Measurement, scene: &Scene, plan: &Plan) -> Result<Report> {
    let crossings = crossings(study, plan);
    let levels = levels(study, plan);
    let mut report = Report {
        text: text(study, scene, plan, &crossings, &levels),
        ..Report::default()
    };
    report.table("stationary.csv", &crossings)?;
    report.table("traces.csv", &traces(study))?;
    report.table("levels.csv", &levels)?;
    charts(&mut report, study);
    Ok(report)
}

/// A spectral route's first state below a `stop_residual`: what a run with that stop rule
/// gives; a row of `stationary.csv`.
struct Crossing<'a> {
    route: &'a str,
    stop_residual: f64,
    at: Point,
    /// (F − F*)/F*.
    relative_energy_error: f64,
}

impl Row for Crossing<'_> {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("route", "route", Format::Plain, |r| r.route.into()),
            Column::both("stop_residual", "stop_residual", Format::Sci(0), |r| {
                r.stop_residual.into()
            }),
            Column::both("steps", "steps", Format::Plain, |r| r.at.steps.into()),
            Column::both("evaluations", "evals", Format::Plain, |r| {
                r.at.evaluations.into()
            }),
            Column::csv("t", |r| r.at.t.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(3), |r: &Self| {
                r.at.wall.into()
            })
            .unit("s"),
            Column::csv("residual", |r| r.at.residual.into()),
            Column::csv("energy", |r| r.at.energy.into()),
            Column::both(
                "relative_energy_error",
                "(F - F*)/F*",
                Format::Sci(2),
                |r| r.relative_energy_error.into(),
            ),
        ]
    }
}

/// Every spectral route's crossing of every `stop_residual` it reaches, route by route.
fn crossings<'a>(study: &'a Measurement, plan: &Plan) -> Vec<Crossing<'a>> {
    let spectral = study.routes.iter().filter(|r| r.family == Family::Spectral);
    spectral
        .flat_map(|r| {
            plan.stop_residual.iter().filter_map(|&tol| {
                r.first_below(tol).map(|p| Crossing {
                    route: &r.name,
                    stop_residual: tol,
                    at: *p,
                    relative_energy_error: (p.energy - study.f_star) / study.f_star,
                })
            })
        })
        .collect()
}

/// A route's end state against the reference (printed only).
struct End<'a> {
    route: &'a str,
    at: Point,
    /// (F − F*)/F*.
    relative_energy_error: f64,
    /// max|φ − φ*|.
    max_dphi: f64,
}

impl Row for End<'_> {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::text("route", Format::Plain, |r| r.route.into()),
            Column::text("steps", Format::Plain, |r| r.at.steps.into()),
            Column::text("residual", Format::Sci(2), |r| r.at.residual.into()),
            Column::text("(F - F*)/F*", Format::Sci(2), |r| {
                r.relative_energy_error.into()
            }),
            Column::text("max|phi - phi*|", Format::Sci(2), |r| r.max_dphi.into()),
        ]
    }
}

/// The end state of every spectral route.
fn ends(study: &Measurement) -> Vec<End<'_>> {
    let spectral = study.routes.iter().filter(|r| r.family == Family::Spectral);
    spectral
        .map(|r| End {
            route: &r.name,
            at: *r.end(),
            relative_energy_error: (r.end().energy - study.f_star) / study.f_star,
            max_dphi: r.max_dphi,
        })
        .collect()
}

/// The fastest spectral and FD route to each of the plan's error levels
/// ([`Measurement::fastest`]).
fn levels<'a>(study: &'a Measurement, plan: &Plan) -> Vec<Level<'a>> {
    plan.levels
        .iter()
        .map(|&level| Level {
            part: "stationary",
            level,
            spectral: study.fastest(Family::Spectral, level),
            fd: study.fastest(Family::Fd, level),
        })
        .collect()
}

/// The printed report: the crossings, the tolerances some route does not meet, the ends, the
/// L-BFGS runs, L-BFGS against the first SBDF1 and SBDF2 routes, the FD notes and the levels.
fn text(
    study: &Measurement,
    scene: &Scene,
    plan: &Plan,
    crossings: &[Crossing],
    levels: &[Level],
) -> String {
    let f_star = study.f_star;
    let lbfgs = &study.routes[0];
    let mut s = format!(
        "stationary state of a {}D scene, n = {:?}, eps = {}, h = {}: F* = {:.12e} (L-BFGS end, residual {:.2e})\n\
         the first state of each route below each stop_residual:\n",
        scene.dim,
        scene.n,
        scene.eps,
        scene.h,
        f_star,
        lbfgs.end().residual,
    );
    s.push_str(&table::text(crossings));
    for r in study.routes.iter().filter(|r| r.family == Family::Spectral) {
        let missed: Vec<String> = plan
            .stop_residual
            .iter()
            .filter(|&&tol| r.first_below(tol).is_none())
            .map(|tol| format!("{tol:.0e}"))
            .collect();
        if !missed.is_empty() {
            let _ = writeln!(s, "  not met by {}: {}", r.name, missed.join(", "));
        }
    }
    s.push_str("each route's end:\n");
    s.push_str(&table::text(&ends(study)));
    let walls: Vec<String> = study
        .relax_walls
        .iter()
        .map(|w| format!("{w:.3}"))
        .collect();
    let _ = writeln!(
        s,
        "L-BFGS runs: {} s to the end; the median run is tabulated",
        walls.join(", ")
    );
    against_lbfgs(&mut s, study);
    for n in &study.fd_notes {
        let _ = writeln!(s, "{n}");
    }
    let _ = writeln!(
        s,
        "FD error modelled as |F*_FD - F*|/F* + the conserved flow's error at the same t (the SBDF1 route of tightest control)"
    );
    s.push_str("\nthe fastest route (least wall time) to each |F - F*|/F* level:\n");
    s.push_str(&table::text(levels));
    s
}

/// L-BFGS against the first SBDF1 and SBDF2 routes: evaluations and wall time to
/// `stop_residual` [`RECOMMENDED`], and to the energy error [`ENERGY_TARGET`].
fn against_lbfgs(s: &mut String, study: &Measurement) {
    let lbfgs = &study.routes[0];
    let first = |scheme: &str| {
        study
            .routes
            .iter()
            .find(|r| r.family == Family::Spectral && r.name.contains(scheme))
    };
    let (Some(c1), Some(c2)) = (first("SBDF1"), first("SBDF2")) else {
        return;
    };
    let at = |r: &Route| r.first_below(RECOMMENDED).copied();
    if let (Some(l), Some(a), Some(b)) = (at(lbfgs), at(c1), at(c2)) {
        let _ = writeln!(
            s,
            "to stop_residual {RECOMMENDED:e}: L-BFGS {} evaluations, SBDF1 {}, SBDF2 {}; L-BFGS takes {:.1}x less wall time than SBDF1 and {:.1}x less than SBDF2; SBDF2 {:.1}x less than SBDF1",
            l.evaluations,
            a.evaluations,
            b.evaluations,
            a.wall / l.wall,
            b.wall / l.wall,
            a.wall / b.wall
        );
    }
    let within = |r: &Route| r.first_within(study.f_star, ENERGY_TARGET).copied();
    if let (Some(l), Some(a), Some(b)) = (within(lbfgs), within(c1), within(c2)) {
        let _ = writeln!(
            s,
            "to (F - F*)/F* <= {ENERGY_TARGET:e}: L-BFGS {:.3} s in {} steps, SBDF1 {:.3} s in {}, SBDF2 {:.3} s in {}: L-BFGS {:.1}x less wall time than SBDF1, {:.1}x less than SBDF2",
            l.wall,
            l.steps,
            a.wall,
            a.steps,
            b.wall,
            b.steps,
            a.wall / l.wall,
            b.wall / l.wall
        );
    }
    let _ = writeln!(s, "(SBDF1: {}; SBDF2: {})", c1.name, c2.name);
}

/// A state of a route, thinned; a row of `traces.csv`.
struct Trace<'a> {
    family: Family,
    config: &'a str,
    at: Point,
    /// |F − F*|/F*.
    error: f64,
}

impl Row for Trace<'_> {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("family", |r| r.family.as_str().into()),
            Column::csv("config", |r| r.config.into()),
            Column::csv("t", |r| r.at.t.into()),
            Column::csv("wall_seconds", |r| r.at.wall.into()),
            Column::csv("error", |r| r.error.into()),
            Column::csv("residual", |r| r.at.residual.into()),
        ]
    }
}

/// The states of a trace worth a row: each whose error is at least 10% below the last row's,
/// and the last (a trace has a state per step; this keeps its shape in a small file).
fn thinned(study: &Measurement, trace: &[Point]) -> Vec<Point> {
    let mut last = f64::INFINITY;
    let n = trace.len();
    trace
        .iter()
        .enumerate()
        .filter(|(i, p)| {
            let e = study.error(p);
            let keep = e.is_finite() && (e < 0.9 * last || i + 1 == n);
            if keep {
                last = e;
            }
            keep
        })
        .map(|(_, p)| *p)
        .collect()
}

/// The thinned trace of every route, route by route.
fn traces(study: &Measurement) -> Vec<Trace<'_>> {
    study
        .routes
        .iter()
        .flat_map(|r| {
            thinned(study, &r.trace).into_iter().map(move |p| Trace {
                family: r.family,
                config: &r.name,
                at: p,
                error: study.error(&p),
            })
        })
        .collect()
}

/// The charts: the spectral routes' energy error against wall time (`convergence`) and
/// against the residual (`residual`), and every route's with the Pareto front
/// (`stationary_pareto`).
fn charts(report: &mut Report, study: &Measurement) {
    let spectral: Vec<&Route> = study
        .routes
        .iter()
        .filter(|r| r.family == Family::Spectral)
        .collect();
    for (stem, title, x_axis, x) in [
        (
            "convergence",
            "Energy error against wall time",
            Axis::linear("wall seconds"),
            (|p: &Point| p.wall) as fn(&Point) -> f64,
        ),
        (
            "residual",
            "Energy error against the residual (the error falls as its square)",
            Axis::log("residual RMS(mu - mean mu)"),
            |p: &Point| p.residual,
        ),
    ] {
        let mut fig = Figure::new(title, x_axis, Axis::log("|F - F*| / F*"));
        fig.legend = Corner::UpperRight;
        for (i, r) in spectral.iter().enumerate() {
            let (c, mark) = style(i);
            let pts = r.trace.iter().map(|p| (x(p), study.error(p))).collect();
            fig.push(Series::new(r.name.clone(), pts, c, mark));
        }
        report.chart(stem, fig);
    }

    let mut fig = Figure::new(
        "Stationary state: energy error against wall time (FD extrapolated)",
        Axis::log("wall time [s]"),
        Axis::log("|F - F*| / F*"),
    );
    fig.legend = Corner::LowerRight;
    let traces: Vec<Vec<(f64, f64)>> = study
        .routes
        .iter()
        .map(|r| {
            thinned(study, &r.trace)
                .iter()
                .filter(|p| p.wall > 0.0)
                .map(|p| (p.wall, study.error(p)))
                .collect()
        })
        .collect();
    // The front first, wide and grey, so that the routes on it stay visible.
    fig.push(Series::new(
        "Pareto front (no route faster at that error)",
        pareto(traces.iter().flatten().copied().collect()),
        [190, 190, 190],
        Mark::Dashed,
    ));
    for (i, (r, pts)) in study.routes.iter().zip(traces).enumerate() {
        let (c, mark) = style(i);
        fig.push(Series::new(r.name.clone(), pts, c, mark));
    }
    report.chart("stationary_pareto", fig);
}
