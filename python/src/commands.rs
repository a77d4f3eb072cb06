//! The command line run in process: every subcommand (`run`, `study`, `diagram`, `axisym`,
//! `render`, ...) from Python, writing its files as the `vesicle` program does.

use crate::drive::off_thread;
use crate::errors::to_py;
use pyo3::prelude::*;

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
