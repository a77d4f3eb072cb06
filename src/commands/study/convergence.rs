//! `vesicle study convergence FILE`: observed orders in Δt, h and ε/R0 (validation ladder rungs
//! 2, 4 and 5), each from a least-squares fit printed beside it ([`super::fit`]).
//!
//! * **time**: from one field, SBDF1 and SBDF2 at Δt, Δt/2, … (fixed steps, the scene's
//!   stabiliser and area constraint) to the time `t`; error max|φ − φ_ref| against SBDF2 at
//!   `reference_dt`. Once from the field after the scene's `prepare_steps` (the smooth start),
//!   once from the raw tanh field (the order reduction of an unprepared start). Fit:
//!   error = C Δt^p.
//! * **space**: the stationary reduced energy e(h) at fixed ε on boxes of edge `length`, with
//!   the FD stencil's symbol (the FD discretisation, relaxed semi-implicitly; docs/src/theory/fd.md) and
//!   with the spectral symbol; error |e(h) − e_ref| against spectral at `reference_h`. Fits:
//!   FD error = C h^p; spectral error = C exp(b ε/h) (straight on a semi-log chart).
//! * **eps**: shapes of the c0 = 0 diagram (axisymmetric starts at the branch's v, R0 = ε/x)
//!   relaxed to the scene's `stop_residual` at ε/R0 = x; v from the φ = 0 surface
//!   ([`crate::analysis::levelset::measure_refined`]), e_ref(v) from [`crate::analysis::axisym::solve`] at that v
//!   (1 for a sphere).
//!   Fits: |e − e_ref| = C x^p; e = e0 + c x^p (the extrapolated limit; also for v); for the
//!   sphere |e − 1| = C exp(b R0/ε).

use super::harness::{self, Report, Study};
use super::{file, fit};
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use crate::output::chart::{colour, slope_guide, Axis, Corner, Figure, Mark, Series, Shape, GUIDE};
use crate::problem::config::{AdaptiveSpec, Laplacian, Scene, Scheme};
use crate::problem::setup::{self, Problem};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"convergence"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Δt halving.
    pub time: TimeSpec,
    /// h halving.
    pub space: SpaceSpec,
    /// ε/R0.
    pub eps: EpsSpec,
}

/// Δt halving at a fixed grid.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// A conserved spectral scene (its `prepare_steps` give the prepared start).
    pub scene: Value,
    /// The time at which the errors are taken.
    pub t: f64,
    /// The coarsest Δt.
    pub dt: f64,
    /// Number of Δt (each half the previous).
    pub levels: usize,
    /// Δt of the SBDF2 reference.
    pub reference_dt: f64,
}

/// h halving at fixed ε.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SpaceSpec {
    /// A stationary scene (a `stop_residual`); its `n` is replaced by `length / h`.
    pub scene: Value,
    /// Edge of the full box (units of the scene).
    pub length: f64,
    /// Spacings of the FD discretisation.
    pub fd_h: Vec<f64>,
    /// Spacings of the spectral discretisation.
    pub spectral_h: Vec<f64>,
    /// Spacing of the spectral reference.
    pub reference_h: f64,
}

/// ε/R0 at fixed h/ε.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct EpsSpec {
    /// A 3D stationary scene (its `initial` and `n` are replaced).
    pub scene: Value,
    /// The values of ε/R0.
    pub eps_over_r0: Vec<f64>,
    /// Bulk kept between the shape and the box faces, in units of ε.
    pub margin: f64,
    /// The shapes.
    pub shapes: Vec<ShapeSpec>,
}

/// One shape of the ε/R0 sweep.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// `"prolate"`, `"oblate"` or `"sphere"`.
    pub branch: String,
    /// The branch's v (not for a sphere).
    #[serde(default)]
    pub reduced_volume: Option<f64>,
    /// This shape's ε/R0 values, if not the sweep's.
    #[serde(default)]
    pub eps_over_r0: Option<Vec<f64>>,
    /// Scene keys merged into the sweep's scene for this shape (e.g. no area constraint for
    /// the sphere).
    #[serde(default)]
    pub scene: Option<Value>,
}

