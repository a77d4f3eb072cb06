//! The stability study's spec: the study file's keys.

use crate::problem::config::Scheme;
use serde::Deserialize;
use serde_json::Value;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"stability"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The base scene at h = ε (its `n` is scaled by ε/h).
    pub scene: Value,
    /// Spacings, in units of ε.
    pub h: Vec<f64>,
    /// Fixed steps per run.
    pub steps: usize,
    /// Smallest Δt of the sweep.
    pub dt_min: f64,
    /// Largest Δt of the sweep.
    pub dt_max: f64,
    /// Δt values per decade.
    pub per_decade: f64,
    /// Adaptive runs.
    pub adaptive: AdaptiveSweep,
    /// The Lagrangian α sweep.
    pub alpha: AlphaSweep,
    /// The spontaneous-curvature axis (optional).
    #[serde(default)]
    pub c0: Option<C0Sweep>,
}

/// The fixed-Δt sweep at h = ε against the spontaneous curvature, default stabiliser.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct C0Sweep {
    /// εc0 values (c0 set uniform to εc0/ε in the scene).
    pub eps_c0: Vec<f64>,
    /// Spectral schemes, each with its default stabiliser.
    pub schemes: Vec<Scheme>,
}

/// Adaptive runs at several tolerances.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveSweep {
    /// The controller's `energy_alpha` values.
    pub energy_alpha: Vec<f64>,
    /// End time.
    pub t_end: f64,
    /// First Δt.
    pub dt: f64,
    /// Largest Δt.
    pub dt_max: f64,
}

/// The Lagrangian α sweep (FD, first h).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct AlphaSweep {
    /// Δt as fractions of the FD bound.
    pub dt_fractions: Vec<f64>,
    /// Smallest α.
    pub alpha_min: f64,
    /// Largest α.
    pub alpha_max: f64,
    /// α values per decade.
    pub per_decade: f64,
    /// Steps per run.
    pub steps: usize,
}
