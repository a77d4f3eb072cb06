//! `vesicle study resolution FILE`: speed against accuracy for stationary shapes. For each
//! shape of the file (started from the axisymmetric reference as a diagram case is:
//! [`super::shape_case`]) and each route, the relative error of the reduced energy against the
//! sharp-interface reference at the reduced volume reached, |e − e_ref(v)|/e_ref(v)
//! (`e_ref` from [`crate::analysis::axisym`], the diagram's reference), and the wall time:
//!
//! * **L-BFGS** at each (h/ε, R0/ε) to the file's residual;
//! * **extrapolated**: at each h/ε, every pair and every three consecutive R0 of the L-BFGS
//!   cases, (v, e) fitted as v∞ + c x^p, e∞ + c' x^p in x = ε/R0 at the file's order p
//!   ([`crate::analysis::curves::power_fit`]); its wall time is the sum of its cases';
//! * **SBDF2 adaptive** (if the file asks): the conserved flow from the same start to the same
//!   residual.
//!
//! Each route's error is given with what the lattice may add at its h (the pinning bound of
//! [`crate::problem::pinning`], relative to e_ref, times Σ|w_i| for an extrapolation
//! e∞ = Σ w_i e_i): at h = ε a lucky extrapolation can land within 1e-4 of the reference, but
//! another R0 would not. The Pareto front (error + pinning against wall time) per shape, and
//! for each error level the cheapest route whose error + pinning is below it on every shape
//! ("for 0.1% use …, it costs … s"). Writes
//! `resolution.txt`, `routes.csv`, `levels.csv` and the chart `resolution` (log–log).

pub mod spec;

use super::harness::{Report, Study};
use super::levels::pareto;
use super::shape_case::{self, Placement, Start};
use super::table::{self, Column, Format, Row};
use crate::analysis::curves::power_fit;
use crate::error::{Error, Result};
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use serde_json::json;
pub use spec::Spec;
use std::path::Path;

/// One route on one shape; a row of `routes.csv`.
#[derive(Clone, Debug)]
pub struct Route {
    /// The shape (`prolate v0 = 0.75`).
    pub shape: String,
    /// `L-BFGS`, `extrapolated` or `SBDF2 adaptive`.
    pub route: &'static str,
    /// h/ε.
    pub h_over_eps: f64,
    /// R0/ε of its cases (`16`, `16+24`).
    pub r0: String,
    /// Reduced volume reached (extrapolated: v∞).
    pub v: f64,
    /// Reduced energy (extrapolated: e∞).
    pub e: f64,
    /// The sharp reference's e at `v`.
    pub e_ref: f64,
    /// |e − e_ref|/e_ref.
    pub error: f64,
    /// What the lattice may add to `error` at this h ([`crate::problem::pinning::bound`]
    /// relative to e_ref; for an extrapolation times Σ|w_i|, the weights of its cases' e in
    /// e∞ = Σ w_i e_i).
    pub pinning: f64,
    /// Wall seconds (extrapolated: the sum of its cases').
    pub wall: f64,
    /// Iterations or steps (extrapolated: summed).
    pub iterations: usize,
}

impl Route {
    /// The error one can count on: the measured error plus what the lattice may add.
    pub fn bound(&self) -> f64 {
        self.error + self.pinning
    }

    /// The configuration, without the shape: `L-BFGS h/eps = 0.5, R0 = 16+24`.
    pub fn config(&self) -> String {
        format!(
            "{} h/eps = {}, R0 = {}",
            self.route,
            short(self.h_over_eps),
            self.r0
        )
    }
}

/// h/ε as a short fraction (`1`, `2/3`, `1/2`, `1/3`) or a number.
fn short(h: f64) -> String {
    for (num, den) in [(1, 1), (2, 3), (1, 2), (1, 3), (1, 4), (3, 4)] {
        if (h - num as f64 / den as f64).abs() < 1e-9 {
            return if den == 1 {
                num.to_string()
            } else {
                format!("{num}/{den}")
            };
        }
    }
    format!("{h:.4}")
}

