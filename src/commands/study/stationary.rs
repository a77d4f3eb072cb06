//! `vesicle study stationary`: what the stop rule `stop_residual` buys, engine by engine, on
//! one scene, timed in one run.
//!
//! 1. The relaxational L-BFGS to [`TIGHTEST`] (or until it stalls at round-off): the
//!    reference stationary state, F* and φ*. It is run [`RELAX_RUNS`] times and the run of
//!    median wall time is tabulated: it lasts a second or so where the conserved flow takes
//!    half a minute, so one pause of a shared host would move its wall time, and every ratio
//!    to it, by far more than the conserved flow's.
//! 2. The conserved flow, spectral SBDF1 and SBDF2 with adaptive steps, to [`TIGHTEST`].
//! 3. For every route and every tolerance of [`TOLERANCES`]: the steps, energy evaluations and
//!    wall time at which the residual RMS(μ − μ̄) first fell below it, and the relative energy
//!    error (F − F*)/F* of that state: what a run with that `stop_residual` would have given.
//! 4. The wall time at which each route first came within [`ENERGY_TARGET`] of F* (DESIGN.md
//!    §7's measure of the relaxational route's speed).
//! 5. The FD reference at 95% of its bound: a few hundred steps timed, and the wall time to
//!    reach the time at which SBDF1 met [`RECOMMENDED`] extrapolated.
//!
//! Near a stationary state F − F* is quadratic in the gradient, so the energy error falls as the
//! square of the residual whatever the engine: one tolerance serves every engine. Writes
//! `stationary.txt` (the table and ratios), `stationary.csv`, `convergence.png` (energy error
//! against wall time) and `residual.png` (energy error against residual).

use crate::commands::run;
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::fd;
use crate::error::Result;
use crate::output;
use crate::problem::config::{
    AdaptiveSettings, AdaptiveSpec, AreaMethod, Dynamics, Method, Scene, Scheme,
};
use crate::problem::setup::{self, Problem};
use ndarray::Array3;
use std::fmt::Write as _;
use std::path::Path;

/// The stop tolerances tabulated.
pub const TOLERANCES: [f64; 5] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8];
/// Where every route is run to.
pub const TIGHTEST: f64 = 1e-8;
/// The tolerance the README recommends for stationary shapes (energy within 1e-6).
pub const RECOMMENDED: f64 = 1e-6;
/// FD steps timed for the extrapolation.
const FD_TIMED_STEPS: usize = 300;
/// The relative energy error of DESIGN.md §7's speed target (the conserved flow's stationary
/// energy to 1e-6).
const ENERGY_TARGET: f64 = 1e-6;
/// Runs of the L-BFGS route, of which the one of median wall time is tabulated.
const RELAX_RUNS: usize = 3;

/// A state a route passed through.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Steps (iterations) taken.
    pub steps: usize,
    /// Energy evaluations so far (steps + rejected attempts; line-search trials for L-BFGS).
    pub evaluations: usize,
    /// Simulated (nominal for L-BFGS) time.
    pub t: f64,
    /// Wall seconds of stepping.
    pub wall: f64,
    /// RMS(μ − μ̄).
    pub residual: f64,
    /// F_sc.
    pub energy: f64,
}

/// One route to the stationary state.
#[derive(Clone, Debug)]
pub struct Route {
    /// Name in the table.
    pub name: &'static str,
    /// Every state along the way.
    pub trace: Vec<Point>,
    /// max|φ − φ*| of the end state against the reference.
    pub max_dphi: f64,
}

impl Route {
    /// The first state whose residual is below `tol`.
    pub fn first_below(&self, tol: f64) -> Option<&Point> {
        self.trace.iter().find(|p| p.residual < tol)
    }

    /// The first state whose energy is within `rel` of `f_star`: (F − F*)/|F*| ≤ `rel`.
    pub fn first_within(&self, f_star: f64, rel: f64) -> Option<&Point> {
        self.trace
            .iter()
            .find(|p| (p.energy - f_star) / f_star.abs() <= rel)
    }

    /// The end state.
    pub fn end(&self) -> &Point {
        self.trace.last().expect("a route has its start state")
    }
}