/// One measured point: `(part, series, x, error)` and what else was measured; a row of
/// `convergence.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// `time`, `space`, `eps`.
    pub part: &'static str,
    /// Series name.
    pub series: String,
    /// Δt, h or ε/R0.
    pub x: f64,
    /// The error.
    pub error: f64,
    /// Reduced energy (space, eps), NaN otherwise.
    pub e: f64,
    /// Reduced volume of the φ = 0 surface (eps), NaN otherwise.
    #[serde(rename = "v_levelset")]
    pub v: f64,
    /// The reference e_ref (space, eps), NaN otherwise.
    pub e_ref: f64,
    /// Stationarity residual RMS(μ − μ̄) at the end (space, eps), NaN otherwise.
    pub residual: f64,
    /// Steps (iterations) of the run.
    pub steps: usize,
    /// Wall seconds of the run.
    #[serde(rename = "wall_seconds")]
    pub wall: f64,
}

/// A fit quoted by the study; a row of `fits.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct Quoted {
    /// Part and series it belongs to.
    pub part: &'static str,
    /// Series name.
    pub series: String,
    /// The law: `power`, `exponential`, `limit e`, `limit v`.
    pub law: &'static str,
    /// The order, rate or limit.
    pub value: f64,
    /// Its standard error (NaN for limits), or the fitted exponent of a limit.
    pub spread: f64,
    /// Printed form.
    pub text: String,
}

/// The study: `convergence.txt`, `convergence.csv`, `fits.csv` and the charts
/// `convergence_time`, `convergence_space`, `convergence_space_semilog`, `convergence_eps`,
/// `convergence_sphere`.
pub struct Convergence;

impl Study for Convergence {
    const NAME: &'static str = "convergence";
    type Spec = Spec;
    type Output = Vec<Row>;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Vec<Row>, Report)> {
        let mut rows = time_part(&spec.time, dir)?;
        rows.extend(space_part(&spec.space, dir)?);
        rows.extend(eps_part(&spec.eps, dir)?);
        let fits = fits(&rows);
        let mut report = Report {
            text: table(&rows, &fits),
            ..Report::default()
        };
        report.table("convergence.csv", &rows)?;
        report.table("fits.csv", &fits)?;
        charts(&mut report, &rows);
        Ok((rows, report))
    }
}

/// Run `s` from `problem.phi` until its stop rules: the simulation, steps and wall seconds.
fn settle(s: &Scene, problem: &Problem, rules: &StopRules) -> Result<(Simulation, f64)> {
    let clock = Instant::now();
    let (mut sim, _) = Simulation::of_scene(s, problem)?;
    sim.run(rules, &mut [])?;
    Ok((sim, clock.elapsed().as_secs_f64()))
}

fn time_part(spec: &TimeSpec, dir: &Path) -> Result<Vec<Row>> {
    let field = "time.scene";
    let base = file::scene(&spec.scene, &[], field, dir)?;
    let mut rows = Vec::new();
    for (start, prepared) in [("prepared", true), ("raw tanh", false)] {
        let mut problem = setup::build(&base)?;
        if prepared {
            problem.phi = super::prepared_field(&base, &problem)?;
        }
        let at = |scheme: Scheme, dt: f64| {
            harness::variant(&base, field, |s| {
                s.scheme = scheme;
                s.dt = dt;
                s.adaptive = AdaptiveSpec::Flag(false);
                s.prepare_steps = 0;
                s.t_end = Some(spec.t);
                s.max_steps = None;
                s.stop_residual = None;
            })
        };
        let rules = StopRules::until(spec.t);
        let (reference, _) = settle(&at(Scheme::Sbdf2, spec.reference_dt)?, &problem, &rules)?;
        for (name, scheme) in [("SBDF1", Scheme::Sbdf1), ("SBDF2", Scheme::Sbdf2)] {
            for level in 0..spec.levels {
                let dt = spec.dt / 2f64.powi(level as i32);
                let (sim, wall) = settle(&at(scheme, dt)?, &problem, &rules)?;
                rows.push(Row {
                    part: "time",
                    series: format!("{name} from the {start} field"),
                    x: dt,
                    error: crate::problem::model::max_abs_diff(
                        sim.engine().phi(),
                        reference.engine().phi(),
                    ),
                    e: f64::NAN,
                    v: f64::NAN,
                    e_ref: f64::NAN,
                    residual: f64::NAN,
                    steps: sim.clock.step,
                    wall,
                });
            }
        }
    }
    Ok(rows)
}

