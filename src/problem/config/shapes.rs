//! The initial field: a shape object (`{"shape": "<kind>", ...}`) or a `.npy` file, and their
//! deserialisation with the inner key of an error kept.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::PathBuf;

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
    /// Flat disc with an m-fold angular modulation of its radius (3D; starfish seeds).
    Star(Star),
    /// Union of shapes: d = max d_i.
    Union(Union),
    /// `base` with `minus` removed: d = min(d_base, −d_minus).
    Difference(Difference),
    /// Surface of revolution from the axisymmetric reference solver or a contour file.
    Axisym(Axisym),
    /// A sphere (circle) with one harmonic on its radius: a quasi-sphere's mode.
    Harmonic(Harmonic),
    /// A slab of fluid between two parallel interfaces, displaced by one cosine wave.
    Slab(Slab),
}

/// The quasi-sphere r = R (1 + a Y(θ)): Y = P_l(cos θ), θ from `axis` (3D), or
/// Y = cos(lθ), θ from the x axis (2D), with l = `mode`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Harmonic {
    /// R.
    pub radius: f64,
    /// l (the Legendre degree in 3D, the Fourier mode in 2D), ≥ 2.
    pub mode: usize,
    /// a, relative to R; |a| < 0.5.
    pub amplitude: f64,
    /// The axis of P_l in 3D (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// The slab |y − a cos(2πx/λ)| < thickness/2 about the box centre, y along `axis` (its
/// normal; default the last) and x the first other axis: two interfaces displaced together
/// by one wave (a bending mode of a flat membrane pair). λ should divide the box's length
/// along x.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slab {
    /// Distance between the two interfaces.
    pub thickness: f64,
    /// λ of the wave.
    pub wavelength: f64,
    /// a, the wave's amplitude (a length).
    pub amplitude: f64,
    /// The normal to the interfaces (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
}

/// Sphere (circle in 2D) of radius `radius`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// Radius (of the sphere, the cup's outer ball, the capsule's tube and caps).
    pub radius: f64,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Ellipsoid (ellipse in 2D) with semi-axes `axes`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ellipsoid {
    /// Semi-axes, one per dimension.
    pub axes: Vec<f64>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Spheroid (ellipse in 2D) with reduced volume (area) `reduced_volume` and `R0 = √(A/4π)`
/// (2D: perimeter/2π); `kind` prolate (long along `axis`) or oblate.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spheroid {
    /// Reduced volume v (reduced area in 2D).
    pub reduced_volume: f64,
    /// R0 = √(A/4π) (2D: perimeter/2π), in lengths of the grid.
    pub r0: f64,
    /// Prolate (long along `axis`) or oblate.
    #[serde(default)]
    pub kind: SpheroidKind,
    /// The symmetry axis (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Stomatocyte-like cup: a ball of `radius` minus a ball of `inner_radius` whose centre is
/// shifted by `offset` along `axis`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cup {
    /// Radius (of the sphere, the cup's outer ball, the capsule's tube and caps).
    pub radius: f64,
    /// Radius of the removed inner ball.
    pub inner_radius: f64,
    /// Shift of the inner ball's centre along `axis`.
    pub offset: f64,
    /// The symmetry axis (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Capsule (tube with round caps): radius `radius`, straight part `length` along `axis`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Capsule {
    /// Radius (of the sphere, the cup's outer ball, the capsule's tube and caps).
    pub radius: f64,
    /// Length of the straight part along `axis`.
    pub length: f64,
    /// The symmetry axis (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Flat star (3D): the ellipsoid-like disc F = (ρ/R(θ))² + (ζ/`thickness`)² ≤ 1 with
/// R(θ) = `radius`·(1 + `amplitude`·cos(`arms`·θ)), ρ, θ polar coordinates in the plane normal to
/// `axis` (θ from the first of the other two axes: an arm along it) and ζ along `axis`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Star {
    /// Mean radius R̄ of the disc in its plane.
    pub radius: f64,
    /// Half-thickness along `axis`.
    pub thickness: f64,
    /// Number of arms m ≥ 2.
    pub arms: u32,
    /// Relative modulation a ∈ [0, 1) of the radius (arm tips at R̄(1 + a), between arms R̄(1 − a)).
    pub amplitude: f64,
    /// The disc's normal (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Union of shapes.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Union {
    /// The shapes joined.
    pub of: Vec<Shape>,
}

