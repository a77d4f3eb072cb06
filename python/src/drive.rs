//! Stepping from Python: the library's step loop runs on a worker thread, in the
//! simulation's rayon pool, with the GIL released; the calling thread waits in slices of
//! [`POLL`] and between them lets Python handle signals (`check_signals` only acts on the main
//! thread, which is why the engine is not run there). A Ctrl-C asks the loop to stop after
//! the step under way, so the simulation is left at its last good state, and then raises
//! `KeyboardInterrupt`. A callback is called on the worker with the GIL taken for it, given a
//! [`StepView`] of the state; its exception, or the interrupt, is raised once the loop has
//! ended.
//!
//! A callback's cost is kept to taking the GIL and one small object: the worker holds a Python
//! thread state for the whole run (taken once, the GIL released at once), so that each call
//! only takes the GIL, and the view copies the record (no dict) and reads φ only when asked.

use crate::arrays::{field_array, record_dict};
use ndarray::Array3;
use pyo3::exceptions::{PyKeyError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;
use vesicle::driver::observers::Recorder;
use vesicle::driver::record::Record;
use vesicle::driver::simulation::{Flow, Now, Observer, Simulation, StopRules};
use vesicle::error::Result;
use vesicle::problem::grid::Grid;

/// How often the waiting thread checks for signals.
const POLL: Duration = Duration::from_millis(50);

/// The stop reason of a run ended by Ctrl-C (raised as `KeyboardInterrupt`).
const INTERRUPTED: &str = "interrupted";
/// The stop reason of a run that a callback ended by returning `False`.
pub const CALLBACK: &str = "callback";
/// The stop reason of a run ended by a callback's exception (which is raised).
const CALLBACK_RAISED: &str = "callback raised";

/// A Python callback and how often to call it.
pub struct Callback {
    /// The callable, given each step's [`StepView`].
    pub function: Py<PyAny>,
    /// Call it every `every` steps.
    pub every: usize,
}

/// φ of the state a callback is called on: the engine's array, readable only while the
/// callback runs (the observer clears it before the engine steps again).
struct Live(*const Array3<f64>);

// SAFETY: the pointer is only dereferenced under the view's mutex, and the observer that set it
// clears it under the same mutex before the array it points to can change or go away.
unsafe impl Send for Live {}

/// The state a callback is called on: the step's record (the timeseries.csv columns), read as
/// a mapping (`view["t"]`, `dict(view)`) or as attributes (`view.t`), and `phi`, the full-box
/// field, readable while the callback runs.
#[pyclass(frozen, module = "vesicle", name = "StepView")]
pub struct StepView {
    record: Record,
    grid: Grid,
    live: Mutex<Option<Live>>,
}

impl StepView {
    /// The value of column `name` as a Python int (step, rejected) or float.
    fn value<'py>(&self, py: Python<'py>, name: &str) -> Option<Bound<'py, PyAny>> {
        let r = &self.record;
        let v = r.get(name)?;
        Some(match name {
            "step" => r.step.into_pyobject(py).ok()?.into_any(),
            "rejected" => r.rejected.into_pyobject(py).ok()?.into_any(),
            _ => v.into_pyobject(py).ok()?.into_any(),
        })
    }
}

#[pymethods]
impl StepView {
    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.value(py, key)
            .ok_or_else(|| PyKeyError::new_err(key.to_string()))
    }

    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.value(py, name).ok_or_else(|| {
            pyo3::exceptions::PyAttributeError::new_err(format!(
                "'StepView' object has no attribute '{name}'"
            ))
        })
    }

    fn __contains__(&self, key: &str) -> bool {
        self.record.names().contains(&key)
    }

    fn __len__(&self) -> usize {
        self.record.names().len()
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        PyList::new(py, self.record.names())?
            .try_iter()
            .map(Bound::into_any)
    }

    /// The column names (those of timeseries.csv).
    fn keys(&self) -> Vec<&'static str> {
        self.record.names()
    }

    /// The values, in the order of keys().
    fn values<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyAny>> {
        self.record
            .names()
            .iter()
            .filter_map(|c| self.value(py, c))
            .collect()
    }

    /// (name, value) pairs, in the order of keys().
    fn items<'py>(&self, py: Python<'py>) -> Vec<(&'static str, Bound<'py, PyAny>)> {
        self.record
            .names()
            .into_iter()
            .filter_map(|c| Some((c, self.value(py, c)?)))
            .collect()
    }

    /// The value of column `key`, or `default`.
    #[pyo3(signature = (key, default=None))]
    fn get<'py>(
        &self,
        py: Python<'py>,
        key: &str,
        default: Option<Bound<'py, PyAny>>,
    ) -> Option<Bound<'py, PyAny>> {
        self.value(py, key).or(default)
    }

    /// The record as a dict (what Simulation.record gives).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        record_dict(py, &self.record)
    }

    /// φ of this state on the full box, as Simulation.phi gives it (a new read-only float64
    /// array of shape n). Readable only while the callback runs: RuntimeError afterwards.
    #[getter]
    fn phi<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let full = {
            let live = self.live.lock().expect("not poisoned");
            let Some(Live(phi)) = live.as_ref() else {
                return Err(PyRuntimeError::new_err(
                    "StepView.phi is readable only inside the callback it was given to \
                     (read sim.phi after the run, or copy it in the callback)",
                ));
            };
            // SAFETY: set from the engine's φ by the observer calling the callback, which
            // clears it (under this lock) before returning to the step loop.
            let phi = unsafe { &**phi };
            self.grid.unfold(phi).into_owned()
        };
        field_array(py, full, self.grid.dim)
    }

    fn __repr__(&self) -> String {
        let r = &self.record;
        format!(
            "StepView(step={}, t={:e}, reduced_energy={}, residual={:e})",
            r.step, r.t, r.reduced_energy, r.residual
        )
    }
}