/// The study's result.
#[derive(Clone, Debug)]
pub struct Stationary {
    /// L-BFGS (the reference), SBDF1, SBDF2.
    pub routes: Vec<Route>,
    /// F* (the reference's end energy).
    pub f_star: f64,
    /// Wall seconds of every L-BFGS run, fastest first (the median one is `routes[0]`).
    pub relax_walls: Vec<f64>,
    /// FD at 95% of its bound: extrapolated steps and wall seconds to SBDF1's time at
    /// [`RECOMMENDED`].
    pub fd_estimate: Option<(usize, f64)>,
}

/// Run the routes on `scene` and write the report into `out`.
///
/// # Errors
/// `Error::Config` for an unsuitable scene or an existing `out` without `force`;
/// `Error::Blowup` if a route diverges.
pub fn stationary(scene: &Scene, out: &Path, force: bool) -> Result<Stationary> {
    run::check_out_dir(out, force)?;
    let problem = setup::build(scene)?;
    let max_steps = scene.max_steps.unwrap_or(200_000);
    let relax = (0..RELAX_RUNS)
        .map(|_| route(scene, &problem, Route::RELAX, max_steps, None))
        .collect::<Result<Vec<_>>>()?;
    let ((reference, phi_star), relax_walls) = median_run(relax);
    let f_star = reference.end().energy;
    let mut routes = vec![reference];
    for kind in [Route::SBDF1, Route::SBDF2] {
        routes.push(route(scene, &problem, kind, max_steps, Some(&phi_star))?.0);
    }
    let fd_estimate = match routes[1].first_below(RECOMMENDED) {
        Some(p) => Some(fd_route(scene, &problem, p.t)?),
        None => None,
    };
    let study = Stationary {
        routes,
        f_star,
        relax_walls,
        fd_estimate,
    };
    run::make_out_dir(out, force)?;
    let text = table(&study, scene);
    println!("{text}");
    super::write_text(out, "stationary.txt", &text)?;
    super::write_text(out, "stationary.csv", &csv(&study))?;
    charts(out, &study)?;
    Ok(study)
}

/// The run of median end wall time among `runs` (the later of the two middle ones for an even
/// count), and the end wall time of every run, fastest first.
fn median_run<T>(mut runs: Vec<(Route, T)>) -> ((Route, T), Vec<f64>) {
    runs.sort_by(|a, b| a.0.end().wall.total_cmp(&b.0.end().wall));
    let walls = runs.iter().map(|(r, _)| r.end().wall).collect();
    let middle = runs.len() / 2;
    (runs.swap_remove(middle), walls)
}

/// Which route.
#[derive(Clone, Copy)]
struct RouteKind {
    name: &'static str,
    dynamics: Dynamics,
    scheme: Scheme,
}

impl Route {
    const RELAX: RouteKind = RouteKind {
        name: "relaxational (L-BFGS)",
        dynamics: Dynamics::Relaxational,
        scheme: Scheme::Sbdf1,
    };
    const SBDF1: RouteKind = RouteKind {
        name: "conserved SBDF1, adaptive",
        dynamics: Dynamics::Conserved,
        scheme: Scheme::Sbdf1,
    };
    const SBDF2: RouteKind = RouteKind {
        name: "conserved SBDF2, adaptive",
        dynamics: Dynamics::Conserved,
        scheme: Scheme::Sbdf2,
    };
}

/// Run one route to [`TIGHTEST`]; its trace and end φ (with max|φ − φ*| when `phi_star`).
fn route(
    scene: &Scene,
    problem: &Problem,
    kind: RouteKind,
    max_steps: usize,
    phi_star: Option<&Array3<f64>>,
) -> Result<(Route, Array3<f64>)> {
    let mut s = scene.clone();
    s.method = Method::Spectral;
    s.dynamics = kind.dynamics;
    s.scheme = kind.scheme;
    s.adaptive = match (kind.dynamics, s.adaptive.settings()) {
        (Dynamics::Relaxational, _) => AdaptiveSpec::Flag(false),
        (Dynamics::Conserved, None) => AdaptiveSpec::Settings(AdaptiveSettings::default()),
        (Dynamics::Conserved, Some(a)) => AdaptiveSpec::Settings(a),
    };
    if s.area_method() == AreaMethod::Lagrangian {
        s.area.method = Some(AreaMethod::Projection);
        s.area.alpha = None;
    }
    let (mut sim, _) = Simulation::of_scene(&s, problem)?;
    let point = |r: &crate::driver::record::Record| Point {
        steps: r.step,
        evaluations: r.step + r.rejected,
        t: r.t,
        wall: r.wall_seconds,
        residual: r.residual,
        energy: r.energy,
    };
    let mut trace = vec![point(&sim.record())];
    let mut probe = Probe(|now: &Now| {
        trace.push(point(&now.record));
        Ok(Flow::Continue)
    });
    let rules = StopRules {
        stop_residual: Some(TIGHTEST),
        max_steps: Some(max_steps),
        ..StopRules::default()
    };
    sim.run(&rules, &mut [&mut probe])
        .map_err(|e| e.within(kind.name))?;
    let phi = sim.engine().phi().clone();
    let max_dphi = phi_star.map_or(0.0, |p| crate::problem::model::max_abs_diff(&phi, p));
    Ok((
        Route {
            name: kind.name,
            trace,
            max_dphi,
        },
        phi,
    ))
}

