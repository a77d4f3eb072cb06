//! The stationary study's spec: the study file's keys ([`Spec`]) and the routes and tolerances
//! they resolve to on a scene ([`Plan`]; a scene file's defaults in [`Plan::for_scene`]).

use crate::error::{Error, Result};
use crate::problem::config::{AdaptiveSettings, Scene, Scheme};
use serde::Deserialize;
use serde_json::Value;

/// The stop tolerances tabulated by default.
pub const TOLERANCES: [f64; 5] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

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
    pub fn name(&self) -> String {
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