/// The observer of a run from Python: stops at an interrupt, calls the callback.
struct Watch<'a> {
    interrupt: &'a AtomicBool,
    callback: Option<&'a Callback>,
    grid: &'a Grid,
    failure: &'a Mutex<Option<PyErr>>,
}

impl Observer for Watch<'_> {
    fn step(&mut self, now: &Now) -> Result<Flow> {
        if self.interrupt.load(Ordering::Relaxed) {
            return Ok(Flow::Stop(INTERRUPTED));
        }
        let Some(cb) = self.callback else {
            return Ok(Flow::Continue);
        };
        if !now.record.step.is_multiple_of(cb.every) {
            return Ok(Flow::Continue);
        }
        let view = StepView {
            record: now.record,
            grid: self.grid.clone(),
            live: Mutex::new(Some(Live(now.engine.phi()))),
        };
        Python::attach(|py| {
            let answer = Bound::new(py, view).and_then(|view| {
                let answer = cb.function.call1(py, (&view,));
                *view.get().live.lock().expect("not poisoned") = None;
                let v = answer?;
                let v = v.bind(py);
                Ok(v.is_instance_of::<PyBool>() && !v.is_truthy()?)
            });
            match answer {
                Ok(true) => Ok(Flow::Stop(CALLBACK)),
                Ok(false) => Ok(Flow::Continue),
                Err(e) => {
                    *self.failure.lock().expect("not poisoned") = Some(e);
                    Ok(Flow::Stop(CALLBACK_RAISED))
                }
            }
        })
    }
}

/// What a simulation needs to be stepped: the library's simulation, the time-series recorder
/// kept across runs, and the thread pool it runs in.
pub struct Stepper {
    /// The library's simulation.
    pub simulation: Simulation,
    /// The time series (in memory).
    pub recorder: Recorder,
    /// The worker threads.
    pub pool: rayon::ThreadPool,
}

/// How a run from Python ended.
pub enum Ended {
    /// A stop rule fired, or the callback returned False: the reason's name.
    Stopped(&'static str),
    /// Python raised (Ctrl-C, a callback's exception).
    Raised(PyErr),
    /// The library's error (a failed step, with the time before it).
    Failed(vesicle::error::Error, f64),
}

/// Run `stepper` under `rules` with the GIL released, hearing Ctrl-C, calling `callback` (with
/// φ unfolded on `grid`), and with the `outputs` observers (snapshots, checkpoints) after the
/// recorder.
pub fn run(
    py: Python<'_>,
    stepper: &mut Stepper,
    grid: &Grid,
    rules: &StopRules,
    callback: Option<&Callback>,
    outputs: &mut [&mut (dyn Observer + Send)],
) -> Ended {
    let interrupt = AtomicBool::new(false);
    let failure = Mutex::new(None);
    let Stepper {
        simulation,
        recorder,
        pool,
    } = stepper;
    let work = || {
        let mut watch = Watch {
            interrupt: &interrupt,
            callback,
            grid,
            failure: &failure,
        };
        let r = pool.install(|| {
            let mut step = || {
                let mut observers: Vec<&mut dyn Observer> = vec![&mut *recorder, &mut watch];
                observers.extend(outputs.iter_mut().map(|o| &mut **o as &mut dyn Observer));
                simulation.run(rules, &mut observers)
            };
            if callback.is_some() {
                // One thread state for the run: each call then only takes the GIL.
                Python::attach(|py| py.detach(step))
            } else {
                step()
            }
        });
        (r, simulation.clock.t)
    };
    let ((result, t), keyboard) = off_thread(py, work, || interrupt.store(true, Ordering::Relaxed));
    if let Some(e) = keyboard {
        return Ended::Raised(e);
    }
    if let Some(e) = failure.into_inner().expect("not poisoned") {
        return Ended::Raised(e);
    }
    match result {
        Ok(stopped) => Ended::Stopped(stopped.as_str()),
        Err(e) => Ended::Failed(e, t),
    }
}

/// Run `work` on a new thread with the GIL released, letting Python handle signals every
/// [`POLL`] meanwhile; at the first exception a signal handler raises (`KeyboardInterrupt`),
/// call `on_signal` (to ask `work` to stop) and keep waiting. Returns what `work` returned and
/// that exception, if any. A panic in `work` is resumed here.
pub fn off_thread<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> T + Send,
    on_signal: impl Fn(),
) -> (T, Option<PyErr>) {
    let done = (Mutex::new(false), Condvar::new());
    let mut raised = None;
    let result = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let r = work();
            *done.0.lock().expect("not poisoned") = true;
            done.1.notify_all();
            r
        });
        loop {
            let finished = py.detach(|| {
                let flag = done.0.lock().expect("not poisoned");
                let (flag, _) = done
                    .1
                    .wait_timeout_while(flag, POLL, |d| !*d)
                    .expect("not poisoned");
                *flag
            });
            if finished {
                break;
            }
            if raised.is_none() {
                if let Err(e) = py.check_signals() {
                    on_signal();
                    raised = Some(e);
                }
            }
        }
        worker.join()
    });
    match result {
        Ok(r) => (r, raised),
        Err(panic) => std::panic::resume_unwind(panic),
    }
}
