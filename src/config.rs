//! The scene (run) file: a strict JSON description of one run, its defaults and its validation.
//!
//! Unknown keys are rejected, every field is checked by [`Scene::validate`], and every error
//! names the dotted key of the field and the reason. `--set key=value` overrides are applied to
//! the JSON before it is read ([`apply_override`]), so they are validated like the file itself.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One run, as read from a scene file (see README's scene-file reference).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free text: what the scene shows.
    #[serde(default)]
    pub description: String,
    /// Spatial dimension, 2 or 3.
    pub dim: usize,
    /// Grid points of the full box along each axis (`dim` entries).
    pub n: Vec<usize>,
    /// Grid spacing h.
    #[serde(default = "one")]
    pub h: f64,
    /// Interface width parameter ε.
    #[serde(default = "one")]
    pub eps: f64,
    /// Engine: Fourier semi-implicit (`spectral`) or the paper's finite differences (`fd`).
    #[serde(default)]
    pub method: Method,
    /// Time scheme of the spectral engine.
    #[serde(default)]
    pub scheme: Scheme,
    /// Time step (the first one when adaptive).
    pub dt: f64,
    /// Adaptive time stepping: `false`, `true` (default controller) or controller settings.
    #[serde(default)]
    pub adaptive: AdaptiveSpec,
    /// Stop at this simulated time.
    #[serde(default)]
    pub t_end: Option<f64>,
    /// Stop after this many steps.
    #[serde(default)]
    pub max_steps: Option<usize>,
    /// Stop when the stationarity residual max|φ^{n+1} − φ^n|/Δt falls below this.
    #[serde(default)]
    pub stop_residual: Option<f64>,
    /// Initial shape, or `{"file": "phi.npy"}`.
    pub initial: Initial,
    /// Unconstrained steps (σ = 0) that build the tanh profile before A0 is taken.
    #[serde(default)]
    pub prepare_steps: usize,
    /// Spontaneous curvature c0: a number (uniform) or a field object.
    #[serde(default)]
    pub c0: C0Spec,
    /// Area constraint.
    #[serde(default)]
    pub area: AreaSpec,
    /// Mirror planes through the box centre: e.g. `["x","y","z"]`, `[]`, or `"auto"`.
    #[serde(default)]
    pub symmetry: Symmetry,
    /// Allow a Δt beyond the method's stability bound (stability studies).
    #[serde(default)]
    pub allow_unstable: bool,
    /// Worker threads (default: all cores).
    #[serde(default)]
    pub threads: Option<usize>,
    /// `conserved` (∂φ/∂t = ∇²μ, the paper's dynamics) or `relaxational` (fastest route to the
    /// same stationary states).
    #[serde(default)]
    pub dynamics: Dynamics,
    /// Discrete Laplacian of the spectral engine: `spectral` (−|k|², the default) or `fd` (the
    /// symbol −Σ (4/h²) sin²(k_a h/2) of the FD reference's (2d+1)-point stencil: the engine
    /// then integrates exactly the FD reference's semi-discrete equations, semi-implicitly).
    #[serde(default)]
    pub laplacian: Laplacian,
    /// L-BFGS memory (pairs kept) of the relaxational dynamics.
    #[serde(default = "default_memory")]
    pub lbfgs_memory: usize,
    /// Linear stabiliser of the spectral engine, S(k) = s2 |k|² + s4 ε² |k|⁴ (default: see
    /// [`Stabilizer::default_for`]).
    #[serde(default)]
    pub stabilizer: StabilizerSpec,
    /// Output schedule.
    #[serde(default)]
    pub output: OutputSpec,
}

fn one() -> f64 {
    1.0
}

/// L-BFGS memory: 5 pairs gave the least wall time on the 48³ prolate (20 pairs take fewer
/// evaluations, 116 against 144, but more vector work per iteration).
fn default_memory() -> usize {
    5
}

/// Engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Fourier pseudo-spectral, semi-implicit.
    #[default]
    Spectral,
    /// Second-order finite differences, explicit Euler (the paper's method).
    Fd,
}

