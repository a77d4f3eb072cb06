//! `vesicle._vesicle`: the Python bindings of the `vesicle` engine (PyO3). The package
//! `vesicle` re-exports these names; the library does the work, this crate only converts:
//! scenes in ([`scene`]), the step loop driven with the GIL released and Ctrl-C heard
//! ([`drive`]), fields and time series out as NumPy arrays ([`arrays`]), errors as exceptions
//! ([`errors`]), the axisymmetric reference ([`axisym`]) and the command line in process
//! ([`commands`]: any command, and the studies by name with their tables typed).

mod arrays;
mod axisym;
mod commands;
mod drive;
mod errors;
mod outputs;
mod scene;
mod simulation;

use pyo3::prelude::*;

/// The compiled part of the `vesicle` package.
#[pymodule]
fn _vesicle(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<scene::Scene>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<drive::StepView>()?;
    m.add("InvalidInput", py.get_type::<errors::InvalidInput>())?;
    m.add("BlowUp", py.get_type::<errors::BlowUp>())?;
    m.add("DeviceError", py.get_type::<errors::DeviceError>())?;
    m.add_function(wrap_pyfunction!(axisym::axisym_solve, m)?)?;
    m.add_function(wrap_pyfunction!(axisym::axisym_follow, m)?)?;
    m.add_function(wrap_pyfunction!(axisym::axisym_updown, m)?)?;
    m.add_function(wrap_pyfunction!(commands::cli, m)?)?;
    m.add_function(wrap_pyfunction!(commands::studies, m)?)?;
    m.add_function(wrap_pyfunction!(commands::study, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
