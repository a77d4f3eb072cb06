//! The convergence study's measurement: the runs of each part, one [`Row`] per run.

use super::spec::{EpsSpec, SpaceSpec, TimeSpec};
use crate::commands::study::{file, harness};
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use crate::problem::config::{AdaptiveSpec, Laplacian, Scene, Scheme};
use crate::problem::setup::{self, Problem};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

/// One measured point: `(part, series, x, error)` and what else was measured; a row of
/// `convergence.csv`.
#[derive(Clone, Debug)]
pub struct Row {
    /// `time`, `space`, `eps`.
    pub part: &'static str,
    /// Series name.
    pub series: String,
    /// Δt, h or ε/R0.
    pub x: f64,
    /// The error.
    pub error: f64,
    /// Reduced energy (space, eps), NaN otherwise.
    pub e: f64,
    /// Reduced volume of the φ = 0 surface (eps), NaN otherwise.
    pub v: f64,
    /// The reference e_ref (space, eps), NaN otherwise.
    pub e_ref: f64,
    /// Stationarity residual RMS(μ − μ̄) at the end (space, eps), NaN otherwise.
    pub residual: f64,
    /// Steps (iterations) of the run.
    pub steps: usize,
    /// Wall seconds of the run.
    pub wall: f64,
}

/// Run `s` from `problem.phi` until its stop rules: the simulation, steps and wall seconds.
fn settle(s: &Scene, problem: &Problem, rules: &StopRules) -> Result<(Simulation, f64)> {
    let clock = Instant::now();
    let (mut sim, _) = Simulation::of_scene(s, problem)?;
    sim.run(rules, &mut [])?;
    Ok((sim, clock.elapsed().as_secs_f64()))
}

/// The time part: SBDF1 and SBDF2 at each Δt of the ladder against SBDF2 at `reference_dt`,
/// from the prepared and from the raw tanh field.
///
/// # Errors
/// `Error::Config` naming `time.scene.…`; `Error::Blowup` if a run diverges.
pub fn time_part(spec: &TimeSpec, dir: &Path) -> Result<Vec<Row>> {
    let field = "time.scene";
    let base = file::scene(&spec.scene, &[], field, dir)?;
    let mut rows = Vec::new();
    for (start, prepared) in [("prepared", true), ("raw tanh", false)] {
        let mut problem = setup::build(&base)?;
        if prepared {
            problem.phi = crate::commands::study::prepared_field(&base, &problem)?;
        }
        let at = |scheme: Scheme, dt: f64| {
            harness::variant(&base, field, |s| {
                s.scheme = scheme;
                s.dt = dt;
                s.adaptive = AdaptiveSpec::Flag(false);
                s.prepare_steps = 0;
                s.t_end = Some(spec.t);
                s.max_steps = None;
                s.stop_residual = None;
            })
        };
        let rules = StopRules::until(spec.t);
        let (reference, _) = settle(&at(Scheme::Sbdf2, spec.reference_dt)?, &problem, &rules)?;
        for (name, scheme) in [("SBDF1", Scheme::Sbdf1), ("SBDF2", Scheme::Sbdf2)] {
            for level in 0..spec.levels {
                let dt = spec.dt / 2f64.powi(level as i32);
                let (sim, wall) = settle(&at(scheme, dt)?, &problem, &rules)?;
                rows.push(Row {
                    part: "time",
                    series: format!("{name} from the {start} field"),
                    x: dt,
                    error: crate::problem::model::max_abs_diff(
                        sim.engine().phi(),
                        reference.engine().phi(),
                    ),
                    e: f64::NAN,
                    v: f64::NAN,
                    e_ref: f64::NAN,
                    residual: f64::NAN,
                    steps: sim.clock.step,
                    wall,
                });
            }
        }
    }
    Ok(rows)
}

/// Grid points for an edge `length` at spacing `h` (even).
fn points(length: f64, h: f64) -> usize {
    2 * ((length / h / 2.0).round() as usize).max(2)
}

/// A relaxed state: reduced energy, full-box φ, residual, steps, wall seconds.
struct Relaxed {
    e: f64,
    phi: ndarray::Array3<f64>,
    residual: f64,
    steps: usize,
    wall: f64,
}

/// Relax the scene `s` to its `stop_residual` (or until L-BFGS stalls at round-off).
fn relaxed(s: &Scene) -> Result<Relaxed> {
    let problem = setup::build(s)?;
    let (sim, wall) = settle(s, &problem, &StopRules::of(s))?;
    Ok(Relaxed {
        e: sim.engine().measures().reduced(s.dim, s.eps).energy,
        phi: problem.grid.unfold(sim.engine().phi()).into_owned(),
        residual: sim.engine().residual(),
        steps: sim.clock.step,
        wall,
    })
}

