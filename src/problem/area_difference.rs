//! Area-difference elasticity (ADE) and the bilayer couple (BC) in the phase field
//! (docs/src/theory/ade.md).
//!
//! The sharp model, with R0 = √(A/4π) and α = κ̄/κ:
//!
//! ```text
//! w  = e + πα(Δa − Δa0)²,     Δa = (1/(8πR0)) ∮ 2H dA   (1 on a sphere)
//! ```
//!
//! In the phase field the integrated mean curvature is carried by the functional that C0
//! multiplies in F_sc: F_sc(C0) = F_sc(0) − 2εC0 M[φ] + ε²C0² ∫(φ² − 1)², with
//!
//! ```text
//! M[φ] = ∫ Φ₀ (1 − φ²) dx,      Φ₀ = φ³ − φ − ε²∇²φ            (Φ at C0 = 0)
//! δM/δφ = (3φ² − 1)(1 − φ²) − 2φ Φ₀ + ε² ∇²(φ²)
//! ```
//!
//! Across the tanh profile Φ₀ → (ε/√2)(1 − φ₀²) 2H and ∫(1 − φ₀²)² dd = (4√2/3) ε, so
//! M → (4/3) ε² ∮ 2H dA: a sphere of radius R0 has M = M₁ = (32π/3) ε² R0, and Δa = M/M₁. The
//! energy F_sc of a reduced energy e = 1 is E₁ = (32√2π/3) ε³, so the phase field's ADE energy
//! and its multiplier (the derivative by M, uniform in space) are
//!
//! ```text
//! F_ade = E₁ πα (Δa − Δa0)²,     λ = dF_ade/dM = 2 E₁ πα (Δa − Δa0) / M₁
//! ```
//!
//! and μ gains λ δM/δφ. A stationary ADE state is a stationary spontaneous-curvature state at
//! c̄0,eff = c̄0 + 2πα(Δa0 − Δa) (E₁/M₁ = √2 ε/R0 turns λ into a shift of εC0).

use crate::problem::config::{AdeMultiplier, C0Spec, Scene};
use std::f64::consts::{PI, SQRT_2};

/// The law of the area-difference term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// Area-difference elasticity: modulus ratio α and preferred Δa0; `lagged` when the
    /// conserved spectral step takes λ of the current state.
    Elastic {
        /// α = κ̄/κ.
        alpha: f64,
        /// Δa0.
        da0: f64,
        /// λ lagged (a stability study's choice) instead of implicit.
        lagged: bool,
    },
    /// The bilayer couple: Δa held by a multiplier.
    Couple {
        /// The Δa held.
        da: f64,
    },
}

/// The area-difference term of a scene at a reference area A0 (which fixes R0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaDifference {
    /// ADE or the bilayer couple.
    pub law: Law,
    /// M₁ = (32π/3) ε² R0: M of the sphere of radius R0, Δa = M/M₁.
    pub m_unit: f64,
    /// E₁ = (32√2π/3) ε³: F_sc of reduced energy 1.
    pub e_unit: f64,
    /// R0 = √(A0/4π).
    pub r0: f64,
    /// c̄0 = c0 R0 of a uniform c0 (NaN for a c0 field): the base of c̄0,eff.
    pub c0_reduced: f64,
}

impl AreaDifference {
    /// The term of `scene` (None without `ade` or `bilayer_couple`) at area `area0`.
    pub fn of(scene: &Scene, area0: f64) -> Option<Self> {
        let law = match (&scene.ade, &scene.bilayer_couple) {
            (Some(a), _) => Law::Elastic {
                alpha: a.alpha,
                da0: a.da0,
                lagged: a.multiplier == Some(AdeMultiplier::Lagged),
            },
            (None, Some(b)) => Law::Couple { da: b.da },
            (None, None) => return None,
        };
        let mut term = Self::new(law, scene.eps, area0);
        term.c0_reduced = match scene.c0 {
            C0Spec::Uniform(c) => c * term.r0,
            C0Spec::Field(_) => f64::NAN,
        };
        Some(term)
    }

    /// The term with `law`, width `eps`, at area `area0`, c0 = 0.
    pub fn new(law: Law, eps: f64, area0: f64) -> Self {
        let r0 = (area0 / (4.0 * PI)).sqrt();
        AreaDifference {
            law,
            m_unit: 32.0 * PI / 3.0 * eps * eps * r0,
            e_unit: 32.0 * SQRT_2 * PI / 3.0 * eps.powi(3),
            r0,
            c0_reduced: 0.0,
        }
    }

