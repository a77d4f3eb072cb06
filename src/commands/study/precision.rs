//! `vesicle study precision FILE`: speed against accuracy on a real relaxation (the 3D prolate),
//! as Pareto charts.
//!
//! * **Stationary**: the error |e − e*|/e* of the reduced energy against wall time, e* from
//!   L-BFGS run to `reference_residual`. Each spectral configuration (conserved SBDF1 and SBDF2
//!   at fixed Δt and adaptive at several controller tolerances `energy_alpha`; relaxational
//!   L-BFGS, whose crossings of each `stop_residual` are what a run with that stop rule gives)
//!   runs once until its residual falls below `final_residual` (or `max_steps`), and its trace
//!   gives the first wall time at which the error falls below each level (e falls
//!   monotonically on these dissipative routes). FD is extrapolated as `study stationary` does:
//!   at each spacing of `fd_h`, `fd_timed_steps` steps at `fd_fraction` of its bound are
//!   timed, and FD's error at simulated time t is modelled as its own spatial error
//!   |e*_FD − e*|/e* (e*_FD from L-BFGS on the FD stencil's symbol at that h) plus the
//!   conserved flow's error at t (adaptive SBDF1 at its tightest tolerance, else the smallest
//!   fixed Δt); wall = t / Δt_FD × seconds per step.
//! * **Transient**: max|φ − φ_ref| at `t` against wall time, from the prepared field, φ_ref from
//!   SBDF2 at `reference_dt`: SBDF1 and SBDF2 at each Δt of `dt`, FD at each fraction of its
//!   bound in `fd_fractions` (its error includes its O(h²) spatial error).
//!
//! For each error level the table gives the fastest spectral and the fastest FD configuration
//! reaching it and the ratio of their wall times. Writes `precision.csv` (every point),
//! `levels.csv`, `precision.txt` and the charts `precision_stationary`, `precision_transient`.

use super::file;
use crate::commands::run;
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::fd;
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
    /// `"precision"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The scene (a spectral scene; its `prepare_steps` prepare the common start).
    pub scene: Value,
    /// The stationary part.
    pub stationary: StationarySpec,
    /// The transient part.
    pub transient: TransientSpec,
}

/// The stationary part's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct StationarySpec {
    /// L-BFGS reference tolerance.
    pub reference_residual: f64,
    /// Every route runs until its residual falls below this.
    pub final_residual: f64,
    /// Step limit of every route.
    pub max_steps: usize,
    /// Fixed Δt of conserved SBDF1.
    pub sbdf1_dt: Vec<f64>,
    /// Fixed Δt of conserved SBDF2.
    pub sbdf2_dt: Vec<f64>,
    /// Controller tolerances (`adaptive.energy_alpha`) of adaptive SBDF1 and SBDF2.
    pub energy_alpha: Vec<f64>,
    /// First Δt and `dt_max` of the adaptive runs.
    pub adaptive_dt: [f64; 2],
    /// `stop_residual` values read off the L-BFGS run.
    pub stop_residual: Vec<f64>,
    /// FD steps timed.
    pub fd_timed_steps: usize,
    /// FD Δt as a fraction of its bound.
    pub fd_fraction: f64,
    /// FD spacings, in units of the scene's h (the box kept, n scaled).
    pub fd_h: Vec<f64>,
    /// Error levels of the table.
    pub levels: Vec<f64>,
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

/// One state of a route: simulated time, wall seconds, error, residual.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Simulated time.
    pub t: f64,
    /// Wall seconds of stepping.
    pub wall: f64,
    /// The error.
    pub error: f64,
    /// RMS(μ − μ̄) (NaN where not measured).
    pub residual: f64,
}

/// A configuration and what it gave.
#[derive(Clone, Debug)]
pub struct Config {
    /// `stationary` or `transient`.
    pub part: &'static str,
    /// `FD` or `spectral`.
    pub family: &'static str,
    /// Name.
    pub name: String,
    /// Its trace (stationary) or its one point (transient).
    pub points: Vec<Point>,
}

impl Config {
    /// The first wall time at which the error is below `level`.
    fn wall_to(&self, level: f64) -> Option<f64> {
        self.points.iter().find(|p| p.error < level).map(|p| p.wall)
    }
}