/// Time scheme of the spectral engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// First-order semi-implicit backward differentiation.
    #[default]
    Sbdf1,
    /// Second-order semi-implicit backward differentiation (variable step).
    Sbdf2,
}

/// Discrete Laplacian used by the spectral engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Laplacian {
    /// Exact Fourier symbol −|k|².
    #[default]
    Spectral,
    /// Symbol of the second-order stencil, −Σ_a (4/h²) sin²(k_a h/2).
    Fd,
}

/// Dynamics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dynamics {
    /// ∂φ/∂t = ∇²μ.
    #[default]
    Conserved,
    /// Preconditioned L-BFGS on the constrained energy (same stationary states; `t` counts
    /// iterations × dt, not physical time).
    Relaxational,
}

/// `adaptive`: a flag or the controller's settings.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub enum AdaptiveSpec {
    /// `false` or `true` (the default controller).
    Flag(bool),
    /// Explicit settings.
    Settings(AdaptiveSettings),
}

impl Default for AdaptiveSpec {
    fn default() -> Self {
        AdaptiveSpec::Flag(false)
    }
}

impl AdaptiveSpec {
    /// The controller settings, or `None` for fixed steps.
    pub fn settings(&self) -> Option<AdaptiveSettings> {
        match self {
            AdaptiveSpec::Flag(false) => None,
            AdaptiveSpec::Flag(true) => Some(AdaptiveSettings::default()),
            AdaptiveSpec::Settings(s) => Some(s.clone()),
        }
    }
}

/// Energy-based step controller (Qiao, Zhang & Tang 2011):
/// `Δt = clamp(dt_max / √(1 + energy_alpha · (Ḟ/F)²), dt_min, growth · Δt_prev)`;
/// a step that raises F_eff beyond round-off or breaks a constraint is retried with
/// `shrink · Δt`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdaptiveSettings {
    /// Smallest step; a rejection below it stops the run (exit 3).
    pub dt_min: Option<f64>,
    /// Largest step.
    pub dt_max: Option<f64>,
    /// Largest ratio of consecutive steps (SBDF2 needs < 1 + √2).
    pub growth: f64,
    /// Factor applied to Δt after a rejected step.
    pub shrink: f64,
    /// Sensitivity α of the energy-based rule to the relative energy rate.
    pub energy_alpha: f64,
}

impl Default for AdaptiveSettings {
    fn default() -> Self {
        AdaptiveSettings {
            dt_min: None,
            dt_max: None,
            growth: 1.5,
            shrink: 0.5,
            energy_alpha: 1e6,
        }
    }
}

/// `initial`: a shape object or a field file.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum Initial {
    /// φ read from a float64 C-order `.npy` of shape `n`.
    File {
        /// Path, relative to the scene file's folder (or the working directory).
        file: PathBuf,
    },
    /// A geometric shape.
    Shape(Shape),
}

impl<'de> Deserialize<'de> for Initial {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v = Value::deserialize(d)?;
        let is_file = v.as_object().is_some_and(|o| o.contains_key("file"));
        if is_file {
            #[derive(Deserialize)]
            #[serde(deny_unknown_fields)]
            struct FileSpec {
                file: PathBuf,
            }
            let f: FileSpec = serde_json::from_value(v).map_err(D::Error::custom)?;
            Ok(Initial::File { file: f.file })
        } else {
            Shape::deserialize(v)
                .map(Initial::Shape)
                .map_err(D::Error::custom)
        }
    }
}

/// Initial shapes: φ = tanh(d/(√2 ε)) with d the (approximate) signed distance, positive inside.
/// `center` defaults to the box centre; `axis` (symmetry axis) defaults to the last axis.
/// Written `{"shape": "<kind>", ...fields of the kind}`.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "shape", rename_all = "lowercase")]
pub enum Shape {
    /// Sphere (circle in 2D).
    Sphere(Sphere),
    /// Ellipsoid (ellipse in 2D).
    Ellipsoid(Ellipsoid),
    /// Spheroid given by reduced volume and size.
    Spheroid(Spheroid),
    /// Stomatocyte-like cup.
    Cup(Cup),
    /// Tube with round caps.
    Capsule(Capsule),
    /// Union of shapes: d = max d_i.
    Union(Union),
    /// `base` with `minus` removed: d = min(d_base, −d_minus).
    Difference(Difference),
}

