//! `Simulation`: a scene's simulation driven from Python — the library's engine, step loop,
//! recorder, checkpoints and writers, with fields and time series as NumPy arrays.

use crate::arrays::{field_array, history_dict, points, record_dict, triangles};
use crate::drive::{self, Callback, Ended, Stepper};
use crate::errors::{check, to_py};
use crate::outputs::{Folder, Kept, Snapshot, Unwritten};
use crate::scene::{from_json, Scene};
use ndarray::{Array3, Axis};
use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use vesicle::analysis::{levelset, surface};
use vesicle::commands::run;
use vesicle::driver::checkpoint::Checkpoint;
use vesicle::driver::observers::Recorder;
use vesicle::driver::record::TimeSeries;
use vesicle::driver::simulation::{build_engine, check_stability, Prepared, StopRules};
use vesicle::engines::AreaConstraint;
use vesicle::error::Error;
use vesicle::output;
use vesicle::problem::config;
use vesicle::problem::grid::{AxisKind, Grid};
use vesicle::problem::model::{max_abs_diff, PHI_BLOWUP};
use vesicle::problem::setup::{self, SYMMETRY_TOL};

/// A simulation of a scene: the engine the scene asks for, prepared and constrained exactly
/// as `vesicle run` does, at t = 0.
///
/// `scene` is a Scene (or anything Scene() accepts: a dict or a scene-file path). `threads`
/// is the number of worker threads (default: the scene's `threads`, else one for a computed
/// grid below 2^17 points and every core above, as on the command line).
///
/// Step it with run() (until a stop rule fires) or step(n). The engine runs with the GIL
/// released; Ctrl-C raises KeyboardInterrupt within about 0.05 s plus one step, and leaves
/// the simulation at its last good state (usable, resumable). A step that fails raises
/// BlowUp and leaves the last good state too.
///
/// Its state: t, step_count, dt, energy, area, volume, reduced_volume, reduced_energy,
/// sigma, residual, record (all as the columns of timeseries.csv), phi (the full box as a
/// read-only NumPy array) and history (the time series, a dict of NumPy arrays, one row every
/// `output.record_every` steps plus the first and last states of every run).
#[pyclass(frozen, module = "vesicle")]
pub struct Simulation {
    state: Mutex<State>,
}

/// What a simulation holds besides the step loop's parts.
struct State {
    stepper: Stepper,
    /// The resolved scene (A0, symmetry, threads and defaults explicit).
    scene: config::Scene,
    /// The computed grid (to unfold a reduced box).
    grid: Grid,
    /// Snapshots kept by runs without a folder, until take_snapshots().
    snapshots: Vec<Snapshot>,
}

