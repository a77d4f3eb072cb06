//! The stability study's report: the frontier (largest stable Δt of each method at each h,
//! `frontier.csv`), every run (`stability.csv`), the printed tables, ratios and fits, and the
//! charts `stability_map` and `stability_alpha`.

use super::measure::{Bounds, Run, METHODS};
use super::spec::Spec;
use crate::commands::study::classify::Class;
use crate::commands::study::fit;
use crate::commands::study::harness::Report;
use crate::commands::study::table::{self, Column, Format, Row};
use crate::error::Result;
use crate::output::chart::{Axis, Corner, Figure, Mark, Series, Shape};
use std::fmt::Write as _;

/// The report of the runs `runs` of `spec`, with the FD bound at each h `bounds` and the
/// scene's `(dim, ε)` (the bound's curve on the map).
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn report(spec: &Spec, runs: &[Run], bounds: &Bounds, scene: (usize, f64)) -> Result<Report> {
    let frontier = frontier(runs, bounds);
    let mut report = Report {
        text: text(runs, &frontier, bounds, spec),
        ..Report::default()
    };
    report.table("stability.csv", runs)?;
    report.table("frontier.csv", &frontier)?;
    charts(&mut report, runs, &frontier, bounds, scene);
    Ok(report)
}

impl Row for Run {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("sweep", |r| r.sweep.into()),
            Column::csv("method", |r| r.method.into()),
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| r.h.into()),
            Column::both("dt", "dt", Format::Sci(3), |r| r.dt.into()),
            Column::both("alpha", "alpha", Format::Sci(1), |r| r.alpha.into()),
            Column::both("class", "class", Format::Plain, |r| r.class.as_str().into()),
            Column::both("steps", "steps", Format::Plain, |r| r.steps.into()),
            Column::both("rejected", "rejected", Format::Plain, |r| r.rejected.into()),
            Column::csv("max_abs_phi", |r| r.max_phi.into()),
            Column::csv("max_area_error", |r| r.area_error.into()),
            Column::text("median rejected dt", Format::Sci(3), |r| {
                median(&r.rejected_dts).into()
            }),
        ]
    }
}

/// The median of `xs` (the upper one of an even count; NaN if empty).
fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Where a sweep in increasing Δt stops being stable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// The last stable Δt below the first failure (`None`: the first Δt fails).
    pub largest_stable: Option<f64>,
    /// The first failure's Δt and class (`None`: no failure in the sweep).
    pub first_failure: Option<(f64, Class)>,
}

impl Edge {
    /// The edge of runs `(Δt, class)` in increasing Δt.
    pub fn of(runs: impl Iterator<Item = (f64, Class)>) -> Self {
        let mut largest_stable = None;
        for (dt, class) in runs {
            if class != Class::Stable {
                return Edge {
                    largest_stable,
                    first_failure: Some((dt, class)),
                };
            }
            largest_stable = Some(dt);
        }
        Edge {
            largest_stable,
            first_failure: None,
        }
    }

    /// The largest stable Δt (NaN: none).
    pub fn largest_dt(&self) -> f64 {
        self.largest_stable.unwrap_or(f64::NAN)
    }

    /// The first failure's Δt (NaN: none).
    pub fn failure_dt(&self) -> f64 {
        self.first_failure.map_or(f64::NAN, |p| p.0)
    }

    /// The first failure's class (`none`: none).
    pub fn failure_class(&self) -> &'static str {
        self.first_failure.map_or("none", |p| p.1.as_str())
    }
}

/// The edge of one fixed method at one h; a row of `frontier.csv`.
pub struct Frontier {
    /// The method's name.
    pub method: &'static str,
    /// h/ε.
    pub h: f64,
    /// Its largest stable Δt and first failure.
    pub edge: Edge,
    /// The FD bound at this h.
    pub fd_bound: f64,
}

impl Row for Frontier {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("method", "method", Format::Plain, |r| r.method.into()),
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| r.h.into()),
            Column::both(
                "largest_stable_dt",
                "largest stable dt",
                Format::Sci(3),
                |r: &Self| r.edge.largest_dt().into(),
            )
            .or("none"),
            Column::both(
                "first_failure_dt",
                "first failure dt",
                Format::Sci(3),
                |r: &Self| r.edge.failure_dt().into(),
            )
            .or("none"),
            Column::both("first_failure_class", "its class", Format::Plain, |r| {
                r.edge.failure_class().into()
            }),
            Column::both("fd_bound", "FD bound", Format::Sci(4), |r| {
                r.fd_bound.into()
            }),
        ]
    }
}

