//! Study files (`runs/studies/*.json`): a small strict schema per study, with the scenes it
//! varies given inline (as scene-file objects) or as a path to a scene file.
//!
//! Every study file has `"study"` (the study's name, checked against the command), an optional
//! `"description"`, the study's own keys, and an optional `"quick"` object whose keys replace
//! the file's (objects merged key by key, `null` removing a key) under `--quick`. Unknown keys
//! are refused naming the key; a scene built from a study is validated like a scene file, its
//! errors naming the study key that holds it (`time.scene.dt`).

use crate::error::{Error, Result};
use crate::problem::config::{self, Scene};
use serde::de::DeserializeOwned;
use serde_json::Value;
use std::path::Path;

/// Whether `path` holds a study file: a JSON object with a `"study"` key (a scene file never
/// has one). Unreadable or invalid files are not, and are reported by whoever reads them.
pub fn is_study_file(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| serde_json::from_str::<Value>(&t).ok())
        .is_some_and(|v| v.get("study").is_some())
}

/// Read the study file at `path` for the study `name`, `--quick` applied if `quick`.
///
/// # Errors
/// `Error::Config` naming the field: an unreadable file or bad JSON (`(study file)`), a
/// `"study"` other than `name`, an unknown key, a wrong type.
pub fn load<T: DeserializeOwned>(path: &Path, name: &str, quick: bool) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        Error::config(
            "(study file)",
            format!("{} cannot be read: {e}", path.display()),
        )
    })?;
    let mut value: Value = serde_json::from_str(&text).map_err(|e| {
        Error::config(
            "(study file)",
            format!("{} is not valid JSON: {e}", path.display()),
        )
    })?;
    let Value::Object(top) = &mut value else {
        return Err(Error::config(
            "(top level)",
            "a study file is a JSON object",
        ));
    };
    match top.get("study") {
        Some(Value::String(s)) if s == name => {}
        Some(other) => {
            return Err(Error::config(
                "study",
                format!("this command runs the {name:?} study, the file is for {other}"),
            ))
        }
        None => {
            return Err(Error::config(
                "study",
                format!("missing (expected {name:?})"),
            ))
        }
    }
    let patch = top.remove("quick");
    if quick {
        match patch {
            Some(p @ Value::Object(_)) => merge(&mut value, &p),
            Some(_) => return Err(Error::config("quick", "must be an object")),
            None => return Err(Error::config("quick", "--quick needs a \"quick\" object")),
        }
    }
    serde_path_to_error::deserialize::<_, T>(value).map_err(|e| {
        let path = e.path().to_string();
        let reason = e.into_inner().to_string();
        // serde names an unknown key in the message, at the path of the object holding it.
        let unknown = reason
            .strip_prefix("unknown field `")
            .and_then(|r| r.split_once('`'))
            .map(|(key, _)| key.to_string());
        let field = match (unknown, path.as_str()) {
            (Some(key), ".") => key,
            (Some(key), p) if !p.ends_with(&key) => format!("{p}.{key}"),
            (Some(_), p) => p.to_string(),
            (None, ".") => "(top level)".to_string(),
            (None, p) => p.to_string(),
        };
        Error::config(field, reason)
    })
}

/// Merge `patch` into `base`: objects key by key (recursively), a `null` removing the key,
/// anything else replacing.
pub fn merge(base: &mut Value, patch: &Value) {
    match (base, patch) {
        (Value::Object(b), Value::Object(p)) => {
            for (k, v) in p {
                if v.is_null() {
                    b.remove(k);
                } else {
                    merge(b.entry(k.clone()).or_insert(Value::Null), v);
                }
            }
        }
        (b, p) => *b = p.clone(),
    }
}

/// The scene the study key `field` gives (an inline scene object, or a path relative to the
/// study file's folder `dir`), with the `patches` merged in order, validated and checked against the memory
/// available.
///
/// # Errors
/// `Error::Config` naming `field.<scene key>`.
pub fn scene(value: &Value, patches: &[Value], field: &str, dir: &Path) -> Result<Scene> {
    let within = |e: Error| match e {
        Error::Config { field: f, reason } => Error::config(format!("{field}.{f}"), reason),
        other => other,
    };
    let mut v = match value {
        Value::String(p) => {
            let path = dir.join(p);
            let text = std::fs::read_to_string(&path).map_err(|e| {
                Error::config(field, format!("{} cannot be read: {e}", path.display()))
            })?;
            serde_json::from_str(&text).map_err(|e| {
                Error::config(field, format!("{} is not valid JSON: {e}", path.display()))
            })?
        }
        Value::Object(_) => value.clone(),
        _ => {
            return Err(Error::config(
                field,
                "must be a scene object or the path of a scene file",
            ))
        }
    };
    for p in patches {
        merge(&mut v, p);
    }
    let s = config::from_value(v).map_err(within)?;
    s.validate().map_err(within)?;
    crate::problem::memory::check(&s).map_err(within)?;
    Ok(s)
}

