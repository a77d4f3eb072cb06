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

use super::harness::{self, Report, Study};
use super::{file, stationary::pareto};
use crate::driver::simulation::{Simulation, StopRules};
use crate::engines::fd;
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::{AdaptiveSpec, AreaMethod, Method, Scene, Scheme};
use crate::problem::setup::Problem;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::fmt::Write as _;
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
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// `transient`.
    pub part: &'static str,
    /// `FD` or `spectral`.
    pub family: &'static str,
    /// Name.
    #[serde(rename = "config")]
    pub name: String,
    /// Simulated time.
    pub t: f64,
    /// Wall seconds of stepping.
    #[serde(rename = "wall_seconds")]
    pub wall: f64,
    /// max|φ − φ_ref| at `t`.
    pub error: f64,
    /// RMS(μ − μ̄) (not measured: NaN).
    pub residual: f64,
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
        let mut report = Report {
            text: table(&configs, &spec.transient.levels),
            ..Report::default()
        };
        report.table("precision.csv", &configs)?;
        report.table("levels.csv", &level_rows(&configs, &spec.transient.levels))?;
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

/// The fastest configuration of `family` reaching `level`: (wall, name).
fn fastest<'a>(configs: &'a [Config], family: &str, level: f64) -> Option<(f64, &'a str)> {
    configs
        .iter()
        .filter(|c| c.family == family && c.error < level)
        .map(|c| (c.wall, c.name.as_str()))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// A row of `levels.csv`.
#[derive(Serialize)]
struct LevelRow<'a> {
    part: &'static str,
    level: f64,
    fastest_spectral: &'a str,
    spectral_wall_seconds: f64,
    fastest_fd: &'a str,
    fd_wall_seconds: f64,
    ratio_spectral_over_fd: f64,
}

fn level_rows<'a>(configs: &'a [Config], levels: &[f64]) -> Vec<LevelRow<'a>> {
    levels
        .iter()
        .map(|&level| {
            let sp = fastest(configs, "spectral", level);
            let fd = fastest(configs, "FD", level);
            LevelRow {
                part: "transient",
                level,
                fastest_spectral: sp.map_or("", |x| x.1),
                spectral_wall_seconds: sp.map_or(f64::NAN, |x| x.0),
                fastest_fd: fd.map_or("", |x| x.1),
                fd_wall_seconds: fd.map_or(f64::NAN, |x| x.0),
                ratio_spectral_over_fd: match (sp, fd) {
                    (Some(a), Some(b)) => a.0 / b.0,
                    _ => f64::NAN,
                },
            }
        })
        .collect()
}

fn table(configs: &[Config], levels: &[f64]) -> String {
    let mut s = String::from("== transient: max|phi - phi_ref| at t ==\n");
    for c in configs {
        let _ = writeln!(
            s,
            "  {:<46} error {:>10.3e} at wall {:>9.3} s",
            c.name, c.error, c.wall
        );
    }
    let _ = writeln!(
        s,
        "  {:>8} {:>10} {:<40} {:>10} {:<44} {:>12}",
        "level", "spectral s", "fastest spectral", "FD s", "fastest FD", "spectral/FD"
    );
    for r in level_rows(configs, levels) {
        let wall = |w: f64| {
            if w.is_finite() {
                format!("{w:.3}")
            } else {
                "-".into()
            }
        };
        let name = |n: &str| {
            if n.is_empty() {
                "not reached".to_string()
            } else {
                n.to_string()
            }
        };
        let _ = writeln!(
            s,
            "  {:>8.0e} {:>10} {:<40} {:>10} {:<44} {:>12}",
            r.level,
            wall(r.spectral_wall_seconds),
            name(r.fastest_spectral),
            wall(r.fd_wall_seconds),
            name(r.fastest_fd),
            if r.ratio_spectral_over_fd.is_finite() {
                format!("{:.3e}", r.ratio_spectral_over_fd)
            } else {
                "-".into()
            }
        );
    }
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