/// The space part: the stationary e at each h of the FD and spectral ladders against spectral
/// at `reference_h`.
///
/// # Errors
/// `Error::Config` naming `space.scene.…`; `Error::Blowup` if a run diverges.
pub fn space_part(spec: &SpaceSpec, dir: &Path) -> Result<Vec<Row>> {
    let field = "space.scene";
    let base = file::scene(&spec.scene, &[], field, dir)?;
    let at = |h: f64, laplacian: Laplacian| -> Result<Scene> {
        harness::variant(&base, field, |s| {
            s.h = h;
            s.n = vec![points(spec.length, h); s.dim];
            s.laplacian = laplacian;
        })
    };
    let e_ref = relaxed(&at(spec.reference_h, Laplacian::Spectral)?)?.e;
    let mut rows = Vec::new();
    for (series, laplacian, hs) in [
        ("FD (stencil symbol)", Laplacian::Fd, &spec.fd_h),
        ("spectral", Laplacian::Spectral, &spec.spectral_h),
    ] {
        for &h in hs {
            let s = at(h, laplacian)?;
            let r = relaxed(&s)?;
            rows.push(Row {
                part: "space",
                series: series.to_string(),
                x: h / s.eps,
                error: (r.e - e_ref).abs(),
                e: r.e,
                v: f64::NAN,
                e_ref,
                residual: r.residual,
                steps: r.steps,
                wall: r.wall,
            });
        }
    }
    Ok(rows)
}

/// The ε/R0 part: each shape relaxed at each ε/R0, against the axisymmetric e_ref at its φ = 0
/// v (1 for the sphere).
///
/// # Errors
/// `Error::Config` naming `eps.…`; `Error::Blowup` if a run diverges or no reference exists at
/// the measured v.
pub fn eps_part(spec: &EpsSpec, dir: &Path) -> Result<Vec<Row>> {
    let field = "eps.scene";
    let base = file::scene(&spec.scene, &[], field, dir)?;
    if base.dim != 3 {
        return Err(Error::config(
            "eps.scene.dim",
            "the ε/R0 sweep needs a 3D scene",
        ));
    }
    let opts = crate::analysis::axisym::Options::default();
    let mut rows = Vec::new();
    for (i, shape) in spec.shapes.iter().enumerate() {
        let name = format!("eps.shapes[{i}]");
        let (branch, v) = match (shape.branch.as_str(), shape.reduced_volume) {
            ("sphere", _) => (None, 1.0),
            ("prolate", Some(v)) => (Some(crate::analysis::axisym::Branch::Prolate), v),
            ("oblate", Some(v)) => (Some(crate::analysis::axisym::Branch::Oblate), v),
            ("prolate" | "oblate", None) => {
                return Err(Error::config(format!("{name}.reduced_volume"), "missing"))
            }
            (other, _) => {
                return Err(Error::config(
                    format!("{name}.branch"),
                    format!("{other:?}: expected \"prolate\", \"oblate\" or \"sphere\""),
                ))
            }
        };
        // Half-extents at R0 = 1 across and along the axis (the last axis).
        let (across, along) = match branch {
            None => (1.0, 1.0),
            Some(b) => {
                let sol = crate::analysis::axisym::solve(b, v, &opts).map_err(|_| {
                    Error::config(
                        format!("{name}.reduced_volume"),
                        "no axisymmetric shape at this v",
                    )
                })?;
                let r = sol.r.iter().fold(0.0f64, |m, x| m.max(*x));
                let (lo, hi) = sol
                    .z
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
                        (a.min(*z), b.max(*z))
                    });
                (r, (hi - lo) / 2.0)
            }
        };
        let label = match branch {
            None => "sphere".to_string(),
            Some(b) => format!("{} v = {v}", b.name()),
        };
        for &x in shape.eps_over_r0.as_ref().unwrap_or(&spec.eps_over_r0) {
            let r0 = base.eps / x;
            let n_of = |half: f64| points(2.0 * (half * r0 + spec.margin * base.eps), base.h);
            let initial = match branch {
                None => json!({"shape": "sphere", "radius": r0}),
                Some(b) => {
                    json!({"shape": "axisym", "branch": b.name(), "reduced_volume": v, "r0": r0})
                }
            };
            let s = file::scene(
                &spec.scene,
                &[
                    json!({"initial": null}),
                    json!({"n": [n_of(across), n_of(across), n_of(along)], "initial": initial}),
                    shape.scene.clone().unwrap_or(json!({})),
                ],
                field,
                dir,
            )?;
            let r = relaxed(&s)?;
            let level = crate::analysis::levelset::measure_refined(&r.phi, 3, s.h);
            let e_ref = match branch {
                None => 1.0,
                Some(b) => crate::analysis::axisym::solve(b, level.reduced_volume, &opts)
                    .map_err(|err| Error::Study(format!("{label} at eps/R0 = {x}: no axisymmetric reference at the φ = 0 v = {}: {err}", level.reduced_volume)))?
                    .e,
            };
            rows.push(Row {
                part: "eps",
                series: label.clone(),
                x,
                error: r.e - e_ref,
                e: r.e,
                v: level.reduced_volume,
                e_ref,
                residual: r.residual,
                steps: r.steps,
                wall: r.wall,
            });
        }
    }
    Ok(rows)
}
