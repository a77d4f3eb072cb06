//! [`Schedule`]: when an output (time-series rows, snapshots, checkpoints) is written, as the
//! scene file gives it under `output.*`.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Every `every_steps` accepted steps, every `every_time` of simulated time, every
/// `every_minutes` of wall time: whichever is due first. None set: never.
///
/// In a scene file: `{"every_steps": 100}`, `{"every_time": 5.0}`, `{"every_minutes": 10}` or
/// several of them together (`{"every_steps": 1000, "every_minutes": 30}`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Schedule {
    /// Accepted steps between two writes; due at the multiples of it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_steps: Option<usize>,
    /// Simulated time between two writes; the driver shortens the step that would pass a due
    /// time so that it lands on it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_time: Option<f64>,
    /// Minutes of wall time between two writes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_minutes: Option<f64>,
}

impl Schedule {
    /// Never due.
    pub const NEVER: Schedule = Schedule {
        every_steps: None,
        every_time: None,
        every_minutes: None,
    };

    /// Every `n` steps.
    pub fn steps(n: usize) -> Self {
        Schedule {
            every_steps: Some(n),
            ..Self::NEVER
        }
    }

    /// Every `dt` of simulated time.
    pub fn time(dt: f64) -> Self {
        Schedule {
            every_time: Some(dt),
            ..Self::NEVER
        }
    }

    /// Every `minutes` of wall time.
    pub fn minutes(minutes: f64) -> Self {
        Schedule {
            every_minutes: Some(minutes),
            ..Self::NEVER
        }
    }

    /// Whether no interval is set.
    pub fn is_never(&self) -> bool {
        *self == Self::NEVER
    }

    /// Check a schedule given in the scene file at the dotted key `field`: at least one
    /// interval, each positive (and finite).
    ///
    /// # Errors
    /// `Error::Config` naming `field` or `field.<interval>`.
    pub fn validate(&self, field: &str) -> Result<()> {
        if self.is_never() {
            return Err(Error::config(
                field,
                "needs at least one of every_steps, every_time, every_minutes",
            ));
        }
        if self.every_steps == Some(0) {
            return Err(Error::config(
                format!("{field}.every_steps"),
                "must be at least 1",
            ));
        }
        for (name, v) in [
            ("every_time", self.every_time),
            ("every_minutes", self.every_minutes),
        ] {
            if let Some(v) = v {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(Error::config(
                        format!("{field}.{name}"),
                        format!("must be positive and finite, got {v}"),
                    ));
                }
            }
        }
        Ok(())
    }
}