/// Sphere (circle in 2D) of radius `radius`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    pub radius: f64,
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Ellipsoid (ellipse in 2D) with semi-axes `axes`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ellipsoid {
    pub axes: Vec<f64>,
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Spheroid (ellipse in 2D) with reduced volume (area) `reduced_volume` and `R0 = √(A/4π)`
/// (2D: perimeter/2π); `kind` prolate (long along `axis`) or oblate.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spheroid {
    pub reduced_volume: f64,
    pub r0: f64,
    #[serde(default)]
    pub kind: SpheroidKind,
    #[serde(default)]
    pub axis: Option<String>,
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Stomatocyte-like cup: a ball of `radius` minus a ball of `inner_radius` whose centre is
/// shifted by `offset` along `axis`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cup {
    pub radius: f64,
    pub inner_radius: f64,
    pub offset: f64,
    #[serde(default)]
    pub axis: Option<String>,
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Capsule (tube with round caps): radius `radius`, straight part `length` along `axis`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Capsule {
    pub radius: f64,
    pub length: f64,
    #[serde(default)]
    pub axis: Option<String>,
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Union of shapes.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Union {
    pub of: Vec<Shape>,
}

/// `base` with `minus` removed.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Difference {
    pub base: Box<Shape>,
    pub minus: Box<Shape>,
}

/// Marks the inner path of a shape's error inside its message (serde keeps no path inside a
/// hand-written deserializer); [`from_value`] turns it back into a dotted field.
const PATH_MARK: char = '\u{1f}';

impl<'de> Deserialize<'de> for Shape {
    /// Reads the `"shape"` tag, then the kind's struct with path tracking, so an error names
    /// the inner key (`initial.radius`, `initial.of[1].axes`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        fn kind<T: serde::de::DeserializeOwned>(v: Value) -> std::result::Result<T, String> {
            serde_path_to_error::deserialize(v).map_err(|e| {
                let path = e.path().to_string();
                let inner = e.into_inner().to_string();
                match (path.as_str(), inner.strip_prefix(PATH_MARK)) {
                    (".", _) => inner,
                    (_, Some(rest)) => format!("{PATH_MARK}{path}.{rest}"),
                    (_, None) => format!("{PATH_MARK}{path}{PATH_MARK}{inner}"),
                }
            })
        }
        let mut v = Value::deserialize(d)?;
        let tag = v
            .as_object_mut()
            .ok_or_else(|| D::Error::custom("expected a shape object"))?
            .remove("shape")
            .ok_or_else(|| D::Error::missing_field("shape"))?;
        let shape = match tag.as_str().unwrap_or_default() {
            "sphere" => kind(v).map(Shape::Sphere),
            "ellipsoid" => kind(v).map(Shape::Ellipsoid),
            "spheroid" => kind(v).map(Shape::Spheroid),
            "cup" => kind(v).map(Shape::Cup),
            "capsule" => kind(v).map(Shape::Capsule),
            "union" => kind(v).map(Shape::Union),
            "difference" => kind(v).map(Shape::Difference),
            _ => Err(format!(
                "{PATH_MARK}shape{PATH_MARK}unknown variant {tag}, expected one of `sphere`, \
                 `ellipsoid`, `spheroid`, `cup`, `capsule`, `union`, `difference`"
            )),
        };
        shape.map_err(D::Error::custom)
    }
}

/// Which way a spheroid is stretched.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpheroidKind {
    /// Long along the axis.
    #[default]
    Prolate,
    /// Short along the axis.
    Oblate,
}

/// `c0`: the membrane's spontaneous curvature (the model uses C0 = c0/√2).
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum C0Spec {
    /// Uniform value.
    Uniform(f64),
    /// A field.
    Field(C0Field),
}

impl Default for C0Spec {
    fn default() -> Self {
        C0Spec::Uniform(0.0)
    }
}

