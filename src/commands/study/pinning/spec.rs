//! The pinning study file (`runs/studies/pinning.json`): which shapes, at which h/ε, over which
//! R0 series and which sub-cell shifts. Strict: unknown keys are refused, every value checked,
//! errors name the key.

use crate::commands::study::shape_case::{Relaxation, ShapeSpec};
use crate::error::{Error, Result};
use serde::Deserialize;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"pinning"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The shapes (branch and reduced volume of the sharp start).
    pub shapes: Vec<ShapeSpec>,
    /// ε/h of each lattice (h = ε/`eps_over_h`).
    pub eps_over_h: Vec<f64>,
    /// The R0/ε series of the fit (at least four, distinct: a quadratic in (ε/R0)² leaves a
    /// residual from the fourth on).
    pub r0: Vec<f64>,
    /// R0/ε of the shift series.
    pub shift_r0: f64,
    /// Shifts of the centre along the axis, in units of h, each in [0, 1) (0 is always run).
    #[serde(default)]
    pub shifts: Vec<f64>,
    /// How every case is relaxed.
    #[serde(default)]
    pub relaxation: Relaxation,
}

impl Spec {
    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key.
    pub fn validate(&self) -> Result<()> {
        self.relaxation.validate().map_err(under("relaxation"))?;
        if self.eps_over_h.is_empty() {
            return Err(Error::config("eps_over_h", "list at least one value"));
        }
        if let Some(x) = self.eps_over_h.iter().find(|x| !(**x >= 0.5 && **x <= 4.0)) {
            return Err(Error::config(
                "eps_over_h",
                format!("need 0.5 ≤ ε/h ≤ 4, got {x}"),
            ));
        }
        if self.r0.len() < 4 {
            return Err(Error::config(
                "r0",
                "give at least four R0/ε (a quadratic fit leaves a residual from the fourth on)",
            ));
        }
        if let Some(r) = self
            .r0
            .iter()
            .chain([&self.shift_r0])
            .find(|r| !(**r >= 6.0 && **r <= 200.0))
        {
            return Err(Error::config(
                if *r == self.shift_r0 {
                    "shift_r0"
                } else {
                    "r0"
                },
                format!("need 6 ≤ R0/ε ≤ 200, got {r}"),
            ));
        }
        let mut r0 = self.r0.clone();
        r0.sort_by(f64::total_cmp);
        if r0.windows(2).any(|w| w[1] - w[0] < 1e-9) {
            return Err(Error::config("r0", "values must be distinct"));
        }
        if let Some(s) = self.shifts.iter().find(|s| !(**s > 0.0 && **s < 1.0)) {
            return Err(Error::config(
                "shifts",
                format!("each shift is a fraction of h in (0, 1), got {s}"),
            ));
        }
        Ok(())
    }

    /// The smallest R0/ε of the study (the thinnest start).
    pub fn r0_min(&self) -> f64 {
        self.r0
            .iter()
            .chain([&self.shift_r0])
            .cloned()
            .fold(f64::INFINITY, f64::min)
    }
}

/// Prefix a configuration error's field with `key.` (an error of a nested object).
pub fn under(key: &'static str) -> impl Fn(Error) -> Error {
    move |e| match e {
        Error::Config { field, reason } => Error::config(format!("{key}.{field}"), reason),
        other => other,
    }
}
