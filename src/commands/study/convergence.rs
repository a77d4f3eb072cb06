//! `vesicle study convergence FILE`: observed orders in Δt, h and ε/R0 (validation ladder rungs
//! 2, 4 and 5), each from a least-squares fit printed beside it ([`super::fit`]).
//!
//! * **time**: from one field, SBDF1 and SBDF2 at Δt, Δt/2, … (fixed steps, the scene's
//!   stabiliser and area constraint) to the time `t`; error max|φ − φ_ref| against SBDF2 at
//!   `reference_dt`. Once from the field after the scene's `prepare_steps` (the smooth start),
//!   once from the raw tanh field (the order reduction of an unprepared start). Fit:
//!   error = C Δt^p.
//! * **space**: the stationary reduced energy e(h) at fixed ε on boxes of edge `length`, with
//!   the FD stencil's symbol (the FD discretisation, relaxed semi-implicitly; DESIGN.md §2) and
//!   with the spectral symbol; error |e(h) − e_ref| against spectral at `reference_h`. Fits:
//!   FD error = C h^p; spectral error = C exp(b ε/h) (straight on a semi-log chart).
//! * **eps**: shapes of the c0 = 0 diagram (axisymmetric starts at the branch's v, R0 = ε/x)
//!   relaxed to the scene's `stop_residual` at ε/R0 = x; v from the φ = 0 surface
//!   ([`crate::analysis::levelset::measure_refined`]), e_ref(v) from [`crate::analysis::axisym::solve`] at that v
//!   (1 for a sphere).
//!   Fits: |e − e_ref| = C x^p; e = e0 + c x^p (the extrapolated limit; also for v); for the
//!   sphere |e − 1| = C exp(b R0/ε).

use super::file;
use super::fit;
use crate::commands::run;
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::Scene;
use crate::problem::setup::{self, Problem};
use serde::Deserialize;
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

/// One measured point: `(part, series, x, error)` and what else was measured.
#[derive(Clone, Debug)]
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
    pub v: f64,
    /// The reference e_ref (space, eps), NaN otherwise.
    pub e_ref: f64,
    /// Stationarity residual RMS(μ − μ̄) at the end (space, eps), NaN otherwise.
    pub residual: f64,
    /// Steps (iterations) of the run.
    pub steps: usize,
    /// Wall seconds of the run.
    pub wall: f64,
}

/// A fit quoted by the study.
#[derive(Clone, Debug)]
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

