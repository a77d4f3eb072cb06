//! The diagram file (`runs/diagram.json`): which branches and reduced volumes, at which
//! resolutions ε/R0, and how each case is run. Strict JSON: unknown keys are refused, every
//! value is checked, and errors name the key.

use crate::analysis::axisym::Branch;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// A diagram: every listed `(branch, v)` at every `r0` is one independent case.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiagramSpec {
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Reduced volumes per branch (`prolate`, `oblate`, `stomatocyte`).
    pub branches: BTreeMap<String, Vec<f64>>,
    /// R0/ε of each resolution (ε = 1); at least two for the extrapolation in ε/R0.
    pub r0: Vec<f64>,
    /// ε/h (the grid spacing is h = 1/eps_over_h).
    #[serde(default = "one")]
    pub eps_over_h: f64,
    /// Outside bulk kept between the shape and the box faces: `margin` ε + `margin_r0` R0.
    #[serde(default = "default_margin")]
    pub margin: f64,
    /// See `margin`: the part that scales with the vesicle, so the box keeps its proportions.
    #[serde(default = "default_margin_r0")]
    pub margin_r0: f64,
    /// Stationarity tolerance RMS(μ − μ̄) of each relaxation (README: 1e-6 for diagrams).
    #[serde(default = "default_stop_residual")]
    pub stop_residual: f64,
    /// Most L-BFGS iterations per case.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Unconstrained SBDF1 steps of Δt = 0.01 that build the profile before A0 is taken.
    #[serde(default = "default_prepare_steps")]
    pub prepare_steps: usize,
    /// Reduced volumes whose finest-resolution shapes get a thumbnail picture.
    #[serde(default)]
    pub thumbnails: Vec<f64>,
}

fn one() -> f64 {
    1.0
}
fn default_margin() -> f64 {
    4.0
}
fn default_margin_r0() -> f64 {
    0.1
}
fn default_stop_residual() -> f64 {
    1e-6
}
fn default_max_iterations() -> usize {
    20_000
}
fn default_prepare_steps() -> usize {
    20
}

/// One case: a branch at a reduced volume and a resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Position in [`DiagramSpec::cases`] (the `--case` number).
    pub index: usize,
    /// The branch.
    pub branch: Branch,
    /// Target reduced volume (the axisymmetric start's).
    pub v: f64,
    /// R0/ε.
    pub r0: f64,
}

impl Case {
    /// Folder name of the case: `<index>_<branch>_v<v>_r<r0>`.
    pub fn folder(&self) -> String {
        format!(
            "{:03}_{}_v{:.4}_r{}",
            self.index,
            self.branch.name(),
            self.v,
            self.r0
        )
    }
}

/// The branch called `name`.
pub fn branch_named(name: &str) -> Option<Branch> {
    Branch::ALL.into_iter().find(|b| b.name() == name)
}

impl DiagramSpec {
    /// Read and check a diagram file.
    ///
    /// # Errors
    /// `Error::Config` naming the key: unreadable file, malformed JSON, unknown key, wrong
    /// type, or a value [`DiagramSpec::validate`] refuses.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| {
            Error::config(
                "(diagram file)",
                format!("{} cannot be read: {e}", path.display()),
            )
        })?;
        let mut de = serde_json::Deserializer::from_slice(&bytes);
        let spec: DiagramSpec = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let at = e.path().to_string();
            let field = if at == "." || at == "?" {
                "(file)".to_string()
            } else {
                at
            };
            Error::config(field, e.inner().to_string())
        })?;
        spec.validate()?;
        Ok(spec)
    }

    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key and the reason.
    pub fn validate(&self) -> Result<()> {
        if self.branches.is_empty() {
            return Err(Error::config("branches", "list at least one branch"));
        }
        for (name, vs) in &self.branches {
            let at = format!("branches.{name}");
            let Some(branch) = branch_named(name) else {
                return Err(Error::config(
                    at,
                    "unknown branch (prolate, oblate or stomatocyte)",
                ));
            };
            let (lo, hi) = match branch {
                Branch::Prolate => (0.3, 1.0),
                Branch::Oblate => (0.51, 1.0),
                Branch::Stomatocyte => (0.3, 0.66),
                // Not listed by `branch_named`: diagram files hold the c0 = 0 branches.
                Branch::Pear => {
                    return Err(Error::config(
                        at,
                        "unknown branch (prolate, oblate or stomatocyte)",
                    ))
                }
            };
            if vs.is_empty() {
                return Err(Error::config(at, "list at least one reduced volume"));
            }
            if let Some(v) = vs.iter().find(|v| !(**v > lo && **v < hi)) {
                return Err(Error::config(
                    at,
                    format!("the {name} branch is computed for {lo} < v < {hi}, got {v}"),
                ));
            }
            let mut sorted = vs.clone();
            sorted.sort_by(f64::total_cmp);
            if sorted.windows(2).any(|w| w[1] - w[0] < 1e-6) {
                return Err(Error::config(at, "reduced volumes must be distinct"));
            }
        }
        if self.r0.len() < 2 {
            return Err(Error::config(
                "r0",
                "give at least two R0/ε to extrapolate in ε/R0",
            ));
        }
        if let Some(r) = self.r0.iter().find(|r| !(**r >= 6.0 && **r <= 200.0)) {
            return Err(Error::config(
                "r0",
                format!("need 6 ≤ R0/ε ≤ 200 (the interface must be thin), got {r}"),
            ));
        }
        let mut r0 = self.r0.clone();
        r0.sort_by(f64::total_cmp);
        if r0.windows(2).any(|w| w[1] - w[0] < 1e-6) {
            return Err(Error::config("r0", "resolutions must be distinct"));
        }
        let positive = [
            ("eps_over_h", self.eps_over_h, 0.5, 4.0),
            ("margin", self.margin, 2.0, 50.0),
            ("margin_r0", self.margin_r0, 0.0, 2.0),
            ("stop_residual", self.stop_residual, 1e-12, 1e-2),
        ];
        for (key, value, lo, hi) in positive {
            if !(value >= lo && value <= hi) {
                return Err(Error::config(
                    key,
                    format!("need {lo} ≤ {key} ≤ {hi}, got {value}"),
                ));
            }
        }
        if self.max_iterations == 0 {
            return Err(Error::config("max_iterations", "must be at least 1"));
        }
        Ok(())
    }

    /// Every case, numbered: branches in diagram order (prolate, oblate, stomatocyte), each
    /// reduced volume in increasing order, each resolution in increasing R0.
    pub fn cases(&self) -> Vec<Case> {
        let mut r0 = self.r0.clone();
        r0.sort_by(f64::total_cmp);
        let mut out = Vec::new();
        for branch in Branch::ALL {
            let Some(vs) = self.branches.get(branch.name()) else {
                continue;
            };
            let mut vs = vs.clone();
            vs.sort_by(f64::total_cmp);
            for &v in &vs {
                for &r in &r0 {
                    out.push(Case {
                        index: out.len(),
                        branch,
                        v,
                        r0: r,
                    });
                }
            }
        }
        out
    }

    /// The largest R0/ε (the finest resolution).
    pub fn finest(&self) -> f64 {
        self.r0.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
    }
}