impl<'de> Deserialize<'de> for C0Spec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v = Value::deserialize(d)?;
        match v {
            Value::Number(x) => Ok(C0Spec::Uniform(x.as_f64().unwrap_or(f64::NAN))),
            Value::Object(_) => C0Field::deserialize(v)
                .map(C0Spec::Field)
                .map_err(D::Error::custom),
            _ => Err(D::Error::custom("expected a number or a field object")),
        }
    }
}

/// A c0 field: a ball-shaped patch with a tanh edge, optionally ramped linearly in time:
/// `c0(x, t) = r(t) [outside + (inside − outside)(1 − tanh((|x − center| − radius)/width))/2]`,
/// `r(t) = min(t/ramp_time, 1)` (1 without a ramp). `radius` absent: uniform `inside`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct C0Field {
    /// c0 inside the patch.
    pub inside: f64,
    /// c0 outside the patch.
    #[serde(default)]
    pub outside: f64,
    /// Patch centre (default: box centre).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
    /// Patch radius; absent means the whole box takes `inside`.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Width of the tanh edge.
    #[serde(default = "one")]
    pub width: f64,
    /// Linear ramp from 0 to full strength over this time.
    #[serde(default)]
    pub ramp_time: Option<f64>,
}

/// Area constraint method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AreaMethod {
    /// σ^{n+1} from the quadratic A(φ^{n+1}(σ)) = A0: the area is held to round-off.
    Projection,
    /// The paper's update σ^{n+1} = σ^n + α (A^n − A0).
    Lagrangian,
    /// No area constraint (σ = 0).
    None,
}

/// `area`: `{"method": ..., "alpha": α, "target": A0}`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaSpec {
    /// Default: `projection` for the spectral engine, `lagrangian` for FD.
    #[serde(default)]
    pub method: Option<AreaMethod>,
    /// Step size α of the Lagrangian update (default 1e-3).
    #[serde(default)]
    pub alpha: Option<f64>,
    /// Target area A0 (default: area of the prepared initial field).
    #[serde(default)]
    pub target: Option<f64>,
}

/// `symmetry`: declared mirror axes or automatic detection.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Symmetry {
    /// Mirror axes among "x", "y", "z".
    Axes(Vec<String>),
    /// `"auto"`: every axis about which the initial field and c0 are even.
    Auto(AutoTag),
}

/// The literal `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoTag {
    /// Detect mirror planes.
    Auto,
}

impl Default for Symmetry {
    fn default() -> Self {
        Symmetry::Axes(Vec::new())
    }
}

/// Spectral stabiliser S(k) = s2 |k|² + s4 ε² |k|⁴, treated implicitly and added explicitly.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stabilizer {
    /// Coefficient of |k|².
    pub s2: f64,
    /// Coefficient of ε²|k|⁴.
    pub s4: f64,
}

/// `stabilizer` as written: either coefficient may be left to the scheme's default.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StabilizerSpec {
    /// Coefficient of |k|².
    #[serde(default)]
    pub s2: Option<f64>,
    /// Coefficient of ε²|k|⁴.
    #[serde(default)]
    pub s4: Option<f64>,
}

impl Stabilizer {
    /// The default of each scheme, measured with `vesicle study stability` (runs/stability2d.json,
    /// 200 steps): SBDF1 with S = 4k² + 4ε²k⁴ (half the bulk linearisation's lower-order part,
    /// the least S that makes it unconditionally stable) never raised F up to Δt = 5.6;
    /// SBDF2 with that S raised F from Δt = 0.1 on, with S = 8k² + 8ε²k⁴ not up to Δt = 10.
    pub fn default_for(scheme: Scheme) -> Self {
        match scheme {
            Scheme::Sbdf1 => Stabilizer { s2: 4.0, s4: 4.0 },
            Scheme::Sbdf2 => Stabilizer { s2: 8.0, s4: 8.0 },
        }
    }
}

