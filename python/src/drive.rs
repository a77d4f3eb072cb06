//! Stepping from Python: the library's step loop runs on a worker thread, in the
//! simulation's rayon pool, with the GIL released; the calling thread waits in slices of
//! [`POLL`] and between them lets Python handle signals (`check_signals` only acts on the main
//! thread, which is why the engine is not run there). A Ctrl-C asks the loop to stop after
//! the step under way, so the simulation is left at its last good state, and then raises
//! `KeyboardInterrupt`. A callback is called on the worker with the GIL taken for it; its
//! exception, or the interrupt, is raised once the loop has ended.

use crate::arrays::record_dict;
use pyo3::prelude::*;
use pyo3::types::PyBool;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;
use vesicle::driver::observers::Recorder;
use vesicle::driver::simulation::{Flow, Now, Observer, Simulation, StopRules};
use vesicle::error::Result;

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
    /// The callable, given each record as a dict.
    pub function: Py<PyAny>,
    /// Call it every `every` steps.
    pub every: usize,
}

/// The observer of a run from Python: stops at an interrupt, calls the callback.
struct Watch<'a> {
    interrupt: &'a AtomicBool,
    callback: Option<&'a Callback>,
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
        Python::attach(|py| {
            let answer = record_dict(py, &now.record)
                .and_then(|d| cb.function.call1(py, (d,)))
                .and_then(|v| {
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

/// Run `stepper` under `rules` with the GIL released, hearing Ctrl-C, calling `callback`.
pub fn run(
    py: Python<'_>,
    stepper: &mut Stepper,
    rules: &StopRules,
    callback: Option<&Callback>,
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
            failure: &failure,
        };
        let r = pool.install(|| simulation.run(rules, &mut [recorder, &mut watch]));
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
