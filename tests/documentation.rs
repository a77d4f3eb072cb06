//! The scene-file reference (`docs/src/reference/scene-file.md`) against the program's own keys.
//!
//! The keys are not listed here by hand: the scene loader refuses an unknown key with serde's
//! message "unknown field `zzz_unknown`, expected one of `a`, `b`, ...", so the test runs
//! `vesicle check runs/ellipse2d.json --set ...` with an unknown key at every level and reads
//! the accepted keys from the refusal:
//!
//! * the top level (`--set zzz_unknown=1`);
//! * every top-level key whose value is an object of named fields, found by setting each key in
//!   turn to `{"zzz_unknown": 1}` (so a new nested object is covered without touching this file);
//! * the two objects whose keys depend on a kind: `initial` (tag `shape`, plus the `{"file": ...}`
//!   form) and `c0` (tag `kind`); their kinds come from the refusal of an unknown kind, and each
//!   kind's keys from an unknown key next to that kind.
//!
//! The page documents each key as a row of a table whose header starts with `| key |`; the first
//! cell is the dotted key in backticks (`area.alpha`). In the tables of `initial` and `c0` the
//! second column, headed `kinds`, lists in backticks the kinds that take the key. The test fails
//! when a key the program accepts has no row (for every kind that takes it), and when a row names
//! a key, or a kind, that the program refuses.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::process::Command;

