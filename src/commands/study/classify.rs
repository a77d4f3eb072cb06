//! How a fixed-Δt run ended, by stated criteria on its time series (the stability map's
//! classes), in order of precedence:
//!
//! 1. **blown up**: a step failed with a diverged state (non-finite, |φ| > 5, or F non-finite;
//!    [`crate::problem::model::diverged`]; [`Cause::BlewUp`]), or max|φ| exceeded
//!    [`Criteria::max_phi`] on some step;
//! 2. **constraint lost**: a step failed a constraint guard (V drifted by more than 1e-9, A off
//!    its target by more than 1e-9 under the projection, no real root of the area quadratic:
//!    [`Cause::Volume`] or [`Cause::Area`]), or |A − A0|/A0 exceeded [`Criteria::area`];
//! 3. **energy rising**: a step failed the energy guard ([`Cause::EnergyRise`]), or on some
//!    step F_eff = F + σⁿA, taken at the σ of the state before the step, rose by more than
//!    [`Criteria::rise`] relative;
//! 4. **stable**: none of these: stable and energy-decreasing.
//!
//! A device failure is not a class: it says nothing of the scheme, and ends the study.

use crate::engines::Cause;

/// One step of a run, as the classification sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepSample {
    /// F_eff before the step, at σⁿ.
    pub f_before: f64,
    /// F_eff after the step, at the same σⁿ.
    pub f_after: f64,
    /// |A − A0| / A0 after the step.
    pub area_error: f64,
    /// max|φ| after the step.
    pub max_phi: f64,
}

/// Thresholds of the classes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Criteria {
    /// Relative rise of F_eff counted as a rise (beyond round-off of the sums).
    pub rise: f64,
    /// Relative area error counted as losing the constraint.
    pub area: f64,
    /// max|φ| counted as a blow-up (a stable run stays near 1).
    pub max_phi: f64,
}

impl Default for Criteria {
    /// Rise 1e-10, area 1e-3, max|φ| 1.5.
    fn default() -> Self {
        Criteria {
            rise: 1e-10,
            area: 1e-3,
            max_phi: 1.5,
        }
    }
}

/// The classes, best first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Class {
    /// Stable and energy-decreasing.
    Stable,
    /// F_eff rose on some step.
    EnergyRising,
    /// A or V not held.
    ConstraintLost,
    /// Diverged.
    BlownUp,
}

impl serde::Serialize for Class {
    /// As its name ([`Class::as_str`]).
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl Class {
    /// All classes, best first.
    pub const ALL: [Class; 4] = [
        Class::Stable,
        Class::EnergyRising,
        Class::ConstraintLost,
        Class::BlownUp,
    ];

    /// Name in tables and CSV files.
    pub fn as_str(self) -> &'static str {
        match self {
            Class::Stable => "stable",
            Class::EnergyRising => "energy rising",
            Class::ConstraintLost => "constraint lost",
            Class::BlownUp => "blown up",
        }
    }
}

/// The class of a run with `steps` and, if a step failed, the `failure`'s cause.
pub fn classify(steps: &[StepSample], failure: Option<Cause>, c: &Criteria) -> Class {
    if failure == Some(Cause::BlewUp)
        || steps
            .iter()
            .any(|s| s.max_phi.is_nan() || s.max_phi > c.max_phi)
    {
        return Class::BlownUp;
    }
    if matches!(
        failure,
        Some(Cause::Area | Cause::Volume | Cause::AreaDifference)
    ) || steps.iter().any(|s| s.area_error > c.area)
    {
        return Class::ConstraintLost;
    }
    if failure == Some(Cause::EnergyRise)
        || steps
            .iter()
            .any(|s| s.f_after > s.f_before + c.rise * s.f_before.abs())
    {
        return Class::EnergyRising;
    }
    Class::Stable
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(f_before: f64, f_after: f64, area_error: f64, max_phi: f64) -> StepSample {
        StepSample {
            f_before,
            f_after,
            area_error,
            max_phi,
        }
    }

    /// A decreasing series is stable; one rise of 1e-8 relative (above the 1e-10 threshold)
    /// makes it energy rising, a rise of 1e-12 (round-off) does not.
    #[test]
    fn energy_criteria() {
        let c = Criteria::default();
        let down = [step(10.0, 9.0, 0.0, 1.0), step(9.0, 8.5, 0.0, 1.0)];
        assert_eq!(classify(&down, None, &c), Class::Stable);
        let up = [step(10.0, 9.0, 0.0, 1.0), step(9.0, 9.0 + 9e-8, 0.0, 1.0)];
        assert_eq!(classify(&up, None, &c), Class::EnergyRising);
        let noise = [step(9.0, 9.0 + 9e-12, 0.0, 1.0)];
        assert_eq!(classify(&noise, None, &c), Class::Stable);
    }

    /// An area error of 2e-3 (above 1e-3) or a failure of the area or the volume is a lost
    /// constraint, even if the energy also rose; a failed energy guard is a rise; a diverged
    /// state, a NaN or max|φ| = 2 is a blow-up, whatever else happened.
    #[test]
    fn constraint_and_blowup_take_precedence() {
        let c = Criteria::default();
        let drift = [step(9.0, 9.5, 2e-3, 1.0)];
        assert_eq!(classify(&drift, None, &c), Class::ConstraintLost);
        let ok = [step(9.0, 8.0, 0.0, 1.0)];
        assert_eq!(classify(&ok, Some(Cause::Area), &c), Class::ConstraintLost);
        assert_eq!(
            classify(&ok, Some(Cause::Volume), &c),
            Class::ConstraintLost
        );
        assert_eq!(
            classify(&ok, Some(Cause::EnergyRise), &c),
            Class::EnergyRising
        );
        assert_eq!(classify(&drift, Some(Cause::BlewUp), &c), Class::BlownUp);
        assert_eq!(
            classify(&[step(9.0, 8.0, 0.0, f64::NAN)], None, &c),
            Class::BlownUp
        );
        assert_eq!(
            classify(&[step(9.0, 8.0, 5e-3, 2.0)], None, &c),
            Class::BlownUp
        );
    }
}
