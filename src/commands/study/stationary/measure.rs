//! The stationary study's measurement: every route of a [`Plan`] from the scene's prepared
//! field, each kept as its trace of states ([`Route`]), and the reference F* and φ* of L-BFGS.

use super::spec::{Conserved, Plan};
use crate::commands::study::harness;
use crate::driver::record::Record;
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::fd;
use crate::error::{Error, Result};
use crate::problem::config::{
    AdaptiveSpec, AreaMethod, Dynamics, Laplacian, Method, Scene, Scheme,
};
use crate::problem::setup::{self, Problem};
use ndarray::Array3;

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
    /// RMS(μ − μ̄) (NaN where not measured: the extrapolated FD route).
    pub residual: f64,
    /// F_sc.
    pub energy: f64,
}

impl Point {
    /// The state a simulation record describes (evaluations: steps and rejected attempts).
    fn of(r: &Record) -> Self {
        Point {
            steps: r.step,
            evaluations: r.step + r.rejected,
            t: r.t,
            wall: r.wall_seconds,
            residual: r.residual,
            energy: r.energy,
        }
    }
}

/// `spectral` (measured) or `FD` (extrapolated).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// A spectral route, measured.
    Spectral,
    /// FD explicit Euler, extrapolated from timed steps.
    Fd,
}

impl Family {
    /// `spectral` or `FD`, as in the CSV files.
    pub fn as_str(self) -> &'static str {
        match self {
            Family::Spectral => "spectral",
            Family::Fd => "FD",
        }
    }
}

/// One route to the stationary state.
#[derive(Clone, Debug)]
pub struct Route {
    /// Name in the tables.
    pub name: String,
    /// Measured or extrapolated.
    pub family: Family,
    /// Every state along the way.
    pub trace: Vec<Point>,
    /// max|φ − φ*| of the end state against the reference (NaN where not known).
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

/// What the study measured.
#[derive(Clone, Debug)]
pub struct Measurement {
    /// L-BFGS (the reference) first, then the conserved routes, then FD.
    pub routes: Vec<Route>,
    /// F* (the reference's end energy).
    pub f_star: f64,
    /// Wall seconds of every L-BFGS run, fastest first (the median one is `routes[0]`).
    pub relax_walls: Vec<f64>,
    /// Notes on the FD extrapolation, one line per spacing.
    pub fd_notes: Vec<String>,
}

impl Measurement {
    /// The relative energy error |F − F*|/|F*| of a state.
    pub fn error(&self, p: &Point) -> f64 {
        ((p.energy - self.f_star) / self.f_star).abs()
    }