/// FD at 95% of its bound: time FD_TIMED_STEPS steps, extrapolate to `t_star`.
fn fd_route(scene: &Scene, problem: &Problem, t_star: f64) -> Result<(usize, f64)> {
    let mut s = scene.clone();
    s.method = Method::Fd;
    s.dynamics = Dynamics::Conserved;
    s.adaptive = AdaptiveSpec::Flag(false);
    s.dt = 0.95 * fd::stability_bound(&problem.grid, scene.eps, 0.0);
    let (mut sim, _) = Simulation::of_scene(&s, problem)?;
    sim.run(&StopRules::steps(FD_TIMED_STEPS), &mut [])?;
    let per_step = sim.clock.wall_seconds / FD_TIMED_STEPS as f64;
    let steps = (t_star / s.dt).ceil() as usize;
    Ok((steps, per_step * steps as f64))
}

fn table(study: &Stationary, scene: &Scene) -> String {
    let f_star = study.f_star;
    let mut s = format!(
        "stationary state of a {}D scene, n = {:?}, eps = {}, h = {}: F* = {:.12e} (L-BFGS end, residual {:.2e})\n\
         {:<28} {:>12} {:>8} {:>8} {:>10} {:>12}\n",
        scene.dim,
        scene.n,
        scene.eps,
        scene.h,
        f_star,
        study.routes[0].end().residual,
        "route",
        "stop_residual",
        "steps",
        "evals",
        "wall [s]",
        "(F - F*)/F*"
    );
    for r in &study.routes {
        for tol in TOLERANCES {
            match r.first_below(tol) {
                Some(p) => {
                    let _ = writeln!(
                        s,
                        "{:<28} {:>12.0e} {:>8} {:>8} {:>10.3} {:>12.2e}",
                        r.name,
                        tol,
                        p.steps,
                        p.evaluations,
                        p.wall,
                        (p.energy - f_star) / f_star
                    );
                }
                None => {
                    let _ = writeln!(s, "{:<28} {:>12.0e} {:>8}", r.name, tol, "not met");
                }
            }
        }
        let _ = writeln!(
            s,
            "{:<28} end: {} steps, residual {:.2e}, (F - F*)/F* = {:.2e}, max|phi - phi*| = {:.2e}",
            r.name,
            r.end().steps,
            r.end().residual,
            (r.end().energy - f_star) / f_star,
            r.max_dphi
        );
    }
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
    let at = |i: usize| study.routes[i].first_below(RECOMMENDED);
    if let (Some(l), Some(c1), Some(c2)) = (at(0), at(1), at(2)) {
        let _ = writeln!(
            s,
            "to stop_residual {RECOMMENDED:e}: L-BFGS takes {:.1}x less wall time than SBDF1 and {:.1}x less than SBDF2; SBDF2 {:.1}x less than SBDF1",
            c1.wall / l.wall,
            c2.wall / l.wall,
            c1.wall / c2.wall
        );
    }
    let within = |i: usize| study.routes[i].first_within(f_star, ENERGY_TARGET);
    if let (Some(l), Some(c1), Some(c2)) = (within(0), within(1), within(2)) {
        let _ = writeln!(
            s,
            "to (F - F*)/F* <= {ENERGY_TARGET:e} (DESIGN.md 7): L-BFGS {:.3} s in {} steps, SBDF1 {:.3} s in {}, SBDF2 {:.3} s in {}: L-BFGS {:.1}x less wall time than SBDF1, {:.1}x less than SBDF2",
            l.wall,
            l.steps,
            c1.wall,
            c1.steps,
            c2.wall,
            c2.steps,
            c1.wall / l.wall,
            c2.wall / l.wall
        );
    }
    if let (Some((steps, wall)), Some(c1)) = (study.fd_estimate, at(1)) {
        let _ = writeln!(
            s,
            "FD at 95% of its bound to SBDF1's time t = {:.4e}: {steps} steps, {wall:.3e} s (extrapolated from {FD_TIMED_STEPS} timed steps): {:.3e}x SBDF1's wall time",
            c1.t,
            wall / c1.wall
        );
    }
    s
}

