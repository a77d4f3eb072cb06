//! `vesicle study …`: measurements that compare methods in one run and print ratios.
//!
//! * [`convergence`], [`stability`], [`precision`]: studies run from a study file
//!   (`runs/studies/*.json`, read by [`mod@file`]), with a `--quick` variant; orders from the
//!   least-squares fits of [`fit`], stability classes from [`classify`];
//! * every study through [`harness`] (the output folder, the report), its tables through
//!   [`table`] (one description of a row's columns for the CSV file and the printed table);
//!   [`levels`]: the speed-against-accuracy rows and Pareto front of `precision` and
//!   `stationary`;
//! * [`stationary`]: what each `stop_residual` buys per engine, on a scene file or a study file;
//! * [`pinning`]: the lattice pinning of stationary energies against h/ε; [`resolution`]: speed
//!   against accuracy for stationary shapes against the sharp reference (both on the shapes of
//!   [`shape_case`]);
//! * [`nonaxisymmetric`]: a non-axisymmetric ADE state (triaxial, starfish) against the
//!   axisymmetric branches at the same (v, α, Δa0), phase field and sharp;
//! * [`budding`]: quasi-static budding in c̄0 through stationary states beside the sharp pear
//!   branch; [`onset`]: where it starts, bisected and converged in ε/R0 beside the sharp
//!   instability; [`heating`]: budding on heating, the same in the ADE model's Δa0.

pub mod budding;
pub mod checks;
pub mod classify;
pub mod convergence;
pub mod file;
pub mod fit;
pub mod harness;
pub mod heating;
pub mod levels;
pub mod nonaxisymmetric;
pub mod onset;
pub mod pinning;
pub mod precision;
pub mod rates;
pub mod resolution;
pub mod shape_case;
pub mod shear;
pub mod stability;
pub mod stationary;
pub mod table;

use crate::driver::simulation::Prepared;
use crate::error::{Error, Result};
use crate::problem::config::{AdaptiveSpec, Scene};
use crate::problem::setup::Problem;
use ndarray::Array3;
use std::path::Path;

/// Write `text` to `dir/name`.
///
/// # Errors
/// `Error::Io` on failure.
pub fn write_text(dir: &Path, name: &str, text: &str) -> Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, text).map_err(|source| Error::Io { path, source })
}

/// The field after the scene's `prepare_steps` unconstrained fixed steps of its `dt` (FD explicit
/// Euler, or spectral SBDF1; [`Prepared`]): the common start of a study's runs.
///
/// # Errors
/// `Error::Config` for a non-finite initial field; `Error::Blowup` if a preparation step
/// diverges.
pub fn prepared_field(scene: &Scene, problem: &Problem) -> Result<Array3<f64>> {
    let mut s = scene.clone();
    s.adaptive = AdaptiveSpec::Flag(false);
    let p = Prepared::new(&s, problem)?;
    p.area_target?;
    Ok(p.simulation.engine().phi().clone())
}