/// `output`: what is written and how often.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// A `timeseries.csv` row every this many steps (the first and last are always written).
    pub record_every: usize,
    /// Snapshots (`.npy`, `.vti`, `.png`) every this many steps; 0 writes only the final state.
    pub snapshot_every: usize,
    /// Write VTK ImageData `.vti` snapshots.
    pub vti: bool,
    /// Write PNG images of the mid-plane slices and charts of the time series.
    pub png: bool,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            record_every: 1,
            snapshot_every: 0,
            vti: true,
            png: true,
        }
    }
}

/// Read a scene file, apply `--set` overrides and validate it.
///
/// # Errors
/// `Error::Io` if the file cannot be read; `Error::Config` naming the field for malformed JSON,
/// unknown keys, wrong types and invalid values.
pub fn load(path: &Path, overrides: &[String]) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut value: Value = serde_json::from_str(&text).map_err(|e| {
        let reason = format!("{} is not valid JSON: {e}", path.display());
        match nonfinite_field(&text, e.line(), e.column()) {
            Some((field, token)) if e.to_string().contains("number out of range") => {
                Error::config(field, format!("must be a finite number, got {token}"))
            }
            _ => Error::config("(file)", reason),
        }
    })?;
    for o in overrides {
        apply_override(&mut value, o)?;
    }
    let mut scene = from_value(value)?;
    if let Initial::File { file } = &mut scene.initial {
        *file = resolve_relative(path, file);
    }
    scene.validate()?;
    Ok(scene)
}

/// The dotted field holding the out-of-range number that ends near (line, column) of `text`,
/// and the number: the number is quoted and the scene read again, so the type error names it.
fn nonfinite_field(text: &str, line: usize, column: usize) -> Option<(String, String)> {
    let offset: usize = text
        .lines()
        .take(line.saturating_sub(1))
        .map(|l| l.len() + 1)
        .sum();
    let bytes = text.as_bytes();
    let is_num = |b: u8| b.is_ascii_digit() || b"eE+-.".contains(&b);
    let mut end = (offset + column).min(bytes.len());
    while end > 0 && !is_num(bytes[end - 1]) {
        end -= 1;
    }
    let mut start = end;
    while start > 0 && is_num(bytes[start - 1]) {
        start -= 1;
    }
    let token = text.get(start..end)?.to_string();
    let quoted = format!("{}\"{token}\"{}", &text[..start], &text[end..]);
    match from_value(serde_json::from_str(&quoted).ok()?) {
        Err(Error::Config { field, .. }) => Some((field, token)),
        _ => None,
    }
}

/// Deserialize a scene from JSON, reporting the dotted path of a bad field.
///
/// # Errors
/// `Error::Config` with the path of the offending key.
pub fn from_value(value: Value) -> Result<Scene> {
    serde_path_to_error::deserialize::<_, Scene>(value.clone()).map_err(|e| {
        let path = e.path().to_string();
        if let Some(err) = refine(&path, &value) {
            return err;
        }
        let field = if path == "." {
            "(top level)".into()
        } else {
            path
        };
        let reason = e.into_inner().to_string();
        // A shape's error carries its inner path: "\u{1f}radius\u{1f}invalid type ...".
        match reason
            .strip_prefix(PATH_MARK)
            .and_then(|r| r.split_once(PATH_MARK))
        {
            Some((inner, rest)) => Error::config(format!("{field}.{inner}"), rest),
            None => Error::config(field, reason),
        }
    })
}

/// Fields read through an intermediate value (`initial`, `c0`, `adaptive`) lose the inner key
/// of an error: read the sub-object again as its concrete type to name it.
fn refine(path: &str, scene: &Value) -> Option<Error> {
    fn inner<T: serde::de::DeserializeOwned>(at: &str, v: &Value) -> Option<Error> {
        let e = serde_path_to_error::deserialize::<_, T>(v.clone()).err()?;
        let p = e.path().to_string();
        let field = if p == "." {
            at.to_string()
        } else {
            format!("{at}.{p}")
        };
        Some(Error::config(field, e.into_inner().to_string()))
    }
    let v = scene.get(path)?;
    if !v.is_object() {
        return None;
    }
    match path {
        "c0" => inner::<C0Field>(path, v),
        "adaptive" => inner::<AdaptiveSettings>(path, v),
        _ => None,
    }
}

