//! `vesicle study stationary FILE`: what each engine and each `stop_residual` buy on the way to
//! a stationary state, as tables and as speed-against-accuracy (Pareto) charts. `FILE` is a
//! scene file (the default routes below) or a study file (`"study": "stationary"`, e.g.
//! `runs/studies/stationary.json`, whose keys choose the routes).
//!
//! From the field after the scene's `prepare_steps`, every route runs once (L-BFGS
//! `relax_runs` times, the run of median wall time tabulated) and its trace — steps, energy
//! evaluations, simulated time, wall time, residual RMS(μ − μ̄), energy F — is kept:
//!
//! 1. **L-BFGS** (relaxational dynamics) to `reference_residual`: its end energy is F*, its end
//!    field φ*; the crossings of each `stop_residual` are what a run with that stop rule gives.
//! 2. **Conserved SBDF1 and SBDF2** to `final_residual` (or `max_steps`), at each fixed Δt of
//!    `sbdf1_dt`, `sbdf2_dt` and adaptive at each `energy_alpha` (first Δt and `dt_max` from
//!    `adaptive_dt`). Defaults for a scene file: adaptive with the scene's controller (or the
//!    default one), no fixed Δt.
//! 3. **FD explicit Euler**, extrapolated: at each spacing of `fd_h` (units of the scene's h;
//!    the box kept), `fd_timed_steps` steps at `fd_fraction` of its bound are timed; its error at
//!    simulated time t is modelled as its own spatial error |F*_FD − F*|/F* (F*_FD from L-BFGS
//!    on the FD stencil's symbol at that h) plus the conserved flow's error at t (adaptive SBDF1
//!    at its largest `energy_alpha`, else the smallest fixed Δt); wall = t / Δt_FD × seconds per
//!    step.
//!
//! Near a stationary state F − F* is quadratic in the gradient, so the energy error falls as the
//! square of the residual whatever the engine: one tolerance serves every engine. Writes
//! `stationary.txt`, `stationary.csv` (each route at each `stop_residual`), `traces.csv` (the
//! error |F − F*|/F* against wall time of every route, thinned), `levels.csv` (the fastest
//! spectral and FD route to each error level) and the charts `convergence` (energy error
//! against wall time), `residual` (energy error against residual) and `stationary_pareto`.

use super::file;
use super::harness::{self, Report, Session};
use crate::driver::record::Record;
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::fd;
use crate::error::{Error, Result};
use crate::output::chart::{style, Axis, Corner, Figure, Mark, Series};
use crate::problem::config::{
    AdaptiveSettings, AdaptiveSpec, AreaMethod, Dynamics, Laplacian, Method, Scene, Scheme,
};
use crate::problem::setup::{self, Problem};
use ndarray::Array3;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The stop tolerances tabulated by default.
pub const TOLERANCES: [f64; 5] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8];
/// The tolerance the guide recommends for stationary shapes (energy within 1e-6).
pub const RECOMMENDED: f64 = 1e-6;
/// The relative energy error of the speed target (the conserved flow's stationary energy to
/// 1e-6).
const ENERGY_TARGET: f64 = 1e-6;