/// Worker threads of the study `name` in the file at `path` (`--quick` applied if `quick`):
/// the largest `threads` its scenes (the values of its `scene` keys, inline or files) set, else
/// all cores. Each run's engine splits its work by its own scene's `threads`.
///
/// # Errors
/// As [`load`]; a scene file that cannot be read is left to the study to report.
pub fn threads(path: &Path, name: &str, quick: bool) -> Result<usize> {
    fn scenes<'v>(v: &'v Value, found: &mut Vec<&'v Value>) {
        match v {
            Value::Object(o) => {
                for (k, inner) in o {
                    if k == "scene" {
                        found.push(inner);
                    } else {
                        scenes(inner, found);
                    }
                }
            }
            Value::Array(a) => a.iter().for_each(|inner| scenes(inner, found)),
            _ => {}
        }
    }
    let study: Value = load(path, name, quick)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut found = Vec::new();
    scenes(&study, &mut found);
    let set = found.into_iter().filter_map(|v| {
        let file: Value;
        let scene = match v {
            Value::String(p) => {
                file = serde_json::from_str(&std::fs::read_to_string(dir.join(p)).ok()?).ok()?;
                &file
            }
            other => other,
        };
        scene.get("threads")?.as_u64().map(|k| k as usize)
    });
    Ok(set.max().unwrap_or_else(crate::cpu::cores).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The `threads` of a study's scenes, inline or in a file, the largest of them; all cores
    /// when none sets it.
    #[test]
    fn threads_come_from_the_scenes() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("base.json"), r#"{"dim": 2, "threads": 3}"#).unwrap();
        let study = |v: Value| {
            let p = dir.path().join("s.json");
            std::fs::write(&p, v.to_string()).unwrap();
            threads(&p, "x", false).unwrap()
        };
        assert_eq!(study(json!({"study": "x", "scene": "base.json"})), 3);
        assert_eq!(
            study(json!({"study": "x", "a": {"scene": {"threads": 5}}, "scene": "base.json"})),
            5
        );
        assert_eq!(
            study(json!({"study": "x", "scene": {"dim": 2}})),
            crate::cpu::cores()
        );
    }

    /// Objects merge key by key, `null` removes, scalars and arrays replace.
    #[test]
    fn merge_is_recursive() {
        let mut a = json!({"x": 1, "o": {"p": 2, "q": 3}, "l": [1, 2]});
        merge(
            &mut a,
            &json!({"o": {"q": null, "r": 4}, "l": [5], "y": "s"}),
        );
        assert_eq!(
            a,
            json!({"x": 1, "o": {"p": 2, "r": 4}, "l": [5], "y": "s"})
        );
    }

    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Tiny {
        study: String,
        #[serde(default)]
        description: String,
        steps: usize,
    }

    fn load_text(text: &str, quick: bool) -> Result<Tiny> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.json");
        std::fs::write(&p, text).unwrap();
        load(&p, "tiny", quick)
    }

    /// `--quick` takes the quick block's values; an unknown key, a wrong study name and a
    /// missing quick block are refused naming the field.
    #[test]
    fn quick_and_strictness() {
        let t = r#"{"study": "tiny", "steps": 100, "quick": {"steps": 3}}"#;
        assert_eq!(load_text(t, false).unwrap().steps, 100);
        assert_eq!(load_text(t, true).unwrap().steps, 3);
        let field = |r: Result<Tiny>| match r {
            Err(Error::Config { field, .. }) => field,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            field(load_text(
                r#"{"study": "tiny", "steps": 1, "stpes": 2}"#,
                false
            )),
            "stpes"
        );
        assert_eq!(
            field(load_text(r#"{"study": "other", "steps": 1}"#, false)),
            "study"
        );
        assert_eq!(
            field(load_text(r#"{"study": "tiny", "steps": 1}"#, true)),
            "quick"
        );
        assert_eq!(
            field(load_text(r#"{"study": "tiny", "steps": "a"}"#, false)),
            "steps"
        );
    }
}