    /// The route of `family` that first gets its error below `level` in the least wall time:
    /// (wall seconds at that state, name). Wall time is what the speed-against-accuracy tables
    /// rank by; it varies from run to run and machine to machine (the evaluations of each
    /// route, in the traces, do not).
    pub fn fastest(&self, family: Family, level: f64) -> Option<(f64, &str)> {
        self.routes
            .iter()
            .filter(|r| r.family == family)
            .filter_map(|r| {
                r.trace
                    .iter()
                    .find(|p| self.error(p) < level)
                    .map(|p| (p.wall, r.name.as_str()))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}

/// Every route of `plan` on `scene`, from the field after the scene's `prepare_steps`: L-BFGS
/// `relax_runs` times (the run of median wall time kept: F* and φ* are its end), each
/// conserved route, then FD extrapolated at each spacing.
///
/// # Errors
/// `Error::Config` (field `sbdf1_dt`) for a plan without a conserved SBDF1 route;
/// `Error::Blowup` if a route diverges.
pub fn routes(scene: &Scene, plan: &Plan) -> Result<Measurement> {
    let mut problem = setup::build(scene)?;
    problem.phi = crate::commands::study::prepared_field(scene, &problem)?;
    let lbfgs_to = plan
        .stop_residual
        .iter()
        .copied()
        .fold(plan.reference_residual, f64::min);
    let relax = (0..plan.relax_runs)
        .map(|_| relaxed_route(scene, &problem, lbfgs_to, plan.max_steps))
        .collect::<Result<Vec<_>>>()?;
    let ((reference, phi_star), relax_walls) = median_run(relax);
    let f_star = reference.end().energy;
    let mut routes = vec![reference];
    for c in &plan.conserved {
        routes.push(conserved_route(scene, &problem, c, plan, &phi_star)?);
    }
    let clock = clock_route(&routes, &plan.conserved)
        .ok_or_else(|| Error::config("sbdf1_dt", "the FD model needs a conserved SBDF1 route"))?
        .clone();
    let mut study = Measurement {
        routes,
        f_star,
        relax_walls,
        fd_notes: Vec::new(),
    };
    for &hf in &plan.fd_h {
        let (route, note) = fd_route(scene, plan, hf, &clock, f_star)?;
        study.routes.push(route);
        study.fd_notes.push(note);
    }
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

/// Run `s` from `problem.phi` under `rules`: the trace (the start state first) and the end φ.
fn trace(
    s: &Scene,
    problem: &Problem,
    rules: &StopRules,
    name: &str,
) -> Result<(Vec<Point>, Array3<f64>)> {
    let (mut sim, _) = Simulation::of_scene(s, problem)?;
    let mut trace = vec![Point::of(&sim.record())];
    let mut probe = Probe(|now: &Now| {
        trace.push(Point::of(&now.record));
        Ok(Flow::Continue)
    });
    sim.run(rules, &mut [&mut probe])
        .map_err(|e| e.within(name))?;
    Ok((trace, sim.engine().phi().clone()))
}

/// The scene of a route: spectral, no preparation (the field is prepared once), the study's
/// stop rules only, the area held by the projection where the scene has the Lagrangian update
/// (a stationary state is the same; the projection does not oscillate).
fn route_scene(scene: &Scene, edit: impl FnOnce(&mut Scene)) -> Result<Scene> {
    harness::variant(scene, "scene", |s| {
        s.method = Method::Spectral;
        s.prepare_steps = 0;
        s.t_end = None;
        s.stop_residual = None;
        s.max_steps = Some(s.max_steps.unwrap_or(1_000_000).max(1));
        if s.area_method() == AreaMethod::Lagrangian {
            s.area.method = Some(AreaMethod::Projection);
            s.area.alpha = None;
        }
        edit(s);
    })
}

/// Stop at residual `tol` or after `max_steps`.
fn rules(tol: f64, max_steps: usize) -> StopRules {
    StopRules {
        stop_residual: Some(tol),
        max_steps: Some(max_steps),
        ..StopRules::default()
    }
}

/// L-BFGS to `tol`: the route and its end field φ*.
fn relaxed_route(
    scene: &Scene,
    problem: &Problem,
    tol: f64,
    max_steps: usize,
) -> Result<(Route, Array3<f64>)> {
    let name = "relaxational (L-BFGS)";
    let s = route_scene(scene, |s| {
        s.dynamics = Dynamics::Relaxational;
        s.adaptive = AdaptiveSpec::Flag(false);
    })?;
    let (trace, phi) = trace(&s, problem, &rules(tol, max_steps), name)?;
    let route = Route {
        name: name.into(),
        family: Family::Spectral,
        trace,
        max_dphi: 0.0,
    };
    Ok((route, phi))
}

/// A conserved route to the plan's `final_residual`, with max|φ − φ*| at its end.
fn conserved_route(
    scene: &Scene,
    problem: &Problem,
    c: &Conserved,
    plan: &Plan,
    phi_star: &Array3<f64>,
) -> Result<Route> {
    let name = c.name();
    let s = route_scene(scene, |s| {
        s.dynamics = Dynamics::Conserved;
        s.scheme = c.scheme;
        s.dt = c.dt;
        s.adaptive = match &c.adaptive {
            None => AdaptiveSpec::Flag(false),
            Some(a) => AdaptiveSpec::Settings(a.clone()),
        };
    })?;
    let (trace, phi) = trace(
        &s,
        problem,
        &rules(plan.final_residual, plan.max_steps),
        &name,
    )?;
    Ok(Route {
        name,
        family: Family::Spectral,
        trace,
        max_dphi: crate::problem::model::max_abs_diff(&phi, phi_star),
    })
}

/// The conserved flow's clock: adaptive SBDF1 at its largest `energy_alpha` (the tightest
/// control), else SBDF1 at its smallest fixed Δt.
fn clock_route<'a>(routes: &'a [Route], conserved: &[Conserved]) -> Option<&'a Route> {
    let key = |c: &Conserved| match &c.adaptive {
        Some(a) => a.energy_alpha,
        None => -c.dt,
    };
    conserved
        .iter()
        .enumerate()
        .filter(|(_, c)| c.scheme == Scheme::Sbdf1)
        .max_by(|a, b| key(a.1).total_cmp(&key(b.1)))
        .map(|(i, _)| &routes[i + 1])
}

/// FD at `hf` × the scene's h: its own stationary F*_FD (L-BFGS on the stencil's symbol),
/// timed steps, and the extrapolated route; the note on it.
fn fd_route(
    scene: &Scene,
    plan: &Plan,
    hf: f64,
    clock: &Route,
    f_star: f64,
) -> Result<(Route, String)> {
    let grid = |s: &mut Scene| {
        s.h = hf * scene.h;
        s.n = scene
            .n
            .iter()
            .map(|&m| (m as f64 / hf).round() as usize)
            .collect();
    };
    let prep = harness::variant(scene, "scene", |s| grid(s))?;
    let mut fine = setup::build(&prep)?;
    fine.phi = crate::commands::study::prepared_field(&prep, &fine)?;
    let symbol = route_scene(&prep, |s| {
        s.dynamics = Dynamics::Relaxational;
        s.adaptive = AdaptiveSpec::Flag(false);
        s.laplacian = Laplacian::Fd;
    })?;
    let (fd_trace, _) = trace(
        &symbol,
        &fine,
        &rules(plan.reference_residual, plan.max_steps),
        "L-BFGS on the FD symbol",
    )?;
    let fd_star = fd_trace.last().map_or(f64::NAN, |p| p.energy);
    let dt_fd = plan.fd_fraction * fd::stability_bound(&fine.grid, scene.eps, 0.0);
    let s = harness::variant(&prep, "scene", |s| {
        s.method = Method::Fd;
        s.dynamics = Dynamics::Conserved;
        s.adaptive = AdaptiveSpec::Flag(false);
        s.prepare_steps = 0;
        s.dt = dt_fd;
        s.t_end = None;
        s.stop_residual = None;
        s.max_steps = Some(plan.fd_timed_steps.max(1));
    })?;
    let (mut sim, _) = Simulation::of_scene(&s, &fine)?;
    sim.run(&StopRules::steps(plan.fd_timed_steps), &mut [])?;
    let per_step = sim.clock.wall_seconds / plan.fd_timed_steps.max(1) as f64;
    let floor = ((fd_star - f_star) / f_star).abs();
    // The modelled energy: F* shifted by FD's spatial error plus the flow's error at t.
    let trace = clock
        .trace
        .iter()
        .map(|p| {
            let flow = ((p.energy - f_star) / f_star).abs();
            Point {
                steps: (p.t / dt_fd).ceil() as usize,
                evaluations: (p.t / dt_fd).ceil() as usize,
                t: p.t,
                wall: p.t / dt_fd * per_step,
                residual: f64::NAN,
                energy: f_star + f_star.abs() * (floor + flow),
            }
        })
        .collect();
    let note = format!(
        "FD at h = {} ({} of its bound, dt = {dt_fd:.4e}): {per_step:.3e} s per step ({} steps timed); F*_FD = {fd_star:.10e}, spatial error {floor:.3e}",
        s.h, plan.fd_fraction, plan.fd_timed_steps
    );
    let route = Route {
        name: format!("FD explicit Euler, h = {} (extrapolated)", s.h),
        family: Family::Fd,
        trace,
        max_dphi: f64::NAN,
    };
    Ok((route, note))
}

#[cfg(test)]
mod tests {
    use super::{median_run, Family, Point, Route};

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

    fn route(trace: Vec<Point>) -> Route {
        Route {
            name: "test".into(),
            family: Family::Spectral,
            trace,
            max_dphi: 0.0,
        }
    }

    /// The energy crossing is the first state within `rel` of F* from above (a conserved route
    /// may end below the L-BFGS reference: a negative error counts as within), and the residual
    /// crossing the first state below the tolerance, each independently of the other.
    #[test]
    fn crossings_are_the_first_states_past_each_tolerance() {
        let route = route(vec![
            point(0, 1e-2, 2.0),
            point(1, 1e-5, 1.00001),
            point(2, 1e-7, 1.0000005),
            point(3, 1e-9, 0.9999999),
        ]);
        assert_eq!(route.first_within(1.0, 1e-6).map(|p| p.steps), Some(2));
        assert_eq!(route.first_within(1.0, 1e-9).map(|p| p.steps), Some(3));
        assert_eq!(route.first_within(1.0, -1.0).map(|p| p.steps), None);
        assert_eq!(route.first_below(1e-6).map(|p| p.steps), Some(2));
    }

    /// The tabulated L-BFGS run is the one of median wall time, whatever order the runs came
    /// in, and the walls are listed fastest first.
    #[test]
    fn the_median_run_is_tabulated() {
        let run =
            |id: usize, wall: usize| (route(vec![point(0, 1.0, 2.0), point(wall, 1e-9, 1.0)]), id);
        for order in [[3, 1, 2], [1, 2, 3], [2, 3, 1]] {
            let runs = order.iter().map(|&w| run(w, w)).collect();
            let ((route, id), walls) = median_run(runs);
            assert_eq!((id, route.end().wall), (2, 2.0), "{order:?}");
            assert_eq!(walls, [1.0, 2.0, 3.0]);
        }
    }
}