/// Grid points for an edge `length` at spacing `h` (even).
fn points(length: f64, h: f64) -> usize {
    2 * ((length / h / 2.0).round() as usize).max(2)
}

/// A relaxed state: reduced energy, full-box φ, residual, steps, wall seconds.
struct Relaxed {
    e: f64,
    phi: ndarray::Array3<f64>,
    residual: f64,
    steps: usize,
    wall: f64,
}

/// Relax the scene `s` to its `stop_residual` (or until L-BFGS stalls at round-off).
fn relaxed(s: &Scene) -> Result<Relaxed> {
    let problem = setup::build(s)?;
    let (sim, wall) = settle(s, &problem, &StopRules::of(s))?;
    Ok(Relaxed {
        e: sim.engine().measures().reduced(s.dim, s.eps).energy,
        phi: problem.grid.unfold(sim.engine().phi()).into_owned(),
        residual: sim.engine().residual(),
        steps: sim.clock.step,
        wall,
    })
}

fn space_part(spec: &SpaceSpec, dir: &Path) -> Result<Vec<Row>> {
    let field = "space.scene";
    let base = file::scene(&spec.scene, &[], field, dir)?;
    let at = |h: f64, laplacian: Laplacian| -> Result<Scene> {
        harness::variant(&base, field, |s| {
            s.h = h;
            s.n = vec![points(spec.length, h); s.dim];
            s.laplacian = laplacian;
        })
    };
    let e_ref = relaxed(&at(spec.reference_h, Laplacian::Spectral)?)?.e;
    let mut rows = Vec::new();
    for (series, laplacian, hs) in [
        ("FD (stencil symbol)", Laplacian::Fd, &spec.fd_h),
        ("spectral", Laplacian::Spectral, &spec.spectral_h),
    ] {
        for &h in hs {
            let s = at(h, laplacian)?;
            let r = relaxed(&s)?;
            rows.push(Row {
                part: "space",
                series: series.to_string(),
                x: h / s.eps,
                error: (r.e - e_ref).abs(),
                e: r.e,
                v: f64::NAN,
                e_ref,
                residual: r.residual,
                steps: r.steps,
                wall: r.wall,
            });
        }
    }
    Ok(rows)
}