    /// Δa = M/M₁.
    pub fn da(&self, m: f64) -> f64 {
        m / self.m_unit
    }

    /// M0 = Δa0 M₁ (ADE) or Δa M₁ (bilayer couple): the M the term pulls towards or holds.
    pub fn target(&self) -> f64 {
        match self.law {
            Law::Elastic { da0, .. } => da0 * self.m_unit,
            Law::Couple { da } => da * self.m_unit,
        }
    }

    /// κ_λ = dλ/dM = 2E₁πα/M₁² (ADE); 0 for the bilayer couple (its λ is a multiplier).
    pub fn stiffness(&self) -> f64 {
        match self.law {
            Law::Elastic { alpha, .. } => 2.0 * self.e_unit * PI * alpha / self.m_unit.powi(2),
            Law::Couple { .. } => 0.0,
        }
    }

    /// F_ade = E₁πα(Δa − Δa0)² = (κ_λ/2)(M − M0)² (0 for the bilayer couple, whose M is held).
    pub fn energy(&self, m: f64) -> f64 {
        0.5 * self.stiffness() * (m - self.target()).powi(2)
    }

    /// λ = κ_λ (M − M0) of a state with integral `m` (ADE; 0 for the bilayer couple).
    pub fn multiplier(&self, m: f64) -> f64 {
        self.stiffness() * (m - self.target())
    }

    /// The reduced ADE energy πα(Δa − Δa0)² = F_ade/E₁.
    pub fn reduced_energy(&self, m: f64) -> f64 {
        self.energy(m) / self.e_unit
    }

    /// The reduced effective spontaneous curvature of a state with integral `m` and multiplier
    /// `lambda`: c̄0 + 2πα(Δa0 − Δa) (ADE); for the bilayer couple c̄0 − λM₁/E₁ =
    /// c̄0 − λR0/(√2ε), the shift its multiplier makes (λ δM/δφ in μ is the term
    /// −2ε δC0 δM/δφ of a uniform δC0).
    pub fn c0_eff(&self, m: f64, lambda: f64) -> f64 {
        match self.law {
            Law::Elastic { alpha, da0, .. } => {
                self.c0_reduced + 2.0 * PI * alpha * (da0 - self.da(m))
            }
            Law::Couple { .. } => self.c0_reduced - lambda * self.m_unit / self.e_unit,
        }
    }
}

/// The integrand of M at one point: Φ₀ (1 − φ²), Φ₀ = φ³ − φ − ε²∇²φ (`lap` = ∇²φ, `e2` = ε²).
#[inline(always)]
pub fn curvature_density(phi: f64, lap: f64, e2: f64) -> f64 {
    let g = 1.0 - phi * phi;
    (phi * phi * phi - phi - e2 * lap) * g
}

/// The local part of δM/δφ at one point: (3φ² − 1)(1 − φ²) − 2φΦ₀; the variation adds
/// ε²∇²(φ²).
#[inline(always)]
pub fn curvature_variation_local(phi: f64, lap: f64, e2: f64) -> f64 {
    let p2 = phi * phi;
    let big = phi * p2 - phi - e2 * lap;
    (3.0 * p2 - 1.0) * (1.0 - p2) - 2.0 * phi * big
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bilayer couple's c̄0,eff equals ADE's where their multipliers agree: an ADE state
    /// with λ = κ_λ(M − M0) read through the couple's formula gives c̄0 + 2πα(Δa0 − Δa) to
    /// round-off (E₁/M₁ = √2ε/R0 is the factor both use).
    #[test]
    fn both_laws_give_one_effective_curvature() {
        let (eps, area0) = (0.7, 4.0 * PI * 15.0f64.powi(2));
        let mut ade = AreaDifference::new(
            Law::Elastic {
                alpha: 1.3,
                da0: 1.4,
                lagged: false,
            },
            eps,
            area0,
        );
        let mut bc = AreaDifference::new(Law::Couple { da: 1.2 }, eps, area0);
        (ade.c0_reduced, bc.c0_reduced) = (0.5, 0.5);
        let m = 1.17 * ade.m_unit;
        let lambda = ade.multiplier(m);
        let from_ade = ade.c0_eff(m, 0.0);
        let from_bc = bc.c0_eff(m, lambda);
        assert!((from_ade - from_bc).abs() < 1e-12, "{from_ade} {from_bc}");
        assert!((from_ade - (0.5 + 2.0 * PI * 1.3 * (1.4 - 1.17))).abs() < 1e-12);
        assert!((ade.e_unit / ade.m_unit - SQRT_2 * eps / 15.0).abs() < 1e-14);
    }
}
