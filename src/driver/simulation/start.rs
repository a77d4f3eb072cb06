//! From a scene to a simulation: the engine the scene asks for, the unconstrained preparation
//! steps, the area target A0, and the stability check of a fixed Δt.

use super::{Simulation, StopRules};
use crate::engines::fd::{self, FdEngine};
use crate::engines::relax::RelaxEngine;
use crate::engines::spectral::{self, SpectralEngine};
use crate::engines::{AreaConstraint, Diverged, Engine};
use crate::error::{Error, Result};
use crate::problem::area_difference::AreaDifference;
use crate::problem::config::{AdaptiveSpec, AreaMethod, Device, Dynamics, Method, Scene, Scheme};
use crate::problem::grid::Grid;
use crate::problem::setup::Problem;

/// Stability bound of the scene's method at σ = 0, if it has one: the FD bound of
/// docs/src/theory/fd.md, or the frozen-coefficient bound of the spectral scheme (infinite when
/// the stabiliser makes the bulk linearisation unconditionally stable).
pub fn stability_bound(scene: &Scene, grid: &Grid) -> Option<f64> {
    match (scene.method, scene.dynamics) {
        (Method::Fd, _) => Some(fd::stability_bound(grid, scene.eps, 0.0)),
        (Method::Spectral, Dynamics::Conserved | Dynamics::Stokes) => {
            // The diffusive channel M∇²μ: the bound of M = 1 divided by M.
            let b =
                spectral::stability_bound(grid, scene.eps, &scene.stabilizer(), scene.laplacian);
            let b = b / scene.mobility();
            b.is_finite().then_some(b)
        }
        (Method::Spectral, Dynamics::Relaxational) => None,
    }
}

/// Refuse a scene the engine it asks for cannot run ([`crate::engines::supports`]; no hardware
/// is touched).
///
/// # Errors
/// `Error::Config` on the key the engine cannot honour.
pub fn check_engine(scene: &Scene) -> Result<()> {
    crate::engines::supports(scene).map_err(|u| Error::config(u.field, u.why))
}

/// Refuse a fixed Δt above the method's bound unless the scene allows it.
///
/// # Errors
/// `Error::Config` on field `dt` with the bound.
pub fn check_stability(scene: &Scene, grid: &Grid) -> Result<()> {
    if scene.allow_unstable || scene.adaptive.settings().is_some() {
        return Ok(());
    }
    match stability_bound(scene, grid) {
        Some(bound) if scene.dt >= bound => Err(Error::config(
            "dt",
            format!(
                "{} exceeds the {} stability bound {bound:.4e} (ε = {}, h = {}, dim = {}); \
                 use dt < {bound:.4e}, or set \"allow_unstable\": true for a stability study",
                scene.dt,
                match scene.method {
                    Method::Fd => "finite-difference explicit-Euler",
                    Method::Spectral => "semi-implicit (frozen-coefficient)",
                },
                scene.eps,
                scene.h,
                scene.dim
            ),
        )),
        _ => Ok(()),
    }
}

/// Build the engine a scene asks for, holding `problem.phi` at time 0, no area constraint, with
/// the energy guard on unless the scene allows unstable steps.
///
/// # Errors
/// `Error::Config` on field `initial` if the initial field is not finite.
pub fn build_engine(scene: &Scene, problem: &Problem) -> Result<Box<dyn Engine + Send>> {
    check_engine(scene)?;
    let grid = problem.grid.clone();
    let c0 = problem.c0.clone();
    let phi = problem.phi.clone();
    let bad = |d: Diverged| Error::config("initial", d.0);
    let mut engine: Box<dyn Engine + Send> = match (scene.method, scene.dynamics) {
        _ if scene.device == Device::Gpu => gpu_engine(scene, grid, c0, phi)?,
        (Method::Fd, _) => {
            Box::new(FdEngine::new(grid, scene.eps, c0, phi, 0.0, scene.threads()).map_err(bad)?)
        }
        (Method::Spectral, Dynamics::Conserved | Dynamics::Stokes) => {
            Box::new(SpectralEngine::new(scene, grid, c0, phi).map_err(bad)?)
        }
        (Method::Spectral, Dynamics::Relaxational) => {
            Box::new(RelaxEngine::new(scene, grid, c0, phi).map_err(bad)?)
        }
    };
    // A stability study asks to see what an unstable Δt does, energy rises included.
    engine.guard_energy(!scene.allow_unstable);
    Ok(engine)
}

/// The GPU engine (`"device": "gpu"`, supported: [`check_engine`]); the hardware is probed
/// here, where the engine is built.
///
/// # Errors
/// `Error::Config` on field `device` if the GPU cannot be set up or this binary has no GPU
/// engine.
fn gpu_engine(
    scene: &Scene,
    grid: Grid,
    c0: crate::problem::model::C0,
    phi: ndarray::Array3<f64>,
) -> Result<Box<dyn Engine + Send>> {
    #[cfg(feature = "gpu")]
    {
        let engine = crate::engines::gpu::GpuEngine::new(scene, grid, c0, phi)
            .map_err(|d| Error::config("device", d.0))?;
        Ok(Box::new(engine))
    }
    #[cfg(not(feature = "gpu"))]
    {
        let _ = (scene, grid, c0, phi);
        Err(Error::config(
            "device",
            crate::engines::gpu::usable().expect_err("no GPU engine in this build"),
        ))
    }
}

