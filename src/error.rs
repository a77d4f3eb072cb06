//! Error types of the library. The CLI maps them to exit codes: invalid input → 2, a run that
//! blew up or broke a constraint → 3, a device that failed during a run (a GPU out of memory) →
//! 4.

use std::path::{Path, PathBuf};

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Invalid input: `field` is the dotted key of a scene or diagram file, or a flag.
    #[error("invalid input: `{field}`: {reason}")]
    Config {
        /// The dotted key, flag or `(name)` refused.
        field: String,
        /// Why, for the user.
        reason: String,
    },
    /// The run diverged or broke a constraint at step `step`, time `t`: `cause` says which.
    #[error("run stopped at step {step}, t = {t:.6e}: {reason}")]
    Blowup {
        /// The step that failed (1 for the first).
        step: usize,
        /// The time the step would have reached.
        t: f64,
        /// The step, its Δt and the check that failed, in words.
        reason: String,
        /// The check that failed.
        cause: Cause,
    },
    /// The device failed at step `step`, time `t` (a GPU out of memory, a kernel that failed):
    /// nothing about the scheme.
    #[error("run stopped at step {step}, t = {t:.6e}: the device failed: {reason}")]
    Device {
        /// The step that failed.
        step: usize,
        /// The time the step would have reached.
        t: f64,
        /// What the device reported.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// A study could not compute what it reports (a point without a sharp-interface
    /// reference).
    #[error("{0}")]
    Study(String),
    /// An output writer failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl Error {
    /// A `Config` error for `field`.
    pub fn config(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Config {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

impl Error {
    /// The error with `what` (an engine or route name) in front of a blow-up's reason; other
    /// errors unchanged.
    pub fn within(self, what: &str) -> Self {
        match self {
            Error::Blowup {
                step,
                t,
                reason,
                cause,
            } => Error::Blowup {
                step,
                t,
                reason: format!("{what}: {reason}"),
                cause,
            },
            Error::Device { step, t, reason } => Error::Device {
                step,
                t,
                reason: format!("{what}: {reason}"),
            },
            other => other,
        }
    }
}

/// Library result type.
pub type Result<T> = std::result::Result<T, Error>;

/// Errors of the file writers and readers ([`crate::output`], [`crate::npy`]); every message
/// names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating, reading or writing a file failed.
    #[error("I/O error on {}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An array had another shape than the one required.
    #[error("{}: expected array shape {expected:?}, found {found:?}", path.display())]
    Shape {
        /// The file concerned.
        path: PathBuf,
        /// The required shape.
        expected: Vec<usize>,
        /// The shape actually found.
        found: Vec<usize>,
    },
    /// Malformed content or unusable arguments (the message names the file).
    #[error("{0}")]
    Format(String),
}

impl OutputError {
    /// An [`OutputError::Io`] for `path`.
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// An [`OutputError::Format`] whose message starts with the file name.
    pub(crate) fn format(path: &Path, message: impl std::fmt::Display) -> Self {
        OutputError::Format(format!("{}: {message}", path.display()))
    }
}

/// What ended a run on a failed step (not a device failure): the class a study charts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cause {
    /// The state diverged.
    BlewUp,
    /// The volume was not held.
    Volume,
    /// The area was not held (off its target, or its projection has no real root).
    Area,
    /// F_eff rose where the scheme guarantees a decrease.
    EnergyRise,
    /// The bilayer couple's area difference was not held.
    AreaDifference,
}