impl Simulation {
    /// The state, or RuntimeError while another call (a run) holds it.
    fn state(&self) -> PyResult<MutexGuard<'_, State>> {
        self.state.try_lock().map_err(|_| {
            PyRuntimeError::new_err(
                "the simulation is running (a callback cannot read it: use the StepView it is \
                 given, with the step's record and phi)",
            )
        })
    }

    fn drive(
        &self,
        py: Python<'_>,
        rules: StopRules,
        callback: Option<Bound<'_, PyAny>>,
        every: usize,
        out: Option<PathBuf>,
    ) -> PyResult<&'static str> {
        if every == 0 {
            return Err(PyValueError::new_err("every must be at least 1"));
        }
        let callback = callback.filter(|c| !c.is_none()).map(|c| Callback {
            function: c.unbind(),
            every,
        });
        let callback = callback.as_ref();
        let mut guard = self.state()?;
        let State {
            stepper,
            scene,
            grid,
            snapshots,
        } = &mut *guard;
        let ended = match out {
            None => {
                let mut kept = Kept::new(scene, grid, snapshots);
                let mut checkpoints = Unwritten(scene.checkpoints());
                let outputs: &mut [&mut (dyn vesicle::driver::simulation::Observer + Send)] =
                    &mut [&mut kept, &mut checkpoints];
                drive::run(py, stepper, grid, &rules, callback, outputs)
            }
            Some(dir) => {
                let folder = check(py, Folder::open(&dir))?;
                let recorder = check(
                    py,
                    folder.recorder(scene.records(), &mut stepper.recorder.history),
                )?;
                let in_memory = std::mem::replace(&mut stepper.recorder, recorder);
                let mut snapshots = folder.snapshots(grid, scene);
                let mut checkpoints = folder.checkpoints(scene);
                let outputs: &mut [&mut (dyn vesicle::driver::simulation::Observer + Send)] =
                    &mut [&mut snapshots, &mut checkpoints];
                let ended = drive::run(py, stepper, grid, &rules, callback, outputs);
                let written = std::mem::replace(&mut stepper.recorder, in_memory);
                stepper.recorder.history = written.history;
                ended
            }
        };
        match ended {
            Ended::Stopped(why) => Ok(why),
            Ended::Raised(e) => Err(e),
            Ended::Failed(e, t) => Err(to_py(py, e, Some(t))),
        }
    }

    /// φ given from Python as the engine's field: an array of the scene's shape n (the full
    /// box), finite, within the engines' blow-up limit, and even about every mirror plane of
    /// the computed box; restricted to the computed box.
    fn phi_argument(
        py: Python<'_>,
        value: &Bound<'_, PyAny>,
        scene: &config::Scene,
        grid: &Grid,
    ) -> PyResult<Array3<f64>> {
        let bad = |reason: String| to_py(py, Error::config("phi", reason), None);
        let kwargs = PyDict::new(py);
        kwargs.set_item("dtype", "float64")?;
        let array = py
            .import("numpy")?
            .call_method("asarray", (value,), Some(&kwargs))
            .map_err(|e| bad(format!("is not an array of numbers ({e})")))?;
        let array: PyReadonlyArrayDyn<'_, f64> = array.extract()?;
        if array.shape() != scene.n.as_slice() {
            return Err(bad(format!(
                "has shape {:?}, the scene's box is n = {:?} (the full box, as Simulation.phi \
                 gives it)",
                array.shape(),
                scene.n
            )));
        }
        let values: Vec<f64> = array.as_array().iter().copied().collect();
        let at = |i: usize| {
            let mut index = Vec::new();
            let mut rest = i;
            for &len in scene.n.iter().rev() {
                index.push(rest % len);
                rest /= len;
            }
            index.reverse();
            index
        };
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!(
                "holds a non-finite value ({}) at index {:?}",
                values[i],
                at(i)
            )));
        }
        if let Some(i) = values.iter().position(|v| v.abs() > PHI_BLOWUP) {
            return Err(bad(format!(
                "holds {} at index {:?}: |φ| may not exceed {PHI_BLOWUP}, the engines' blow-up \
                 limit (φ is about ±1 in the bulk)",
                values[i],
                at(i)
            )));
        }
        let full = Array3::from_shape_vec(grid.full_shape(), values).expect("the scene's n");
        for a in (0..3).filter(|&a| grid.kinds[a] == AxisKind::Mirror) {
            let mut flipped = full.view();
            flipped.invert_axis(Axis(a));
            let d = max_abs_diff(&full, flipped);
            if d > SYMMETRY_TOL {
                let name = ["x", "y", "z"][a + scene.dim - 3];
                return Err(bad(format!(
                    "is not even about the plane {name} = 0 through the box centre (max |φ − \
                     mirror φ| = {d:.2e}), a mirror plane of this simulation's reduced box; make \
                     it even (e.g. (phi + numpy.flip(phi, {})) / 2) or run a scene without that \
                     plane in symmetry",
                    a + scene.dim - 3
                )));
            }
        }
        Ok(grid.restrict(&full))
    }
}

/// A scene argument as a Scene: a Scene itself, or what Scene() accepts.
fn scene_of(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<config::Scene> {
    if let Ok(s) = scene.cast::<Scene>() {
        return Ok(s.get().scene.clone());
    }
    let s = Bound::new(py, Scene::parse(py, scene, &[])?)?;
    Ok(s.get().scene.clone())
}

fn pool(threads: usize) -> PyResult<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {threads} threads: {e}")))
}