/// Run the study of `path` (quick variant if `quick`) into `out`.
///
/// # Errors
/// `Error::Config` for a bad study file (naming the key) or an existing `out` without `force`;
/// `Error::Blowup` if a run diverges.
pub fn convergence(path: &Path, quick: bool, out: &Path, force: bool) -> Result<Vec<Row>> {
    let spec: Spec = file::load(path, "convergence", quick)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    run::check_out_dir(out, force)?;
    let started = Instant::now();
    let mut rows = time_part(&spec.time, dir)?;
    rows.extend(space_part(&spec.space, dir)?);
    rows.extend(eps_part(&spec.eps, dir)?);
    let fits = fits(&rows);
    run::make_out_dir(out, force)?;
    let text = table(&rows, &fits, started.elapsed().as_secs_f64());
    println!("{text}");
    super::write_text(out, "convergence.txt", &text)?;
    super::write_text(out, "convergence.csv", &csv(&rows))?;
    super::write_text(out, "fits.csv", &fits_csv(&fits))?;
    charts(out, &rows)?;
    Ok(rows)
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
        let at = |scheme: &str, dt: f64| {
            file::scene(
                &spec.scene,
                &[
                    json!({"scheme": scheme, "dt": dt, "adaptive": false, "prepare_steps": 0,
                        "t_end": spec.t, "max_steps": null, "stop_residual": null}),
                ],
                field,
                dir,
            )
        };
        let rules = StopRules::until(spec.t);
        let (reference, _) = settle(&at("sbdf2", spec.reference_dt)?, &problem, &rules)?;
        for scheme in ["sbdf1", "sbdf2"] {
            for level in 0..spec.levels {
                let dt = spec.dt / 2f64.powi(level as i32);
                let (sim, wall) = settle(&at(scheme, dt)?, &problem, &rules)?;
                rows.push(Row {
                    part: "time",
                    series: format!("{} from the {start} field", scheme.to_uppercase()),
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
    let at = |h: f64, laplacian: &str| -> Result<Scene> {
        let base = file::scene(&spec.scene, &[], field, dir)?;
        let n = vec![points(spec.length, h); base.dim];
        file::scene(
            &spec.scene,
            &[json!({"h": h, "n": n, "laplacian": laplacian})],
            field,
            dir,
        )
    };
    let e_ref = relaxed(&at(spec.reference_h, "spectral")?)?.e;
    let mut rows = Vec::new();
    for (series, laplacian, hs) in [
        ("FD (stencil symbol)", "fd", &spec.fd_h),
        ("spectral", "spectral", &spec.spectral_h),
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
                    .map_err(|err| Error::Blowup {
                        step: r.steps,
                        t: 0.0,
                        reason: format!("{label} at eps/R0 = {x}: no axisymmetric reference at the φ = 0 v = {}: {err}", level.reduced_volume),
                    })?
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
        if let Some(f) = fit::power(&column(&rs, |r| r.x), &column(&rs, |r| r.error)) {
            push(
                "time",
                name,
                "power",
                f.order(),
                f.line.slope_error,
                f.to_string(),
            );
        }
    }
    for (name, rs) in series_of(rows, "space") {
        let (x, e) = (column(&rs, |r| r.x), column(&rs, |r| r.error));
        if name.starts_with("FD") {
            if let Some(f) = fit::power(&x, &e) {
                push(
                    "space",
                    name,
                    "power",
                    f.order(),
                    f.line.slope_error,
                    f.to_string(),
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
                    format!("{f} with x = eps/h"),
                );
            }
        }
    }
    for (name, rs) in series_of(rows, "eps") {
        let x = column(&rs, |r| r.x);
        let err = column(&rs, |r| r.error.abs());
        if name == "sphere" {
            let inv: Vec<f64> = x.iter().map(|v| 1.0 / v).collect();
            if let Some(f) = fit::exponential(&inv, &err) {
                push(
                    "eps",
                    name,
                    "exponential",
                    f.line.slope,
                    f.line.slope_error,
                    format!("|e - 1|: {f} with x = R0/eps"),
                );
            }
            continue;
        }
        if let Some(f) = fit::power(&x, &err) {
            push(
                "eps",
                name,
                "power",
                f.order(),
                f.line.slope_error,
                format!("|e - e_ref(v)|: {f}"),
            );
        }
        if let Some(f) = fit::limit(&x, &column(&rs, |r| r.e)) {
            push("eps", name, "limit e", f.e0, f.p, format!("e: {f}"));
        }
        if let Some(f) = fit::limit(&x, &column(&rs, |r| r.v)) {
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

fn table(rows: &[Row], fits: &[Quoted], wall: f64) -> String {
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
            for r in rs {
                let _ = writeln!(
                    s,
                    "  {:>10.4e} {:>24.4e} {:>12.7} {:>10.5} {:>12.7} {:>9.1e} {:>8} {:>9.2}",
                    r.x, r.error, r.e, r.v, r.e_ref, r.residual, r.steps, r.wall
                );
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
    let _ = writeln!(s, "study wall time {wall:.1} s");
    s
}

fn csv(rows: &[Row]) -> String {
    let mut s =
        String::from("part,series,x,error,e,v_levelset,e_ref,residual,steps,wall_seconds\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},\"{}\",{},{},{},{},{},{},{},{}",
            r.part, r.series, r.x, r.error, r.e, r.v, r.e_ref, r.residual, r.steps, r.wall
        );
    }
    s
}

fn fits_csv(fits: &[Quoted]) -> String {
    let mut s = String::from("part,series,law,value,spread,text\n");
    for f in fits {
        let _ = writeln!(
            s,
            "{},\"{}\",{},{},{},\"{}\"",
            f.part,
            f.series,
            f.law,
            f.value,
            f.spread,
            f.text.replace('"', "'")
        );
    }
    s
}

/// A fitted law's legend text and its function.
type Law = Option<(String, Box<dyn Fn(f64) -> f64>)>;

/// A marker series for the points of `rs` and the fitted law drawn dashed over their x range.
fn with_fit(fig: &mut Figure, i: usize, name: &str, pts: Vec<(f64, f64)>, law: Law) {
    let shapes = [Shape::Circle, Shape::Square, Shape::Triangle, Shape::Cross];
    if let Some((label, f)) = law {
        let (lo, hi) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        let line = (0..=20)
            .map(|k| lo * (hi / lo).powf(k as f64 / 20.0))
            .map(|x| (x, f(x)))
            .collect();
        fig.push(Series::new(label, line, colour(i), Mark::Dashed));
    }
    fig.push(Series::new(
        name,
        pts,
        colour(i),
        Mark::Points(shapes[i % shapes.len()]),
    ));
}

fn charts(out: &Path, rows: &[Row]) -> Result<()> {
    let mut time = Figure::new(
        "Temporal convergence: error at fixed t against dt",
        Axis::log("dt [time units]"),
        Axis::log("max |phi - phi_ref|"),
    );
    time.legend = Corner::LowerRight;
    for (i, (name, rs)) in series_of(rows, "time").into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = rs.iter().map(|r| (r.x, r.error)).collect();
        let f = fit::power(&column(&rs, |r| r.x), &column(&rs, |r| r.error));
        let law = f.map(|f| {
            (
                format!("fit: slope {:.2}", f.order()),
                Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
            )
        });
        with_fit(&mut time, i, name, pts, law);
    }
    time.write(&out.join("convergence_time"))?;

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
        let (x, e) = (column(&rs, |r| r.x), column(&rs, |r| r.error));
        let pts: Vec<(f64, f64)> = x.iter().copied().zip(e.iter().copied()).collect();
        let inv: Vec<f64> = x.iter().map(|h| 1.0 / h).collect();
        let semi: Vec<(f64, f64)> = inv.iter().copied().zip(e.iter().copied()).collect();
        if name.starts_with("FD") {
            let law = fit::power(&x, &e).map(|f| {
                (
                    format!("fit: slope {:.2}", f.order()),
                    Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
                )
            });
            with_fit(&mut space, i, name, pts, law);
            semilog.push(Series::new(
                name,
                semi,
                colour(i),
                Mark::LinePoints(Shape::Square),
            ));
        } else {
            let law = fit::exponential(&inv, &e).map(|f| {
                (
                    format!("fit: exp({:.2} eps/h)", f.line.slope),
                    Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
                )
            });
            with_fit(&mut semilog, i, name, semi, law);
            space.push(Series::new(
                name,
                pts,
                colour(i),
                Mark::LinePoints(Shape::Circle),
            ));
        }
    }
    space.write(&out.join("convergence_space"))?;
    semilog.write(&out.join("convergence_space_semilog"))?;

    let mut eps = Figure::new(
        "Phase-field error against eps/R0 (v on the phi = 0 surface)",
        Axis::log("eps / R0"),
        Axis::log("|e - e_ref(v)|"),
    );
    eps.legend = Corner::LowerRight;
    let mut sphere = Figure::new(
        "Control: sphere, c0 = 0",
        Axis::linear("R0 / eps"),
        Axis::log("|e - 1|"),
    );
    sphere.legend = Corner::UpperRight;
    for (i, (name, rs)) in series_of(rows, "eps").into_iter().enumerate() {
        let (x, e) = (column(&rs, |r| r.x), column(&rs, |r| r.error.abs()));
        if name == "sphere" {
            let inv: Vec<f64> = x.iter().map(|v| 1.0 / v).collect();
            let pts = inv.iter().copied().zip(e.iter().copied()).collect();
            let law = fit::exponential(&inv, &e).map(|f| {
                (
                    format!("fit: exp({:.2} R0/eps)", f.line.slope),
                    Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
                )
            });
            with_fit(&mut sphere, i, name, pts, law);
            eps.push(Series::new(
                name,
                x.iter().copied().zip(e.iter().copied()).collect(),
                colour(i),
                Mark::LinePoints(Shape::Cross),
            ));
        } else {
            let pts = x.iter().copied().zip(e.iter().copied()).collect();
            let law = fit::power(&x, &e).map(|f| {
                (
                    format!("fit: slope {:.2}", f.order()),
                    Box::new(move |x| f.at(x)) as Box<dyn Fn(f64) -> f64>,
                )
            });
            with_fit(&mut eps, i, name, pts, law);
        }
    }
    eps.write(&out.join("convergence_eps"))?;
    sphere.write(&out.join("convergence_sphere"))?;
    Ok(())
}