/// `base` with `minus` removed.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Difference {
    /// The shape cut from.
    pub base: Box<Shape>,
    /// The shape removed.
    pub minus: Box<Shape>,
}

/// Surface of revolution about `axis`: the stationary shape of the axisymmetric reference
/// solver (`branch` + `reduced_volume`) or an `r,z` contour file at `R0 = 1` (`contour`, as
/// `vesicle axisym` writes `contours/<branch>_v<v>.csv`; relative to the scene file's folder),
/// scaled to `r0`. Exactly one of the two sources. `center` offsets the middle of the shape's
/// extent along the axis (the mirror centre of a prolate or oblate) from the box centre.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axisym {
    /// The reference solver's branch (with `reduced_volume`).
    #[serde(default)]
    pub branch: Option<AxisymBranch>,
    /// Reduced volume v (reduced area in 2D).
    #[serde(default)]
    pub reduced_volume: Option<f64>,
    /// An `r,z` contour file at R0 = 1 (instead of `branch`).
    #[serde(default)]
    pub contour: Option<PathBuf>,
    /// R0 = √(A/4π) (2D: perimeter/2π), in lengths of the grid.
    pub r0: f64,
    /// The symmetry axis (`"x"`, `"y"` or `"z"`; default the last).
    #[serde(default)]
    pub axis: Option<String>,
    /// Offset of the shape's centre from the box centre (`dim` numbers; default 0).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
}

/// Branch of the c0 = 0 shape diagram (`vesicle::analysis::axisym::Branch`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisymBranch {
    /// Up–down symmetric, elongated along the axis.
    Prolate,
    /// Up–down symmetric, flattened (discocytes at smaller v).
    Oblate,
    /// An invaginated cup, not up–down symmetric.
    Stomatocyte,
}

impl AxisymBranch {
    /// Lower-case name, as in the scene file.
    pub fn name(self) -> &'static str {
        match self {
            AxisymBranch::Prolate => "prolate",
            AxisymBranch::Oblate => "oblate",
            AxisymBranch::Stomatocyte => "stomatocyte",
        }
    }

    /// Reduced volumes `(lo, hi]` where the reference solver's branch exists as a surface
    /// without self-contact: the oblate touches itself at the poles below v ≈ 0.503 and the
    /// stomatocyte ends at a limit point, v ≈ 0.6608 (tests/axisym.rs). Where the solver still
    /// fails inside the range (the stomatocyte's neck closes at small v, self-contact near
    /// v ≈ 0.2), building the field says so.
    pub fn range(self) -> (f64, f64) {
        match self {
            AxisymBranch::Prolate => (0.0, 1.0),
            AxisymBranch::Oblate => (0.503, 1.0),
            AxisymBranch::Stomatocyte => (0.0, 0.6608),
        }
    }
}

impl Shape {
    /// Every `contour` path inside the shape (for resolving them against the scene's folder).
    pub fn contours_mut(&mut self) -> Vec<&mut PathBuf> {
        match self {
            Shape::Axisym(a) => a.contour.iter_mut().collect(),
            Shape::Union(u) => u.of.iter_mut().flat_map(|s| s.contours_mut()).collect(),
            Shape::Difference(d) => {
                let mut v = d.base.contours_mut();
                v.extend(d.minus.contours_mut());
                v
            }
            _ => Vec::new(),
        }
    }
}

/// Marks the inner path of a shape's error inside its message (serde keeps no path inside a
/// hand-written deserializer); [`super::from_value`] turns it back into a dotted field.
pub(super) const PATH_MARK: char = '\u{1f}';

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
            "star" => kind(v).map(Shape::Star),
            "union" => kind(v).map(Shape::Union),
            "difference" => kind(v).map(Shape::Difference),
            "axisym" => kind(v).map(Shape::Axisym),
            "harmonic" => kind(v).map(Shape::Harmonic),
            "slab" => kind(v).map(Shape::Slab),
            _ => Err(format!(
                "{PATH_MARK}shape{PATH_MARK}unknown variant {tag}, expected one of `sphere`, \
                 `ellipsoid`, `spheroid`, `cup`, `capsule`, `star`, `union`, `difference`, `axisym`, \
                 `harmonic`, `slab`"
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