fn csv(study: &Stationary) -> String {
    let mut s = String::from(
        "route,stop_residual,steps,evaluations,t,wall_seconds,residual,energy,relative_energy_error\n",
    );
    for r in &study.routes {
        for tol in TOLERANCES {
            if let Some(p) = r.first_below(tol) {
                let _ = writeln!(
                    s,
                    "\"{}\",{tol},{},{},{},{},{},{},{}",
                    r.name,
                    p.steps,
                    p.evaluations,
                    p.t,
                    p.wall,
                    p.residual,
                    p.energy,
                    (p.energy - study.f_star) / study.f_star
                );
            }
        }
    }
    s
}

fn charts(out: &Path, study: &Stationary) -> Result<()> {
    let error = |p: &Point| ((p.energy - study.f_star) / study.f_star).abs();
    let series = |x: fn(&Point) -> f64| -> Vec<(&str, Vec<(f64, f64)>)> {
        study
            .routes
            .iter()
            .map(|r| (r.name, r.trace.iter().map(|p| (x(p), error(p))).collect()))
            .collect()
    };
    output::chart::write_timeseries_png(
        &out.join("convergence.png"),
        &series(|p| p.wall),
        "wall seconds",
        "|F - F*| / F*",
        true,
    )?;
    output::chart::write_timeseries_png(
        &out.join("residual.png"),
        &series(|p| p.residual.log10()),
        "log10 residual RMS(mu - mean mu)",
        "|F - F*| / F*",
        true,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{median_run, Point, Route};

    fn point(steps: usize, residual: f64, energy: f64) -> Point {
        Point {
            steps,
            evaluations: steps,
            t: steps as f64,
            wall: steps as f64,
            residual,
            energy,
        }
    }

    /// The energy crossing is the first state within `rel` of F* from above (a conserved route
    /// may end below the L-BFGS reference: a negative error counts as within), and the residual
    /// crossing the first state below the tolerance, each independently of the other.
    #[test]
    fn crossings_are_the_first_states_past_each_tolerance() {
        let route = Route {
            name: "test",
            trace: vec![
                point(0, 1e-2, 2.0),
                point(1, 1e-5, 1.00001),
                point(2, 1e-7, 1.0000005),
                point(3, 1e-9, 0.9999999),
            ],
            max_dphi: 0.0,
        };
        assert_eq!(route.first_within(1.0, 1e-6).map(|p| p.steps), Some(2));
        assert_eq!(route.first_within(1.0, 1e-9).map(|p| p.steps), Some(3));
        assert_eq!(route.first_within(1.0, -1.0).map(|p| p.steps), None);
        assert_eq!(route.first_below(1e-6).map(|p| p.steps), Some(2));
    }

    /// The tabulated L-BFGS run is the one of median wall time, whatever order the runs came
    /// in, and the walls are listed fastest first.
    #[test]
    fn the_median_run_is_tabulated() {
        let run = |id: usize, wall: usize| {
            let route = Route {
                name: "test",
                trace: vec![point(0, 1.0, 2.0), point(wall, 1e-9, 1.0)],
                max_dphi: 0.0,
            };
            (route, id)
        };
        for order in [[3, 1, 2], [1, 2, 3], [2, 3, 1]] {
            let runs = order.iter().map(|&w| run(w, w)).collect();
            let ((route, id), walls) = median_run(runs);
            assert_eq!((id, route.end().wall), (2, 2.0), "{order:?}");
            assert_eq!(walls, [1.0, 2.0, 3.0]);
        }
    }
}