fn eps_part(spec: &EpsSpec, dir: &Path) -> Result<Vec<Row>> {
    let field = "eps.scene";
    let base = file::scene(&spec.scene, &[], field, dir)?;
    if base.dim != 3 {
        return Err(Error::config(
            "eps.scene.dim",
            "the ε/R0 sweep needs a 3D scene",
        ));
    }
    let opts = crate::analysis::axisym::Options::default();
    let mut rows = Vec::new();
    for (i, shape) in spec.shapes.iter().enumerate() {
        let name = format!("eps.shapes[{i}]");
        let (branch, v) = match (shape.branch.as_str(), shape.reduced_volume) {
            ("sphere", _) => (None, 1.0),
            ("prolate", Some(v)) => (Some(crate::analysis::axisym::Branch::Prolate), v),
            ("oblate", Some(v)) => (Some(crate::analysis::axisym::Branch::Oblate), v),
            ("prolate" | "oblate", None) => {
                return Err(Error::config(format!("{name}.reduced_volume"), "missing"))
            }
            (other, _) => {
                return Err(Error::config(
                    format!("{name}.branch"),
                    format!("{other:?}: expected \"prolate\", \"oblate\" or \"sphere\""),
                ))
            }
        };
        // Half-extents at R0 = 1 across and along the axis (the last axis).
        let (across, along) = match branch {
            None => (1.0, 1.0),
            Some(b) => {
                let sol = crate::analysis::axisym::solve(b, v, &opts).map_err(|_| {
                    Error::config(
                        format!("{name}.reduced_volume"),
                        "no axisymmetric shape at this v",
                    )
                })?;
                let r = sol.r.iter().fold(0.0f64, |m, x| m.max(*x));
                let (lo, hi) = sol
                    .z
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
                        (a.min(*z), b.max(*z))
                    });
                (r, (hi - lo) / 2.0)
            }
        };
        let label = match branch {
            None => "sphere".to_string(),
            Some(b) => format!("{} v = {v}", b.name()),
        };
        for &x in shape.eps_over_r0.as_ref().unwrap_or(&spec.eps_over_r0) {
            let r0 = base.eps / x;
            let n_of = |half: f64| points(2.0 * (half * r0 + spec.margin * base.eps), base.h);
            let initial = match branch {
                None => json!({"shape": "sphere", "radius": r0}),
                Some(b) => {
                    json!({"shape": "axisym", "branch": b.name(), "reduced_volume": v, "r0": r0})
                }
            };
            let s = file::scene(
                &spec.scene,
                &[
                    json!({"initial": null}),
                    json!({"n": [n_of(across), n_of(across), n_of(along)], "initial": initial}),
                    shape.scene.clone().unwrap_or(json!({})),
                ],
                field,
                dir,
            )?;
            let r = relaxed(&s)?;
            let level = crate::analysis::levelset::measure_refined(&r.phi, 3, s.h);
            let e_ref = match branch {
                None => 1.0,
                Some(b) => crate::analysis::axisym::solve(b, level.reduced_volume, &opts)
                    .map_err(|err| Error::Study(format!("{label} at eps/R0 = {x}: no axisymmetric reference at the φ = 0 v = {}: {err}", level.reduced_volume)))?
                    .e,
            };
            rows.push(Row {
                part: "eps",
                series: label.clone(),
                x,
                error: r.e - e_ref,
                e: r.e,
                v: level.reduced_volume,
                e_ref,
                residual: r.residual,
                steps: r.steps,
                wall: r.wall,
            });
        }
    }
    Ok(rows)
}

/// The series of `part`, in order of appearance.
fn series_of<'a>(rows: &'a [Row], part: &str) -> Vec<(&'a str, Vec<&'a Row>)> {
    let mut out: Vec<(&str, Vec<&Row>)> = Vec::new();
    for r in rows.iter().filter(|r| r.part == part) {
        match out.iter_mut().find(|(n, _)| *n == r.series) {
            Some((_, v)) => v.push(r),
            None => out.push((r.series.as_str(), vec![r])),
        }
    }
    out
}

fn column(rs: &[&Row], f: impl Fn(&Row) -> f64) -> Vec<f64> {
    rs.iter().map(|r| f(r)).collect()
}

/// The points of a series above its floor ([`fit::resolved`]), coarse to fine (x falling):
/// `(x, error)` with the error taken by `err`; the laws are fitted to these only.
fn resolved(rs: &[&Row], err: impl Fn(&Row) -> f64) -> (Vec<f64>, Vec<f64>) {
    let mut pts: Vec<(f64, f64)> = rs.iter().map(|r| (r.x, err(r))).collect();
    pts.sort_by(|a, b| b.0.total_cmp(&a.0));
    let keep = fit::resolved(&pts.iter().map(|p| p.1).collect::<Vec<_>>());
    pts.truncate(keep);
    pts.into_iter().unzip()
}

/// Points fitted, for the quoted text: `, 4 of 6 points above the floor` when some were left.
fn floor_note(kept: usize, all: usize) -> String {
    if kept < all {
        format!("; {kept} of {all} points above the floor fitted")
    } else {
        String::new()
    }
}