/// `threads` from Python (None: the command line's choice for `scene`).
fn threads_for(scene: &config::Scene, threads: Option<usize>) -> PyResult<usize> {
    match threads {
        Some(0) => Err(PyValueError::new_err("threads must be at least 1")),
        Some(n) => Ok(n),
        None => Ok(scene.threads()),
    }
}

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

#[pymethods]
impl Simulation {
    #[new]
    #[pyo3(signature = (scene, threads=None))]
    fn new(py: Python<'_>, scene: &Bound<'_, PyAny>, threads: Option<usize>) -> PyResult<Self> {
        let scene = scene_of(py, scene)?;
        let pool = pool(threads_for(&scene, threads)?)?;
        let built = py.detach(|| {
            pool.install(|| -> vesicle::error::Result<_> {
                let mut problem = setup::build(&scene)?;
                check_stability(&scene, &problem.grid)?;
                let prepared = Prepared::new(&scene, &problem)?;
                problem.phi = ndarray::Array3::zeros((0, 0, 0));
                let a0 = prepared.area_target?;
                Ok((prepared.simulation, problem, a0))
            })
        });
        let (simulation, problem, a0) = check(py, built)?;
        let mut resolved = run::resolved_scene(&scene, a0, &problem.mirror);
        resolved.threads = Some(pool.current_num_threads());
        Ok(Simulation {
            state: Mutex::new(State {
                stepper: Stepper {
                    simulation,
                    recorder: Recorder::in_memory(resolved.records()),
                    pool,
                },
                scene: resolved,
                grid: problem.grid,
                snapshots: Vec::new(),
            }),
        })
    }

    /// Continue the run whose checkpoint is in `folder` (a folder written by checkpoint(), or
    /// a `vesicle run` output folder), exactly: stepping it gives the same fields, bit for bit,
    /// as the run that wrote it would have. The time series is read back from
    /// folder/timeseries.csv (rows after the checkpoint's step dropped) when it is there.
    ///
    /// `overrides` (a dict or "key=value" strings) may change only max_steps, t_end,
    /// stop_residual, threads and output, as `vesicle resume --set`. Raises InvalidInput
    /// (field "checkpoint") for a missing, truncated, corrupted or foreign checkpoint.
    #[staticmethod]
    #[pyo3(signature = (folder, overrides=None, threads=None))]
    fn resume(
        py: Python<'_>,
        folder: PathBuf,
        overrides: Option<&Bound<'_, PyAny>>,
        threads: Option<usize>,
    ) -> PyResult<Self> {
        let overrides = crate::scene::assignments(py, overrides)?;
        check(py, output::lock::refuse_if_held(&folder))?;
        let cp = check(py, Checkpoint::read(&folder))?;
        let scene = check(py, run::resumed_scene(cp.scene.clone(), &overrides))?;
        let pool = pool(threads_for(&scene, threads)?)?;
        let (simulation, problem) =
            check(py, py.detach(|| pool.install(|| run::restore(cp, &scene))))?;
        let mut recorder = Recorder::in_memory(scene.records());
        let csv = folder.join("timeseries.csv");
        if csv.exists() {
            let (_, kept) = check(py, TimeSeries::resume(&csv, simulation.clock.step))?;
            recorder.history = kept;
        }
        Ok(Simulation {
            state: Mutex::new(State {
                stepper: Stepper {
                    simulation,
                    recorder,
                    pool,
                },
                scene,
                grid: problem.grid,
                snapshots: Vec::new(),
            }),
        })
    }

