//! `vesicle study stationary`: the routes to a stationary shape, timed in one run.
//!
//! 1. The conserved flow, spectral engine with adaptive steps, until its residual falls below
//!    the scene's `stop_residual` (default 1e-10): the reference end state F*.
//! 2. The relaxational L-BFGS, until F is within 1e-6 of F* (relative) and φ within 1e-3 of
//!    φ* (max norm): iterations, energy evaluations, wall time.
//! 3. The FD reference at 95% of its stability bound: a few hundred steps timed, and the wall
//!    time to reach the conserved run's end time t* extrapolated (t*/Δt_FD steps).
//!
//! Prints the table and the wall-time ratios and writes `stationary.csv`, `stationary.txt`
//! and `convergence.png` (relative energy error against wall time for both spectral routes).

use crate::config::{AdaptiveSettings, AdaptiveSpec, AreaMethod, Dynamics, Method, Scene, Scheme};
use crate::error::{Error, Result};
use crate::fd;
use crate::output;
use crate::run;
use crate::setup::{self, Problem};
use crate::simulation::{Flow, Now, Probe, Simulation, StopRules};
use ndarray::Array3;
use std::fmt::Write as _;
use std::path::Path;

/// Relative energy distance at which the relaxational route counts as arrived ...
pub const ENERGY_TOL: f64 = 1e-6;
/// ... together with this max|φ − φ*|.
pub const PHI_TOL: f64 = 1e-3;
/// FD steps timed for the extrapolation.
const FD_TIMED_STEPS: usize = 300;

/// One route's result.
#[derive(Clone, Debug)]
pub struct Route {
    /// Name in the table.
    pub name: &'static str,
    /// Steps or iterations.
    pub steps: usize,
    /// Energy evaluations (each costs the same four transforms); steps + rejections.
    pub evaluations: usize,
    /// Simulated time reached (iterations × dt for the relaxational route).
    pub t: f64,
    /// Wall seconds (extrapolated for FD).
    pub wall: f64,
    /// Final F_sc.
    pub energy: f64,
    /// Final reduced energy.
    pub reduced_energy: f64,
    /// max|φ − φ*| against the conserved end state.
    pub max_dphi: f64,
    /// (wall, relative energy error) along the way.
    pub trace: Vec<(f64, f64)>,
}

/// Run the three routes on `scene` and write the report into `out`.
///
/// # Errors
/// `Error::Config` for an unsuitable scene or an existing `out` without `force`;
/// `Error::Blowup` if a route diverges.
pub fn stationary(scene: &Scene, out: &Path, force: bool) -> Result<Vec<Route>> {
    if out.exists() && !force {
        run::make_out_dir(out, false)?;
    }
    let problem = setup::build(scene)?;
    let tol = scene.stop_residual.unwrap_or(1e-10);
    let max_steps = scene.max_steps.unwrap_or(200_000);
    let conserved = conserved_route(scene, &problem, tol, max_steps)?;
    let (f_star, phi_star) = (conserved.0.energy, conserved.1);
    let mut routes = vec![conserved.0];
    routes[0]
        .trace
        .iter_mut()
        .for_each(|p| p.1 = (p.1 - f_star).abs() / f_star);
    routes[0].max_dphi = 0.0;
    routes.push(relax_route(scene, &problem, f_star, &phi_star, max_steps)?);
    routes.push(fd_route(scene, &problem, routes[0].t)?);
    run::make_out_dir(out, force)?;
    let table = table(&routes, scene);
    println!("{table}");
    super::write_text(out, "stationary.txt", &table)?;
    super::write_text(out, "stationary.csv", &csv(&routes))?;
    let series: Vec<(&str, Vec<(f64, f64)>)> = routes[..2]
        .iter()
        .map(|r| (r.name, r.trace.clone()))
        .collect();
    output::chart::write_timeseries_png(
        &out.join("convergence.png"),
        &series,
        "wall seconds",
        "|F - F*| / F*",
        true,
    )?;
    Ok(routes)
}

fn variant(scene: &Scene, f: impl FnOnce(&mut Scene)) -> Scene {
    let mut s = scene.clone();
    s.method = Method::Spectral;
    f(&mut s);
    s
}

/// Conserved flow with adaptive steps to residual < tol; returns the route and the end φ.
fn conserved_route(
    scene: &Scene,
    problem: &Problem,
    tol: f64,
    max_steps: usize,
) -> Result<(Route, Array3<f64>)> {
    let s = variant(scene, |s| {
        s.dynamics = Dynamics::Conserved;
        s.scheme = Scheme::Sbdf1;
        if s.adaptive.settings().is_none() {
            s.adaptive = AdaptiveSpec::Settings(AdaptiveSettings::default());
        }
    });
    let (mut sim, _) = Simulation::of_scene(&s, problem)?;
    let mut trace = Vec::new();
    let mut probe = Probe(|now: &Now| {
        trace.push((now.record.wall_seconds, now.record.energy));
        Ok(Flow::Continue)
    });
    let rules = StopRules {
        stop_residual: Some(tol),
        max_steps: Some(max_steps),
        t_end: None,
    };
    sim.run(&rules, &mut [&mut probe])
        .map_err(|e| tagged("conserved", e))?;
    let route = route("conserved (spectral, adaptive)", &sim, scene, 0.0, trace);
    Ok((route, sim.engine().phi().clone()))
}

