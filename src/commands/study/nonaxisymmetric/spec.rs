//! The non-axisymmetric study file (`runs/studies/nonaxisymmetric.json`): the scene of the
//! non-axisymmetric start, the Δa0 and h/ε it is run at, the axisymmetric starts it is compared
//! with in the same box, and the sharp branches. Strict: unknown keys are refused, every value
//! checked, errors name the key.

use crate::analysis::axisym::Branch;
use crate::commands::diagram::spec::branch_named;
use crate::error::{Error, Result};
use serde::Deserialize;
use serde_json::Value;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"nonaxisymmetric"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The scene of the non-axisymmetric start (an object, or a path relative to the study
    /// file): 3D, `"dynamics": "relaxational"`, an `ade` block, `eps` = 1. Its box and shapes
    /// are kept in units of ε at every h of `eps_over_h` (`n` scaled by the ratio of the h).
    pub scene: Value,
    /// The α of every case (replacing the scene's `ade.alpha`; absent: the scene's).
    #[serde(default)]
    pub alpha: Vec<f64>,
    /// The Δa0 of every case (replacing the scene's `ade.da0`).
    pub da0: Vec<f64>,
    /// ε/h of each resolution.
    pub eps_over_h: Vec<f64>,
    /// The axisymmetric starts run in the same box at the same (α, Δa0, h).
    pub axisymmetric: Vec<AxisymStart>,
    /// The branches of the sharp reference (`axisym::ade_solution`) at the non-axisymmetric
    /// state's v: any of `prolate`, `oblate`, `stomatocyte`, `pear`.
    #[serde(default = "default_sharp")]
    pub sharp: Vec<String>,
}

fn default_sharp() -> Vec<String> {
    ["prolate", "oblate", "stomatocyte", "pear"]
        .map(String::from)
        .to_vec()
}

/// An axisymmetric start: the sharp shape of `branch` (an `axisym` initial shape) with its
/// symmetry axis along `axis`.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct AxisymStart {
    /// `prolate`, `oblate` or `stomatocyte`.
    pub branch: String,
    /// `x`, `y` or `z`.
    pub axis: String,
}

impl Spec {
    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key.
    pub fn validate(&self) -> Result<()> {
        if self.da0.is_empty() {
            return Err(Error::config("da0", "list at least one value"));
        }
        if let Some(d) = self.da0.iter().find(|d| !(**d > 0.0 && d.is_finite())) {
            return Err(Error::config("da0", format!("need Δa0 > 0, got {d}")));
        }
        if let Some(a) = self.alpha.iter().find(|a| !(**a > 0.0 && a.is_finite())) {
            return Err(Error::config("alpha", format!("need α > 0, got {a}")));
        }
        if self.eps_over_h.is_empty() {
            return Err(Error::config("eps_over_h", "list at least one value"));
        }
        if let Some(x) = self.eps_over_h.iter().find(|x| !(**x >= 0.5 && **x <= 4.0)) {
            return Err(Error::config(
                "eps_over_h",
                format!("need 0.5 ≤ ε/h ≤ 4, got {x}"),
            ));
        }
        for (i, a) in self.axisymmetric.iter().enumerate() {
            match branch_named(&a.branch) {
                Some(Branch::Prolate | Branch::Oblate | Branch::Stomatocyte) => {}
                _ => {
                    return Err(Error::config(
                        format!("axisymmetric[{i}].branch"),
                        "unknown branch (prolate, oblate or stomatocyte)",
                    ))
                }
            }
            if !["x", "y", "z"].contains(&a.axis.as_str()) {
                return Err(Error::config(
                    format!("axisymmetric[{i}].axis"),
                    "must be \"x\", \"y\" or \"z\"",
                ));
            }
        }
        self.sharp_branches().map(|_| ())
    }

    /// The sharp branches of `sharp`.
    ///
    /// # Errors
    /// `Error::Config` (field `sharp[i]`) for an unknown name.
    pub fn sharp_branches(&self) -> Result<Vec<Branch>> {
        self.sharp
            .iter()
            .enumerate()
            .map(|(i, s)| {
                Branch::WITH_PEAR
                    .into_iter()
                    .find(|b| b.name() == s)
                    .ok_or_else(|| {
                        Error::config(
                            format!("sharp[{i}]"),
                            "unknown branch (prolate, oblate, stomatocyte or pear)",
                        )
                    })
            })
            .collect()
    }
}
