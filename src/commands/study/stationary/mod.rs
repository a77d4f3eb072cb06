//! `vesicle study stationary FILE`: what each engine and each `stop_residual` buy on the way to
//! a stationary state, as tables and as speed-against-accuracy (Pareto) charts. `FILE` is a
//! scene file (the default routes of [`Plan::for_scene`]) or a study file (`"study":
//! "stationary"`, e.g. `runs/studies/stationary.json`, whose keys choose the routes: [`Spec`]).
//!
//! From the field after the scene's `prepare_steps`, every route runs once (L-BFGS
//! `relax_runs` times, the run of median wall time tabulated) and its trace — steps, energy
//! evaluations, simulated time, wall time, residual RMS(μ − μ̄), energy F — is kept
//! ([`measure`]):
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
//! ([`report`]) `stationary.txt`, `stationary.csv` (each route at each `stop_residual`),
//! `traces.csv` (the error |F − F*|/F* against wall time of every route, thinned), `levels.csv`
//! (the fastest spectral and FD route to each error level, by wall time) and the charts
//! `convergence` (energy error against wall time), `residual` (energy error against residual)
//! and `stationary_pareto`.

pub mod measure;
pub mod report;
pub mod spec;

pub use measure::{Family, Measurement, Point, Route};
pub use spec::{Conserved, Plan, Spec, TOLERANCES};

use super::file;
use super::harness::{self, Report, Study};
use crate::error::Result;
use crate::problem::config::Scene;
use std::path::Path;

/// The study on a study file ([`Spec`]); [`stationary`] runs it on a scene file.
pub struct Stationary;

impl Study for Stationary {
    const NAME: &'static str = "stationary";
    type Spec = Spec;
    type Output = Measurement;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Measurement, Report)> {
        let scene = file::scene(&spec.scene, &[], "scene", dir)?;
        let plan = Plan::of_spec(spec, &scene)?;
        measured(&scene, &plan)
    }
}

/// The routes of `plan` on `scene` and their report.
fn measured(scene: &Scene, plan: &Plan) -> Result<(Measurement, Report)> {
    let study = measure::routes(scene, plan)?;
    let report = report::report(&study, scene, plan)?;
    Ok((study, report))
}

/// Run the study on the scene file's `scene` (the default routes of [`Plan::for_scene`]) into
/// `out`.
///
/// # Errors
/// `Error::Config` for an unsuitable scene or an existing `out` without `force`;
/// `Error::Blowup` if a route diverges.
pub fn stationary(scene: &Scene, out: &Path, force: bool) -> Result<Measurement> {
    harness::run_with::<Stationary>(out, force, || on_scene(scene))
}

/// The study's measurement and report on the scene file's `scene` (the default routes of
/// [`Plan::for_scene`]), nothing written.
///
/// # Errors
/// As [`stationary`], but for the output folder.
pub fn on_scene(scene: &Scene) -> Result<(Measurement, Report)> {
    measured(scene, &Plan::for_scene(scene))
}

/// Run the study file at `path` (its quick variant if `quick`) into `out` ([`harness::run`]).
///
/// # Errors
/// As [`stationary`], and `Error::Config` naming the key of a bad study file.
pub fn stationary_file(path: &Path, quick: bool, out: &Path, force: bool) -> Result<Measurement> {
    harness::run::<Stationary>(path, quick, out, force)
}
