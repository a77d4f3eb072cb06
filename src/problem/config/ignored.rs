//! Keys the scene's method or dynamics ignores. A scene file that sets one is refused (a key
//! that silently does nothing misleads), and the resolved scene leaves them out, so it can be
//! read back ([`Scene::resolved_value`]).
//!
//! | key            | ignored when                      | because                                  |
//! |----------------|-----------------------------------|------------------------------------------|
//! | `scheme`       | `"method": "fd"`                  | the FD reference is explicit Euler       |
//! | `adaptive`     | `"method": "fd"`                  | the FD reference runs with a fixed step  |
//! | `laplacian`    | `"method": "fd"`                  | the FD reference uses its own stencil    |
//! | `stabilizer`   | `"method": "fd"`                  | only the semi-implicit scheme has one    |
//! | `scheme`       | `"dynamics": "relaxational"`      | the L-BFGS has no time scheme            |
//! | `adaptive`     | `"dynamics": "relaxational"`      | the L-BFGS steps are its iterations      |
//! | `lbfgs_memory` | `"dynamics": "conserved"`         | only the relaxational L-BFGS keeps pairs |
//! | `area.alpha`   | area method projection or none    | only the lagrangian update uses α        |
//!
//! `stabilizer` and `laplacian` are used by relaxational runs (the preparation steps are
//! spectral SBDF1 steps; the L-BFGS evaluates μ with the scene's Laplacian).

use super::scene::{AreaMethod, Dynamics, Method, Scene};
use crate::error::{Error, Result};
use serde_json::Value;

/// A key that the scene's settings make meaningless.
pub(super) struct Ignored {
    /// Dotted key.
    pub key: &'static str,
    /// The setting that makes it ignored, as written in a scene file.
    pub by: String,
    /// Why.
    pub why: &'static str,
}

/// The keys `scene`'s method, dynamics and area method ignore (each key once).
pub(super) fn ignored_keys(scene: &Scene) -> Vec<Ignored> {
    let mut out: Vec<Ignored> = Vec::new();
    let mut add = |key, by: &str, why| {
        if !out.iter().any(|i| i.key == key) {
            out.push(Ignored {
                key,
                by: by.to_string(),
                why,
            });
        }
    };
    if scene.method == Method::Fd {
        let by = r#""method": "fd""#;
        add("scheme", by, "the FD reference is explicit Euler");
        add(
            "adaptive",
            by,
            "the FD reference runs with a fixed step, below its stability bound",
        );
        add(
            "laplacian",
            by,
            "the FD reference uses its own stencil; laplacian picks the spectral engine's symbol",
        );
        add(
            "stabilizer",
            by,
            "only the semi-implicit spectral scheme is stabilised",
        );
    }
    match scene.dynamics {
        Dynamics::Relaxational => {
            let by = r#""dynamics": "relaxational""#;
            add("scheme", by, "the L-BFGS has no time scheme");
            add(
                "adaptive",
                by,
                "the L-BFGS chooses its steps by line search; t counts iterations × dt",
            );
        }
        Dynamics::Conserved | Dynamics::Stokes => add(
            "lbfgs_memory",
            if scene.dynamics == Dynamics::Stokes {
                r#""dynamics": "stokes""#
            } else {
                r#""dynamics": "conserved""#
            },
            "only the relaxational L-BFGS keeps pairs",
        ),
    }
    let area = scene.area_method();
    if area != AreaMethod::Lagrangian {
        let name = match area {
            AreaMethod::Projection => "projection",
            AreaMethod::Fixed => "fixed",
            _ => "none",
        };
        add(
            "area.alpha",
            &format!(r#""area.method": "{name}""#),
            "only the lagrangian area update uses alpha",
        );
    }
    out
}

/// Refuse a key of the scene JSON `raw` (after overrides) that `scene` ignores. A key whose
/// value is `null` counts as absent.
///
/// # Errors
/// `Error::Config` naming the first such key, the setting that ignores it and how to drop it.
pub(super) fn refuse_ignored(raw: &Value, scene: &Scene) -> Result<()> {
    let set: Vec<Ignored> = ignored_keys(scene)
        .into_iter()
        .filter(|i| lookup(raw, i.key).is_some_and(|v| !v.is_null()))
        .collect();
    let Some(first) = set.first() else {
        return Ok(());
    };
    let mut reason = format!(
        "ignored by {} ({}); remove it or use --set {}=null",
        first.by, first.why, first.key
    );
    for i in &set[1..] {
        reason += &format!("; `{}` is ignored too (by {})", i.key, i.by);
    }
    Err(Error::config(first.key, reason))
}

/// Remove from `value` every key `scene` ignores.
pub(super) fn drop_ignored(value: &mut Value, scene: &Scene) {
    for i in ignored_keys(scene) {
        let (parent, last) = match i.key.rsplit_once('.') {
            Some((p, l)) => (lookup_mut(value, p), l),
            None => (Some(&mut *value), i.key),
        };
        if let Some(Value::Object(o)) = parent {
            o.remove(last);
        }
    }
}

fn lookup<'a>(v: &'a Value, dotted: &str) -> Option<&'a Value> {
    dotted.split('.').try_fold(v, |node, k| node.get(k))
}

