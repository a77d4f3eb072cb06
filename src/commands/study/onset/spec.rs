//! The onset study's file: its keys ([`Spec`]), their checks, the path's parameter
//! ([`Parameter`]: c̄0, or Δa of the bilayer couple), and the scene of one R0 with the box sized
//! to the start prolate and the budded pear (the heating study's [`sized_scene`]).

use super::super::budding::MAX_EPS_C0;
use super::super::heating::spec::sized_scene;
use crate::error::{Error, Result};
use crate::problem::config::{BilayerCoupleSpec, C0Spec, Scene};
use serde::Deserialize;
use serde_json::Value;

/// Keys of the scene that the study sets itself.
const STUDY_KEYS: [&str; 8] = [
    "initial",
    "n",
    "c0",
    "dynamics",
    "symmetry",
    "volume",
    "ade",
    "bilayer_couple",
];

/// Most bisections of an onset bracket the file may ask for (2⁻¹² of a coarse step is far
/// below what the stop residual resolves).
pub const MAX_BISECTIONS: usize = 12;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"onset"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The lattice spacing, width and relaxation: a scene object (`dim` 3, `h`, `eps`, `dt`,
    /// `stop_residual`, `max_steps`, `prepare_steps`, …) without `initial`, `n`, `c0`,
    /// `dynamics`, `symmetry` and `volume`, which the study sets.
    pub scene: Value,
    /// Reduced volume of the start prolate (the sharp one, at `c0[0]`), in (0, 1).
    pub v: f64,
    /// The R0/ε of the runs, increasing.
    pub r0: Vec<f64>,
    /// How the onset is found: `"seeded"` (default: seeded relaxations, the skewness
    /// threshold, bisections) or `"hessian"` (the lowest up–down odd eigenvalue of the
    /// symmetric state, regula falsi; [`super::hessian`]).
    #[serde(default)]
    pub method: Method,
    /// The seed strengths δ, each a run of its own at every R0, in (0, 0.1] (`seeded` only).
    #[serde(default)]
    pub seeds: Vec<f64>,
    /// The coarse path in c̄0 = c0 R0 (spontaneous curvature), increasing: stepped up until the
    /// first state that is not up–down symmetric. One of `c0` and `da`.
    #[serde(default)]
    pub c0: Vec<f64>,
    /// The coarse path in Δa of the bilayer couple (c0 = 0), increasing, as `c0` is for the
    /// spontaneous-curvature model (`hessian` only). One of `c0` and `da`.
    #[serde(default)]
    pub da: Vec<f64>,
    /// Bisections of the bracket (last symmetric c̄0, first asymmetric c̄0), each from the last
    /// symmetric state; with `hessian`, regula falsi steps on the eigenvalue.
    pub bisections: usize,
    /// `hessian`: the eigensolver's stop, ‖Bx − θx‖_M (the eigenvalue's error is below it).
    #[serde(default = "default_eigen_tolerance")]
    pub eigen_tolerance: f64,
    /// `hessian`: the most products with the second variation per eigenvalue.
    #[serde(default = "default_eigen_products")]
    pub eigen_products: usize,
}

/// What the path steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// c̄0 = c0 R0 of the spontaneous-curvature model (`c0`).
    C0,
    /// Δa held by the bilayer couple at c0 = 0 (`da`).
    Couple,
}

impl Parameter {
    /// The file's key of the path.
    pub fn key(self) -> &'static str {
        match self {
            Parameter::C0 => "c0",
            Parameter::Couple => "da",
        }
    }

    /// The path's variable as tables and charts print it.
    pub fn label(self) -> &'static str {
        match self {
            Parameter::C0 => "c0 R0",
            Parameter::Couple => "da",
        }
    }

    /// `scene` at the path's value `value`, for a vesicle of radius `r0` (length units):
    /// c0 = c̄0/R0, or the bilayer couple holding Δa = `value`.
    pub fn set(self, scene: &mut Scene, value: f64, r0: f64) {
        match self {
            Parameter::C0 => scene.c0 = C0Spec::Uniform(value / r0),
            Parameter::Couple => scene.bilayer_couple = Some(BilayerCoupleSpec { da: value }),
        }
    }
}

impl Spec {
    /// The path's parameter: `c0` or `da` (the file has one, [`check`]).
    pub fn parameter(&self) -> Parameter {
        if self.da.is_empty() {
            Parameter::C0
        } else {
            Parameter::Couple
        }
    }

    /// The coarse path: the values of `c0` or `da`.
    pub fn path(&self) -> &[f64] {
        match self.parameter() {
            Parameter::C0 => &self.c0,
            Parameter::Couple => &self.da,
        }
    }
}

/// How the onset study finds the onset.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Seeded relaxations classified by their skewness.
    #[default]
    Seeded,
    /// The sign of the symmetric state's lowest up–down odd eigenvalue.
    Hessian,
}

