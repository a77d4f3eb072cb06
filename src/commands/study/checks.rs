//! The value checks the Stokes study files share (`rates.json`, `shear.json`): each names the
//! key it refuses.

use crate::error::{Error, Result};

/// x ≥ `lo` (false for NaN).
pub fn at_least(x: f64, lo: f64) -> bool {
    x >= lo
}

/// A finite value > 0 under `key`.
///
/// # Errors
/// `Error::Config` naming `key` otherwise.
pub fn positive(key: &str, v: f64) -> Result<()> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(Error::config(
            key,
            format!("must be finite and > 0, got {v}"),
        ))
    }
}

/// `h_over_eps` in (0, 1].
///
/// # Errors
/// `Error::Config` naming `h_over_eps` otherwise.
pub fn h_over_eps(v: f64) -> Result<()> {
    if v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        Err(Error::config("h_over_eps", "need 0 < h/ε ≤ 1"))
    }
}

/// `e` with its field under `key` (`key.field`); other errors unchanged.
pub fn within(key: &str, e: Error) -> Error {
    match e {
        Error::Config { field, reason } => Error::config(format!("{key}.{field}"), reason),
        other => other,
    }
}
