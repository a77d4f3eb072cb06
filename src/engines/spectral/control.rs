//! The step controller of the spectral step ([`super::stepper`]): the multiplier after a step,
//! the checks a step must pass, the rejection and retry of adaptive steps and the proposal of the
//! next step (docs/src/theory/spectral.md, "The adaptive step").

use crate::engines::numerics::{CONSTRAINT_TOL, ENERGY_RISE_TOL};
use crate::engines::{AreaConstraint, Rejection, StepError};
use crate::problem::config::{AdaptiveSettings, AreaMethod, Scene, Scheme};
use crate::problem::model::Measures;

/// The scene's adaptive-step controller with `dt_min` and `dt_max` resolved (defaults 1e-3 and
/// 1e3 times `dt`), or `None` for fixed steps.
pub(crate) fn adaptive_settings(scene: &Scene) -> Option<AdaptiveSettings> {
    scene.adaptive.settings().map(|a| AdaptiveSettings {
        dt_min: Some(a.dt_min.unwrap_or(1e-3 * scene.dt)),
        dt_max: Some(a.dt_max.unwrap_or(1e3 * scene.dt)),
        ..a
    })
}

/// Energy-based proposal for the next step (Qiao–Zhang–Tang), limited by `growth`:
/// `clamp(dt_max / √(1 + α (Ḟ/F)²), dt_min, growth · Δt)`.
pub(crate) fn propose(a: &AdaptiveSettings, dt: f64, f_old: f64, f_new: f64) -> f64 {
    let rate = (f_new - f_old).abs() / dt / f_new.abs().max(1e-300);
    let (dt_min, dt_max) = (a.dt_min.unwrap_or(dt), a.dt_max.unwrap_or(dt));
    let target = dt_max / (1.0 + a.energy_alpha * rate * rate).sqrt();
    target
        .clamp(dt_min, (a.growth * dt).max(dt_min))
        .min(dt_max)
}

/// σ of the state after a step that used `step_sigma`: the same, except under the Lagrangian
/// update σ^{n+1} = σ^n + α (A^n − A0), with σ^n = `sigma` and A^n = `area_now`.
pub(crate) fn sigma_after(
    area: &AreaConstraint,
    sigma: f64,
    area_now: f64,
    step_sigma: f64,
) -> f64 {
    match area.method {
        AreaMethod::Lagrangian => sigma + area.alpha * (area_now - area.target),
        _ => step_sigma,
    }
}

/// The checks of a step from `before` to `after` taken at multiplier `sigma`: the volume held
/// at `volume_target`, the area on its target under the projection, and, when `guard`, F_eff =
/// F + σA not risen beyond round-off (the caller decides where the scheme guarantees that it
/// falls).
pub(crate) fn check_step(
    before: &Measures,
    after: &Measures,
    sigma: f64,
    volume_target: f64,
    area: &AreaConstraint,
    guard: bool,
) -> Result<(), Rejection> {
    let dv = (after.volume - volume_target).abs() / volume_target.abs().max(1e-300);
    if dv > CONSTRAINT_TOL {
        return Err(Rejection::VolumeDrift(dv));
    }
    if area.method == AreaMethod::Projection {
        let da = (after.area - area.target).abs() / area.target;
        if da > CONSTRAINT_TOL {
            return Err(Rejection::AreaDrift(da));
        }
    }
    if guard {
        let (f0, f1) = (
            before.energy + sigma * before.area,
            after.energy + sigma * after.area,
        );
        if f1 > f0 + ENERGY_RISE_TOL * f0.abs() {
            return Err(Rejection::EnergyRise {
                before: f0,
                after: f1,
            });
        }
    }
    Ok(())
}

/// Whether F_eff must not rise: adaptive steps, and fixed SBDF1 steps (the stabilised
/// first-order step is dissipative; SBDF2 is not guaranteed to be).
pub(crate) fn dissipative(adaptive: Option<&AdaptiveSettings>, scheme: Scheme) -> bool {
    adaptive.is_some() || scheme == Scheme::Sbdf1
}

/// Attempt a step of `dt`, and after a rejection again with `shrink` times the step, down to
/// `dt_min` (fixed steps: a rejection ends the run). `attempt` returns the step's result, its
/// rejection, or a failure that no smaller step mends. Returns the result, the step taken and
/// the rejections.
pub(crate) fn with_retries<R>(
    adaptive: Option<&AdaptiveSettings>,
    dt: f64,
    mut attempt: impl FnMut(f64) -> Result<Result<R, Rejection>, StepError>,
) -> Result<(R, f64, usize), StepError> {
    let mut dt = dt;
    let mut rejected = 0;
    loop {
        let check = match attempt(dt)? {
            Ok(r) => return Ok((r, dt, rejected)),
            Err(check) => check,
        };
        let Some(a) = adaptive else {
            let context = match check {
                Rejection::EnergyRise { .. } => {
                    ": the step is not dissipative at this Δt; lower dt or use adaptive steps"
                }
                _ => "",
            };
            return Err(StepError::Rejected {
                check,
                context: context.to_string(),
            });
        };
        let dt_min = a.dt_min.unwrap_or(dt);
        rejected += 1;
        if dt <= dt_min {
            return Err(StepError::Rejected {
                check,
                context: format!(
                    " (the step was rejected at the smallest step dt_min = {dt_min:.3e})"
                ),
            });
        }
        dt = (dt * a.shrink).max(dt_min);
    }
}
