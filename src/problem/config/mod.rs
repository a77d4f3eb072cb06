//! The scene (run) file: a strict JSON description of one run, its defaults and its validation.
//!
//! Unknown keys are rejected, every field is checked by [`Scene::validate`], and every error
//! names the dotted key of the field and the reason. `--set key=value` overrides are applied to
//! the JSON before it is read ([`apply_override`]), so they are validated like the file itself;
//! `--set key=null` removes the key. A key the scene's method or dynamics ignores is refused
//! (see the `ignored` module's table).

mod c0;
mod ignored;
mod scene;
mod schedule;
mod shapes;
mod validation;

pub use c0::{C0Ball, C0Band, C0Cap, C0Field, C0File, C0Spec, Pole};
pub use scene::{
    axis_index, AdaptiveSettings, AdaptiveSpec, AdeMultiplier, AdeSpec, AreaMethod, AreaSpec,
    AutoTag, BilayerCoupleSpec, Device, Dynamics, FlowSpec, Laplacian, Method, OutputSpec, Scene,
    Scheme, Stabilizer, StabilizerSpec, Symmetry, VolumeRamp, CHECKPOINT_MINUTES, MAX_LBFGS_MEMORY,
    RECORD_ROWS, SERIAL_BELOW,
};
pub use schedule::Schedule;
pub use shapes::{
    Axisym, AxisymBranch, Capsule, Cup, Difference, Ellipsoid, Harmonic, Initial, Shape, Slab,
    Sphere, Spheroid, SpheroidKind, Star, Union,
};

use crate::error::{Error, Result};
use serde_json::Value;
use shapes::PATH_MARK;
use std::path::{Path, PathBuf};

/// Read a scene file, apply `--set` overrides and validate it.
///
/// # Errors
/// `Error::Config` naming the field for an unreadable file (`(scene file)`), malformed JSON
/// (`(file)`), unknown keys, wrong types, invalid values, and a grid whose estimated peak
/// memory exceeds the memory available (`n`, [`crate::problem::memory::check`]).
pub fn load(path: &Path, overrides: &[String]) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| {
        Error::config(
            "(scene file)",
            format!("{} cannot be read: {e}", path.display()),
        )
    })?;
    let value: Value = serde_json::from_slice(&bytes).map_err(|e| {
        let reason = format!("{} is not valid JSON: {e}", path.display());
        let text = std::str::from_utf8(&bytes).unwrap_or("");
        match nonfinite_field(text, e.line(), e.column()) {
            Some((field, token)) if e.to_string().contains("number out of range") => {
                Error::config(field, format!("must be a finite number, got {token}"))
            }
            _ => Error::config("(file)", reason),
        }
    })?;
    load_value(value, overrides, Some(path))
}

/// A scene from its JSON `value` (as read from a scene file), with `key=value` `overrides`
/// applied and validated exactly as [`load`] does: relative file paths inside the scene
/// (`initial.file`, a shape's `contour`, a `c0` field file) are taken beside `scene_file` when
/// it is given and such a file exists there, else as they are.
///
/// # Errors
/// As [`load`], past reading the file.
pub fn load_value(
    mut value: Value,
    overrides: &[String],
    scene_file: Option<&Path>,
) -> Result<Scene> {
    for o in overrides {
        apply_override(&mut value, o)?;
    }
    let mut scene = from_value(value)?;
    if let Some(path) = scene_file {
        match &mut scene.initial {
            Initial::File { file } => *file = resolve_relative(path, file),
            Initial::Shape(shape) => {
                for contour in shape.contours_mut() {
                    *contour = resolve_relative(path, contour);
                }
            }
        }
        if let C0Spec::Field(C0Field::File(f)) = &mut scene.c0 {
            f.file = resolve_relative(path, &f.file);
        }
    }
    scene.validate()?;
    crate::problem::memory::check(&scene)?;
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

/// Deserialize a scene from JSON, reporting the dotted path of a bad field, and refuse a key
/// that the scene's method or dynamics ignores (a key set to `null` counts as absent).
///
/// # Errors
/// `Error::Config` with the path of the offending key.
pub fn from_value(value: Value) -> Result<Scene> {
    objects_where_objects(&value)?;
    let scene = serde_path_to_error::deserialize::<_, Scene>(value.clone()).map_err(|e| {
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
            Some((inner, rest)) => missing_or(format!("{field}.{inner}"), rest),
            None => missing_or(field, &reason),
        }
    })?;
    ignored::refuse_ignored(&value, &scene)?;
    Ok(scene)
}

/// The error of `reason` at `field`; serde's "missing field `k`" names the object that lacks
/// the key, so that one names the key itself (`dt`, `initial.radius`) as the field.
fn missing_or(field: String, reason: &str) -> Error {
    let missing = reason
        .strip_prefix("missing field `")
        .and_then(|r| r.split_once('`'))
        .map(|(key, _)| key);
    match missing {
        Some(key) if field == "(top level)" => Error::config(key, "required, missing"),
        Some(key) => Error::config(format!("{field}.{key}"), "required, missing"),
        None => Error::config(field, reason),
    }
}