    /// Step until a stop rule fires; return why it stopped: "stationary" (residual below
    /// stop_residual), "t_end", "max_steps", "wall_time", "stalled" (no further progress
    /// possible) or "callback" (the callback returned False).
    ///
    /// With none of until, max_steps, stop_residual given, the scene's t_end, max_steps,
    /// stop_residual and max_wall_minutes apply (a run from t = 0 then matches `vesicle run`
    /// bit for bit); with any given, only those. `until` is a time (the last step is shortened
    /// to land on it); `max_steps` counts every step since t = 0, not this call's;
    /// `stop_residual` bounds the stationarity residual RMS(μ − mean μ).
    ///
    /// The scene's output schedules apply as in `vesicle run`: a row of the history on
    /// `output.records`, a snapshot on `output.snapshots`, a checkpoint on `output.checkpoints`
    /// (and at the end), steps landing on their simulated times. With `out` (a folder, created
    /// if missing, continued if it exists) they are written there as `vesicle run --out`
    /// writes them: timeseries.csv (the history so far, then row by row),
    /// snapshots/phi_<step>.npy (.vti, .png as the scene asks) and checkpoint.bin, the folder
    /// locked meanwhile. Without `out` the snapshots are kept in memory (take_snapshots())
    /// and no checkpoint is written.
    ///
    /// `callback(view)` is called every `every` steps with a StepView of the step: its record
    /// (the timeseries.csv columns: view["t"], view.t, dict(view)) and view.phi (the full box,
    /// readable while the callback runs). Returning False (not None) stops the run; an
    /// exception stops it and propagates. The callback runs while the simulation is busy: it
    /// must not read the simulation itself, only its view.
    ///
    /// Raises BlowUp if a step fails, KeyboardInterrupt on Ctrl-C; either way the simulation
    /// keeps its last good state.
    #[pyo3(signature = (until=None, max_steps=None, stop_residual=None, callback=None, every=1, out=None))]
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        py: Python<'_>,
        until: Option<f64>,
        max_steps: Option<usize>,
        stop_residual: Option<f64>,
        callback: Option<Bound<'_, PyAny>>,
        every: usize,
        out: Option<PathBuf>,
    ) -> PyResult<&'static str> {
        let rules = if until.is_none() && max_steps.is_none() && stop_residual.is_none() {
            StopRules::of(&self.state()?.scene)
        } else {
            StopRules {
                t_end: until,
                max_steps,
                stop_residual,
                ..StopRules::default()
            }
        };
        self.drive(py, rules, callback, every, out)
    }

    /// Take `n` steps (fewer if the engine stalls, the callback returns False, or a step
    /// fails); return why it stopped, as run() does ("max_steps" when all n were taken). The
    /// output schedules and `out` as in run().
    #[pyo3(signature = (n=1, callback=None, every=1, out=None))]
    fn step(
        &self,
        py: Python<'_>,
        n: usize,
        callback: Option<Bound<'_, PyAny>>,
        every: usize,
        out: Option<PathBuf>,
    ) -> PyResult<&'static str> {
        let target = self.state()?.stepper.simulation.clock.step + n;
        self.drive(py, StopRules::steps(target), callback, every, out)
    }

    /// The snapshots kept by runs without `out` (on the scene's `output.snapshots` schedule),
    /// oldest first, as a list of (step, t, phi) with phi the full box (a read-only float64
    /// array); they are handed over, not copied, and no longer kept.
    fn take_snapshots<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let (taken, dim) = {
            let mut state = self.state()?;
            (std::mem::take(&mut state.snapshots), state.scene.dim)
        };
        let items = taken
            .into_iter()
            .map(|s| {
                let phi = field_array(py, s.phi, dim)?;
                PyTuple::new(
                    py,
                    [
                        s.step.into_pyobject(py)?.into_any(),
                        s.t.into_pyobject(py)?.into_any(),
                        phi,
                    ],
                )
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// Write a checkpoint of the current state into `folder` (created if needed):
    /// folder/checkpoint.bin, written atomically (a temporary file, flushed, renamed) as
    /// `vesicle run` writes it, and folder/timeseries.csv with the history so far.
    /// Simulation.resume(folder) or `vesicle resume folder` continues it exactly.
    fn checkpoint(&self, py: Python<'_>, folder: PathBuf) -> PyResult<()> {
        let state = self.state()?;
        check(py, output::lock::refuse_if_held(&folder))?;
        check(
            py,
            std::fs::create_dir_all(&folder).map_err(|e| io_error(&folder, e)),
        )?;
        let sim = &state.stepper.simulation;
        check(
            py,
            Checkpoint::of(sim, state.scene.resolved_value()).write(&folder),
        )?;
        // The time series beside it, replaced whole (a temporary file renamed over it).
        let csv = folder.join("timeseries.csv");
        let tmp = folder.join("timeseries.csv.tmp");
        let written = (|| {
            let mut ts = TimeSeries::create(&tmp)?;
            for r in &state.stepper.recorder.history {
                ts.push(r)?;
            }
            ts.flush()?;
            std::fs::rename(&tmp, &csv).map_err(|e| io_error(&csv, e))
        })();
        check(py, written)
    }

    /// The scene being run, resolved: every default explicit, the area target A0, the mirror
    /// planes and the thread count as summary.json's "spec" records them.
    #[getter]
    fn scene(&self) -> PyResult<Scene> {
        Ok(Scene::of(self.state()?.scene.clone()))
    }

    /// Simulated time t.
    #[getter]
    fn t(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.clock.t)
    }

    /// Accepted steps since t = 0.
    #[getter]
    fn step_count(&self) -> PyResult<usize> {
        Ok(self.state()?.stepper.simulation.clock.step)
    }

    /// The step Δt the engine will be offered next.
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.clock.dt)
    }

    /// The current state's record: a dict of the timeseries.csv columns (step, t, dt, energy,
    /// area, volume, reduced_volume, reduced_energy, sigma, residual, rate, rejected,
    /// wall_seconds).
    #[getter]
    fn record<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        record_dict(py, &self.state()?.stepper.simulation.record())
    }

    /// Bending energy F_sc = ∫Φ² (diffuse).
    #[getter]
    fn energy(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.record().energy)
    }

    /// Diffuse area A = (3/(2√2)) ε ∫|∇φ|² (the perimeter in 2D).
    #[getter]
    fn area(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.record().area)
    }

    /// Diffuse volume V = ∫(1 + φ)/2 (the enclosed area in 2D).
    #[getter]
    fn volume(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.record().volume)
    }

    /// Reduced volume v of the diffuse measures (1 for a sphere or circle).
    #[getter]
    fn reduced_volume(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.record().reduced_volume)
    }

    /// Reduced bending energy e (1 for a sphere).
    #[getter]
    fn reduced_energy(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.record().reduced_energy)
    }

    /// The area multiplier σ.
    #[getter]
    fn sigma(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.engine().sigma())
    }

    /// The stationarity residual RMS(μ − mean μ) over the full box.
    #[getter]
    fn residual(&self) -> PyResult<f64> {
        Ok(self.state()?.stepper.simulation.engine().residual())
    }

    /// φ on the full box as a read-only float64 NumPy array of shape n ((nx, ny) in 2D,
    /// (nx, ny, nz) in 3D; a mirrored reduced box unfolded), the same values as the
    /// phi_final.npy `vesicle run` writes. Each read is one new copy.
    ///
    /// Settable (`sim.phi = array`): an array of shape n, finite, with |φ| ≤ 5 and even about
    /// every mirror plane of a reduced box (else InvalidInput, field "phi"); the engine is built
    /// again on it, the state evaluated anew, t, the step count and A0 kept, the scheme started
    /// afresh. A spectral engine holds its spectrum: phi reads back within round-off.
    #[getter]
    fn phi<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let state = self.state()?;
        let full = state
            .grid
            .unfold(state.stepper.simulation.engine().phi())
            .into_owned();
        field_array(py, full, state.scene.dim)
    }

    /// Set φ: `sim.phi = array`, an array of the scene's shape n (the full box, as phi
    /// gives it), finite, with |φ| ≤ 5 (the engines' blow-up limit) and even about every
    /// mirror plane of a reduced box. The engine is built again on it, as a run starts: the
    /// state (energy, area, volume, σ, residual) is evaluated anew, t, the step count and the
    /// area target A0 are kept, and the next step starts the scheme afresh (SBDF2 and L-BFGS
    /// without their history). The history's row of the current step, if any, is replaced.
    /// Raises InvalidInput (field "phi") for a wrong shape, a non-finite value or one beyond
    /// the limit, a field that is not even about a mirror plane, or one whose state diverges
    /// (its energy not finite). A spectral engine holds φ as its spectrum: phi then reads back
    /// within round-off (about 1e-15) of the array set.
    #[setter(phi)]
    fn set_phi(&self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut guard = self.state()?;
        let state = &mut *guard;
        let computed = Self::phi_argument(py, value, &state.scene, &state.grid)?;
        let (scene, stepper) = (&state.scene, &mut state.stepper);
        let old = &stepper.simulation;
        let (clock, timers) = (old.clock, old.timers.clone());
        let pool = &stepper.pool;
        let built = py.detach(|| {
            pool.install(|| -> vesicle::error::Result<_> {
                let mut problem = setup::frame(scene)?;
                problem.phi = computed;
                let mut engine = build_engine(scene, &problem)?;
                let target = scene.area.target.unwrap_or_else(|| engine.measures().area);
                engine.set_area(AreaConstraint {
                    method: scene.area_method(),
                    alpha: scene.alpha(),
                    target,
                    sigma: scene.area.sigma.unwrap_or(0.0),
                });
                let mut simulation = vesicle::driver::simulation::Simulation::new(
                    engine, scene.dt, scene.dim, scene.eps,
                );
                simulation.clock = clock;
                simulation.clock.last_rate = f64::NAN;
                simulation.timers = timers;
                Ok(simulation)
            })
        });
        // The engine's own refusal of a field (a state that diverged) names its argument.
        let built = built.map_err(|e| match e {
            Error::Config { field, reason } if field == "initial" => Error::config("phi", reason),
            other => other,
        });
        stepper.simulation = check(py, built)?;
        let now = stepper.simulation.record();
        if let Some(last) = stepper.recorder.history.last_mut() {
            if last.step == now.step {
                *last = now;
            }
        }
        Ok(())
    }

    /// The time series: a dict of 1-D NumPy arrays keyed by the timeseries.csv columns.
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        history_dict(py, &self.state()?.stepper.recorder.history)
    }

    /// The worker threads this simulation runs on.
    #[getter]
    fn threads(&self) -> PyResult<usize> {
        Ok(self.state()?.stepper.pool.current_num_threads())
    }

    /// The φ = 0 surface of a 3D field: (vertices, faces, area, volume, v) with vertices an
    /// (n, 3) float64 array of physical coordinates (grid point [i, j, k] at (ih, jh, kh)),
    /// faces an (m, 3) int64 array of vertex indices wound outward (marching tetrahedra), and
    /// area, volume and the reduced volume v of the sharp surface (as summary.json's
    /// "levelset"). Raises InvalidInput for a 2D scene (see levelset()).
    fn surface<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let state = self.state()?;
        let dim = state.scene.dim;
        if dim != 3 {
            return Err(to_py(
                py,
                Error::config(
                    "dim",
                    "surface() needs a 3D scene; levelset() measures a 2D curve",
                ),
                None,
            ));
        }
        let h = state.scene.h;
        let full = state.grid.unfold(state.stepper.simulation.engine().phi());
        let (mesh, ls) =
            py.detach(|| (surface::extract(&full, h), levelset::measure(&full, dim, h)));
        PyTuple::new(
            py,
            [
                points(py, &mesh.vertices),
                triangles(py, &mesh.triangles),
                ls.area.into_pyobject(py)?.into_any(),
                ls.volume.into_pyobject(py)?.into_any(),
                ls.reduced_volume.into_pyobject(py)?.into_any(),
            ],
        )
    }

    /// The φ = 0 level set's measures on the full box as a dict {"area", "volume",
    /// "reduced_volume"}: area and enclosed volume in 3D, perimeter and enclosed area in 2D.
    /// `refined=True` measures again on the band-limited interpolant at h/2 and extrapolates
    /// the volume (accurate enough for shape diagrams).
    #[pyo3(signature = (refined=false))]
    fn levelset<'py>(&self, py: Python<'py>, refined: bool) -> PyResult<Bound<'py, PyAny>> {
        let state = self.state()?;
        let (dim, h) = (state.scene.dim, state.scene.h);
        let full = state.grid.unfold(state.stepper.simulation.engine().phi());
        let ls = py.detach(|| {
            if refined {
                levelset::measure_refined(&full, dim, h)
            } else {
                levelset::measure(&full, dim, h)
            }
        });
        from_json(py, &serde_json::to_value(ls).expect("serialisable"))
    }

    /// Write φ (full box) to a .npy file, as phi_final.npy: float64, C order, shape n.
    fn write_npy(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let state = self.state()?;
        let full = state.grid.unfold(state.stepper.simulation.engine().phi());
        check(
            py,
            output::npy::write_npy(&path, &full, state.scene.dim).map_err(Error::from),
        )
    }

    /// Write φ (full box) to a VTK ImageData .vti file (point data named `name`, spacing h),
    /// for ParaView.
    #[pyo3(signature = (path, name="phi"))]
    fn write_vti(&self, py: Python<'_>, path: PathBuf, name: &str) -> PyResult<()> {
        let state = self.state()?;
        let full = state.grid.unfold(state.stepper.simulation.engine().phi());
        let (dim, h) = (state.scene.dim, state.scene.h);
        check(
            py,
            output::vti::write_vti(&path, &full, dim, h, name).map_err(Error::from),
        )
    }

    /// Write the φ = 0 surface of a 3D field as binary PLY (the mesh of surface()).
    fn write_ply(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let state = self.state()?;
        if state.scene.dim != 3 {
            return Err(to_py(
                py,
                Error::config("dim", "write_ply() needs a 3D scene"),
                None,
            ));
        }
        let full = state.grid.unfold(state.stepper.simulation.engine().phi());
        let mesh = surface::extract(&full, state.scene.h);
        let c = state.stepper.simulation.clock;
        let comment = format!("vesicle phi = 0 surface, step {} t {:e}", c.step, c.t);
        check(
            py,
            output::ply::write_ply(&path, &mesh, &comment).map_err(Error::from),
        )
    }

    /// Write a PNG of φ: the field in 2D, the three mid-plane slices in 3D (as
    /// shape_final.png), under `title` (default: step and t).
    #[pyo3(signature = (path, title=None))]
    fn write_png(&self, py: Python<'_>, path: PathBuf, title: Option<String>) -> PyResult<()> {
        let state = self.state()?;
        let full = state.grid.unfold(state.stepper.simulation.engine().phi());
        let c = state.stepper.simulation.clock;
        let title = title.unwrap_or_else(|| format!("step {} t = {:.4e}", c.step, c.t));
        check(
            py,
            output::image::write_slices_png(&path, &full, state.scene.dim, &title)
                .map_err(Error::from),
        )
    }

    /// Write the charts of the time series into `folder` (which must exist): energy.png (e
    /// against t) and residual.png (the residual against t, log scale), as `vesicle run` does.
    fn write_charts(&self, py: Python<'_>, folder: PathBuf) -> PyResult<()> {
        let state = self.state()?;
        check(
            py,
            run::write_charts(&folder, &state.stepper.recorder.history),
        )
    }

    fn __repr__(&self) -> String {
        match self.state() {
            Ok(s) => {
                let c = s.stepper.simulation.clock;
                format!(
                    "Simulation({} engine, dim={}, n={:?}, step={}, t={:e})",
                    s.stepper.simulation.engine().name(),
                    s.scene.dim,
                    s.scene.n,
                    c.step,
                    c.t
                )
            }
            Err(_) => "Simulation(running)".to_string(),
        }
    }
}