/// The study file's keys (all but `study` and `scene` optional, with the defaults of a scene
/// file).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"stationary"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The scene (its `prepare_steps` prepare the common start).
    pub scene: Value,
    /// L-BFGS runs to this residual; its end is the reference (default 1e-8).
    #[serde(default)]
    pub reference_residual: Option<f64>,
    /// Every conserved route runs until its residual falls below this (default 1e-8).
    #[serde(default)]
    pub final_residual: Option<f64>,
    /// Step limit of every route (default: the scene's `max_steps`, else 200 000).
    #[serde(default)]
    pub max_steps: Option<usize>,
    /// L-BFGS runs, of which the median is tabulated (default 1).
    #[serde(default)]
    pub relax_runs: Option<usize>,
    /// Fixed Δt of conserved SBDF1.
    #[serde(default)]
    pub sbdf1_dt: Vec<f64>,
    /// Fixed Δt of conserved SBDF2.
    #[serde(default)]
    pub sbdf2_dt: Vec<f64>,
    /// Controller tolerances (`adaptive.energy_alpha`) of adaptive SBDF1 and SBDF2 (default:
    /// the scene's controller).
    #[serde(default)]
    pub energy_alpha: Vec<f64>,
    /// First Δt and `dt_max` of the adaptive runs (with `energy_alpha`).
    #[serde(default)]
    pub adaptive_dt: Option<[f64; 2]>,
    /// `stop_residual` values tabulated (default 1e-4 … 1e-8).
    #[serde(default)]
    pub stop_residual: Option<Vec<f64>>,
    /// FD steps timed (default 300).
    #[serde(default)]
    pub fd_timed_steps: Option<usize>,
    /// FD Δt as a fraction of its bound (default 0.95).
    #[serde(default)]
    pub fd_fraction: Option<f64>,
    /// FD spacings, in units of the scene's h (default `[1]`).
    #[serde(default)]
    pub fd_h: Option<Vec<f64>>,
    /// Error levels of the table (default 1e-2 … 1e-8).
    #[serde(default)]
    pub levels: Option<Vec<f64>>,
}

/// A conserved route: scheme, first Δt, and the controller (`None`: fixed steps).
#[derive(Clone, Debug)]
pub struct Conserved {
    /// SBDF1 or SBDF2.
    pub scheme: Scheme,
    /// Δt (the first one when adaptive).
    pub dt: f64,
    /// The controller, if adaptive.
    pub adaptive: Option<AdaptiveSettings>,
}

impl Conserved {
    /// `conserved SBDF1, dt = 10` or `conserved SBDF2, adaptive (energy_alpha 1e6)`.
    fn name(&self) -> String {
        let scheme = match self.scheme {
            Scheme::Sbdf1 => "SBDF1",
            Scheme::Sbdf2 => "SBDF2",
        };
        match &self.adaptive {
            None => format!("conserved {scheme}, dt = {}", self.dt),
            Some(a) => format!(
                "conserved {scheme}, adaptive (energy_alpha {:.0e})",
                a.energy_alpha
            ),
        }
    }
}

/// The routes and tolerances of one study, resolved from a study file or a scene.
#[derive(Clone, Debug)]
pub struct Plan {
    /// L-BFGS tolerance (the reference).
    pub reference_residual: f64,
    /// Conserved routes' tolerance.
    pub final_residual: f64,
    /// Step limit of every route.
    pub max_steps: usize,
    /// L-BFGS runs.
    pub relax_runs: usize,
    /// The conserved routes.
    pub conserved: Vec<Conserved>,
    /// `stop_residual` values tabulated.
    pub stop_residual: Vec<f64>,
    /// FD steps timed.
    pub fd_timed_steps: usize,
    /// FD Δt / its bound.
    pub fd_fraction: f64,
    /// FD spacings / the scene's h.
    pub fd_h: Vec<f64>,
    /// Error levels.
    pub levels: Vec<f64>,
}

