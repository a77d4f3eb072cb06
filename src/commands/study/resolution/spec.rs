//! The resolution study file (`runs/studies/resolution.json`): which shapes, at which h/ε and
//! R0/ε, which routes. Strict: unknown keys are refused, every value checked, errors name the
//! key.

use crate::commands::study::pinning::spec::under;
use crate::commands::study::shape_case::{Relaxation, ShapeSpec};
use crate::error::{Error, Result};
use serde::Deserialize;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"resolution"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The shapes (branch and reduced volume of the sharp start).
    pub shapes: Vec<ShapeSpec>,
    /// ε/h of each lattice.
    pub eps_over_h: Vec<f64>,
    /// R0/ε of each L-BFGS case (every pair and every three consecutive are extrapolated).
    pub r0: Vec<f64>,
    /// Cases with more computed points than this are left out (their cost), if set.
    #[serde(default)]
    pub max_points: Option<usize>,
    /// Order p of the extrapolation e(x) = e∞ + c x^p in x = ε/R0 (and the same for v).
    #[serde(default = "default_order")]
    pub order: f64,
    /// The adaptive SBDF2 route, if wanted.
    #[serde(default)]
    pub sbdf2: Option<Sbdf2Spec>,
    /// Relative error levels of the summary ("for 0.1% use …").
    pub levels: Vec<f64>,
    /// How every case is relaxed.
    #[serde(default)]
    pub relaxation: Relaxation,
}

fn default_order() -> f64 {
    2.0
}

/// The adaptive SBDF2 route: conserved flow from the same start to the same residual.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Sbdf2Spec {
    /// ε/h of its cases (each among `eps_over_h`).
    pub eps_over_h: Vec<f64>,
    /// R0/ε of its cases.
    pub r0: Vec<f64>,
    /// The controller's `energy_alpha`.
    #[serde(default = "default_energy_alpha")]
    pub energy_alpha: f64,
    /// The controller's `dt_max`.
    #[serde(default = "default_dt_max")]
    pub dt_max: f64,
    /// Most steps.
    #[serde(default = "default_max_steps")]
    pub max_steps: usize,
}

fn default_energy_alpha() -> f64 {
    1e6
}
fn default_dt_max() -> f64 {
    50.0
}
fn default_max_steps() -> usize {
    200_000
}

impl Spec {
    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key.
    pub fn validate(&self) -> Result<()> {
        self.relaxation.validate().map_err(under("relaxation"))?;
        let in_range = |key: &str, xs: &[f64], lo: f64, hi: f64| -> Result<()> {
            if xs.is_empty() {
                return Err(Error::config(key, "list at least one value"));
            }
            if let Some(x) = xs.iter().find(|x| !(**x >= lo && **x <= hi)) {
                return Err(Error::config(
                    key,
                    format!("need {lo} ≤ value ≤ {hi}, got {x}"),
                ));
            }
            let mut s = xs.to_vec();
            s.sort_by(f64::total_cmp);
            if s.windows(2).any(|w| w[1] - w[0] < 1e-9) {
                return Err(Error::config(key, "values must be distinct"));
            }
            Ok(())
        };
        in_range("eps_over_h", &self.eps_over_h, 0.5, 4.0)?;
        in_range("r0", &self.r0, 6.0, 200.0)?;
        in_range("levels", &self.levels, 1e-8, 1.0)?;
        if self.r0.len() < 2 {
            return Err(Error::config(
                "r0",
                "give at least two R0/ε (the extrapolation)",
            ));
        }
        if !(self.order >= 0.5 && self.order <= 4.0) {
            return Err(Error::config(
                "order",
                format!("need 0.5 ≤ order ≤ 4, got {}", self.order),
            ));
        }
        if self.max_points == Some(0) {
            return Err(Error::config("max_points", "must be at least 1"));
        }
        if let Some(s) = &self.sbdf2 {
            in_range("sbdf2.eps_over_h", &s.eps_over_h, 0.5, 4.0)?;
            in_range("sbdf2.r0", &s.r0, 6.0, 200.0)?;
            if !(s.energy_alpha > 0.0 && s.energy_alpha.is_finite()) {
                return Err(Error::config("sbdf2.energy_alpha", "must be positive"));
            }
            if !(s.dt_max > 0.0 && s.dt_max.is_finite()) {
                return Err(Error::config("sbdf2.dt_max", "must be positive"));
            }
            if s.max_steps == 0 {
                return Err(Error::config("sbdf2.max_steps", "must be at least 1"));
            }
        }
        Ok(())
    }

    /// The smallest R0/ε of the study.
    pub fn r0_min(&self) -> f64 {
        let sbdf2 = self.sbdf2.iter().flat_map(|s| s.r0.iter());
        self.r0
            .iter()
            .chain(sbdf2)
            .cloned()
            .fold(f64::INFINITY, f64::min)
    }
}
