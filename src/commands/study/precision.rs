//! `vesicle study precision FILE`: speed against accuracy on a transient (the 3D prolate), as
//! a Pareto chart. (The stationary side — energy error against wall time on the way to the
//! stationary state — is `vesicle study stationary`, one study for every route there.)
//!
//! * **Transient**: max|φ − φ_ref| at `t` against wall time, from the prepared field, φ_ref from
//!   SBDF2 at `reference_dt`: SBDF1 and SBDF2 at each Δt of `dt`, FD at each fraction of its
//!   bound in `fd_fractions` (its error includes its O(h²) spatial error).
//!
//! For each error level the table gives the fastest spectral and the fastest FD configuration
//! reaching it and the ratio of their wall times. Writes `precision.csv` (every point),
//! `levels.csv`, `precision.txt` and the chart `precision_transient`.

use super::file;
use super::harness::{self, Report, Study};
use super::levels::{pareto, Level};
use super::table::{self, Column, Format, Row};
use crate::driver::simulation::{Simulation, StopRules};
use crate::engines::fd;
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::{AdaptiveSpec, AreaMethod, Method, Scene, Scheme};
use crate::problem::setup::Problem;
use serde::Deserialize;
use serde_json::Value;
use std::path::Path;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"precision"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The scene (a spectral scene; its `prepare_steps` prepare the common start).
    pub scene: Value,
    /// The transient part.
    pub transient: TransientSpec,
}

/// The transient part's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct TransientSpec {
    /// The time at which φ is compared.
    pub t: f64,
    /// Fixed Δt of SBDF1 and SBDF2.
    pub dt: Vec<f64>,
    /// Δt of the SBDF2 reference.
    pub reference_dt: f64,
    /// FD Δt as fractions of its bound.
    pub fd_fractions: Vec<f64>,
    /// Error levels of the table.
    pub levels: Vec<f64>,
}

/// One configuration's point; a row of `precision.csv`.
#[derive(Clone, Debug)]
pub struct Config {
    /// `transient`.
    pub part: &'static str,
    /// `FD` or `spectral`.
    pub family: &'static str,
    /// Name.
    pub name: String,
    /// Simulated time.
    pub t: f64,
    /// Wall seconds of stepping.
    pub wall: f64,
    /// max|φ − φ_ref| at `t`.
    pub error: f64,
    /// RMS(μ − μ̄) (not measured: NaN).
    pub residual: f64,
}

impl Row for Config {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("part", |r| r.part.into()),
            Column::csv("family", |r| r.family.into()),
            Column::both("config", "config", Format::Plain, |r| {
                r.name.as_str().into()
            }),
            Column::csv("t", |r| r.t.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(3), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
            Column::both("error", "max|phi - phi_ref|", Format::Sci(3), |r| {
                r.error.into()
            }),
            Column::csv("residual", |r| r.residual.into()),
        ]
    }
}

/// The study.
pub struct Precision;

impl Study for Precision {
    const NAME: &'static str = "precision";
    type Spec = Spec;
    type Output = Vec<Config>;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Vec<Config>, Report)> {
        let base = file::scene(&spec.scene, &[], "scene", dir)?;
        let mut problem = crate::problem::setup::build(&base)?;
        problem.phi = super::prepared_field(&base, &problem)?;
        let configs = transient(&spec.transient, &base, &problem)?;
        let levels = levels(&configs, &spec.transient.levels);
        let mut report = Report {
            text: text(&configs, &levels),
            ..Report::default()
        };
        report.table("precision.csv", &configs)?;
        report.table("levels.csv", &levels)?;
        report.chart("precision_transient", chart(&configs));
        Ok((configs, report))
    }
}

/// A run's scene: the base scene from the prepared field (no preparation), no area
/// constraint (the reference and every run alike), stopped at `t`.
fn at(base: &Scene, t: f64, edit: impl FnOnce(&mut Scene)) -> Result<Scene> {
    harness::variant(base, "scene", |s| {
        s.prepare_steps = 0;
        s.adaptive = AdaptiveSpec::Flag(false);
        s.t_end = Some(t);
        s.max_steps = None;
        s.stop_residual = None;
        s.area.method = Some(AreaMethod::None);
        s.area.alpha = None;
        edit(s);
    })
}