/// The default eigensolver stop: near the onset the lowest eigenvalue moves by ~5e-7 per 0.1 of
/// c̄0 at R0 = 20ε (h = 2ε/3), and its error is below the residual (below residual²/gap once
/// converged), so 1e-9 places the zero to well under 1e-3 in c̄0.
fn default_eigen_tolerance() -> f64 {
    1e-9
}

/// The default cap on products per eigenvalue (130–360 were needed at R0 = 20ε).
fn default_eigen_products() -> usize {
    2000
}

/// Refuse a bad study file, naming the key.
///
/// # Errors
/// `Error::Config` naming the key.
pub fn check(spec: &Spec) -> Result<()> {
    if !(spec.v > 0.0 && spec.v < 1.0) {
        return Err(Error::config(
            "v",
            format!("must lie in (0, 1), got {}", spec.v),
        ));
    }
    if spec.r0.is_empty() || spec.r0.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(Error::config("r0", "needs one or more R0/eps, each > 0"));
    }
    if spec.r0.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::config("r0", "must increase"));
    }
    match spec.method {
        Method::Seeded => {
            if spec.seeds.is_empty() || spec.seeds.iter().any(|s| !(*s > 0.0 && *s <= 0.1)) {
                return Err(Error::config(
                    "seeds",
                    "needs one or more seed strengths, each in (0, 0.1]",
                ));
            }
        }
        Method::Hessian => {
            if !spec.seeds.is_empty() {
                return Err(Error::config(
                    "seeds",
                    "the hessian method seeds nothing (it reads the symmetric state's \
                     eigenvalue): remove seeds",
                ));
            }
        }
    }
    if !(spec.eigen_tolerance > 0.0 && spec.eigen_tolerance < 1.0) {
        return Err(Error::config(
            "eigen_tolerance",
            format!("must lie in (0, 1), got {}", spec.eigen_tolerance),
        ));
    }
    if spec.eigen_products < 2 {
        return Err(Error::config("eigen_products", "needs at least 2"));
    }
    match (spec.c0.is_empty(), spec.da.is_empty()) {
        (false, false) => {
            return Err(Error::config(
                "da",
                "give the path in c0 (spontaneous curvature) or in da (the bilayer couple), \
                 not both",
            ))
        }
        (true, true) => return Err(Error::config("c0", "needs the path: c0 or da")),
        _ => {}
    }
    let key = spec.parameter().key();
    let path = spec.path();
    if path.len() < 2
        || path.windows(2).any(|w| w[1] <= w[0])
        || path.iter().any(|v| !v.is_finite())
    {
        return Err(Error::config(
            key,
            format!(
                "needs two or more values of {}, increasing",
                spec.parameter().label()
            ),
        ));
    }
    if spec.parameter() == Parameter::Couple {
        if spec.method != Method::Hessian {
            return Err(Error::config(
                "da",
                "the bilayer couple's path takes the hessian method (\"method\": \"hessian\")",
            ));
        }
        if let Some(d) = spec.da.iter().find(|d| **d <= 1.0) {
            return Err(Error::config(
                "da",
                format!(
                    "a prolate has da > 1 (1 is the sphere), got {d}: the up-down instability \
                     lies on the prolate branch"
                ),
            ));
        }
    }
    let smallest = spec.r0[0];
    if let Some(c) = spec
        .c0
        .iter()
        .find(|c| !c.is_finite() || c.abs() / smallest > MAX_EPS_C0 + 1e-12)
    {
        return Err(Error::config(
            "c0",
            format!(
                "c0 R0 = {c} at R0 = {smallest} eps is eps|c0| = {:.3}, above {MAX_EPS_C0}: the \
                 preferred bud radius 2/c0 would come within ten interface widths",
                c.abs() / smallest
            ),
        ));
    }
    if spec.bisections > MAX_BISECTIONS {
        return Err(Error::config(
            "bisections",
            format!("at most {MAX_BISECTIONS}, got {}", spec.bisections),
        ));
    }
    Ok(())
}