/// Serde reads a struct from an array too, positionally (`"area": ["lagrangian", 0.01]`); a
/// scene names its fields, so an array where an object belongs (the scene itself, `area`,
/// `volume`, `stabilizer`, `output`, `adaptive`, `c0`, `initial` and the shapes inside it) is refused.
fn objects_where_objects(scene: &Value) -> Result<()> {
    fn kind(v: &Value) -> &'static str {
        match v {
            Value::Null => "null",
            Value::Bool(_) => "a boolean",
            Value::Number(_) => "a number",
            Value::String(_) => "a string",
            Value::Array(_) => "an array",
            Value::Object(_) => "an object",
        }
    }
    fn shapes(v: &Value, at: &str) -> Result<()> {
        match v {
            Value::Array(_) => Err(Error::config(
                at,
                "must be an object {\"shape\": ..., ...} or {\"file\": ...}, got an array",
            )),
            Value::Object(o) => {
                for k in ["base", "minus"] {
                    if let Some(inner) = o.get(k) {
                        shapes(inner, &format!("{at}.{k}"))?;
                    }
                }
                if let Some(Value::Array(of)) = o.get("of") {
                    for (i, inner) in of.iter().enumerate() {
                        shapes(inner, &format!("{at}.of[{i}]"))?;
                    }
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }
    let Value::Object(top) = scene else {
        return Err(Error::config(
            "(top level)",
            format!(
                "a scene is a JSON object {{\"dim\": ..., ...}}, got {}",
                kind(scene)
            ),
        ));
    };
    for key in ["area", "volume", "stabilizer", "output", "adaptive", "c0"] {
        if let Some(v @ Value::Array(_)) = top.get(key) {
            return Err(Error::config(
                key,
                format!("must be an object of named fields, got {}", kind(v)),
            ));
        }
    }
    if let Some(Value::Object(output)) = top.get("output") {
        for key in ["records", "snapshots", "checkpoints"] {
            if let Some(v @ Value::Array(_)) = output.get(key) {
                return Err(Error::config(
                    format!("output.{key}"),
                    format!(
                        "must be a schedule object such as {{\"every_steps\": 100}}, got {}",
                        kind(v)
                    ),
                ));
            }
        }
    }
    if let Some(initial) = top.get("initial") {
        shapes(initial, "initial")?;
    }
    Ok(())
}

/// Fields read through an intermediate value (`adaptive`) lose the inner key of an error: read
/// the sub-object again as its concrete type to name it (`initial` and `c0` mark theirs).
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
        "adaptive" => inner::<AdaptiveSettings>(path, v),
        _ => None,
    }
}

/// A relative `.npy` path (`initial.file`, `c0.file`) is taken from the scene file's folder if
/// it exists there, else from the working directory.
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
/// `key=null` removes the key (nothing happens if it is absent), so the field takes its
/// default, or is reported missing if it is required.
///
/// # Errors
/// `Error::Config` if the text has no `=` or the path runs through a non-object.
pub fn apply_override(scene: &mut Value, assignment: &str) -> Result<()> {
    let (key, raw) = assignment
        .split_once('=')
        .ok_or_else(|| Error::config(assignment, "--set expects key=value"))?;
    let value = serde_json::from_str(raw).unwrap_or_else(|_| Value::String(raw.to_string()));
    let remove = value.is_null();
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
            if remove {
                obj.remove(*part);
            } else {
                obj.insert(part.to_string(), value);
            }
            return Ok(());
        }
        node = if remove {
            match obj.get_mut(*part) {
                Some(next) => next,
                None => return Ok(()),
            }
        } else {
            obj.entry(part.to_string())
                .or_insert_with(|| Value::Object(Default::default()))
        };
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{apply_override, from_value};
    use crate::error::Error;
    use serde_json::{json, Value};

    fn scene() -> Value {
        json!({
            "dim": 2, "n": [32, 32], "dt": 0.001, "max_steps": 3, "scheme": "sbdf2",
            "initial": {"shape": "sphere", "radius": 6.0},
            "area": {"method": "lagrangian", "alpha": 0.01}
        })
    }

    #[test]
    fn set_null_removes_the_key() {
        let mut v = scene();
        apply_override(&mut v, "scheme=null").unwrap();
        apply_override(&mut v, "area.alpha=null").unwrap();
        assert!(v.get("scheme").is_none());
        assert_eq!(v["area"], json!({"method": "lagrangian"}));
        // absent keys, also under an absent object: nothing to remove, nothing created
        apply_override(&mut v, "adaptive=null").unwrap();
        apply_override(&mut v, "c0.inside=null").unwrap();
        assert!(v.get("adaptive").is_none() && v.get("c0").is_none());
        // a path through a non-object is still refused
        assert!(apply_override(&mut v, "dt.x=null").is_err());
        let s = from_value(v).unwrap();
        assert_eq!(s.scheme, super::Scheme::Sbdf1);
        assert_eq!(s.alpha(), 1e-3);
    }

    #[test]
    fn set_null_on_a_required_key_reports_it_missing() {
        let mut v = scene();
        apply_override(&mut v, "dt=null").unwrap();
        match from_value(v) {
            Err(Error::Config { field, reason }) => {
                assert_eq!(
                    (field.as_str(), reason.as_str()),
                    ("dt", "required, missing")
                )
            }
            other => panic!("{other:?}"),
        }
    }
}
