//! `c0`: the spontaneous curvature, a uniform number or a field object.

use super::scene::one;
use serde::{Deserialize, Serialize};
use serde_json::Value;

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
