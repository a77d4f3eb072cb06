//! The command line run in process: every subcommand (`run`, `study`, `diagram`, `axisym`,
//! `render`, ...) from Python, writing its files as the `vesicle` program does; and the studies
//! by name from the library's registry (the command line's own list), their tables returned
//! typed.

use crate::drive::off_thread;
use crate::errors::to_py;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use vesicle::commands::studies::{self as registry, Values};

/// Run the `vesicle` command line with `args` (without the program name) in this process and
/// return its exit code; what it prints goes to this process's stdout and stderr.
#[pyfunction]
pub fn cli(py: Python<'_>, args: Vec<String>) -> PyResult<i32> {
    let argv = std::iter::once("vesicle".to_string()).chain(args);
    // A run installs its own SIGINT handler (it finishes its step and exits with 130) and
    // calls Python's after it; other commands go on to their end before KeyboardInterrupt.
    let (result, raised) = off_thread(py, || vesicle::commands::cli::run_args(argv), || ());
    if let Some(e) = raised {
        return Err(e);
    }
    result.map_err(|e| to_py(py, e, None))
}

/// The studies of the command line (`vesicle study NAME`), in its order: (name, description).
#[pyfunction]
pub fn studies() -> Vec<(String, String)> {
    registry::list()
        .into_iter()
        .map(|e| (e.name, e.about))
        .collect()
}

/// Run the study `name` as `vesicle study NAME FILE [--quick] [--set ...] --out OUT
/// [--force]` does (the same folder), in this process with the GIL released, and return its
/// tables: {CSV file stem: {column: array}}, counts as int64, numbers as float64 (an empty
/// cell NaN), names as str arrays.
#[pyfunction]
#[pyo3(signature = (name, file, out, quick=false, force=false, overrides=None))]
pub fn study<'py>(
    py: Python<'py>,
    name: &str,
    file: PathBuf,
    out: PathBuf,
    quick: bool,
    force: bool,
    overrides: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let set = crate::scene::assignments(py, overrides)?;
    let args = registry::Args {
        file: &file,
        quick,
        set: &set,
        out: &out,
        force,
    };
    let (result, raised) = off_thread(py, || registry::run(name, &args), || ());
    if let Some(e) = raised {
        return Err(e);
    }
    let tables = result.map_err(|e| to_py(py, e, None))?;
    let d = PyDict::new(py);
    for t in tables {
        let columns = PyDict::new(py);
        for (header, column) in t.columns {
            let array = match column {
                Values::Int(v) => PyArray1::from_vec(py, v).into_any(),
                Values::Float(v) => PyArray1::from_vec(py, v).into_any(),
                Values::Text(v) => {
                    let list = PyList::new(py, v)?;
                    py.import("numpy")?.call_method1("array", (list,))?
                }
            };
            columns.set_item(header, array)?;
        }
        d.set_item(t.name, columns)?;
    }
    Ok(d)
}
