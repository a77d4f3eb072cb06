//! The energy models of the axisymmetric reference: spontaneous curvature (SC),
//! area-difference elasticity (ADE) and the bilayer couple (BC), and the equivalence that maps
//! ADE and BC shapes onto SC shapes at an effective spontaneous curvature.
//!
//! With `R0 = 1`, `e = e_0 − c̄0 Δa + c̄0²/4` (`e_0 = ∮(2H)² dA/16π`, `Δa = J = ∮2H dA/8π`):
//!
//! ```text
//! SC:   e                                    stationary at fixed A, V
//! ADE:  w = e + πα (Δa − Δa0)²,  α = κ̄/κ    stationary at fixed A, V
//! BC:   e                                    stationary at fixed A, V and Δa
//! ```
//!
//! **Equivalence.** At fixed `A` (`R0 = 1`) `c̄0²/4` is a constant, so
//! `δw = δe_0 − c̄0 δΔa + 2πα (Δa − Δa0) δΔa = δe_0 − c̄0,eff δΔa` with
//! `c̄0,eff = c̄0 + 2πα (Δa0 − Δa)`: the first variation of `w` is that of `e` at `c̄0,eff`, so
//! a stationary ADE shape is a stationary SC shape at `c̄0,eff` (same `v`). For BC, the
//! Lagrangian `e + λ_Δa (Δa − Δa_target)` has the variation of `e` at `c̄0 − λ_Δa`: a
//! stationary BC shape is a stationary SC shape at `c̄0,eff = c̄0 − λ_Δa`, and
//! `∂e_BC/∂Δa = −λ_Δa` along the BC branch at fixed `v`. Hence the ADE branch at fixed `v`
//! is the image of the BC branch under `Δa0 = Δa + (c̄0,eff − c̄0)/(2πα)` (Miao et al.,
//! Phys. Rev. E 49, 5389, 1994): [`super::ade`].

use std::f64::consts::PI;

/// The energy model of a solve.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Model {
    /// Spontaneous curvature: the energy is `e` at [`super::Options::c0`].
    #[default]
    Sc,
    /// Area-difference elasticity: the energy is `w = e + πα(Δa − Δa0)²`.
    Ade {
        /// `α = κ̄/κ`, the ratio of the non-local to the local bending modulus.
        alpha: f64,
        /// Preferred (reduced) area difference `Δa0`.
        da0: f64,
    },
    /// Bilayer couple: `Δa` is held at `da` (a constraint); the energy is `e`.
    Bc {
        /// The (reduced) area difference `Δa`.
        da: f64,
    },
}

impl Model {
    /// The model's energy `w` of a shape with bending energy `e` and area difference `da`:
    /// `e + πα(Δa − Δa0)²` for ADE, `e` otherwise.
    pub fn energy(&self, e: f64, da: f64) -> f64 {
        match *self {
            Model::Ade { alpha, da0 } => e + ade_penalty(alpha, da, da0),
            Model::Sc | Model::Bc { .. } => e,
        }
    }

    /// Lower-case name (`sc`, `ade`, `bc`).
    pub fn name(&self) -> &'static str {
        match self {
            Model::Sc => "sc",
            Model::Ade { .. } => "ade",
            Model::Bc { .. } => "bc",
        }
    }
}

/// The ADE term `πα(Δa − Δa0)²`.
pub fn ade_penalty(alpha: f64, da: f64, da0: f64) -> f64 {
    PI * alpha * (da - da0).powi(2)
}

/// The effective spontaneous curvature of an ADE shape: `c̄0,eff = c̄0 + 2πα(Δa0 − Δa)`.
pub fn ade_c0_eff(c0: f64, alpha: f64, da: f64, da0: f64) -> f64 {
    c0 + 2.0 * PI * alpha * (da0 - da)
}

/// The preferred area difference `Δa0` at which a stationary SC shape at `c̄0,eff` with area
/// difference `Δa` is a stationary ADE shape of `α` and `c̄0` (the inverse of [`ade_c0_eff`]):
/// `Δa0 = Δa + (c̄0,eff − c̄0)/(2πα)`.
pub fn ade_da0(c0: f64, alpha: f64, da: f64, c0_eff: f64) -> f64 {
    da + (c0_eff - c0) / (2.0 * PI * alpha)
}