/// Run the study of `path` (quick variant if `quick`) into `out`.
///
/// # Errors
/// `Error::Config` for a bad study file (naming the key) or an existing `out` without `force`;
/// `Error::Blowup` if a run diverges.
pub fn precision(path: &Path, quick: bool, out: &Path, force: bool) -> Result<Vec<Config>> {
    let spec: Spec = file::load(path, "precision", quick)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    run::check_out_dir(out, force)?;
    let started = Instant::now();
    let base = file::scene(&spec.scene, &[], "scene", dir)?;
    let mut problem = setup::build(&base)?;
    problem.phi = super::prepared_field(&base, &problem)?;
    let at = |patches: &[Value]| -> Result<Scene> {
        // The stop rules are the study's; the scene keeps a step limit to be valid.
        let mut all = vec![json!({"prepare_steps": 0, "adaptive": null, "t_end": null,
                                   "max_steps": 1_000_000, "stop_residual": null, "scheme": null})];
        all.extend_from_slice(patches);
        file::scene(&spec.scene, &all, "scene", dir)
    };
    let (mut configs, notes) = stationary(&spec.stationary, &problem, &at)?;
    configs.extend(transient(&spec.transient, &problem, &at)?);
    run::make_out_dir(out, force)?;
    let text = table(&configs, &spec, &notes, started.elapsed().as_secs_f64());
    println!("{text}");
    super::write_text(out, "precision.txt", &text)?;
    super::write_text(out, "precision.csv", &csv(&configs))?;
    super::write_text(out, "levels.csv", &levels_csv(&configs, &spec))?;
    charts(out, &configs)?;
    Ok(configs)
}

/// Run `s` from `problem.phi` under `rules`, calling `error` on every state (the initial one
/// included): the trace.
fn trace(
    s: &Scene,
    problem: &Problem,
    rules: &StopRules,
    error: &dyn Fn(&Now) -> f64,
) -> Result<Vec<Point>> {
    let (mut sim, _) = Simulation::of_scene(s, problem)?;
    let r = sim.record();
    let mut points = vec![Point {
        t: 0.0,
        wall: 0.0,
        error: f64::INFINITY,
        residual: r.residual,
    }];
    let mut probe = Probe(|now: &Now| {
        points.push(Point {
            t: now.record.t,
            wall: now.record.wall_seconds,
            error: error(now),
            residual: now.record.residual,
        });
        Ok(Flow::Continue)
    });
    sim.run(rules, &mut [&mut probe])?;
    Ok(points)
}

type SceneAt<'a> = dyn Fn(&[Value]) -> Result<Scene> + 'a;