/// The edge of every fixed method (in the order of [`METHODS`]) at each h of `bounds`.
fn frontier(runs: &[Run], bounds: &Bounds) -> Vec<Frontier> {
    let mut f = Vec::new();
    for name in METHODS.map(|m| m.name) {
        for &(h, fd_bound) in bounds {
            let rs = runs
                .iter()
                .filter(|r| r.sweep == "fixed" && r.method == name && r.h == h);
            f.push(Frontier {
                method: name,
                h,
                edge: Edge::of(rs.map(|r| (r.dt, r.class))),
                fd_bound,
            });
        }
    }
    f
}

/// The largest stable Δt of the method `name` at `h`.
fn largest(f: &[Frontier], name: &str, h: f64) -> Option<f64> {
    f.iter()
        .find(|x| x.method == name && x.h == h)
        .and_then(|x| x.edge.largest_stable)
}

/// The printed report: the frontier, the spectral/FD ratios and their fits in h, the adaptive
/// runs, the largest stable α of the Lagrangian update at each Δt.
fn text(runs: &[Run], f: &[Frontier], bounds: &Bounds, spec: &Spec) -> String {
    let mut s = format!(
        "{} fixed steps per run, dt from {:.1e} to {:.1e} ({} per decade), from the prepared field\n\
         classes: stable (and energy-decreasing); energy rising (F_eff at the step's sigma rose > 1e-10 relative); \
         constraint lost (a V or A guard failed, or |A - A0|/A0 > 1e-3); blown up (diverged or max|phi| > 1.5)\n\n",
        spec.steps, spec.dt_min, spec.dt_max, spec.per_decade,
    );
    s.push_str(&table::text(f));
    let _ = writeln!(s, "\nspectral / FD largest stable dt:");
    for name in METHODS.map(|m| m.name).into_iter().skip(1) {
        let mut hs = Vec::new();
        let mut ratios = Vec::new();
        for &h in &spec.h {
            if let (Some(a), Some(b)) = (largest(f, name, h), largest(f, "FD explicit Euler", h)) {
                hs.push(h);
                ratios.push(a / b);
            }
        }
        let list: Vec<String> = hs
            .iter()
            .zip(&ratios)
            .map(|(h, r)| format!("h = {h}: {r:.3e}"))
            .collect();
        let scaling =
            fit::power(&hs, &ratios).map_or(String::new(), |p| format!("; ratio ∝ h^p, {p}"));
        let _ = writeln!(s, "  {name:<18} {}{scaling}", list.join(", "));
    }
    for name in METHODS.map(|m| m.name) {
        let (hs, dts): (Vec<f64>, Vec<f64>) = spec
            .h
            .iter()
            .filter_map(|&h| largest(f, name, h).map(|d| (h, d)))
            .unzip();
        if let Some(p) = fit::power(&hs, &dts) {
            let _ = writeln!(s, "  largest stable dt of {name} ∝ h^p: {p}");
        }
    }
    let _ = writeln!(
        s,
        "\nadaptive SBDF1 to t = {} (dt_max {}): dt the median accepted dt, alpha the controller's energy_alpha",
        spec.adaptive.t_end, spec.adaptive.dt_max,
    );
    s.push_str(&table::text(runs.iter().filter(|r| r.sweep == "adaptive")));
    let _ = writeln!(
        s,
        "\nLagrangian area update (FD, h = {}): largest stable alpha against dt",
        spec.h[0]
    );
    let bound = bounds[0].1;
    for &frac in &spec.alpha.dt_fractions {
        let rs: Vec<&Run> = runs
            .iter()
            .filter(|r| r.sweep == "alpha" && (r.dt / bound - frac).abs() < 1e-9)
            .collect();
        let first = rs
            .iter()
            .position(|r| r.class != Class::Stable)
            .unwrap_or(rs.len());
        let best = first
            .checked_sub(1)
            .map_or("none".into(), |i| format!("{:.3e}", rs[i].alpha));
        let dt = frac * bound;
        let _ = writeln!(
            s,
            "  dt = {dt:.3e} ({frac} of the bound): largest stable alpha {best}"
        );
    }
    s
}

/// Colour of a class on the map.
pub(super) fn class_colour(c: Class) -> [u8; 3] {
    match c {
        Class::Stable => [44, 160, 44],
        Class::EnergyRising => [255, 165, 0],
        Class::ConstraintLost => [148, 103, 189],
        Class::BlownUp => [214, 39, 40],
    }
}

