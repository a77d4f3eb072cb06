//! The library's errors as Python exceptions: invalid input as [`InvalidInput`] (a
//! `ValueError` carrying the field), a failed step as [`BlowUp`] (step, t, Δt, the failed
//! check and its cause), a failed device as [`DeviceError`], reading and writing files as
//! `OSError`.

use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use vesicle::error::Error;
use vesicle::output::OutputError;

create_exception!(
    vesicle,
    InvalidInput,
    PyValueError,
    "Invalid input (a scene key, an override, a checkpoint that does not fit), with the \
     message the command line prints. Attributes: `field` (the dotted scene key, e.g. \
     `\"initial.r0\"`, or a name in parentheses such as `\"(file)\"`) and `reason`."
);

create_exception!(
    vesicle,
    BlowUp,
    PyRuntimeError,
    "A step failed (the field diverged, the energy rose, a constraint broke). The simulation \
     still holds the last good state. Attributes: `step` (the step that failed), `t` (the time \
     it would have reached), `dt` (its Δt), `check` (the check that failed, in words) and \
     `cause` (`\"blew up\"`, `\"volume\"`, `\"area\"` or `\"energy rise\"`)."
);

create_exception!(
    vesicle,
    DeviceError,
    PyRuntimeError,
    "The device failed during a run (a GPU out of memory, a kernel that failed): nothing about \
     the scheme. The simulation still holds the last good state. Attributes: `step` and `t`."
);

/// `e` as the Python exception of its kind, the simulation's time before the failed step
/// being `t_before` (for a blow-up's Δt; `None` where no step was attempted).
pub fn to_py(py: Python<'_>, e: Error, t_before: Option<f64>) -> PyErr {
    let message = e.to_string();
    match e {
        Error::Config { field, reason } => {
            let err = InvalidInput::new_err(message);
            let value = err.value(py);
            let _ = value.setattr("field", field);
            let _ = value.setattr("reason", reason);
            err
        }
        Error::Blowup {
            step,
            t,
            reason,
            cause,
        } => {
            let check = reason
                .split_once("failed: ")
                .map_or(reason.as_str(), |(_, c)| c)
                .to_string();
            let dt = t_before.map_or(f64::NAN, |t0| t - t0);
            let err = BlowUp::new_err(message);
            let value = err.value(py);
            let _ = value.setattr("step", step);
            let _ = value.setattr("t", t);
            let _ = value.setattr("dt", dt);
            let _ = value.setattr("check", check);
            let _ = value.setattr("cause", cause_name(cause));
            err
        }
        Error::Device { step, t, .. } => {
            let err = DeviceError::new_err(message);
            let value = err.value(py);
            let _ = value.setattr("step", step);
            let _ = value.setattr("t", t);
            err
        }
        Error::Study(_) => PyRuntimeError::new_err(message),
        Error::Io { path, source } => os_error(&source, &path, &message),
        Error::Output(OutputError::Io { path, source }) => os_error(&source, &path, &message),
        Error::Output(other) => PyOSError::new_err(other.to_string()),
    }
}

/// The name of a failed step's cause, as `BlowUp.cause` gives it.
fn cause_name(cause: vesicle::engines::Cause) -> &'static str {
    use vesicle::engines::Cause;
    match cause {
        Cause::BlewUp => "blew up",
        Cause::Volume => "volume",
        Cause::Area => "area",
        Cause::EnergyRise => "energy rise",
        Cause::AreaDifference => "area difference",
    }
}

/// An `OSError` with the errno of `source` where it has one (so Python picks the subclass,
/// e.g. `FileNotFoundError`), the file name and the library's message.
fn os_error(source: &std::io::Error, path: &std::path::Path, message: &str) -> PyErr {
    match source.raw_os_error() {
        Some(code) => PyOSError::new_err((code, message.to_string(), path.to_path_buf())),
        None => PyOSError::new_err(message.to_string()),
    }
}

/// A `vesicle::error::Result` as a `PyResult` (no step attempted).
pub fn check<T>(py: Python<'_>, r: vesicle::error::Result<T>) -> PyResult<T> {
    r.map_err(|e| to_py(py, e, None))
}