/// A relative `.npy` path is taken from the scene file's folder if it exists there, else from
/// the working directory.
fn resolve_relative(scene: &Path, file: &Path) -> PathBuf {
    if file.is_absolute() {
        return file.to_path_buf();
    }
    let beside = scene.parent().unwrap_or(Path::new(".")).join(file);
    if beside.exists() {
        beside
    } else {
        file.to_path_buf()
    }
}

/// Apply one `key=value` override to the scene JSON. `key` is dotted for nested fields
/// (`area.alpha=0.01`); `value` is read as JSON, or taken as a string if it is not JSON.
///
/// # Errors
/// `Error::Config` if the text has no `=` or the path runs through a non-object.
pub fn apply_override(scene: &mut Value, assignment: &str) -> Result<()> {
    let (key, raw) = assignment
        .split_once('=')
        .ok_or_else(|| Error::config(assignment, "--set expects key=value"))?;
    let value = serde_json::from_str(raw).unwrap_or_else(|_| Value::String(raw.to_string()));
    let parts: Vec<&str> = key.split('.').collect();
    let mut node = scene;
    for (i, part) in parts.iter().enumerate() {
        let obj = node.as_object_mut().ok_or_else(|| {
            Error::config(
                parts[..i].join("."),
                "is not an object, so --set cannot set a key inside it",
            )
        })?;
        if i + 1 == parts.len() {
            obj.insert(part.to_string(), value);
            return Ok(());
        }
        node = obj
            .entry(part.to_string())
            .or_insert_with(|| Value::Object(Default::default()));
    }
    Ok(())
}

impl Scene {
    /// The area method after defaults: projection for spectral, Lagrangian for FD.
    pub fn area_method(&self) -> AreaMethod {
        self.area.method.unwrap_or(match self.method {
            Method::Spectral => AreaMethod::Projection,
            Method::Fd => AreaMethod::Lagrangian,
        })
    }

    /// The stabiliser after defaults ([`Stabilizer::default_for`] the scheme).
    pub fn stabilizer(&self) -> Stabilizer {
        let d = Stabilizer::default_for(self.scheme);
        Stabilizer {
            s2: self.stabilizer.s2.unwrap_or(d.s2),
            s4: self.stabilizer.s4.unwrap_or(d.s4),
        }
    }

    /// α of the Lagrangian area update (default 1e-3).
    pub fn alpha(&self) -> f64 {
        self.area.alpha.unwrap_or(1e-3)
    }

    /// Check every field that can be checked without building the initial field.
    ///
    /// # Errors
    /// `Error::Config` naming the first invalid field and the reason.
    pub fn validate(&self) -> Result<()> {
        if self.dim != 2 && self.dim != 3 {
            return Err(Error::config(
                "dim",
                format!("must be 2 or 3, got {}", self.dim),
            ));
        }
        if self.n.len() != self.dim {
            return Err(Error::config(
                "n",
                format!(
                    "needs {} entries (dim = {}), got {}",
                    self.dim,
                    self.dim,
                    self.n.len()
                ),
            ));
        }
        if let Some(&bad) = self.n.iter().find(|&&m| m < 4) {
            return Err(Error::config(
                "n",
                format!("every entry must be at least 4, got {bad}"),
            ));
        }
        positive("h", self.h)?;
        positive("eps", self.eps)?;
        positive("dt", self.dt)?;
        if let Some(t) = self.t_end {
            positive("t_end", t)?;
        }
        if self.max_steps == Some(0) {
            return Err(Error::config("max_steps", "must be at least 1"));
        }
        if let Some(r) = self.stop_residual {
            positive("stop_residual", r)?;
        }
        if self.t_end.is_none() && self.max_steps.is_none() && self.stop_residual.is_none() {
            return Err(Error::config(
                "t_end",
                "the run needs a stop rule: set t_end, max_steps or stop_residual",
            ));
        }
        if self.threads == Some(0) {
            return Err(Error::config("threads", "must be at least 1"));
        }
        self.validate_method()?;
        self.validate_area()?;
        self.validate_c0()?;
        self.validate_symmetry()?;
        if let Initial::Shape(s) = &self.initial {
            validate_shape(s, "initial", self.dim)?;
        }
        if self.output.record_every == 0 {
            return Err(Error::config("output.record_every", "must be at least 1"));
        }
        Ok(())
    }