fn fits(rows: &[Row]) -> Vec<Quoted> {
    let mut q = Vec::new();
    let mut push = |part, series: &str, law, value, spread, text: String| {
        q.push(Quoted {
            part,
            series: series.to_string(),
            law,
            value,
            spread,
            text,
        })
    };
    for (name, rs) in series_of(rows, "time") {
        let (x, e) = resolved(&rs, |r| r.error);
        if let Some(f) = fit::power(&x, &e) {
            let note = floor_note(x.len(), rs.len());
            push(
                "time",
                name,
                "power",
                f.order(),
                f.line.slope_error,
                format!("{f}{note}"),
            );
        }
    }
    for (name, rs) in series_of(rows, "space") {
        let (x, e) = resolved(&rs, |r| r.error);
        let note = floor_note(x.len(), rs.len());
        if name.starts_with("FD") {
            if let Some(f) = fit::power(&x, &e) {
                push(
                    "space",
                    name,
                    "power",
                    f.order(),
                    f.line.slope_error,
                    format!("{f}{note}"),
                );
            }
        } else {
            let inv: Vec<f64> = x.iter().map(|h| 1.0 / h).collect();
            if let Some(f) = fit::exponential(&inv, &e) {
                push(
                    "space",
                    name,
                    "exponential",
                    f.line.slope,
                    f.line.slope_error,
                    format!("{f} with x = eps/h{note}"),
                );
            }
        }
    }
    for (name, rs) in series_of(rows, "eps") {
        let (x, err) = resolved(&rs, |r| r.error.abs());
        let note = floor_note(x.len(), rs.len());
        if name == "sphere" {
            let inv: Vec<f64> = x.iter().map(|v| 1.0 / v).collect();
            // Three points above the floor at least: with two, a line fits any pair.
            if let Some(f) = fit::exponential(&inv, &err).filter(|_| x.len() >= 3) {
                push(
                    "eps",
                    name,
                    "exponential",
                    f.line.slope,
                    f.line.slope_error,
                    format!("|e - 1|: {f} with x = R0/eps{note}"),
                );
            }
            continue;
        }
        if let Some(f) = fit::power(&x, &err).filter(|_| x.len() >= 3) {
            push(
                "eps",
                name,
                "power",
                f.order(),
                f.line.slope_error,
                format!("|e - e_ref(v)|: {f}{note}"),
            );
        }
        let all_x = column(&rs, |r| r.x);
        if let Some(f) = fit::limit(&all_x, &column(&rs, |r| r.e)) {
            push("eps", name, "limit e", f.e0, f.p, format!("e: {f}"));
        }
        if let Some(f) = fit::limit(&all_x, &column(&rs, |r| r.v)) {
            push(
                "eps",
                name,
                "limit v",
                f.e0,
                f.p,
                format!("v (phi = 0): {f}"),
            );
        }
    }
    q
}

/// A series' floor, for the table: where the error stopped falling, if it did.
fn floor_line(rs: &[&Row], err: impl Fn(&Row) -> f64) -> Option<String> {
    let (x, _) = resolved(rs, &err);
    (x.len() < rs.len()).then(|| {
        let lo = rs.iter().map(|r| err(r)).fold(f64::INFINITY, f64::min);
        format!(
            "  floor: the error stops falling after {} of {} points (smallest {lo:.2e}); no law is fitted through the rest",
            x.len(),
            rs.len()
        )
    })
}

fn table(rows: &[Row], fits: &[Quoted]) -> String {
    let mut s = String::new();
    let heads = [
        ("time", "dt", "max|phi - phi_ref| at t"),
        ("space", "h/eps", "|e(h) - e_ref|"),
        ("eps", "eps/R0", "e - e_ref(v)"),
    ];
    for (part, xname, ename) in heads {
        let _ = writeln!(s, "== {part} ==");
        for (name, rs) in series_of(rows, part) {
            let _ = writeln!(
                s,
                "{name}\n  {xname:>10} {ename:>24} {:>12} {:>10} {:>12} {:>9} {:>8} {:>9}",
                "e", "v (phi=0)", "e_ref", "residual", "steps", "wall [s]"
            );
            for r in &rs {
                let _ = writeln!(
                    s,
                    "  {:>10.4e} {:>24.4e} {:>12.7} {:>10.5} {:>12.7} {:>9.1e} {:>8} {:>9.2}",
                    r.x, r.error, r.e, r.v, r.e_ref, r.residual, r.steps, r.wall
                );
            }
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

fn power_law(x: &[f64], e: &[f64]) -> Law {
    fit::power(x, e).map(|f| {
        (
            format!("fit: slope {:.2}", f.order()),
            Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
        )
    })
}

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