/// Colours of the measured frontiers: none of them a class's colour.
pub(super) const FRONTIER: [[u8; 3]; 3] = [[31, 119, 180], [140, 86, 75], [23, 190, 207]];

/// The charts `stability_map` (every fixed run by method and class, the FD bound, the measured
/// frontiers, the adaptive runs' rejected attempts) and `stability_alpha`.
fn charts(
    report: &mut Report,
    runs: &[Run],
    f: &[Frontier],
    bounds: &[(f64, f64)],
    (dim, eps): (usize, f64),
) {
    let mut map = Figure::new(
        "Stability map: fixed dt against h (markers by method, colour by class)",
        Axis::log("h / eps (methods offset sideways)"),
        Axis::log("dt [time units]"),
    );
    map.legend = Corner::LowerRight;
    let offset = |i: usize| 1.12f64.powf(i as f64 - (METHODS.len() as f64 - 1.0) / 2.0);
    for (i, m) in METHODS.iter().enumerate() {
        for class in Class::ALL {
            let pts: Vec<(f64, f64)> = runs
                .iter()
                .filter(|r| r.sweep == "fixed" && r.method == m.name && r.class == class)
                .map(|r| (r.h * offset(i), r.dt))
                .collect();
            map.push(Series::new("", pts, class_colour(class), Mark::Points(m.shape)).unlisted());
        }
        map.push(Series::new(
            m.name,
            Vec::new(),
            [90, 90, 90],
            Mark::Points(m.shape),
        ));
    }
    for class in Class::ALL {
        map.push(Series::new(
            class.as_str(),
            Vec::new(),
            class_colour(class),
            Mark::Line,
        ));
    }
    let (lo, hi) = bounds.iter().fold((f64::INFINITY, 0.0f64), |(a, b), x| {
        (a.min(x.0), b.max(x.0))
    });
    let curve: Vec<(f64, f64)> = (0..=40)
        .map(|k| lo / 1.5 * (1.5 * 1.5 * hi / lo).powf(k as f64 / 40.0))
        .map(|h| (h, fd_bound(dim, h * eps, eps)))
        .collect();
    map.push(Series::new(
        "FD bound 1/(λ(2 + ε²λ)²), λ = 4d/h²",
        curve,
        [0, 0, 0],
        Mark::Dashed,
    ));
    for (i, name) in ["SBDF1, default S", "SBDF2, default S", "SBDF1, S = 0"]
        .into_iter()
        .enumerate()
    {
        let pts: Vec<(f64, f64)> = f
            .iter()
            .filter(|x| x.method == name)
            .filter_map(|x| x.edge.largest_stable.map(|d| (x.h, d)))
            .collect();
        map.push(Series::new(
            format!("measured frontier, {name}"),
            pts,
            FRONTIER[i],
            Mark::Line,
        ));
    }
    let rejected: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.sweep == "adaptive")
        .flat_map(|r| r.rejected_dts.iter().map(move |d| (r.h * 1.35, *d)))
        .collect();
    map.push(Series::new(
        "adaptive SBDF1: rejected attempts",
        rejected,
        [0, 0, 0],
        Mark::Points(Shape::Cross),
    ));
    report.chart("stability_map", map);

    let mut alpha = Figure::new(
        "Lagrangian area update (FD): stable alpha against dt",
        Axis::log("dt [time units]"),
        Axis::log("alpha"),
    );
    alpha.legend = Corner::LowerLeft;
    for class in Class::ALL {
        let pts: Vec<(f64, f64)> = runs
            .iter()
            .filter(|r| r.sweep == "alpha" && r.class == class)
            .map(|r| (r.dt, r.alpha))
            .collect();
        alpha.push(Series::new(
            class.as_str(),
            pts,
            class_colour(class),
            Mark::Points(Shape::Circle),
        ));
    }
    report.chart("stability_alpha", alpha);
}

/// The FD bound of docs/src/theory/fd.md at σ = 0: Δt = 1 / (λ (2 + ε²λ)²), λ = 4d/h² (the curve on
/// the map; [`crate::engines::fd::stability_bound`] gives the same at the computed grids).
fn fd_bound(dim: usize, h: f64, eps: f64) -> f64 {
    let l = 4.0 * dim as f64 / (h * h);
    1.0 / (l * (2.0 + eps * eps * l).powi(2))
}