    fn validate_method(&self) -> Result<()> {
        if self.method == Method::Fd {
            if self.scheme != Scheme::Sbdf1 {
                return Err(Error::config(
                    "scheme",
                    "the fd method is explicit Euler; sbdf schemes belong to the spectral method",
                ));
            }
            if self.adaptive.settings().is_some() {
                return Err(Error::config(
                    "adaptive",
                    "the fd reference runs with a fixed step (its stability bound); use the spectral method",
                ));
            }
            if self.dynamics != Dynamics::Conserved {
                return Err(Error::config(
                    "dynamics",
                    "the fd method runs conserved dynamics only",
                ));
            }
        }
        if self.dynamics == Dynamics::Relaxational && self.area_method() == AreaMethod::Lagrangian {
            return Err(Error::config(
                "area.method",
                "relaxational dynamics holds the area exactly; use projection or none",
            ));
        }
        if self.lbfgs_memory == 0 {
            return Err(Error::config("lbfgs_memory", "must be at least 1"));
        }
        if !(self.stabilizer().s2 >= 0.0 && self.stabilizer().s2.is_finite()) {
            return Err(Error::config("stabilizer.s2", "must be finite and ≥ 0"));
        }
        if !(self.stabilizer().s4 >= 0.0 && self.stabilizer().s4.is_finite()) {
            return Err(Error::config("stabilizer.s4", "must be finite and ≥ 0"));
        }
        if let Some(a) = self.adaptive.settings() {
            if let Some(m) = a.dt_min {
                positive("adaptive.dt_min", m)?;
                if m > self.dt {
                    return Err(Error::config("adaptive.dt_min", "must not exceed dt"));
                }
            }
            if let Some(m) = a.dt_max {
                positive("adaptive.dt_max", m)?;
                if m < self.dt {
                    return Err(Error::config("adaptive.dt_max", "must not be below dt"));
                }
            }
            if !(a.growth > 1.0 && a.growth < 1.0 + 2f64.sqrt()) {
                return Err(Error::config(
                    "adaptive.growth",
                    format!(
                        "must lie in (1, 1+√2) for SBDF2 stability, got {}",
                        a.growth
                    ),
                ));
            }
            if !(a.shrink > 0.0 && a.shrink < 1.0) {
                return Err(Error::config("adaptive.shrink", "must lie in (0, 1)"));
            }
            if !(a.energy_alpha >= 0.0 && a.energy_alpha.is_finite()) {
                return Err(Error::config(
                    "adaptive.energy_alpha",
                    "must be finite and ≥ 0",
                ));
            }
        }
        Ok(())
    }

    fn validate_area(&self) -> Result<()> {
        if let Some(a) = self.area.alpha {
            positive("area.alpha", a)?;
        }
        if let Some(t) = self.area.target {
            positive("area.target", t)?;
        }
        if self.area.alpha.is_some() && self.area_method() != AreaMethod::Lagrangian {
            return Err(Error::config(
                "area.alpha",
                "only the lagrangian area method uses alpha",
            ));
        }
        Ok(())
    }

    fn validate_c0(&self) -> Result<()> {
        match &self.c0 {
            C0Spec::Uniform(c) => finite("c0", *c),
            C0Spec::Field(f) => {
                finite("c0.inside", f.inside)?;
                finite("c0.outside", f.outside)?;
                positive("c0.width", f.width)?;
                if let Some(r) = f.radius {
                    positive("c0.radius", r)?;
                }
                if let Some(t) = f.ramp_time {
                    positive("c0.ramp_time", t)?;
                }
                check_center("c0.center", &f.center, self.dim)
            }
        }
    }

