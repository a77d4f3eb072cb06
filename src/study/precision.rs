//! `vesicle study precision`: work against precision of the time steppers (a work-precision
//! chart). From one prepared field, each stepper runs to `t_end` at a ladder of fixed Δt:
//! FD explicit Euler at 90%, 45% and 22.5% of its bound, spectral SBDF1 and SBDF2 at
//! dt, dt/2, …, dt/16 (the scene's dt). The error is max|φ − φ_ref| at `t_end` against spectral
//! SBDF2 at dt/64 on the same grid, so FD's error includes its O(h²) spatial error. The flow is
//! the unconstrained one (area method none), to compare the steppers alone.
//!
//! Writes `precision.csv`, `precision.txt` and `precision.png` (log10 error against log10 wall
//! seconds, one line per stepper).

use crate::config::{AdaptiveSpec, AreaMethod, Method, Scene, Scheme};
use crate::error::{Error, Result};
use crate::fd;
use crate::output;
use crate::run;
use crate::setup::{self, Problem};
use crate::simulation::{Simulation, StopRules};
use ndarray::Array3;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// One run of the ladder.
#[derive(Clone, Debug)]
pub struct Point {
    /// Stepper name.
    pub stepper: &'static str,
    /// Time step.
    pub dt: f64,
    /// Steps taken.
    pub steps: usize,
    /// Wall seconds.
    pub wall: f64,
    /// max|φ − φ_ref| at t_end.
    pub error: f64,
}

/// Run the ladder on `scene` over `[0, t_end]` and write the report into `out`.
///
/// # Errors
/// `Error::Config` if the scene has no `t_end` or `out` exists without `force`;
/// `Error::Blowup` if a run diverges.
pub fn precision(scene: &Scene, out: &Path, force: bool) -> Result<Vec<Point>> {
    let t_end = scene
        .t_end
        .ok_or_else(|| Error::config("t_end", "the precision study needs t_end"))?;
    run::check_out_dir(out, force)?;
    let problem = prepared(scene)?;
    let reference = advance(
        &variant(scene, Method::Spectral, Scheme::Sbdf2, scene.dt / 64.0),
        &problem,
        t_end,
    )?
    .0;
    let bound = fd::stability_bound(&problem.grid, scene.eps, 0.0);
    let mut points = Vec::new();
    let mut ladder = |name: &'static str, method, scheme, dts: Vec<f64>| -> Result<()> {
        for dt in dts {
            let (phi, steps, wall) = advance(&variant(scene, method, scheme, dt), &problem, t_end)?;
            let error = crate::model::max_abs_diff(&phi, &reference);
            points.push(Point {
                stepper: name,
                dt,
                steps,
                wall,
                error,
            });
        }
        Ok(())
    };
    let halvings = |base: f64, n: i32| (0..n).map(|i| base / 2f64.powi(i)).collect::<Vec<_>>();
    ladder(
        "fd explicit Euler",
        Method::Fd,
        Scheme::Sbdf1,
        halvings(0.9 * bound, 3),
    )?;
    ladder(
        "spectral SBDF1",
        Method::Spectral,
        Scheme::Sbdf1,
        halvings(scene.dt, 5),
    )?;
    ladder(
        "spectral SBDF2",
        Method::Spectral,
        Scheme::Sbdf2,
        halvings(scene.dt, 5),
    )?;
    run::make_out_dir(out, force)?;
    let mut csv = String::from("stepper,dt,steps,wall_seconds,max_abs_error\n");
    let mut txt = format!(
        "max|phi - phi_ref| at t = {t_end} (reference: spectral SBDF2, dt = {:.3e})\n{:<20} {:>11} {:>9} {:>11} {:>11}\n",
        scene.dt / 64.0, "stepper", "dt", "steps", "wall [s]", "error"
    );
    for p in &points {
        let _ = writeln!(
            csv,
            "\"{}\",{},{},{},{}",
            p.stepper, p.dt, p.steps, p.wall, p.error
        );
        let _ = writeln!(
            txt,
            "{:<20} {:>11.3e} {:>9} {:>11.4} {:>11.3e}",
            p.stepper, p.dt, p.steps, p.wall, p.error
        );
    }
    println!("{txt}");
    super::write_text(out, "precision.csv", &csv)?;
    super::write_text(out, "precision.txt", &txt)?;
    let mut names: Vec<&str> = points.iter().map(|p| p.stepper).collect();
    names.dedup();
    let series: Vec<(&str, Vec<(f64, f64)>)> = names
        .iter()
        .map(|&n| {
            let pts = points
                .iter()
                .filter(|p| p.stepper == n)
                .map(|p| (p.wall.max(1e-6).log10(), p.error))
                .collect();
            (n, pts)
        })
        .collect();
    output::chart::write_timeseries_png(
        &out.join("precision.png"),
        &series,
        "log10 wall seconds",
        "max |phi - phi_ref|",
        true,
    )?;
    Ok(points)
}

/// The scene's field after its preparation steps (spectral SBDF1), shared by every run.
fn prepared(scene: &Scene) -> Result<Problem> {
    let mut problem = setup::build(scene)?;
    let s = variant(scene, Method::Spectral, Scheme::Sbdf1, scene.dt);
    let (sim, _) = Simulation::of_scene(
        &Scene {
            prepare_steps: scene.prepare_steps,
            ..s
        },
        &problem,
    )?;
    problem.phi = sim.engine().phi().clone();
    Ok(problem)
}

/// The scene as one run of the ladder: fixed Δt, no area constraint, no preparation.
fn variant(scene: &Scene, method: Method, scheme: Scheme, dt: f64) -> Scene {
    let mut s = scene.clone();
    s.method = method;
    s.scheme = scheme;
    s.dt = dt;
    s.adaptive = AdaptiveSpec::Flag(false);
    s.area.method = Some(AreaMethod::None);
    s.area.alpha = None;
    s.area.target = None;
    s.prepare_steps = 0;
    s
}

/// Run `s` from `problem.phi` to `t_end`: the final φ, the steps and the wall seconds
/// (planning included).
fn advance(s: &Scene, problem: &Problem, t_end: f64) -> Result<(Array3<f64>, usize, f64)> {
    let clock = Instant::now();
    let (mut sim, _) = Simulation::of_scene(s, problem)?;
    sim.run(&StopRules::until(t_end), &mut [])?;
    Ok((
        sim.engine().phi().clone(),
        sim.clock.step,
        clock.elapsed().as_secs_f64(),
    ))
}
