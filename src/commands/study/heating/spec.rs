//! The heating study's file: its keys ([`Spec`]), their checks, and the scene of one R0 with
//! the box sized to hold the prolate and the budded pear ([`box_size`]).

use super::super::budding::within;
use crate::error::{Error, Result};
use crate::problem::config::{self, Scene};
use serde::Deserialize;
use serde_json::{json, Value};

/// Keys of the scene that the study sets itself.
const STUDY_KEYS: [&str; 7] = [
    "initial", "n", "c0", "ade", "dynamics", "symmetry", "volume",
];

/// Bulk between the shape's extent and the box face, in ε (φ ≈ −0.99 there).
const PAD: f64 = 4.0;

/// Half-extents (units of R0) the box holds at least: across the axis the larger sphere of
/// the budded pear (0.93 R0 at v = 0.85), along it the pear from its centroid (1.65 R0).
const MIN_HALF: (f64, f64) = (0.95, 1.7);

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"heating"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The lattice spacing, width and relaxation: a scene object (`dim` 3, `h`, `eps`, `dt`,
    /// `stop_residual`, `max_steps`, `prepare_steps`, …) without `initial`, `n`, `c0`, `ade`,
    /// `dynamics`, `symmetry` and `volume`, which the study sets.
    pub scene: Value,
    /// Reduced volume of the start prolate, in (0, 1).
    pub v: f64,
    /// α = κ̄/κ of the ADE energy, > 0.
    pub alpha: f64,
    /// The R0/ε of the runs, each a continuation of its own.
    pub r0: Vec<f64>,
    /// The path in Δa0 (no value twice in a row).
    pub da0: Vec<f64>,
    /// Strength δ of the up–down asymmetry seeded before each relaxation, in [0, 0.1].
    pub seed: f64,
    /// Quadrature nodes of the sharp reference (K = (nodes − 1)/3 modes; default 241).
    #[serde(default = "default_nodes")]
    pub nodes: usize,
    /// Δa0 values of the path at which the largest R0's state is pictured.
    #[serde(default)]
    pub renders: Vec<f64>,
}

fn default_nodes() -> usize {
    241
}

/// Refuse a bad study file, naming the key.
pub(super) fn check(spec: &Spec) -> Result<()> {
    if !(spec.v > 0.0 && spec.v < 1.0) {
        return Err(Error::config(
            "v",
            format!("must lie in (0, 1), got {}", spec.v),
        ));
    }
    if !(spec.alpha > 0.0 && spec.alpha.is_finite()) {
        return Err(Error::config(
            "alpha",
            format!("must be > 0, got {}", spec.alpha),
        ));
    }
    if spec.r0.is_empty() || spec.r0.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(Error::config("r0", "list one or more R0/eps > 0"));
    }
    if spec.da0.is_empty() || spec.da0.iter().any(|x| !x.is_finite()) {
        return Err(Error::config("da0", "list one or more finite values"));
    }
    if let Some(w) = spec.da0.windows(2).find(|w| w[1] == w[0]) {
        return Err(Error::config(
            "da0",
            format!("a path of steps: {} twice in a row", w[0]),
        ));
    }
    if !(0.0..=0.1).contains(&spec.seed) {
        return Err(Error::config(
            "seed",
            format!("must lie in [0, 0.1], got {}", spec.seed),
        ));
    }
    if spec.nodes < 61 {
        return Err(Error::config(
            "nodes",
            format!("at least 61, got {}", spec.nodes),
        ));
    }
    if let Some(x) = spec.renders.iter().find(|x| !spec.da0.contains(x)) {
        return Err(Error::config(
            "renders",
            format!("{x} is not a value of da0"),
        ));
    }
    Ok(())
}

/// The smallest even 2-3-5-smooth integer ≥ `x` (an FFT-friendly box side).
pub fn box_side(x: f64) -> usize {
    let smooth = |mut n: usize| {
        for p in [2, 3, 5] {
            while n.is_multiple_of(p) {
                n /= p;
            }
        }
        n == 1
    };
    (x.ceil().max(2.0) as usize..)
        .find(|&n| n.is_multiple_of(2) && smooth(n))
        .expect("smooth numbers are unbounded")
}

/// The box `[n, n, n_z]` for R0 = `r0` ε at spacing `h` and width `eps`, holding the contour
/// `(r, z)` (R0 = 1) and at least [`MIN_HALF`], with [`PAD`] ε of bulk to each face:
/// `n = 2 (max(r_max, 0.95) R0 + PAD ε)/h`, `n_z = 2 (max(half-length, 1.7) R0 + PAD ε)/h`,
/// each rounded up by [`box_side`].
pub fn box_size(r: &[f64], z: &[f64], r0: f64, h: f64, eps: f64) -> [usize; 3] {
    let r_max = r.iter().copied().fold(0.0, f64::max);
    let (lo, hi) = z
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let side = |half: f64| box_side(2.0 * (half * r0 * eps + PAD * eps) / h);
    let across = side(r_max.max(MIN_HALF.0));
    [across, across, side((0.5 * (hi - lo)).max(MIN_HALF.1))]
}

