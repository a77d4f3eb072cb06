//! `Scene`: a scene from a dict or a JSON file, with overrides, validated by the library
//! exactly as `vesicle run` validates a scene file (same messages, same fields).

use crate::errors::check;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use serde_json::Value;
use std::path::PathBuf;
use vesicle::problem::config;

/// A validated scene: what `vesicle run` reads from a scene file.
///
/// `spec` is a dict (the JSON object of a scene file) or the path of a scene file (str or
/// os.PathLike; relative file names inside it are taken beside it, as the command line does).
/// `overrides` are applied before validation, like `--set`: a dict `{"dt": 0.05,
/// "initial.r0": 10}` (dotted keys into nested objects; a value of None removes the key) or a
/// list of "key=value" strings (the value read as JSON, else as a string).
///
/// Raises InvalidInput (a ValueError) naming the field, with the command line's message, and
/// refuses a grid whose estimated memory exceeds what the machine has.
///
/// The keys are those of the scene-file reference: dim, n, h, eps, method ("spectral" | "fd"),
/// dynamics ("conserved" | "relaxational" | "stokes", with flow), scheme, dt, adaptive, t_end, max_steps,
/// stop_residual, initial, c0, area, symmetry, prepare_steps, threads, output, ...
#[pyclass(frozen, module = "vesicle")]
pub struct Scene {
    /// The validated scene.
    pub scene: config::Scene,
    /// Its JSON value after the overrides (before defaults), to apply further overrides to.
    value: Value,
    /// The scene file it was read from, if any (for relative file names).
    file: Option<PathBuf>,
}

impl Scene {
    fn build(
        py: Python<'_>,
        value: Value,
        overrides: &[String],
        file: Option<PathBuf>,
    ) -> PyResult<Self> {
        let mut with = value.clone();
        for o in overrides {
            check(py, config::apply_override(&mut with, o))?;
        }
        let scene = check(
            py,
            supported(config::load_value(value, overrides, file.as_deref())),
        )?;
        Ok(Scene {
            scene,
            value: with,
            file,
        })
    }

    /// A scene wrapping an already validated library scene (a resumed run's).
    pub fn of(scene: config::Scene) -> Self {
        Scene {
            value: scene.resolved_value(),
            scene,
            file: None,
        }
    }
}

/// `overrides` (None, a dict or a list of "key=value" strings) as `--set` assignments.
pub fn assignments(py: Python<'_>, overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(o) = overrides else {
        return Ok(Vec::new());
    };
    if o.is_none() {
        return Ok(Vec::new());
    }
    if let Ok(d) = o.cast::<PyDict>() {
        let mut out = Vec::new();
        for (k, v) in d.iter() {
            let key: String = k.extract()?;
            out.push(format!("{key}={}", to_json(py, &v)?));
        }
        return Ok(out);
    }
    if o.is_instance_of::<PyList>() || o.is_instance_of::<pyo3::types::PyTuple>() {
        return o.extract();
    }
    Err(PyTypeError::new_err(
        "overrides must be a dict {key: value} or a list of \"key=value\" strings",
    ))
}

/// The JSON text of a Python value (json.dumps, NaN and infinities refused).
fn to_json(py: Python<'_>, v: &Bound<'_, PyAny>) -> PyResult<String> {
    let json = py.import("json")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("allow_nan", false)?;
    json.call_method("dumps", (v,), Some(&kwargs))?.extract()
}

/// A JSON value as a Python object (json.loads).
pub fn from_json<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).expect("a JSON value serialises");
    py.import("json")?.call_method1("loads", (text,))
}

impl Scene {
    /// A scene from `spec` (a dict or a scene-file path) with `overrides` (`--set` assignments).
    pub fn parse(py: Python<'_>, spec: &Bound<'_, PyAny>, overrides: &[String]) -> PyResult<Self> {
        if spec.is_instance_of::<PyDict>() {
            let text = to_json(py, spec).map_err(|e| {
                let reason =
                    format!("not a JSON object of finite numbers, strings, lists and dicts: {e}");
                crate::errors::to_py(py, vesicle::error::Error::config("(dict)", reason), None)
            })?;
            let value: Value = serde_json::from_str(&text).expect("json.dumps writes JSON");
            return Self::build(py, value, overrides, None);
        }
        if spec.is_instance_of::<PyString>() || spec.hasattr("__fspath__")? {
            let path: PathBuf = spec.extract()?;
            // The library's own reading: the same messages for a missing file or bad JSON.
            let scene = check(py, supported(config::load(&path, overrides)))?;
            let bytes = std::fs::read(&path).map_err(|e| {
                pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", path.display()))
            })?;
            let mut value: Value = serde_json::from_slice(&bytes).expect("load parsed it");
            for o in overrides {
                check(py, config::apply_override(&mut value, o))?;
            }
            return Ok(Scene {
                scene,
                value,
                file: Some(path),
            });
        }
        Err(PyTypeError::new_err(
            "Scene(spec): spec must be a dict or the path of a scene file",
        ))
    }
}

#[pymethods]
impl Scene {
    #[new]
    #[pyo3(signature = (spec, overrides=None))]
    fn new(
        py: Python<'_>,
        spec: &Bound<'_, PyAny>,
        overrides: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        Self::parse(py, spec, &assignments(py, overrides)?)
    }

    /// A new scene: this one with `overrides` (a dict or "key=value" strings) applied and
    /// validated again.
    fn with_overrides(&self, py: Python<'_>, overrides: &Bound<'_, PyAny>) -> PyResult<Self> {
        let overrides = assignments(py, Some(overrides))?;
        Self::build(py, self.value.clone(), &overrides, self.file.clone())
    }

    /// The scene as a dict with every default made explicit (what summary.json stores under
    /// "spec" before the run resolves the area target and symmetry).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        from_json(py, &self.scene.resolved_value())
    }

    /// The scene as JSON text (a scene file `vesicle run` reads).
    fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.scene.resolved_value()).expect("a scene serialises")
    }

    /// Dimension: 2 or 3.
    #[getter]
    fn dim(&self) -> usize {
        self.scene.dim
    }

    /// Grid points along each axis of the full box.
    #[getter]
    fn n(&self) -> Vec<usize> {
        self.scene.n.clone()
    }

    /// Grid spacing h.
    #[getter]
    fn h(&self) -> f64 {
        self.scene.h
    }

    /// Interface width ε.
    #[getter]
    fn eps(&self) -> f64 {
        self.scene.eps
    }

    /// The (first) time step Δt.
    #[getter]
    fn dt(&self) -> f64 {
        self.scene.dt
    }

    fn __repr__(&self) -> String {
        let method = serde_json::to_value(self.scene.method).expect("a method serialises");
        format!(
            "Scene(dim={}, n={:?}, h={}, eps={}, method={method}, dt={})",
            self.scene.dim, self.scene.n, self.scene.h, self.scene.eps, self.scene.dt
        )
    }
}

/// A loaded scene refused, as the command line refuses it, when the engine it asks for cannot
/// run it (no hardware is touched).
fn supported(
    scene: vesicle::error::Result<config::Scene>,
) -> vesicle::error::Result<config::Scene> {
    let scene = scene?;
    vesicle::driver::simulation::check_engine(&scene)?;
    Ok(scene)
}
