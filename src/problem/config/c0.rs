//! `c0`: the spontaneous curvature, a uniform number or a field object.
//!
//! A field object picks its form with `"kind"` (absent: `"ball"`, the original patch):
//!
//! | kind   | keys                                                                      |
//! |--------|---------------------------------------------------------------------------|
//! | `ball` | `inside`, `outside`, `center`, `radius`, `width`, `ramp_time`              |
//! | `cap`  | `inside`, `outside`, `angle`, `axis`, `pole`, `center`, `width`, `ramp_time` |
//! | `band` | `inside`, `outside`, `axis`, `center`, `half_width`, `width`, `ramp_time`  |
//! | `file` | `file`, `ramp_time`                                                        |
//!
//! Every kind is ramped linearly in time: c0(x, t) = min(t/ramp_time, 1) c0(x) (no ramp when
//! `ramp_time` is absent). The patches blend `inside` and `outside` with a tanh edge,
//!
//! ```text
//! c0(x) = outside + (inside − outside) · (1 − tanh(d(x)/width)) / 2
//! ```
//!
//! where d is a signed distance to the patch edge, negative inside the patch; see each kind.

use super::scene::one;
use super::shapes::PATH_MARK;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::PathBuf;

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

/// A c0 field object, by `"kind"`.
#[derive(Clone, Debug)]
pub enum C0Field {
    /// `"ball"` (also when `kind` is absent): a ball patch.
    Ball(C0Ball),
    /// `"cap"`: a polar cap of the initial membrane.
    Cap(C0Cap),
    /// `"band"`: a band across an axis (tubes: pearling, budding).
    Band(C0Band),
    /// `"file"`: c0(x) read from a `.npy` file.
    File(C0File),
}

impl C0Field {
    /// The ramp time of any kind.
    pub fn ramp_time(&self) -> Option<f64> {
        match self {
            C0Field::Ball(f) => f.ramp_time,
            C0Field::Cap(f) => f.ramp_time,
            C0Field::Band(f) => f.ramp_time,
            C0Field::File(f) => f.ramp_time,
        }
    }
}

impl Serialize for C0Field {
    /// The kind's keys, with `"kind"` added except for the ball (whose JSON stays as it was).
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::Error as _;
        let (kind, value) = match self {
            C0Field::Ball(f) => (None, serde_json::to_value(f)),
            C0Field::Cap(f) => (Some("cap"), serde_json::to_value(f)),
            C0Field::Band(f) => (Some("band"), serde_json::to_value(f)),
            C0Field::File(f) => (Some("file"), serde_json::to_value(f)),
        };
        let mut value = value.map_err(S::Error::custom)?;
        if let (Some(k), Some(o)) = (kind, value.as_object_mut()) {
            o.insert("kind".into(), Value::String(k.into()));
        }
        value.serialize(s)
    }
}

impl<'de> Deserialize<'de> for C0Field {
    /// Reads the `"kind"` tag (absent: ball), then the kind's struct with path tracking, so an
    /// error names the inner key (`c0.angle`), marked as the shapes mark theirs.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        fn kind<T: serde::de::DeserializeOwned>(v: Value) -> std::result::Result<T, String> {
            serde_path_to_error::deserialize(v).map_err(|e| {
                let path = e.path().to_string();
                let inner = e.into_inner().to_string();
                if path == "." {
                    inner
                } else {
                    format!("{PATH_MARK}{path}{PATH_MARK}{inner}")
                }
            })
        }
        let mut v = Value::deserialize(d)?;
        let tag = v
            .as_object_mut()
            .ok_or_else(|| D::Error::custom("expected a number or a field object"))?
            .remove("kind");
        let field = match tag {
            None => kind(v).map(C0Field::Ball),
            Some(Value::String(t)) => match t.as_str() {
                "ball" => kind(v).map(C0Field::Ball),
                "cap" => kind(v).map(C0Field::Cap),
                "band" => kind(v).map(C0Field::Band),
                "file" => kind(v).map(C0Field::File),
                _ => Err(format!(
                    "{PATH_MARK}kind{PATH_MARK}unknown kind {t:?}, expected one of `ball`, \
                     `cap`, `band`, `file`"
                )),
            },
            Some(other) => Err(format!(
                "{PATH_MARK}kind{PATH_MARK}must be a string (`ball`, `cap`, `band` or `file`), \
                 got {other}"
            )),
        };
        field.map_err(D::Error::custom)
    }
}