/// The reference page, relative to the crate root.
const PAGE: &str = "docs/src/reference/scene-file.md";
/// A valid scene that the probes modify.
const BASE: &str = "runs/ellipse2d.json";
/// A key no scene has.
const PROBE: &str = "zzz_unknown";
/// Objects whose keys depend on a kind: (top-level key, the key naming the kind).
const TAGGED: [(&str, &str); 2] = [("initial", "shape"), ("c0", "kind")];
/// Forms of a tagged object that are not one of its kinds: (top-level key, the form's name on
/// the page, a value of that form carrying the probe key).
const FORMS: [(&str, &str, &str); 1] = [(
    "initial",
    "file",
    r#"{"file": "zzz_unknown.npy", "zzz_unknown": 1}"#,
)];

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `vesicle check BASE --set s ...`: (exit code, stderr).
fn check(sets: &[String]) -> (Option<i32>, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_vesicle"));
    cmd.arg("check").arg(BASE).current_dir(crate_dir());
    for s in sets {
        cmd.arg("--set").arg(s);
    }
    let o = cmd.output().expect("the vesicle binary runs");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The error line of a scene the loader must refuse (exit 2).
fn refusal(sets: &[String]) -> String {
    let (code, err) = check(sets);
    assert_eq!(
        code,
        Some(2),
        "vesicle check {BASE} --set {sets:?} should be refused with exit 2; stderr:\n{err}"
    );
    err.lines()
        .find(|l| l.contains("invalid input"))
        .unwrap_or_else(|| panic!("no \"invalid input\" line for --set {sets:?}:\n{err}"))
        .to_string()
}

/// The dotted key an error line names: "error: invalid input: `FIELD`: reason".
fn field(line: &str) -> String {
    line.split_once("invalid input: `")
        .and_then(|(_, rest)| rest.split_once('`'))
        .map(|(f, _)| f.to_string())
        .unwrap_or_else(|| panic!("no field in {line:?}"))
}

/// The names in backticks in `text`.
fn backticked(text: &str) -> BTreeSet<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// The names a serde-style message lists after "expected": "expected `a`", "expected `a` or
/// `b`", "expected one of `a`, `b`, ..."; none for "there are no fields".
fn expected_names(line: &str) -> BTreeSet<String> {
    if line.contains("there are no fields") {
        return BTreeSet::new();
    }
    let (_, tail) = line
        .rsplit_once(", expected ")
        .unwrap_or_else(|| panic!("no \", expected\" list in {line:?}"));
    let names = backticked(tail);
    assert!(!names.is_empty(), "no names after \"expected\" in {line:?}");
    names
}

/// The keys accepted where the refusal `line` reports the probe key as unknown, if it does.
fn unknown_probe_keys(line: &str) -> Option<BTreeSet<String>> {
    line.contains(&format!("unknown field `{PROBE}`"))
        .then(|| expected_names(line))
}

/// What the program accepts.
struct ProgramKeys {
    /// Top-level keys.
    top: BTreeSet<String>,
    /// Keys of each top-level object with fixed fields (`area` → {`method`, ...}).
    plain: BTreeMap<String, BTreeSet<String>>,
    /// Keys of each kind (and extra form) of each tagged object, the tag included
    /// (`initial` → `sphere` → {`shape`, `radius`, `center`}).
    tagged: BTreeMap<String, BTreeMap<String, BTreeSet<String>>>,
}

fn program_keys() -> ProgramKeys {
    let top_line = refusal(&[format!("{PROBE}=1")]);
    let top = unknown_probe_keys(&top_line)
        .unwrap_or_else(|| panic!("the top level does not report {PROBE}: {top_line}"));
    assert!(
        top.len() >= 10 && top.contains("dim") && top.contains("initial"),
        "implausible top-level keys {top:?} from {top_line}"
    );

    let mut plain = BTreeMap::new();
    let probe_object = format!(r#"{{"{PROBE}": 1}}"#);
    for key in &top {
        if TAGGED.iter().any(|(t, _)| t == key) {
            continue;
        }
        let (code, err) = check(&[format!("{key}={probe_object}")]);
        if code == Some(0) {
            continue; // the key takes any value (free text)
        }
        let line = err
            .lines()
            .find(|l| l.contains("invalid input"))
            .unwrap_or("");
        if let Some(keys) = unknown_probe_keys(line) {
            plain.insert(key.clone(), keys);
        } else {
            assert!(
                !line.contains("missing field"),
                "`{key}` looks like an object whose keys depend on a kind ({line}); add it to \
                 TAGGED in tests/documentation.rs"
            );
        }
    }
    for must in ["adaptive", "area", "output", "stabilizer"] {
        assert!(
            plain.contains_key(must),
            "`{must}` was not found to be an object of named keys: {plain:?}"
        );
    }

    let mut tagged = BTreeMap::new();
    for (key, tag) in TAGGED {
        let line = refusal(&[format!(r#"{key}={{"{tag}": "{PROBE}"}}"#)]);
        assert_eq!(
            field(&line),
            format!("{key}.{tag}"),
            "an unknown `{key}.{tag}` should be refused naming `{key}.{tag}`: {line}"
        );
        let kinds = expected_names(&line);
        let mut by_kind = BTreeMap::new();
        for kind in kinds {
            let line = refusal(&[format!(r#"{key}={{"{tag}": "{kind}", "{PROBE}": 1}}"#)]);
            let mut keys = unknown_probe_keys(&line).unwrap_or_else(|| {
                panic!("`{key}` of kind `{kind}` does not report {PROBE}: {line}")
            });
            keys.insert(tag.to_string());
            by_kind.insert(kind, keys);
        }
        for (form_key, form, value) in FORMS {
            if form_key == key {
                let line = refusal(&[format!("{key}={value}")]);
                let keys = unknown_probe_keys(&line).unwrap_or_else(|| {
                    panic!("`{key}` in its `{form}` form does not report {PROBE}: {line}")
                });
                by_kind.insert(form.to_string(), keys);
            }
        }
        tagged.insert(key.to_string(), by_kind);
    }
    ProgramKeys { top, plain, tagged }
}

/// One documented key: its dotted path and, in a table with a `kinds` column, the kinds named.
#[derive(Debug)]
struct Row {
    line: usize,
    key: String,
    kinds: Option<BTreeSet<String>>,
}

/// The cells of a table row, `\|` kept inside a cell.
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut out = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                out.last_mut().unwrap().push('|');
                chars.next();
            }
            '|' => out.push(String::new()),
            _ => out.last_mut().unwrap().push(c),
        }
    }
    out.into_iter().map(|c| c.trim().to_string()).collect()
}

fn is_separator(line: &str) -> bool {
    let t = line.trim();
    t.starts_with('|') && t.chars().all(|c| matches!(c, '|' | '-' | ':' | ' '))
}

/// The rows of every table on the page whose header's first cell is `key`.
fn documented_rows(page: &str) -> Vec<Row> {
    let lines: Vec<&str> = page.lines().collect();
    let mut rows = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let is_header =
            lines[i].trim().starts_with('|') && lines.get(i + 1).is_some_and(|l| is_separator(l));
        if !is_header {
            i += 1;
            continue;
        }
        let header = cells(lines[i]);
        let with_kinds = header.get(1).map(String::as_str) == Some("kinds");
        i += 2;
        while i < lines.len() && lines[i].trim().starts_with('|') {
            if header.first().map(String::as_str) == Some("key") {
                let c = cells(lines[i]);
                let first = &c[0];
                let key = first
                    .strip_prefix('`')
                    .and_then(|k| k.strip_suffix('`'))
                    .filter(|k| {
                        !k.is_empty()
                            && k.chars().all(|ch| {
                                ch.is_ascii_lowercase() || ch.is_ascii_digit() || "._".contains(ch)
                            })
                    })
                    .unwrap_or_else(|| {
                        panic!(
                            "{PAGE}:{}: the first cell of a key table must be one dotted key in \
                             backticks, got {first:?}",
                            i + 1
                        )
                    });
                let kinds = with_kinds.then(|| backticked(c.get(1).map_or("", String::as_str)));
                rows.push(Row {
                    line: i + 1,
                    key: key.to_string(),
                    kinds,
                });
            }
            i += 1;
        }
    }
    rows
}

#[test]
fn every_scene_key_is_documented_and_every_documented_key_exists() {
    let page = std::fs::read_to_string(crate_dir().join(PAGE)).expect("the reference page");
    let rows = documented_rows(&page);
    assert!(
        rows.len() >= 20,
        "only {} key rows found on {PAGE}",
        rows.len()
    );
    let program = program_keys();
    let mut failures = Vec::new();

    // Every key the program accepts has a row (for every kind that takes it).
    let documented = |path: &str, kind: Option<&str>| {
        rows.iter().any(|r| {
            r.key == path
                && match (kind, &r.kinds) {
                    (None, _) => true,
                    (Some(k), Some(kinds)) => kinds.contains(k),
                    (Some(_), None) => false,
                }
        })
    };
    for key in &program.top {
        if !documented(key, None) {
            failures.push(format!("the top-level key `{key}` has no row on {PAGE}"));
        }
    }
    for (object, keys) in &program.plain {
        for key in keys {
            let path = format!("{object}.{key}");
            if !documented(&path, None) {
                failures.push(format!("`{path}` has no row on {PAGE}"));
            }
        }
    }
    for (object, kinds) in &program.tagged {
        for (kind, keys) in kinds {
            for key in keys {
                let path = format!("{object}.{key}");
                if !documented(&path, Some(kind)) {
                    failures.push(format!(
                        "`{path}` of kind `{kind}` has no row on {PAGE} naming `{kind}` in its \
                         kinds column"
                    ));
                }
            }
        }
    }

    // Every row names a key (and kinds) the program accepts.
    let mut seen = BTreeSet::new();
    for row in &rows {
        let at = format!("{PAGE}:{}", row.line);
        let (object, key) = match row.key.split_once('.') {
            Some((o, k)) => (Some(o), k),
            None => (None, row.key.as_str()),
        };
        match (object, &row.kinds) {
            (None, _) => {
                if !program.top.contains(key) {
                    failures.push(format!("{at}: `{key}` is not a key the program accepts"));
                }
                if !seen.insert(row.key.clone()) {
                    failures.push(format!("{at}: `{key}` is documented twice"));
                }
            }
            (Some(o), None) => match program.plain.get(o) {
                Some(keys) if keys.contains(key) => {
                    if !seen.insert(row.key.clone()) {
                        failures.push(format!("{at}: `{}` is documented twice", row.key));
                    }
                }
                Some(_) => failures.push(format!("{at}: the program refuses `{}`", row.key)),
                None if program.tagged.contains_key(o) => failures.push(format!(
                    "{at}: `{}` belongs to a table with a kinds column",
                    row.key
                )),
                None => failures.push(format!(
                    "{at}: `{o}` is not an object of named keys in the program"
                )),
            },
            (Some(o), Some(kinds)) => {
                let Some(by_kind) = program.tagged.get(o) else {
                    failures.push(format!(
                        "{at}: `{}` has a kinds column but `{o}` has no kinds",
                        row.key
                    ));
                    continue;
                };
                if kinds.is_empty() {
                    failures.push(format!("{at}: `{}` names no kind", row.key));
                }
                for kind in kinds {
                    match by_kind.get(kind) {
                        None => failures.push(format!(
                            "{at}: `{kind}` is not a kind of `{o}` (the program has {:?})",
                            by_kind.keys().collect::<Vec<_>>()
                        )),
                        Some(keys) if !keys.contains(key) => failures.push(format!(
                            "{at}: the program refuses `{}` in a `{o}` of kind `{kind}`",
                            row.key
                        )),
                        Some(_) => {
                            if !seen.insert(format!("{}#{kind}", row.key)) {
                                failures.push(format!(
                                    "{at}: `{}` of kind `{kind}` is documented twice",
                                    row.key
                                ));
                            }
                        }
                    }
                }
            }
        }
    }

    assert!(
        failures.is_empty(),
        "{PAGE} and the program disagree:\n  {}",
        failures.join("\n  ")
    );
}

/// The parser itself: a page with a missing key, an unknown key and an unknown kind is caught
/// by the checks above (run on a hand-made page and hand-made program keys, no binary).
#[test]
fn the_page_parser_reads_key_tables_only() {
    let page = "\
# t

| key | type | meaning |
|---|---|---|
| `dim` | 2 or 3 | the \\| dimension |
| `area.alpha` | number | α |

| key | kinds | type |
|---|---|---|
| `initial.radius` | `sphere`, `cup` | number |

| file | content |
|---|---|
| `timeseries.csv` | not a key table |
";
    let rows = documented_rows(page);
    let keys: Vec<&str> = rows.iter().map(|r| r.key.as_str()).collect();
    assert_eq!(keys, ["dim", "area.alpha", "initial.radius"]);
    assert_eq!(rows[0].kinds, None);
    assert_eq!(
        rows[2].kinds,
        Some(["sphere", "cup"].iter().map(|s| s.to_string()).collect())
    );
    assert_eq!(
        expected_names("error: invalid input: `x`: unknown field `zzz_unknown`, expected `of`"),
        ["of".to_string()].into()
    );
    assert_eq!(
        expected_names(
            "error: invalid input: `x`: unknown field `zzz_unknown`, expected `base` or `minus`"
        )
        .len(),
        2
    );
    assert_eq!(
        expected_names(
            "error: invalid input: `initial.shape`: unknown variant \"zzz_unknown\", expected one \
             of `sphere`, `ellipsoid`"
        )
        .len(),
        2
    );
    assert_eq!(
        field("error: invalid input: `c0.kind`: unknown kind"),
        "c0.kind"
    );
}