/// A simulation after the preparation steps: ready with its area constraint and A0, or
/// holding the last good state of a preparation step that diverged.
pub struct Prepared {
    /// The simulation (at t = 0, step 0: preparation does not count).
    pub simulation: Simulation,
    /// A0, or the preparation's failure.
    pub area_target: Result<f64>,
}

impl Prepared {
    /// Run the unconstrained preparation steps (σ = 0, fixed steps of the scene's `dt`: FD
    /// explicit Euler, or spectral SBDF1 for every spectral scheme and dynamics), build the engine the
    /// scene asks for on the prepared field, then install the area constraint with A0 = the
    /// scene's target or the prepared area.
    ///
    /// # Errors
    /// `Error::Config` if the initial field is not finite. A preparation step that diverges is
    /// not an error here: it is in `area_target`, beside the last good state.
    pub fn new(scene: &Scene, problem: &Problem) -> Result<Self> {
        let mut engine = if scene.prepare_steps == 0 {
            build_engine(scene, problem)?
        } else {
            match prepare(scene, problem)? {
                Ok(prepared) => build_engine(scene, &prepared)?,
                Err((engine, failure)) => {
                    return Ok(Prepared {
                        simulation: Simulation::new(engine, scene.dt, scene.dim, scene.eps),
                        area_target: Err(failure),
                    })
                }
            }
        };
        let a0 = scene.area.target.unwrap_or(engine.measures().area);
        constrain(engine.as_mut(), scene, a0)?;
        Ok(Prepared {
            simulation: Simulation::new(engine, scene.dt, scene.dim, scene.eps),
            area_target: Ok(a0),
        })
    }
}

/// Install the area constraint of `scene` with A0 = `a0` on `engine`, and its area-difference
/// term (ADE or the bilayer couple) with R0 = √(A0/4π).
///
/// # Errors
/// `Error::Config` on field `ade` (or `bilayer_couple`) if the engine cannot hold the term.
pub fn constrain(engine: &mut (dyn Engine + Send), scene: &Scene, a0: f64) -> Result<()> {
    engine.set_area(AreaConstraint {
        method: scene.area_method(),
        alpha: scene.alpha(),
        target: a0,
        sigma: scene.area.sigma.unwrap_or(0.0),
    });
    if let Some(term) = AreaDifference::of(scene, a0) {
        let field = if scene.ade.is_some() {
            "ade"
        } else {
            "bilayer_couple"
        };
        engine
            .set_area_difference(term)
            .map_err(|m| Error::config(field, m))?;
    }
    Ok(())
}

/// The problem with its field after `scene.prepare_steps` unconstrained fixed steps of
/// `scene.dt` of the conserved flow (FD explicit Euler, or spectral SBDF1 whatever the scene's
/// scheme and dynamics), or the engine holding the last good state and the failure.
type Preparation = std::result::Result<Problem, (Box<dyn Engine + Send>, Error)>;

fn prepare(scene: &Scene, problem: &Problem) -> Result<Preparation> {
    // The same preparation for every scheme and dynamics of a method, so that scenes differing
    // only in those start from the same field and A0; a volume ramp starts after it (V_init is
    // the prepared field's volume).
    let mut prep_scene = scene.clone();
    prep_scene.volume = None;
    prep_scene.ade = None;
    prep_scene.bilayer_couple = None;
    prep_scene.adaptive = AdaptiveSpec::Flag(false);
    prep_scene.dynamics = Dynamics::Conserved;
    prep_scene.scheme = Scheme::Sbdf1;
    let mut engine = build_engine(&prep_scene, problem)?;
    // A fixed tension shapes the interface's profile (it pulls on ∫|∇φ|²): the preparation
    // builds the profile the run will hold, at that tension; the other methods prepare at σ = 0.
    engine.set_area(match scene.area_method() {
        AreaMethod::Fixed => AreaConstraint {
            sigma: scene.area.sigma.unwrap_or(0.0),
            method: AreaMethod::Fixed,
            ..AreaConstraint::none()
        },
        _ => AreaConstraint::none(),
    });
    let mut prep = Simulation::new(engine, scene.dt, scene.dim, scene.eps);
    if let Err(e) = prep.run(&StopRules::steps(scene.prepare_steps), &mut []) {
        let during =
            |step: usize, reason: &str| format!("during preparation step {step}: {reason}");
        let failure = match e {
            Error::Blowup {
                step,
                reason,
                cause,
                ..
            } => Error::Blowup {
                step: 0,
                t: 0.0,
                reason: during(step, &reason),
                cause,
            },
            Error::Device { step, reason, .. } => Error::Device {
                step: 0,
                t: 0.0,
                reason: during(step, &reason),
            },
            other => other,
        };
        return Ok(Err((prep.into_engine(), failure)));
    }
    let mut prepared = problem.clone();
    prepared.phi = prep.engine().phi().clone();
    Ok(Ok(prepared))
}

impl Simulation {
    /// The simulation a scene describes, prepared and constrained (see [`Prepared::new`]),
    /// with A0.
    ///
    /// # Errors
    /// `Error::Config` if the initial field is not finite; `Error::Blowup` if a preparation
    /// step diverges.
    pub fn of_scene(scene: &Scene, problem: &Problem) -> Result<(Self, f64)> {
        let p = Prepared::new(scene, problem)?;
        Ok((p.simulation, p.area_target?))
    }
}