/// The scene of one R0: the file's `scene` through the heating study's
/// [`sized_scene`], with a stop residual.
///
/// # Errors
/// `Error::Config` naming `scene.<key>` for a key the study sets, a scene without
/// `stop_residual` or an invalid scene.
pub fn base_scene(spec: &Spec, r0: f64, r: &[f64], z: &[f64]) -> Result<Scene> {
    let set_by = "initial: the axisymmetric prolate at v and the path's first value; n: sized \
                  to R0; c0, ade, bilayer_couple: the path; dynamics: relaxational; symmetry: \
                  x and y";
    let scene = sized_scene(&spec.scene, &STUDY_KEYS, set_by, r0, (r, z))?;
    if scene.stop_residual.is_none() {
        return Err(Error::config(
            "scene.stop_residual",
            "each relaxation needs stop_residual (a state is classified only once stationary)",
        ));
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn spec(edit: impl FnOnce(&mut Value)) -> std::result::Result<Spec, String> {
        let mut v = json!({
            "study": "onset",
            "scene": {"dim": 3, "h": 1.0, "dt": 0.01, "stop_residual": 1e-6, "max_steps": 100},
            "v": 0.8, "r0": [10.0, 14.0], "seeds": [0.02, 0.05], "c0": [1.0, 1.5],
            "bisections": 2
        });
        edit(&mut v);
        let spec: Spec = serde_json::from_value(v).map_err(|e| e.to_string())?;
        check(&spec).map_err(|e| e.to_string())?;
        let (r, z) = ([0.0, 0.6, 0.0], [-1.3, 0.0, 1.3]);
        base_scene(&spec, spec.r0[0], &r, &z).map_err(|e| e.to_string())?;
        Ok(spec)
    }

    fn refused(edit: impl FnOnce(&mut Value)) -> String {
        spec(edit).expect_err("should be refused")
    }

    /// The file's refusals name the key: v outside (0, 1), R0 not increasing, a seed of 0 (no
    /// asymmetry: the symmetric state would never be left) or above 0.1, a path that does not
    /// increase, ε|c0| above 0.2 at the smallest R0 (c0 R0 = 2.5 at 10ε), too many bisections,
    /// a scene key the study sets, a scene without a stop residual, seeds given to the hessian
    /// method (it seeds nothing), an eigensolver tolerance or cap out of range; and for the
    /// bilayer couple's path: both paths or none, the seeded method, Δa ≤ 1 (no prolate) and a
    /// path that does not increase.
    #[test]
    fn bad_files_are_refused_naming_the_key() {
        assert!(spec(|_| {}).is_ok());
        assert!(refused(|v| v["v"] = json!(1.0)).contains("`v`"));
        assert!(refused(|v| v["r0"] = json!([14.0, 10.0])).contains("`r0`"));
        assert!(refused(|v| v["seeds"] = json!([0.0])).contains("`seeds`"));
        assert!(refused(|v| v["seeds"] = json!([0.2])).contains("`seeds`"));
        assert!(refused(|v| v["c0"] = json!([1.5, 1.0])).contains("`c0`"));
        let high = refused(|v| v["c0"] = json!([1.0, 2.5]));
        assert!(high.contains("`c0`") && high.contains("0.250"), "{high}");
        assert!(refused(|v| v["bisections"] = json!(13)).contains("`bisections`"));
        assert!(refused(|v| v["scene"]["n"] = json!([8, 8, 8])).contains("`scene.n`"));
        let no_stop = refused(|v| {
            v["scene"]
                .as_object_mut()
                .expect("an object")
                .remove("stop_residual");
        });
        assert!(no_stop.contains("`scene.stop_residual`"), "{no_stop}");
        assert!(refused(|v| v["method"] = json!("hessian")).contains("`seeds`"));
        let hessian = |v: &mut Value| {
            v["method"] = json!("hessian");
            v.as_object_mut().expect("an object").remove("seeds");
        };
        assert!(spec(hessian).is_ok());
        let tolerance = refused(|v| {
            hessian(v);
            v["eigen_tolerance"] = json!(0.0);
        });
        assert!(tolerance.contains("`eigen_tolerance`"), "{tolerance}");
        let products = refused(|v| {
            hessian(v);
            v["eigen_products"] = json!(1);
        });
        assert!(products.contains("`eigen_products`"), "{products}");
        assert!(refused(|v| v["method"] = json!("lanczos")).contains("unknown variant"));
        let couple = |v: &mut Value| {
            hessian(v);
            v.as_object_mut().expect("an object").remove("c0");
            v["da"] = json!([1.1, 1.15]);
        };
        assert!(spec(couple).is_ok());
        let both = refused(|v| {
            couple(v);
            v["c0"] = json!([1.0, 1.5]);
        });
        assert!(both.contains("`da`") && both.contains("not both"), "{both}");
        let none = refused(|v| {
            v.as_object_mut().expect("an object").remove("c0");
        });
        assert!(none.contains("`c0`"), "{none}");
        let seeded = refused(|v| {
            couple(v);
            v["method"] = json!("seeded");
            v["seeds"] = json!([0.02]);
        });
        assert!(
            seeded.contains("`da`") && seeded.contains("hessian"),
            "{seeded}"
        );
        let sphere = refused(|v| {
            couple(v);
            v["da"] = json!([1.0, 1.1]);
        });
        assert!(sphere.contains("`da`"), "{sphere}");
        let falling = refused(|v| {
            couple(v);
            v["da"] = json!([1.2, 1.1]);
        });
        assert!(falling.contains("`da`"), "{falling}");
        let set = refused(|v| v["scene"]["bilayer_couple"] = json!({"da": 1.1}));
        assert!(set.contains("`scene.bilayer_couple`"), "{set}");
    }
}
