//! The convergence study's spec: the study file's keys, one block per part.

use serde::Deserialize;
use serde_json::Value;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"convergence"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Δt halving.
    pub time: TimeSpec,
    /// h halving.
    pub space: SpaceSpec,
    /// ε/R0.
    pub eps: EpsSpec,
}

/// Δt halving at a fixed grid.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// A conserved spectral scene (its `prepare_steps` give the prepared start).
    pub scene: Value,
    /// The time at which the errors are taken.
    pub t: f64,
    /// The coarsest Δt.
    pub dt: f64,
    /// Number of Δt (each half the previous).
    pub levels: usize,
    /// Δt of the SBDF2 reference.
    pub reference_dt: f64,
}

/// h halving at fixed ε.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SpaceSpec {
    /// A stationary scene (a `stop_residual`); its `n` is replaced by `length / h`.
    pub scene: Value,
    /// Edge of the full box (units of the scene).
    pub length: f64,
    /// Spacings of the FD discretisation.
    pub fd_h: Vec<f64>,
    /// Spacings of the spectral discretisation.
    pub spectral_h: Vec<f64>,
    /// Spacing of the spectral reference.
    pub reference_h: f64,
}

/// ε/R0 at fixed h/ε.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct EpsSpec {
    /// A 3D stationary scene (its `initial` and `n` are replaced).
    pub scene: Value,
    /// The values of ε/R0.
    pub eps_over_r0: Vec<f64>,
    /// Bulk kept between the shape and the box faces, in units of ε.
    pub margin: f64,
    /// The shapes.
    pub shapes: Vec<ShapeSpec>,
}

/// One shape of the ε/R0 sweep.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// `"prolate"`, `"oblate"` or `"sphere"`.
    pub branch: String,
    /// The branch's v (not for a sphere).
    #[serde(default)]
    pub reduced_volume: Option<f64>,
    /// This shape's ε/R0 values, if not the sweep's.
    #[serde(default)]
    pub eps_over_r0: Option<Vec<f64>>,
    /// Scene keys merged into the sweep's scene for this shape (e.g. no area constraint for
    /// the sphere).
    #[serde(default)]
    pub scene: Option<Value>,
}