/// Every configuration of the transient part: max|φ − φ_ref| at `t` and the wall time of
/// SBDF1 and SBDF2 at each Δt and FD at each fraction of its bound, φ_ref from SBDF2 at
/// `reference_dt`.
fn transient(spec: &TransientSpec, base: &Scene, problem: &Problem) -> Result<Vec<Config>> {
    let until = StopRules::until(spec.t);
    let end = |s: &Scene| -> Result<(ndarray::Array3<f64>, f64)> {
        let (mut sim, _) = Simulation::of_scene(s, problem)?;
        sim.run(&until, &mut [])?;
        Ok((sim.engine().phi().clone(), sim.clock.wall_seconds))
    };
    let spectral = |scheme: Scheme, dt: f64| {
        at(base, spec.t, |s| {
            s.method = Method::Spectral;
            s.scheme = scheme;
            s.dt = dt;
        })
    };
    let (reference, _) = end(&spectral(Scheme::Sbdf2, spec.reference_dt)?)?;
    let mut configs = Vec::new();
    let mut one = |family, name: String, s: Scene| -> Result<()> {
        let (phi, wall) = end(&s)?;
        configs.push(Config {
            part: "transient",
            family,
            name,
            t: spec.t,
            wall,
            error: crate::problem::model::max_abs_diff(&phi, &reference),
            residual: f64::NAN,
        });
        Ok(())
    };
    for (name, scheme) in [("SBDF1", Scheme::Sbdf1), ("SBDF2", Scheme::Sbdf2)] {
        for &dt in &spec.dt {
            one(
                "spectral",
                format!("{name} dt = {dt}"),
                spectral(scheme, dt)?,
            )?;
        }
    }
    let bound = fd::stability_bound(&problem.grid, base.eps, 0.0);
    for &f in &spec.fd_fractions {
        let s = at(base, spec.t, |s| {
            s.method = Method::Fd;
            s.dt = f * bound;
        })?;
        one("FD", format!("FD explicit Euler, {f} of bound"), s)?;
    }
    Ok(configs)
}

/// The configuration of `family` with an error below `level` in the least wall time: (wall,
/// name).
fn fastest<'a>(configs: &'a [Config], family: &str, level: f64) -> Option<(f64, &'a str)> {
    configs
        .iter()
        .filter(|c| c.family == family && c.error < level)
        .map(|c| (c.wall, c.name.as_str()))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// The fastest spectral and FD configuration to each error level.
fn levels<'a>(configs: &'a [Config], levels: &[f64]) -> Vec<Level<'a>> {
    levels
        .iter()
        .map(|&level| Level {
            part: "transient",
            level,
            spectral: fastest(configs, "spectral", level),
            fd: fastest(configs, "FD", level),
        })
        .collect()
}

/// The printed report: every configuration, then the levels.
fn text(configs: &[Config], levels: &[Level]) -> String {
    let mut s = String::from("== transient: max|phi - phi_ref| at t ==\n");
    s.push_str(&table::text(configs));
    s.push_str("the fastest configuration (least wall time) to each error level:\n");
    s.push_str(&table::text(levels));
    s
}

/// Error against wall time: a marker per configuration, joined per family and scheme, and the
/// Pareto front.
fn chart(configs: &[Config]) -> Figure {
    let mut fig = Figure::new(
        "Transient 3D prolate: error in phi at fixed t against wall time",
        Axis::log("wall time [s]"),
        Axis::log("max |phi - phi_ref|"),
    );
    fig.legend = Corner::LowerLeft;
    let groups = [
        ("SBDF1", Shape::Circle),
        ("SBDF2", Shape::Square),
        ("FD", Shape::Triangle),
    ];
    for (i, (prefix, shape)) in groups.into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = configs
            .iter()
            .filter(|c| c.name.starts_with(prefix) && c.wall > 0.0)
            .map(|c| (c.wall, c.error))
            .collect();
        let name = match prefix {
            "FD" => "FD explicit Euler (fractions of its bound)".to_string(),
            p => format!("{p} (dt halved along the line)"),
        };
        fig.push(Series::new(name, pts, colour(i), Mark::LinePoints(shape)));
    }
    let all = configs
        .iter()
        .filter(|c| c.wall > 0.0)
        .map(|c| (c.wall, c.error))
        .collect();
    fig.push(Series::new(
        "Pareto front",
        pareto(all),
        [0, 0, 0],
        Mark::Dashed,
    ));
    fig
}