/// A ball-shaped patch with a tanh edge, d = |x − center| − radius:
/// `c0(x) = outside + (inside − outside)(1 − tanh((|x − center| − radius)/width))/2`.
/// `radius` absent: uniform `inside`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct C0Ball {
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

/// Which end of the axis a cap sits on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Pole {
    /// The +axis end.
    #[default]
    #[serde(rename = "+")]
    Plus,
    /// The −axis end.
    #[serde(rename = "-")]
    Minus,
}

impl Pole {
    /// +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Pole::Plus => 1.0,
            Pole::Minus => -1.0,
        }
    }
}

/// A polar cap about `center`: with q = x − center, ζ = s q·ê (s = ±1 from `pole`, ê the unit
/// vector of `axis`), ρ = |q| and the polar angle ϑ = atan2(√(ρ² − ζ²), ζ) ∈ [0, π],
///
/// ```text
/// d(x)  = ρ (ϑ − angle·π/180)          (arc length at radius ρ from the cap edge)
/// c0(x) = outside + (inside − outside)(1 − tanh(d/width))/2
/// ```
///
/// On a sphere of radius R about `center`, d is the arc length along the membrane from the cap's
/// rim, so `width` is the rim's width along the membrane. At x = center, d = 0.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct C0Cap {
    /// c0 on the cap.
    pub inside: f64,
    /// c0 elsewhere.
    #[serde(default)]
    pub outside: f64,
    /// Polar angle of the cap's rim in degrees, in (0, 180).
    pub angle: f64,
    /// Axis of the cap (default: the last axis, y in 2D, z in 3D).
    #[serde(default)]
    pub axis: Option<String>,
    /// `"+"` (default) or `"-"`: the end of the axis the cap is centred on.
    #[serde(default)]
    pub pole: Pole,
    /// Centre the angle is measured from (default: box centre).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
    /// Width of the tanh rim (arc length).
    #[serde(default = "one")]
    pub width: f64,
    /// Linear ramp from 0 to full strength over this time.
    #[serde(default)]
    pub ramp_time: Option<f64>,
}

/// A band across `axis`: with ζ = (x − center)·ê the coordinate along the axis,
///
/// ```text
/// d(x)  = |ζ| − half_width
/// c0(x) = outside + (inside − outside)(1 − tanh(d/width))/2
/// ```
///
/// (only the axis component of `center` matters).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct C0Band {
    /// c0 in the band.
    pub inside: f64,
    /// c0 elsewhere.
    #[serde(default)]
    pub outside: f64,
    /// Axis across which the band lies (default: the last axis).
    #[serde(default)]
    pub axis: Option<String>,
    /// Centre of the band (default: box centre).
    #[serde(default)]
    pub center: Option<Vec<f64>>,
    /// Half the band's extent along the axis.
    pub half_width: f64,
    /// Width of the tanh edges.
    #[serde(default = "one")]
    pub width: f64,
    /// Linear ramp from 0 to full strength over this time.
    #[serde(default)]
    pub ramp_time: Option<f64>,
}

/// c0(x) from a float64 C-order `.npy` of shape `n` (the full box), finite everywhere.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct C0File {
    /// Path, relative to the scene file's folder (or the working directory).
    pub file: PathBuf,
    /// Linear ramp from 0 to full strength over this time.
    #[serde(default)]
    pub ramp_time: Option<f64>,
}