    fn validate_symmetry(&self) -> Result<()> {
        if let Symmetry::Axes(axes) = &self.symmetry {
            let mut seen = Vec::new();
            for a in axes {
                let i = axis_index(a, self.dim).ok_or_else(|| {
                    Error::config(
                        "symmetry",
                        format!(
                            "unknown axis {a:?} for dim {} (use x, y{})",
                            self.dim,
                            if self.dim == 3 { ", z" } else { "" }
                        ),
                    )
                })?;
                if seen.contains(&i) {
                    return Err(Error::config("symmetry", format!("axis {a:?} given twice")));
                }
                seen.push(i);
                if !self.n[i].is_multiple_of(2) {
                    return Err(Error::config(
                        "symmetry",
                        format!("mirror axis {a:?} needs an even n, got {}", self.n[i]),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Index of the scene axis named `name` ("x", "y", "z").
pub fn axis_index(name: &str, dim: usize) -> Option<usize> {
    let i = match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => return None,
    };
    (i < dim).then_some(i)
}

fn positive(field: &str, x: f64) -> Result<()> {
    if x > 0.0 && x.is_finite() {
        Ok(())
    } else {
        Err(Error::config(
            field,
            format!("must be a finite number > 0, got {x}"),
        ))
    }
}

fn finite(field: &str, x: f64) -> Result<()> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(Error::config(field, format!("must be finite, got {x}")))
    }
}

fn check_center(field: &str, center: &Option<Vec<f64>>, dim: usize) -> Result<()> {
    if let Some(c) = center {
        if c.len() != dim {
            return Err(Error::config(
                field,
                format!("needs {dim} entries, got {}", c.len()),
            ));
        }
        if c.iter().any(|x| !x.is_finite()) {
            return Err(Error::config(field, "entries must be finite"));
        }
    }
    Ok(())
}

fn check_axis(field: &str, axis: &Option<String>, dim: usize) -> Result<()> {
    match axis {
        Some(a) if axis_index(a, dim).is_none() => Err(Error::config(
            field,
            format!("unknown axis {a:?} for dim {dim}"),
        )),
        _ => Ok(()),
    }
}

fn validate_shape(s: &Shape, at: &str, dim: usize) -> Result<()> {
    let f = |k: &str| format!("{at}.{k}");
    match s {
        Shape::Sphere(s) => {
            positive(&f("radius"), s.radius)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Ellipsoid(s) => {
            if s.axes.len() != dim {
                return Err(Error::config(
                    f("axes"),
                    format!("needs {dim} entries, got {}", s.axes.len()),
                ));
            }
            for a in &s.axes {
                positive(&f("axes"), *a)?;
            }
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Spheroid(s) => {
            if !(s.reduced_volume > 0.0 && s.reduced_volume <= 1.0) {
                return Err(Error::config(
                    f("reduced_volume"),
                    format!("must lie in (0, 1], got {}", s.reduced_volume),
                ));
            }
            positive(&f("r0"), s.r0)?;
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Cup(s) => {
            positive(&f("radius"), s.radius)?;
            positive(&f("inner_radius"), s.inner_radius)?;
            finite(&f("offset"), s.offset)?;
            if s.inner_radius + s.offset.abs() <= s.radius {
                return Err(Error::config(
                    f("offset"),
                    "the inner ball lies inside the outer one (no opening): need inner_radius + |offset| > radius",
                ));
            }
            if s.offset.abs() - s.inner_radius >= s.radius {
                return Err(Error::config(
                    f("offset"),
                    "the inner ball misses the outer one",
                ));
            }
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Capsule(s) => {
            positive(&f("radius"), s.radius)?;
            if !(s.length >= 0.0 && s.length.is_finite()) {
                return Err(Error::config(f("length"), "must be finite and ≥ 0"));
            }
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Union(u) => {
            if u.of.is_empty() {
                return Err(Error::config(f("of"), "needs at least one shape"));
            }
            for (i, s) in u.of.iter().enumerate() {
                validate_shape(s, &format!("{at}.of[{i}]"), dim)?;
            }
            Ok(())
        }
        Shape::Difference(d) => {
            validate_shape(&d.base, &f("base"), dim)?;
            validate_shape(&d.minus, &f("minus"), dim)
        }
    }
}