fn lookup_mut<'a>(v: &'a mut Value, dotted: &str) -> Option<&'a mut Value> {
    dotted.split('.').try_fold(v, |node, k| node.get_mut(k))
}

#[cfg(test)]
mod tests {
    use crate::error::Error;
    use crate::problem::config::from_value;
    use serde_json::{json, Value};

    /// A valid 2D scene with `extra` merged in.
    fn with(extra: Value) -> Value {
        let mut v = json!({
            "dim": 2, "n": [32, 32], "dt": 0.001, "max_steps": 3,
            "initial": {"shape": "sphere", "radius": 6.0}
        });
        v.as_object_mut()
            .unwrap()
            .extend(extra.as_object().unwrap().clone());
        v
    }

    fn refused_field(v: Value) -> Option<(String, String)> {
        match from_value(v) {
            Err(Error::Config { field, reason }) => Some((field, reason)),
            Err(e) => panic!("unexpected error {e}"),
            Ok(_) => None,
        }
    }

    #[test]
    fn each_ignored_key_is_refused_by_name() {
        for (extra, key) in [
            (json!({"method": "fd", "scheme": "sbdf1"}), "scheme"),
            (json!({"method": "fd", "adaptive": false}), "adaptive"),
            (json!({"method": "fd", "laplacian": "fd"}), "laplacian"),
            (json!({"method": "fd", "stabilizer": {}}), "stabilizer"),
            (json!({"method": "fd", "lbfgs_memory": 5}), "lbfgs_memory"),
            (
                json!({"dynamics": "relaxational", "scheme": "sbdf2"}),
                "scheme",
            ),
            (
                json!({"dynamics": "relaxational", "adaptive": true}),
                "adaptive",
            ),
            (json!({"lbfgs_memory": 5}), "lbfgs_memory"),
            (
                json!({"area": {"method": "none", "alpha": 0.1}}),
                "area.alpha",
            ),
        ] {
            let (field, reason) = refused_field(with(extra.clone()))
                .unwrap_or_else(|| panic!("{extra} was accepted"));
            assert_eq!(field, key, "{extra}");
            assert!(reason.contains(&format!("--set {key}=null")), "{reason}");
        }
    }

    #[test]
    fn used_keys_and_nulls_are_accepted() {
        for extra in [
            json!({"scheme": "sbdf2", "laplacian": "fd", "stabilizer": {"s2": 1.0}}),
            json!({"dynamics": "relaxational", "lbfgs_memory": 3, "stabilizer": {"s2": 1.0},
                   "laplacian": "fd", "dt": 0.1}),
            json!({"method": "fd", "area": {"method": "lagrangian", "alpha": 0.01}}),
            json!({"area": {"method": "projection", "alpha": null}}),
        ] {
            assert_eq!(refused_field(with(extra.clone())), None, "{extra}");
        }
    }

    #[test]
    fn every_ignored_key_of_the_scene_is_named() {
        let (field, reason) = refused_field(with(
            json!({"method": "fd", "scheme": "sbdf1", "adaptive": false}),
        ))
        .unwrap();
        assert_eq!(field, "scheme");
        assert!(reason.contains("`adaptive`"), "{reason}");
    }

    #[test]
    fn resolved_value_drops_ignored_keys_and_reads_back() {
        for extra in [
            json!({"method": "fd"}),
            json!({"dynamics": "relaxational", "dt": 0.1}),
            json!({"area": {"method": "none"}}),
            json!({"scheme": "sbdf2"}),
        ] {
            let scene = from_value(with(extra.clone())).unwrap();
            let v = scene.resolved_value();
            let back = from_value(v.clone()).unwrap_or_else(|e| panic!("{extra}: {e}\n{v}"));
            back.validate().unwrap();
            assert_eq!(back.resolved_value(), v, "{extra}");
        }
        let fd = from_value(with(json!({"method": "fd"})))
            .unwrap()
            .resolved_value();
        for key in [
            "scheme",
            "adaptive",
            "laplacian",
            "stabilizer",
            "lbfgs_memory",
        ] {
            assert!(fd.get(key).is_none(), "fd spec keeps {key}");
        }
        let sp = from_value(with(json!({}))).unwrap().resolved_value();
        assert!(sp["area"].get("alpha").is_none() && sp.get("lbfgs_memory").is_none());
        assert!(sp.get("scheme").is_some() && sp.get("stabilizer").is_some());
    }
}