fn stationary(
    spec: &StationarySpec,
    problem: &Problem,
    at: &SceneAt,
) -> Result<(Vec<Config>, String)> {
    let relax = json!({"dynamics": "relaxational", "dt": 1.0});
    let energy = |s: &Scene| {
        let (dim, eps) = (s.dim, s.eps);
        move |now: &Now| now.engine.measures().reduced(dim, eps).energy
    };
    let reference_rules = StopRules {
        stop_residual: Some(spec.reference_residual),
        max_steps: Some(spec.max_steps),
        ..StopRules::default()
    };
    let s = at(std::slice::from_ref(&relax))?;
    let e_of = energy(&s);
    let reference = trace(&s, problem, &reference_rules, &|n: &Now| e_of(n))?;
    let e_star = reference.last().map_or(f64::NAN, |p| p.error);
    let rel = move |e: f64| (e - e_star).abs() / e_star;
    let rules = StopRules {
        stop_residual: Some(spec.final_residual),
        max_steps: Some(spec.max_steps),
        ..StopRules::default()
    };
    let mut configs = Vec::new();
    let mut run = |name: String, patch: Value, rules: &StopRules| -> Result<Vec<Point>> {
        let s = at(&[patch])?;
        let e_of = energy(&s);
        let pts =
            trace(&s, problem, rules, &|n: &Now| rel(e_of(n))).map_err(|e| e.within(&name))?;
        configs.push(Config {
            part: "stationary",
            family: "spectral",
            name,
            points: pts.clone(),
        });
        Ok(pts)
    };
    // L-BFGS to the tightest stop_residual: each tolerance's crossing is a run with that rule.
    let tightest = spec
        .stop_residual
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let lbfgs_rules = StopRules {
        stop_residual: Some(tightest),
        ..rules
    };
    let lbfgs = run("relaxational L-BFGS".into(), relax.clone(), &lbfgs_rules)?;
    // The conserved flow's clock: adaptive SBDF1 at its tightest tolerance (else the smallest
    // fixed Δt) tells when the flow reaches each level. Keyed by energy_alpha, or −Δt.
    let mut clock: Option<(f64, Vec<Point>)> = None;
    for (scheme, dts) in [("sbdf1", &spec.sbdf1_dt), ("sbdf2", &spec.sbdf2_dt)] {
        for &dt in dts {
            let name = format!("{} dt = {dt}", scheme.to_uppercase());
            let pts = run(name, json!({"scheme": scheme, "dt": dt}), &rules)?;
            if scheme == "sbdf1" && clock.as_ref().is_none_or(|c| c.0 < -dt) {
                clock = Some((-dt, pts));
            }
        }
        for &ea in &spec.energy_alpha {
            let name = format!(
                "{} adaptive, energy_alpha = {ea:.0e}",
                scheme.to_uppercase()
            );
            let patch = json!({"scheme": scheme, "dt": spec.adaptive_dt[0],
                               "adaptive": {"energy_alpha": ea, "dt_max": spec.adaptive_dt[1]}});
            let pts = run(name, patch, &rules)?;
            if scheme == "sbdf1" && clock.as_ref().is_none_or(|c| c.0 < ea) {
                clock = Some((ea, pts));
            }
        }
    }
    let mut notes = format!(
        "e* = {e_star:.10} (L-BFGS to residual {:.0e})\n",
        spec.reference_residual
    );
    for &r in &spec.stop_residual {
        if let Some(p) = lbfgs.iter().find(|p| p.residual < r) {
            let _ = writeln!(
                notes,
                "L-BFGS stop_residual {r:.0e}: wall {:.3} s, error {:.2e}",
                p.wall, p.error
            );
        }
    }
    // FD at each h: its own stationary e*_FD(h) (L-BFGS on the stencil's symbol), timed steps,
    // then the wall time to the conserved flow's time at each level.
    let clock = clock
        .ok_or_else(|| Error::config("stationary.sbdf1_dt", "needs a conserved SBDF1 route"))?
        .1;
    for &hf in &spec.fd_h {
        let base = at(&[])?;
        let n: Vec<usize> = base
            .n
            .iter()
            .map(|&m| (m as f64 / hf).round() as usize)
            .collect();
        let grid = json!({"h": hf * base.h, "n": n});
        let s = at(&[grid.clone(), relax.clone(), json!({"laplacian": "fd"})])?;
        let mut fine = setup::build(&s)?;
        let prep = at(&[grid.clone(), json!({"prepare_steps": base.prepare_steps})])?;
        fine.phi = super::prepared_field(&prep, &fine)?;
        let e_of = energy(&s);
        let fd_star = trace(&s, &fine, &reference_rules, &|n: &Now| e_of(n))?
            .last()
            .map_or(f64::NAN, |p| p.error);
        let dt_fd = spec.fd_fraction * fd::stability_bound(&fine.grid, s.eps, 0.0);
        let s = at(&[grid, json!({"method": "fd", "dt": dt_fd})])?;
        let (mut sim, _) = Simulation::of_scene(&s, &fine)?;
        sim.run(&StopRules::steps(spec.fd_timed_steps), &mut [])?;
        let per_step = sim.clock.wall_seconds / spec.fd_timed_steps as f64;
        let floor = rel(fd_star);
        let _ = writeln!(
            notes,
            "FD at h = {} ({} of its bound, dt = {dt_fd:.4e}): {per_step:.3e} s per step ({} steps timed); e*_FD = {fd_star:.8}, spatial error {floor:.3e}",
            s.h, spec.fd_fraction, spec.fd_timed_steps
        );
        configs.push(Config {
            part: "stationary",
            family: "FD",
            name: format!("FD explicit Euler, h = {} (extrapolated)", s.h),
            points: clock
                .iter()
                .filter(|p| p.error.is_finite())
                .map(|p| Point {
                    t: p.t,
                    wall: p.t / dt_fd * per_step,
                    error: floor + p.error,
                    residual: f64::NAN,
                })
                .collect(),
        });
    }
    let _ = writeln!(
        notes,
        "FD error modelled as |e*_FD - e*|/e* + the conserved flow's error at the same t (adaptive SBDF1, tightest tolerance)"
    );
    Ok((configs, notes))
}