/// The scene of one R0: the file's `scene` through [`sized_scene`], with a stop.
///
/// # Errors
/// `Error::Config` naming `scene.<key>` for a key the study sets or an invalid scene.
pub(super) fn base_scene(spec: &Spec, r0: f64, r: &[f64], z: &[f64]) -> Result<Scene> {
    let set_by = "initial: the axisymmetric ADE prolate at v and da0[0]; n: sized to R0; c0: 0; \
                  ade: alpha and the path; dynamics: relaxational; symmetry: x and y";
    let scene = sized_scene(&spec.scene, &STUDY_KEYS, set_by, r0, (r, z))?;
    if scene.stop_residual.is_none() && scene.max_steps.is_none() {
        return Err(Error::config(
            "scene.stop_residual",
            "each relaxation needs a stop: stop_residual (and max_steps as a cap)",
        ));
    }
    Ok(scene)
}

/// The 3D scene of one R0 of a continuation along the prolate's axis (the heating and onset
/// studies): the study file's `scene`, which must not hold any of `keys` (`set_by` says what
/// the study sets them to), with L-BFGS, mirror planes x and y (a pear breaks the up–down
/// mirror), the box of [`box_size`] for the contour `(r, z)` (R0 = 1) at R0 = `r0` ε, and a
/// placeholder initial shape, a sphere of radius R0/2 that fits every such box (the start
/// field, checked on its own, replaces it).
///
/// # Errors
/// `Error::Config` naming `scene.<key>` for a key the study sets, a 2D scene or an invalid
/// scene.
pub fn sized_scene(
    scene: &Value,
    keys: &[&str],
    set_by: &str,
    r0: f64,
    (r, z): (&[f64], &[f64]),
) -> Result<Scene> {
    let Value::Object(obj) = scene else {
        return Err(Error::config("scene", "must be a scene object"));
    };
    if let Some(k) = keys.iter().find(|k| obj.contains_key(**k)) {
        return Err(Error::config(
            format!("scene.{k}"),
            format!("is set by the study ({set_by}); remove it"),
        ));
    }
    let num = |k: &str| obj.get(k).and_then(Value::as_f64).unwrap_or(1.0);
    let (h, eps) = (num("h"), num("eps"));
    let mut value = scene.clone();
    value["n"] = json!(box_size(r, z, r0, h, eps));
    value["initial"] = json!({"shape": "sphere", "radius": 0.5 * r0 * eps});
    value["dynamics"] = json!("relaxational");
    value["symmetry"] = json!(["x", "y"]);
    let scene = config::load_value(value, &[], None).map_err(within("scene"))?;
    if scene.dim != 3 {
        return Err(Error::config("scene.dim", "the study is 3D"));
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Box sides are even and 2-3-5-smooth: 80.4 → 90 (81 is odd), 57.6 → 60, 96 → 96.
    #[test]
    fn box_sides_are_even_and_smooth() {
        assert_eq!(box_side(80.4), 90);
        assert_eq!(box_side(57.6), 60);
        assert_eq!(box_side(96.0), 96);
    }

    /// The file's refusals name the key.
    #[test]
    fn bad_files_are_refused_naming_the_key() {
        let spec = |edit: &dyn Fn(&mut Value)| {
            let mut v = json!({
                "study": "heating",
                "scene": {"dim": 3, "dt": 0.01, "stop_residual": 1e-6},
                "v": 0.85, "alpha": 1.4, "r0": [8.0], "da0": [1.4, 1.5], "seed": 0.02
            });
            edit(&mut v);
            let spec: Spec = serde_json::from_value(v).expect("parses");
            check(&spec)
                .and_then(|_| base_scene(&spec, 8.0, &[0.0, 0.5, 0.0], &[-1.0, 0.0, 1.0]))
                .map_err(|e| e.to_string())
        };
        assert!(spec(&|_| {}).is_ok());
        assert!(spec(&|v| v["alpha"] = json!(0.0))
            .unwrap_err()
            .contains("`alpha`"));
        assert!(spec(&|v| v["da0"] = json!([1.4, 1.4]))
            .unwrap_err()
            .contains("twice"));
        assert!(spec(&|v| v["renders"] = json!([1.45]))
            .unwrap_err()
            .contains("`renders`"));
        assert!(spec(&|v| v["scene"]["n"] = json!([8, 8, 8]))
            .unwrap_err()
            .contains("`scene.n`"));
        assert!(spec(&|v| v["scene"]["ade"] = json!({"alpha": 1, "da0": 1}))
            .unwrap_err()
            .contains("`scene.ade`"));
    }
}