impl Row for Route {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("shape", "shape", Format::Plain, |r| r.shape.as_str().into()),
            Column::both("route", "route", Format::Plain, |r| r.route.into()),
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| {
                r.h_over_eps.into()
            }),
            Column::both("r0", "R0/eps", Format::Plain, |r| r.r0.as_str().into()),
            Column::both("v", "v", Format::Fixed(5), |r| r.v.into()),
            Column::both("e", "e", Format::Fixed(6), |r| r.e.into()),
            Column::both("e_ref", "e_ref(v)", Format::Fixed(6), |r| r.e_ref.into()),
            Column::both("error", "|e - e_ref|/e_ref", Format::Sci(2), |r| {
                r.error.into()
            }),
            Column::both("pinning", "+ pinning", Format::Sci(2), |r| r.pinning.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(2), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
            Column::both("iterations", "iterations", Format::Plain, |r| {
                r.iterations.into()
            }),
        ]
    }
}

/// The cheapest configuration that reaches an error level on every shape; a row of
/// `levels.csv`.
#[derive(Clone, Debug)]
pub struct Level {
    /// The relative error level.
    pub level: f64,
    /// The configuration (empty: none reaches it).
    pub config: String,
    /// Its largest error plus pinning ([`Route::bound`]) over the shapes.
    pub error: f64,
    /// Its largest wall time over the shapes.
    pub wall: f64,
}