impl Plan {
    /// The default routes on `scene`: L-BFGS three times, SBDF1 and SBDF2 adaptive with the
    /// scene's controller, FD at the scene's h at 0.95 of its bound; every route to 1e-8.
    pub fn for_scene(scene: &Scene) -> Self {
        let a = scene.adaptive.settings().unwrap_or_default();
        Plan {
            reference_residual: 1e-8,
            final_residual: 1e-8,
            max_steps: scene.max_steps.unwrap_or(200_000),
            relax_runs: 3,
            conserved: [Scheme::Sbdf1, Scheme::Sbdf2]
                .map(|scheme| Conserved {
                    scheme,
                    dt: scene.dt,
                    adaptive: Some(a.clone()),
                })
                .to_vec(),
            stop_residual: TOLERANCES.to_vec(),
            fd_timed_steps: 300,
            fd_fraction: 0.95,
            fd_h: vec![1.0],
            levels: vec![1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
        }
    }

    /// The plan of a study file on its scene `scene` (defaults from [`Plan::for_scene`]).
    ///
    /// # Errors
    /// `Error::Config` naming the key: `energy_alpha` without `adaptive_dt`.
    pub fn of_spec(spec: &Spec, scene: &Scene) -> Result<Self> {
        let d = Plan::for_scene(scene);
        let mut conserved = Vec::new();
        for (scheme, dts) in [
            (Scheme::Sbdf1, &spec.sbdf1_dt),
            (Scheme::Sbdf2, &spec.sbdf2_dt),
        ] {
            conserved.extend(dts.iter().map(|&dt| Conserved {
                scheme,
                dt,
                adaptive: None,
            }));
            match (spec.energy_alpha.as_slice(), spec.adaptive_dt) {
                ([], _) => {
                    conserved.extend(d.conserved.iter().filter(|c| c.scheme == scheme).cloned())
                }
                (_, None) => {
                    return Err(Error::config(
                        "adaptive_dt",
                        "missing: energy_alpha needs the adaptive runs' [first dt, dt_max]",
                    ))
                }
                (alphas, Some([dt, dt_max])) => {
                    conserved.extend(alphas.iter().map(|&ea| Conserved {
                        scheme,
                        dt,
                        adaptive: Some(AdaptiveSettings {
                            energy_alpha: ea,
                            dt_max: Some(dt_max),
                            ..AdaptiveSettings::default()
                        }),
                    }))
                }
            }
        }
        Ok(Plan {
            reference_residual: spec.reference_residual.unwrap_or(d.reference_residual),
            final_residual: spec.final_residual.unwrap_or(d.final_residual),
            max_steps: spec.max_steps.unwrap_or(d.max_steps),
            relax_runs: spec.relax_runs.unwrap_or(1).max(1),
            conserved,
            stop_residual: spec.stop_residual.clone().unwrap_or(d.stop_residual),
            fd_timed_steps: spec.fd_timed_steps.unwrap_or(d.fd_timed_steps),
            fd_fraction: spec.fd_fraction.unwrap_or(d.fd_fraction),
            fd_h: spec.fd_h.clone().unwrap_or(d.fd_h),
            levels: spec.levels.clone().unwrap_or(d.levels),
        })
    }
}

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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Family {
    /// A spectral route, measured.
    #[serde(rename = "spectral")]
    Spectral,
    /// FD explicit Euler, extrapolated from timed steps.
    #[serde(rename = "FD")]
    Fd,
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

/// The study's result.
#[derive(Clone, Debug)]
pub struct Stationary {
    /// L-BFGS (the reference) first, then the conserved routes, then FD.
    pub routes: Vec<Route>,
    /// F* (the reference's end energy).
    pub f_star: f64,
    /// Wall seconds of every L-BFGS run, fastest first (the median one is `routes[0]`).
    pub relax_walls: Vec<f64>,
    /// Notes on the FD extrapolation, one line per spacing.
    pub fd_notes: Vec<String>,
}

impl Stationary {
    /// The relative energy error |F − F*|/|F*| of a state.
    pub fn error(&self, p: &Point) -> f64 {
        ((p.energy - self.f_star) / self.f_star).abs()
    }

    /// The fastest route of `family` whose error falls below `level`: (wall, name).
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

/// Run the study on the scene file's `scene` (the default routes of [`Plan::for_scene`]) into
/// `out`.
///
/// # Errors
/// `Error::Config` for an unsuitable scene or an existing `out` without `force`;
/// `Error::Blowup` if a route diverges.
pub fn stationary(scene: &Scene, out: &Path, force: bool) -> Result<Stationary> {
    let session = Session::open(out, force)?;
    let (study, report) = measure(scene, &Plan::for_scene(scene))?;
    session.finish("stationary", report)?;
    Ok(study)
}

/// Run the study file at `path` (its quick variant if `quick`) into `out`.
///
/// # Errors
/// As [`stationary`], and `Error::Config` naming the key of a bad study file.
pub fn stationary_file(path: &Path, quick: bool, out: &Path, force: bool) -> Result<Stationary> {
    let spec: Spec = file::load(path, "stationary", quick)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let scene = file::scene(&spec.scene, &[], "scene", dir)?;
    let plan = Plan::of_spec(&spec, &scene)?;
    let session = Session::open(out, force)?;
    let (study, report) = measure(&scene, &plan)?;
    session.finish("stationary", report)?;
    Ok(study)
}

/// Every route of `plan` on `scene`, and the report.
fn measure(scene: &Scene, plan: &Plan) -> Result<(Stationary, Report)> {
    let mut problem = setup::build(scene)?;
    problem.phi = super::prepared_field(scene, &problem)?;
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
    let mut study = Stationary {
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
    let mut report = Report {
        text: table(&study, scene, plan),
        ..Report::default()
    };
    report.table("stationary.csv", &tolerance_rows(&study, plan))?;
    report.table("traces.csv", &trace_rows(&study))?;
    report.table("levels.csv", &level_rows(&study, plan))?;
    charts(&mut report, &study);
    Ok((study, report))
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
    fine.phi = super::prepared_field(&prep, &fine)?;
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

fn table(study: &Stationary, scene: &Scene, plan: &Plan) -> String {
    let f_star = study.f_star;
    let lbfgs = &study.routes[0];
    let mut s = format!(
        "stationary state of a {}D scene, n = {:?}, eps = {}, h = {}: F* = {:.12e} (L-BFGS end, residual {:.2e})\n\
         {:<48} {:>12} {:>8} {:>8} {:>10} {:>12}\n",
        scene.dim,
        scene.n,
        scene.eps,
        scene.h,
        f_star,
        lbfgs.end().residual,
        "route",
        "stop_residual",
        "steps",
        "evals",
        "wall [s]",
        "(F - F*)/F*"
    );
    for r in study.routes.iter().filter(|r| r.family == Family::Spectral) {
        for &tol in &plan.stop_residual {
            match r.first_below(tol) {
                Some(p) => {
                    let _ = writeln!(
                        s,
                        "{:<48} {:>12.0e} {:>8} {:>8} {:>10.3} {:>12.2e}",
                        r.name,
                        tol,
                        p.steps,
                        p.evaluations,
                        p.wall,
                        (p.energy - f_star) / f_star
                    );
                }
                None => {
                    let _ = writeln!(s, "{:<48} {:>12.0e} {:>8}", r.name, tol, "not met");
                }
            }
        }
        let _ = writeln!(
            s,
            "{:<48} end: {} steps, residual {:.2e}, (F - F*)/F* = {:.2e}, max|phi - phi*| = {:.2e}",
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
    // The ratios between L-BFGS and the first SBDF1 and SBDF2 routes.
    let first = |scheme: &str| {
        study
            .routes
            .iter()
            .find(|r| r.family == Family::Spectral && r.name.contains(scheme))
    };
    if let (Some(c1), Some(c2)) = (first("SBDF1"), first("SBDF2")) {
        let at = |r: &Route| r.first_below(RECOMMENDED).copied();
        if let (Some(l), Some(a), Some(b)) = (at(lbfgs), at(c1), at(c2)) {
            let _ = writeln!(
                s,
                "to stop_residual {RECOMMENDED:e}: L-BFGS takes {:.1}x less wall time than SBDF1 and {:.1}x less than SBDF2; SBDF2 {:.1}x less than SBDF1",
                a.wall / l.wall,
                b.wall / l.wall,
                a.wall / b.wall
            );
        }
        let within = |r: &Route| r.first_within(f_star, ENERGY_TARGET).copied();
        if let (Some(l), Some(a), Some(b)) = (within(lbfgs), within(c1), within(c2)) {
            let _ = writeln!(
                s,
                "to (F - F*)/F* <= {ENERGY_TARGET:e}: L-BFGS {:.3} s in {} steps, SBDF1 {:.3} s in {}, SBDF2 {:.3} s in {}: L-BFGS {:.1}x less wall time than SBDF1, {:.1}x less than SBDF2",
                l.wall,
                l.steps,
                a.wall,
                a.steps,
                b.wall,
                b.steps,
                a.wall / l.wall,
                b.wall / l.wall
            );
        }
        let _ = writeln!(s, "(SBDF1: {}; SBDF2: {})", c1.name, c2.name);
    }
    for n in &study.fd_notes {
        let _ = writeln!(s, "{n}");
    }
    let _ = writeln!(
        s,
        "FD error modelled as |F*_FD - F*|/F* + the conserved flow's error at the same t (the SBDF1 route of tightest control)"
    );
    let _ = writeln!(
        s,
        "\n  {:>8} {:>10} {:<48} {:>10} {:<44} {:>12}",
        "level", "spectral s", "fastest spectral", "FD s", "fastest FD", "spectral/FD"
    );
    for r in level_rows(study, plan) {
        let _ = writeln!(
            s,
            "  {:>8.0e} {:>10} {:<48} {:>10} {:<44} {:>12}",
            r.level,
            fmt_wall(r.spectral_wall_seconds),
            or_not(&r.fastest_spectral),
            fmt_wall(r.fd_wall_seconds),
            or_not(&r.fastest_fd),
            if r.ratio_spectral_over_fd.is_finite() {
                format!("{:.3e}", r.ratio_spectral_over_fd)
            } else {
                "-".into()
            }
        );
    }
    s
}

fn fmt_wall(w: f64) -> String {
    if w.is_finite() {
        format!("{w:.3}")
    } else {
        "-".into()
    }
}

fn or_not(name: &str) -> &str {
    if name.is_empty() {
        "not reached"
    } else {
        name
    }
}

/// A row of `stationary.csv`: a spectral route at a `stop_residual`.
#[derive(Serialize)]
struct ToleranceRow<'a> {
    route: &'a str,
    stop_residual: f64,
    steps: usize,
    evaluations: usize,
    t: f64,
    wall_seconds: f64,
    residual: f64,
    energy: f64,
    relative_energy_error: f64,
}

fn tolerance_rows<'a>(study: &'a Stationary, plan: &Plan) -> Vec<ToleranceRow<'a>> {
    let mut rows = Vec::new();
    for r in study.routes.iter().filter(|r| r.family == Family::Spectral) {
        for &tol in &plan.stop_residual {
            if let Some(p) = r.first_below(tol) {
                rows.push(ToleranceRow {
                    route: &r.name,
                    stop_residual: tol,
                    steps: p.steps,
                    evaluations: p.evaluations,
                    t: p.t,
                    wall_seconds: p.wall,
                    residual: p.residual,
                    energy: p.energy,
                    relative_energy_error: (p.energy - study.f_star) / study.f_star,
                });
            }
        }
    }
    rows
}

/// A row of `traces.csv`: a state of a route.
#[derive(Serialize)]
struct TraceRow<'a> {
    family: Family,
    config: &'a str,
    t: f64,
    wall_seconds: f64,
    error: f64,
    residual: f64,
}

/// The states of a trace worth a row: each whose error is at least 10% below the last row's,
/// and the last (a trace has a state per step; this keeps its shape in a small file).
fn thinned(study: &Stationary, trace: &[Point]) -> Vec<Point> {
    let mut last = f64::INFINITY;
    let n = trace.len();
    trace
        .iter()
        .enumerate()
        .filter(|(i, p)| {
            let e = study.error(p);
            let keep = e.is_finite() && (e < 0.9 * last || i + 1 == n);
            if keep {
                last = e;
            }
            keep
        })
        .map(|(_, p)| *p)
        .collect()
}

fn trace_rows(study: &Stationary) -> Vec<TraceRow<'_>> {
    study
        .routes
        .iter()
        .flat_map(|r| {
            thinned(study, &r.trace).into_iter().map(move |p| TraceRow {
                family: r.family,
                config: &r.name,
                t: p.t,
                wall_seconds: p.wall,
                error: study.error(&p),
                residual: p.residual,
            })
        })
        .collect()
}

/// A row of `levels.csv`: the fastest spectral and FD route to an error level.
#[derive(Serialize)]
struct LevelRow {
    part: &'static str,
    level: f64,
    fastest_spectral: String,
    spectral_wall_seconds: f64,
    fastest_fd: String,
    fd_wall_seconds: f64,
    ratio_spectral_over_fd: f64,
}

fn level_rows(study: &Stationary, plan: &Plan) -> Vec<LevelRow> {
    plan.levels
        .iter()
        .map(|&level| {
            let sp = study.fastest(Family::Spectral, level);
            let fd = study.fastest(Family::Fd, level);
            LevelRow {
                part: "stationary",
                level,
                fastest_spectral: sp.map_or(String::new(), |x| x.1.to_string()),
                spectral_wall_seconds: sp.map_or(f64::NAN, |x| x.0),
                fastest_fd: fd.map_or(String::new(), |x| x.1.to_string()),
                fd_wall_seconds: fd.map_or(f64::NAN, |x| x.0),
                ratio_spectral_over_fd: match (sp, fd) {
                    (Some(a), Some(b)) => a.0 / b.0,
                    _ => f64::NAN,
                },
            }
        })
        .collect()
}

/// The Pareto front of `(wall, error)` points: those no other point beats in both.
pub fn pareto(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
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

fn charts(report: &mut Report, study: &Stationary) {
    let spectral: Vec<&Route> = study
        .routes
        .iter()
        .filter(|r| r.family == Family::Spectral)
        .collect();
    for (stem, title, x_axis, x) in [
        (
            "convergence",
            "Energy error against wall time",
            Axis::linear("wall seconds"),
            (|p: &Point| p.wall) as fn(&Point) -> f64,
        ),
        (
            "residual",
            "Energy error against the residual (the error falls as its square)",
            Axis::log("residual RMS(mu - mean mu)"),
            |p: &Point| p.residual,
        ),
    ] {
        let mut fig = Figure::new(title, x_axis, Axis::log("|F - F*| / F*"));
        fig.legend = Corner::UpperRight;
        for (i, r) in spectral.iter().enumerate() {
            let (c, mark) = style(i);
            let pts = r.trace.iter().map(|p| (x(p), study.error(p))).collect();
            fig.push(Series::new(r.name.clone(), pts, c, mark));
        }
        report.chart(stem, fig);
    }

    let mut fig = Figure::new(
        "Stationary state: energy error against wall time (FD extrapolated)",
        Axis::log("wall time [s]"),
        Axis::log("|F - F*| / F*"),
    );
    fig.legend = Corner::LowerRight;
    let traces: Vec<Vec<(f64, f64)>> = study
        .routes
        .iter()
        .map(|r| {
            thinned(study, &r.trace)
                .iter()
                .filter(|p| p.wall > 0.0)
                .map(|p| (p.wall, study.error(p)))
                .collect()
        })
        .collect();
    // The front first, wide and grey, so that the routes on it stay visible.
    fig.push(Series::new(
        "Pareto front (no route faster at that error)",
        pareto(traces.iter().flatten().copied().collect()),
        [190, 190, 190],
        Mark::Dashed,
    ));
    for (i, (r, pts)) in study.routes.iter().zip(traces).enumerate() {
        let (c, mark) = style(i);
        fig.push(Series::new(r.name.clone(), pts, c, mark));
    }
    report.chart("stationary_pareto", fig);
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

    /// The Pareto front keeps the points no other beats in both wall time and error.
    #[test]
    fn the_pareto_front_is_the_undominated_points() {
        let front = super::pareto(vec![
            (1.0, 1e-2),
            (2.0, 1e-3),
            (1.5, 1e-2),
            (3.0, 1e-4),
            (2.5, 1e-3),
        ]);
        assert_eq!(front, vec![(1.0, 1e-2), (2.0, 1e-3), (3.0, 1e-4)]);
    }
}