fn transient(spec: &TransientSpec, problem: &Problem, at: &SceneAt) -> Result<Vec<Config>> {
    let until = StopRules::until(spec.t);
    let end = |s: &Scene| -> Result<(ndarray::Array3<f64>, f64)> {
        let (mut sim, _) = Simulation::of_scene(s, problem)?;
        sim.run(&until, &mut [])?;
        Ok((sim.engine().phi().clone(), sim.clock.wall_seconds))
    };
    let none = json!({"area": {"method": "none"}});
    let (reference, _) = end(&at(&[
        none.clone(),
        json!({"scheme": "sbdf2", "dt": spec.reference_dt}),
    ])?)?;
    let mut configs = Vec::new();
    let mut one = |family, name: String, s: Scene| -> Result<()> {
        let (phi, wall) = end(&s)?;
        configs.push(Config {
            part: "transient",
            family,
            name,
            points: vec![Point {
                t: spec.t,
                wall,
                error: crate::problem::model::max_abs_diff(&phi, &reference),
                residual: f64::NAN,
            }],
        });
        Ok(())
    };
    for scheme in ["sbdf1", "sbdf2"] {
        for &dt in &spec.dt {
            let s = at(&[none.clone(), json!({"scheme": scheme, "dt": dt})])?;
            one(
                "spectral",
                format!("{} dt = {dt}", scheme.to_uppercase()),
                s,
            )?;
        }
    }
    let probe = at(&[
        none.clone(),
        json!({"method": "fd", "dt": 1.0, "allow_unstable": true}),
    ])?;
    let bound = fd::stability_bound(&problem.grid, probe.eps, 0.0);
    for &f in &spec.fd_fractions {
        let s = at(&[none.clone(), json!({"method": "fd", "dt": f * bound})])?;
        one("FD", format!("FD explicit Euler, {f} of bound"), s)?;
    }
    Ok(configs)
}