impl Row for Level {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("level", "level", Format::Sci(0), |r| r.level.into()),
            Column::both(
                "config",
                "cheapest on every shape",
                Format::Plain,
                |r: &Self| r.config.as_str().into(),
            )
            .or("not reached"),
            Column::both("error", "worst error + pinning", Format::Sci(2), |r| {
                r.error.into()
            }),
            Column::both("wall_seconds", "wall", Format::Fixed(2), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// What the study returns.
#[derive(Clone, Debug)]
pub struct Output {
    /// Every route on every shape.
    pub routes: Vec<Route>,
    /// The cheapest configuration per level.
    pub levels: Vec<Level>,
}

/// The study.
pub struct ResolutionStudy;

impl Study for ResolutionStudy {
    const NAME: &'static str = "resolution";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Output, Report)> {
        spec.validate()?;
        let starts = shape_case::starts(
            &spec.shapes,
            "shapes",
            spec.r0_min(),
            spec.relaxation.min_width,
        )?;
        let mut routes = Vec::new();
        for start in &starts {
            routes.extend(shape_routes(start, spec)?);
        }
        let levels = levels(&routes, &spec.levels, starts.len());
        let mut text = String::from("== every route ==\n");
        text.push_str(&table::text(&routes));
        for start in &starts {
            let label = start.label();
            text.push_str(&format!(
                "\nPareto front, {label} (wall [s], error + pinning):"
            ));
            for (w, e) in front(&routes, &label) {
                text.push_str(&format!(" ({w:.2}, {e:.2e})"));
            }
            text.push('\n');
        }
        text.push_str(
            "\n== the cheapest configuration to each error level, on every shape (the measured \
             error plus what the lattice may add at its h: the error one can count on) ==\n",
        );
        text.push_str(&table::text(&levels));
        for l in &levels {
            if !l.config.is_empty() {
                text.push_str(&format!(
                    "for {:.2}% use {}: it costs {:.2} s (worst error + pinning {:.3}%)\n",
                    l.level * 100.0,
                    l.config,
                    l.wall,
                    l.error * 100.0
                ));
            }
        }
        let mut report = Report {
            text,
            ..Report::default()
        };
        report.table("routes.csv", &routes)?;
        report.table("levels.csv", &levels)?;
        report.chart("resolution", chart(&routes, &starts));
        Ok((Output { routes, levels }, report))
    }
}

/// Every route on `start`.
fn shape_routes(start: &Start, spec: &Spec) -> Result<Vec<Route>> {
    let label = start.label();
    let mut routes = Vec::new();
    let mut r0 = spec.r0.clone();
    r0.sort_by(f64::total_cmp);
    let row = |route: &'static str,
               h_over_eps: f64,
               r0: String,
               v: f64,
               e: f64,
               wall: f64,
               iterations: usize,
               amplification: f64|
     -> Result<Route> {
        let e_ref = shape_case::e_ref(start, v)?;
        let pinning = amplification * crate::problem::pinning::bound(h_over_eps).value() / e_ref;
        Ok(Route {
            shape: label.clone(),
            route,
            h_over_eps,
            r0,
            v,
            e,
            e_ref,
            error: (e - e_ref).abs() / e_ref,
            pinning,
            wall,
            iterations,
        })
    };
    let case = |eps_over_h: f64, r0: f64, patch: Option<&serde_json::Value>| {
        let at = Placement::centred(r0, eps_over_h);
        let r = shape_case::relax(start, at, &spec.relaxation, patch)
            .map_err(|e| e.within(&format!("{label}, R0 = {r0}, h = eps/{eps_over_h}")))?;
        if !r.converged {
            return Err(Error::config(
                "relaxation.max_iterations",
                format!(
                    "{label} at R0 = {r0} ε, h = ε/{eps_over_h} did not reach the residual {:e} \
                     (residual {:.2e} after {} steps)",
                    spec.relaxation.stop_residual, r.residual, r.iterations
                ),
            ));
        }
        eprintln!(
            "resolution: {label} h/eps {:.4} R0 {r0}{}: e {:.6} v {:.5} ({} steps, {:.1} s)",
            1.0 / eps_over_h,
            if patch.is_some() { " SBDF2" } else { "" },
            r.e,
            r.v,
            r.iterations,
            r.wall
        );
        Ok(r)
    };
    for &eps_over_h in &spec.eps_over_h {
        let h = 1.0 / eps_over_h;
        let mut done = Vec::new();
        for &r in &r0 {
            let at = Placement::centred(r, eps_over_h);
            if spec
                .max_points
                .is_some_and(|m| shape_case::points(start, at, &spec.relaxation) > m)
            {
                continue;
            }
            let c = case(eps_over_h, r, None)?;
            routes.push(row(
                "L-BFGS",
                h,
                r.to_string(),
                c.v,
                c.e,
                c.wall,
                c.iterations,
                1.0,
            )?);
            done.push((r, c));
        }
        let mut sets: Vec<Vec<usize>> = Vec::new();
        for i in 0..done.len() {
            for j in i + 1..done.len() {
                sets.push(vec![i, j]);
            }
        }
        for i in 0..done.len().saturating_sub(2) {
            sets.push(vec![i, i + 1, i + 2]);
        }
        for set in sets {
            let x: Vec<f64> = set.iter().map(|&k| 1.0 / done[k].0).collect();
            let v: Vec<f64> = set.iter().map(|&k| done[k].1.v).collect();
            let e: Vec<f64> = set.iter().map(|&k| done[k].1.e).collect();
            let name: Vec<String> = set.iter().map(|&k| done[k].0.to_string()).collect();
            let wall = set.iter().map(|&k| done[k].1.wall).sum();
            let iterations = set.iter().map(|&k| done[k].1.iterations).sum();
            let (v_inf, e_inf) = (
                power_fit(spec.order, &x, &v).0,
                power_fit(spec.order, &x, &e).0,
            );
            // e∞ is linear in the cases' e: its weights are the fits of the unit vectors.
            let amplification: f64 = (0..x.len())
                .map(|i| {
                    let unit: Vec<f64> =
                        (0..x.len()).map(|k| f64::from(u8::from(k == i))).collect();
                    power_fit(spec.order, &x, &unit).0.abs()
                })
                .sum();
            routes.push(row(
                "extrapolated",
                h,
                name.join("+"),
                v_inf,
                e_inf,
                wall,
                iterations,
                amplification,
            )?);
        }
    }
    if let Some(s) = &spec.sbdf2 {
        let patch = json!({
            "dynamics": "conserved",
            "scheme": "sbdf2",
            "max_steps": s.max_steps,
            "adaptive": {"energy_alpha": s.energy_alpha, "dt_max": s.dt_max}
        });
        for &eps_over_h in &s.eps_over_h {
            for &r in &s.r0 {
                let c = case(eps_over_h, r, Some(&patch))?;
                routes.push(row(
                    "SBDF2 adaptive",
                    1.0 / eps_over_h,
                    r.to_string(),
                    c.v,
                    c.e,
                    c.wall,
                    c.iterations,
                    1.0,
                )?);
            }
        }
    }
    Ok(routes)
}

/// The Pareto front (wall, error) of the routes on the shape `label`.
fn front(routes: &[Route], label: &str) -> Vec<(f64, f64)> {
    pareto(
        routes
            .iter()
            .filter(|r| r.shape == label && r.wall > 0.0 && r.bound() > 0.0)
            .map(|r| (r.wall, r.bound()))
            .collect(),
    )
}

/// For each level, the configuration run on all `shapes` shapes whose largest error is below
/// the level, with the least largest wall time.
fn levels(routes: &[Route], levels: &[f64], shapes: usize) -> Vec<Level> {
    let mut configs: Vec<(String, f64, f64, usize)> = Vec::new();
    for r in routes {
        let c = r.config();
        match configs.iter_mut().find(|k| k.0 == c) {
            Some(k) => {
                k.1 = k.1.max(r.bound());
                k.2 = k.2.max(r.wall);
                k.3 += 1;
            }
            None => configs.push((c, r.bound(), r.wall, 1)),
        }
    }
    let mut levels = levels.to_vec();
    levels.sort_by(|a, b| b.total_cmp(a));
    levels
        .into_iter()
        .map(|level| {
            configs
                .iter()
                .filter(|k| k.3 == shapes && k.1 < level)
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .map_or(
                    Level {
                        level,
                        config: String::new(),
                        error: f64::NAN,
                        wall: f64::NAN,
                    },
                    |k| Level {
                        level,
                        config: k.0.clone(),
                        error: k.1,
                        wall: k.2,
                    },
                )
        })
        .collect()
}

/// Error against wall time: per shape and route a marker series, and each shape's Pareto front.
fn chart(routes: &[Route], starts: &[Start]) -> Figure {
    let mut fig = Figure::new(
        "Stationary shapes: error of e against the sharp reference, against wall time",
        Axis::log("wall time [s]"),
        Axis::log("|e - e_ref(v)| / e_ref(v)"),
    );
    fig.legend = Corner::LowerLeft;
    let kinds = [
        ("L-BFGS", Shape::Circle),
        ("extrapolated", Shape::Square),
        ("SBDF2 adaptive", Shape::Triangle),
    ];
    for (i, start) in starts.iter().enumerate() {
        let label = start.label();
        for (j, (route, shape)) in kinds.iter().enumerate() {
            let pts: Vec<(f64, f64)> = routes
                .iter()
                .filter(|r| r.shape == label && r.route == *route && r.wall > 0.0 && r.error > 0.0)
                .map(|r| (r.wall, r.error))
                .collect();
            if !pts.is_empty() {
                fig.push(Series::new(
                    format!("{label}: {route}"),
                    pts,
                    colour(i * kinds.len() + j),
                    Mark::Points(*shape),
                ));
            }
        }
        fig.push(Series::new(
            format!("{label}: Pareto front of error + pinning"),
            front(routes, &label),
            colour(i * kinds.len()),
            Mark::Dashed,
        ));
    }
    fig
}