/// L-BFGS until |F − F*|/F* < ENERGY_TOL and max|φ − φ*| ≤ PHI_TOL.
fn relax_route(
    scene: &Scene,
    problem: &Problem,
    f_star: f64,
    phi_star: &Array3<f64>,
    max_steps: usize,
) -> Result<Route> {
    let s = variant(scene, |s| {
        s.dynamics = Dynamics::Relaxational;
        s.adaptive = AdaptiveSpec::Flag(false);
        if s.area_method() == AreaMethod::Lagrangian {
            s.area.method = Some(AreaMethod::Projection);
            s.area.alpha = None;
        }
    });
    let (mut sim, _) = Simulation::of_scene(&s, problem)?;
    let mut trace = Vec::new();
    let mut probe = Probe(|now: &Now| {
        let error = (now.record.energy - f_star).abs() / f_star;
        trace.push((now.record.wall_seconds, error));
        let arrived =
            error < ENERGY_TOL && crate::model::max_abs_diff(now.engine.phi(), phi_star) <= PHI_TOL;
        Ok(if arrived {
            Flow::Stop("arrived")
        } else {
            Flow::Continue
        })
    });
    sim.run(&StopRules::steps(max_steps), &mut [&mut probe])
        .map_err(|e| tagged("relaxational", e))?;
    let max_dphi = crate::model::max_abs_diff(sim.engine().phi(), phi_star);
    Ok(route("relaxational (L-BFGS)", &sim, scene, max_dphi, trace))
}

/// A route's row from its finished simulation.
fn route(
    name: &'static str,
    sim: &Simulation,
    scene: &Scene,
    max_dphi: f64,
    trace: Vec<(f64, f64)>,
) -> Route {
    let r = sim.record();
    Route {
        name,
        steps: r.step,
        evaluations: r.step + r.rejected,
        t: r.t,
        wall: r.wall_seconds,
        energy: r.energy,
        reduced_energy: sim.engine().measures().reduced(scene.dim, scene.eps).energy,
        max_dphi,
        trace,
    }
}

/// FD at 95% of its bound: time FD_TIMED_STEPS steps, extrapolate to `t_star`.
fn fd_route(scene: &Scene, problem: &Problem, t_star: f64) -> Result<Route> {
    let bound = fd::stability_bound(&problem.grid, scene.eps, 0.0);
    let mut s = scene.clone();
    s.method = Method::Fd;
    s.scheme = Scheme::Sbdf1;
    s.dynamics = Dynamics::Conserved;
    s.adaptive = AdaptiveSpec::Flag(false);
    s.dt = 0.95 * bound;
    s.area.method = Some(scene.area_method());
    let (mut sim, _) = Simulation::of_scene(&s, problem)?;
    sim.run(&StopRules::steps(FD_TIMED_STEPS), &mut [])
        .map_err(|e| tagged("fd", e))?;
    let per_step = sim.clock.wall_seconds / FD_TIMED_STEPS as f64;
    let steps = (t_star / s.dt).ceil() as usize;
    Ok(Route {
        name: "fd (extrapolated)",
        steps,
        evaluations: steps,
        t: t_star,
        wall: per_step * steps as f64,
        energy: f64::NAN,
        reduced_energy: f64::NAN,
        max_dphi: f64::NAN,
        trace: Vec::new(),
    })
}

/// The error with the route's name in front of a blow-up's reason.
fn tagged(name: &str, e: Error) -> Error {
    match e {
        Error::Blowup { step, t, reason } => Error::Blowup {
            step,
            t,
            reason: format!("{name}: {reason}"),
        },
        other => other,
    }
}

fn table(routes: &[Route], scene: &Scene) -> String {
    let mut s = format!(
        "stationary shape of a {}D scene, n = {:?}, eps = {}, h = {}\n{:<32} {:>11} {:>11} {:>12} {:>11} {:>16} {:>10}\n",
        scene.dim, scene.n, scene.eps, scene.h, "route", "steps", "evals", "t", "wall [s]", "e", "max|dphi|"
    );
    for r in routes {
        let _ = writeln!(
            s,
            "{:<32} {:>11} {:>11} {:>12.4e} {:>11.3} {:>16.10} {:>10.2e}",
            r.name, r.steps, r.evaluations, r.t, r.wall, r.reduced_energy, r.max_dphi
        );
    }
    let (c, l, f) = (&routes[0], &routes[1], &routes[2]);
    let _ = writeln!(
        s,
        "L-BFGS reaches F* to {ENERGY_TOL:e} and phi* to {PHI_TOL:e}: {:.1}x less wall time, {:.1}x fewer evaluations than the conserved flow",
        c.wall / l.wall,
        c.evaluations as f64 / l.evaluations as f64
    );
    let _ = writeln!(
        s,
        "conserved spectral vs FD at 95% of its bound to the same t*: {:.3e}x less wall time (FD extrapolated from {FD_TIMED_STEPS} timed steps)",
        f.wall / c.wall
    );
    s
}

fn csv(routes: &[Route]) -> String {
    let mut s =
        String::from("route,steps,evaluations,t,wall_seconds,energy,reduced_energy,max_abs_dphi\n");
    for r in routes {
        let _ = writeln!(
            s,
            "\"{}\",{},{},{},{},{},{},{}",
            r.name, r.steps, r.evaluations, r.t, r.wall, r.energy, r.reduced_energy, r.max_dphi
        );
    }
    s
}