/// The fastest configuration of `family` in `part` reaching `level`: (wall, name).
fn fastest<'a>(
    configs: &'a [Config],
    part: &str,
    family: &str,
    level: f64,
) -> Option<(f64, &'a str)> {
    configs
        .iter()
        .filter(|c| c.part == part && c.family == family)
        .filter_map(|c| c.wall_to(level).map(|w| (w, c.name.as_str())))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

fn table(configs: &[Config], spec: &Spec, notes: &str, wall: f64) -> String {
    let mut s = String::from(notes);
    for (part, levels, what) in [
        ("stationary", &spec.stationary.levels, "|e - e*|/e*"),
        (
            "transient",
            &spec.transient.levels,
            "max|phi - phi_ref| at t",
        ),
    ] {
        let _ = writeln!(s, "\n== {part}: {what} ==");
        for c in configs.iter().filter(|c| c.part == part) {
            let last = c.points.last().expect("a configuration has points");
            let _ = writeln!(
                s,
                "  {:<46} final error {:>10.3e} at wall {:>9.3} s",
                c.name, last.error, last.wall
            );
        }
        let _ = writeln!(
            s,
            "  {:>8} {:>10} {:<40} {:>10} {:<44} {:>12}",
            "level", "spectral s", "fastest spectral", "FD s", "fastest FD", "spectral/FD"
        );
        for &l in levels.iter() {
            let sp = fastest(configs, part, "spectral", l);
            let fd = fastest(configs, part, "FD", l);
            let ratio = match (sp, fd) {
                (Some(a), Some(b)) => format!("{:.3e}", a.0 / b.0),
                _ => "-".into(),
            };
            let _ = writeln!(
                s,
                "  {:>8.0e} {:>10} {:<40} {:>10} {:<44} {:>12}",
                l,
                sp.map_or("-".into(), |x| format!("{:.3}", x.0)),
                sp.map_or("not reached", |x| x.1),
                fd.map_or("-".into(), |x| format!("{:.3}", x.0)),
                fd.map_or("not reached", |x| x.1),
                ratio
            );
        }
    }
    let _ = writeln!(s, "study wall time {wall:.1} s");
    s
}

/// The points of a trace worth a CSV row: each one whose error is at least 10% below the last
/// row's, and the last (a trace has a row per step; this keeps its shape in a small file).
fn thinned(points: &[Point]) -> Vec<Point> {
    let finite: Vec<Point> = points
        .iter()
        .copied()
        .filter(|p| p.error.is_finite())
        .collect();
    let mut last = f64::INFINITY;
    let mut rows: Vec<Point> = Vec::new();
    for (i, p) in finite.iter().enumerate() {
        if p.error < 0.9 * last || i + 1 == finite.len() {
            last = p.error;
            rows.push(*p);
        }
    }
    rows
}

fn csv(configs: &[Config]) -> String {
    let mut s = String::from("part,family,config,t,wall_seconds,error,residual\n");
    for c in configs {
        for p in thinned(&c.points) {
            let _ = writeln!(
                s,
                "{},{},\"{}\",{},{},{},{}",
                c.part, c.family, c.name, p.t, p.wall, p.error, p.residual
            );
        }
    }
    s
}

fn levels_csv(configs: &[Config], spec: &Spec) -> String {
    let mut s = String::from(
        "part,level,fastest_spectral,spectral_wall_seconds,fastest_fd,fd_wall_seconds,ratio_spectral_over_fd\n",
    );
    for (part, levels) in [
        ("stationary", &spec.stationary.levels),
        ("transient", &spec.transient.levels),
    ] {
        for &l in levels.iter() {
            let sp = fastest(configs, part, "spectral", l);
            let fd = fastest(configs, part, "FD", l);
            let _ = writeln!(
                s,
                "{part},{l},\"{}\",{},\"{}\",{},{}",
                sp.map_or("", |x| x.1),
                sp.map_or(f64::NAN, |x| x.0),
                fd.map_or("", |x| x.1),
                fd.map_or(f64::NAN, |x| x.0),
                match (sp, fd) {
                    (Some(a), Some(b)) => a.0 / b.0,
                    _ => f64::NAN,
                }
            );
        }
    }
    s
}

/// The Pareto front of `(wall, error)` points: those no other point beats in both.
fn pareto(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::INFINITY;
    pts.into_iter()
        .filter(|p| {
            let keep = p.1 < best;
            best = best.min(p.1);
            keep
        })
        .collect()
}

fn charts(out: &Path, configs: &[Config]) -> Result<()> {
    for (part, title) in [
        (
            "stationary",
            "Stationary 3D prolate: energy error against wall time",
        ),
        (
            "transient",
            "Transient 3D prolate: error in phi at fixed t against wall time",
        ),
    ] {
        let mut fig = Figure::new(
            title,
            Axis::log("wall time [s]"),
            Axis::log(if part == "stationary" {
                "|e - e*| / e*"
            } else {
                "max |phi - phi_ref|"
            }),
        );
        fig.legend = Corner::LowerRight;
        let shapes = [
            Shape::Circle,
            Shape::Square,
            Shape::Triangle,
            Shape::Diamond,
            Shape::Cross,
        ];
        let mut all = Vec::new();
        for (i, c) in configs.iter().filter(|c| c.part == part).enumerate() {
            let pts: Vec<(f64, f64)> = thinned(&c.points)
                .iter()
                .filter(|p| p.wall > 0.0)
                .map(|p| (p.wall, p.error))
                .collect();
            all.extend(pts.iter().copied());
            let mark = if part == "stationary" && c.family == "spectral" && pts.len() > 1 {
                Mark::Line
            } else if c.family == "FD" && pts.len() > 1 {
                Mark::Dashed
            } else {
                Mark::Points(shapes[i % shapes.len()])
            };
            fig.push(Series::new(c.name.clone(), pts, colour(i), mark));
        }
        fig.push(Series::new(
            "Pareto front",
            pareto(all),
            [0, 0, 0],
            if part == "stationary" {
                Mark::Line
            } else {
                Mark::LinePoints(Shape::Cross)
            },
        ));
        fig.write(&out.join(format!("precision_{part}")))?;
    }
    Ok(())
}
