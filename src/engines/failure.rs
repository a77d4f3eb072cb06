//! Why a step failed, by type: the driver and the studies tell a blow-up from a broken
//! constraint and from a failed device by variant, never by reading a message.

pub use crate::error::Cause;

/// The state diverged: not finite, |φ| beyond its limit, or F not finite.
#[derive(Clone, Debug, PartialEq)]
pub struct Diverged(pub String);

/// Why an attempted step was rejected (no allocation: adaptive runs reject routinely).
#[derive(Clone, Debug, PartialEq)]
pub enum Rejection {
    /// A(φ^{n+1}(σ)) = A0 has no real root.
    NoRealRoot,
    /// The new state diverged.
    Diverged(Diverged),
    /// V drifted by this relative amount.
    VolumeDrift(f64),
    /// A is off its target by this relative amount (projection).
    AreaDrift(f64),
    /// The area-difference multiplier's equation (the bilayer couple's M = M0, ADE's
    /// λ = κ_λ(M − M0)) missed by this amount relative to M0.
    AreaDifferenceDrift(f64),
    /// F_eff rose where the scheme guarantees a decrease.
    EnergyRise {
        /// F_eff before the step.
        before: f64,
        /// F_eff after it.
        after: f64,
    },
}

impl Rejection {
    /// The check that rejected the step.
    pub fn cause(&self) -> Cause {
        match self {
            Rejection::NoRealRoot | Rejection::AreaDrift(_) => Cause::Area,
            Rejection::Diverged(_) => Cause::BlewUp,
            Rejection::VolumeDrift(_) => Cause::Volume,
            Rejection::EnergyRise { .. } => Cause::EnergyRise,
            Rejection::AreaDifferenceDrift(_) => Cause::AreaDifference,
        }
    }
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rejection::NoRealRoot => write!(f, "the area projection has no real root"),
            Rejection::Diverged(d) => write!(f, "{}", d.0),
            Rejection::VolumeDrift(d) => write!(f, "volume drifted by {d:.2e} (relative)"),
            Rejection::AreaDrift(d) => write!(f, "area off its target by {d:.2e} (relative)"),
            Rejection::AreaDifferenceDrift(d) => write!(
                f,
                "the area-difference multiplier missed its equation by {d:.2e} of M0 (the \
                 bilayer couple's Δa or ADE's implicit λ)"
            ),
            Rejection::EnergyRise { before, after } => write!(
                f,
                "F_eff rose from {before:.12e} to {after:.12e} (relative {:.2e})",
                (after - before) / before.abs()
            ),
        }
    }
}

/// Why a step could not be completed; the engine still holds the last good state.
#[derive(Clone, Debug, PartialEq)]
pub enum StepError {
    /// The step was rejected and no smaller step is allowed (a fixed step, or an adaptive one
    /// at its smallest): the check, and `context` (the step, a hint) after it.
    Rejected {
        /// The check that rejected the last attempt.
        check: Rejection,
        /// What follows the check's sentence (may be empty).
        context: String,
    },
    /// The device failed (a GPU out of memory, a launch that failed): no smaller step mends
    /// it, and it says nothing of the scheme's stability.
    Device(String),
}

impl StepError {
    /// A rejection with no context.
    pub fn rejected(check: Rejection) -> Self {
        StepError::Rejected {
            check,
            context: String::new(),
        }
    }

    /// The cause of the failure, or `None` for a device failure.
    pub fn cause(&self) -> Option<Cause> {
        match self {
            StepError::Rejected { check, .. } => Some(check.cause()),
            StepError::Device(_) => None,
        }
    }
}

impl From<Diverged> for StepError {
    fn from(d: Diverged) -> Self {
        StepError::rejected(Rejection::Diverged(d))
    }
}

impl std::fmt::Display for StepError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepError::Rejected { check, context } => write!(f, "{check}{context}"),
            StepError::Device(why) => write!(f, "{why}"),
        }
    }
}
