//! The walls between the layers of `src/` (docs/src/architecture.md, "The walls").
//!
//! Every file of `src/` belongs to the top-level module it lies in (`src/engines/fd/mod.rs` to
//! `engines`; `lib.rs` and `main.rs` to none). The test reads every file, drops comments (doc
//! comments included), string and character literals, and finds the modules it reaches: the first
//! segment of every path that starts at the crate root, `crate::x` (and `$crate::x` in macros),
//! each item of a grouped `use crate::{a, b::c}`, and `super::` chains that climb to the root.
//! A module reaching one that its row of [`RULES`] lists is a violation, reported as
//! `file:line: rule (path)`. Only `commands` (and `lib.rs`, `main.rs`) may know the command
//! line: the identifier `clap`, the attributes `#[arg]`, `#[command]`, `#[clap]`, and the
//! derives `Args`, `Parser`, `Subcommand`, `ValueEnum`.
//!
//! The manual states the same table: [`the_manual_states_these_walls`] compares them.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Each top-level module of `src/` and the modules it may not reach, from the bottom up.
const RULES: &[(&str, &[&str])] = &[
    (
        "error",
        &[
            "cpu", "npy", "analysis", "problem", "engines", "output", "driver", "commands",
        ],
    ),
    (
        "cpu",
        &[
            "npy", "analysis", "problem", "engines", "output", "driver", "commands",
        ],
    ),
    (
        "npy",
        &[
            "cpu", "analysis", "problem", "engines", "output", "driver", "commands",
        ],
    ),
    (
        "analysis",
        &["problem", "engines", "output", "driver", "commands"],
    ),
    ("problem", &["engines", "output", "driver", "commands"]),
    ("engines", &["output", "driver", "commands"]),
    ("output", &["engines", "driver", "commands"]),
    ("driver", &["commands"]),
    ("commands", &[]),
];

/// The modules that may know the command line (besides `lib.rs` and `main.rs`).
const COMMAND_LINE: &[&str] = &["commands"];

/// The manual's page that states the walls.
const PAGE: &str = "docs/src/architecture.md";

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Punct(char),
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    line: usize,
}

/// The tokens of `src` that matter here: identifiers, `::` and other punctuation, with their
/// lines; comments, string and character literals and numbers are dropped (of a lifetime, its
/// name stays, as an identifier).
fn tokens(src: &str) -> Vec<Token> {
    let c: Vec<char> = src.chars().collect();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    let at = |k: usize| c.get(k).copied().unwrap_or('\0');
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += usize::from(c[i] == '\n');
                    i += 1;
                }
            }
        } else if ch == '"' {
            i = skip_string(&c, i + 1, &mut line);
        } else if ch == '\'' {
            if at(i + 1) == '\\' {
                // An escape: the quote, the backslash and the escaped character, then to the
                // closing quote (`'\u{…}'`).
                i += 3;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if at(i + 2) == '\'' {
                i += 3;
            } else {
                // A lifetime or label: its name follows as an identifier.
                i += 1;
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            if matches!(word.as_str(), "r" | "br" | "cr") && (at(i) == '"' || at(i) == '#') {
                let mut j = i;
                while at(j) == '#' {
                    j += 1;
                }
                if at(j) == '"' {
                    i = skip_raw_string(&c, j + 1, j - i, &mut line);
                    continue;
                }
            }
            out.push(Token {
                tok: Tok::Ident(word),
                line,
            });
        } else if ch.is_ascii_digit() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
        } else if ch == ':' && at(i + 1) == ':' {
            out.push(Token {
                tok: Tok::PathSep,
                line,
            });
            i += 2;
        } else {
            out.push(Token {
                tok: Tok::Punct(ch),
                line,
            });
            i += 1;
        }
    }
    out
}

/// The index after the string literal whose contents start at `i`.
fn skip_string(c: &[char], mut i: usize, line: &mut usize) -> usize {
    while i < c.len() && c[i] != '"' {
        if c[i] == '\\' {
            i += 1;
        }
        *line += usize::from(c.get(i) == Some(&'\n'));
        i += 1;
    }
    i + 1
}

/// The index after the raw string literal with `hashes` hashes whose contents start at `i`.
fn skip_raw_string(c: &[char], mut i: usize, hashes: usize, line: &mut usize) -> usize {
    while i < c.len() {
        if c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#')) {
            return i + 1 + hashes;
        }
        *line += usize::from(c[i] == '\n');
        i += 1;
    }
    i
}

/// A module that a file reaches: the top-level module, the path as written (from the root),
/// and the line.
#[derive(Clone, Debug, PartialEq)]
struct Reach {
    module: String,
    path: String,
    line: usize,
}

/// The text of the path that starts at `t[i]`: identifiers joined by `::`, a group as `{…}`.
fn path_text(t: &[Token], mut i: usize) -> String {
    let mut text = String::new();
    loop {
        match t.get(i).map(|x| &x.tok) {
            Some(Tok::Ident(w)) => text.push_str(w),
            Some(Tok::Punct('*')) => return text + "*",
            Some(Tok::Punct('{')) => {
                let mut depth = 0;
                while let Some(tok) = t.get(i) {
                    match &tok.tok {
                        Tok::Punct('{') => {
                            depth += 1;
                            text.push('{');
                        }
                        Tok::Punct('}') => {
                            depth -= 1;
                            text.push('}');
                            if depth == 0 {
                                return text;
                            }
                        }
                        Tok::Punct(',') => text.push_str(", "),
                        Tok::Punct('*') => text.push('*'),
                        Tok::Ident(w) => text.push_str(w),
                        Tok::PathSep => text.push_str("::"),
                        Tok::Punct(_) => {}
                    }
                    i += 1;
                }
                return text;
            }
            _ => return text,
        }
        i += 1;
        if t.get(i).map(|x| &x.tok) != Some(&Tok::PathSep) {
            return text;
        }
        text.push_str("::");
        i += 1;
    }
}

/// The modules reached by the path that continues at the crate root at `t[i]` (the token after
/// `crate::` or after a `super::` chain that climbed to the root): one, or each item of a group.
fn from_root(t: &[Token], i: usize, out: &mut Vec<Reach>) {
    match t.get(i).map(|x| &x.tok) {
        Some(Tok::Ident(name)) => {
            out.push(Reach {
                module: name.clone(),
                path: format!("crate::{}", path_text(t, i)),
                line: t[i].line,
            });
        }
        Some(Tok::Punct('{')) => {
            // Each item of the group: its first identifier, at depth 1.
            let (mut k, mut depth, mut first) = (i + 1, 1usize, true);
            while let Some(tok) = t.get(k) {
                match &tok.tok {
                    Tok::Punct('{') => depth += 1,
                    Tok::Punct('}') => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    Tok::Punct(',') if depth == 1 => first = true,
                    Tok::Ident(name) if depth == 1 && first => {
                        first = false;
                        if name != "self" {
                            out.push(Reach {
                                module: name.clone(),
                                path: format!("crate::{}", path_text(t, k)),
                                line: tok.line,
                            });
                        }
                    }
                    _ => {}
                }
                k += 1;
            }
        }
        _ => {}
    }
}

/// The module path of the file `rel` (relative to `src/`): `engines/fd/mod.rs` is
/// `[engines, fd]`, `lib.rs` and `main.rs` the root.
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.strip_suffix(".rs").unwrap_or(&last);
    if parts.is_empty() && (stem == "lib" || stem == "main") {
        return Vec::new();
    }
    if stem != "mod" {
        parts.push(stem.to_string());
    }
    parts
}

/// Every module the source `src` of the file at module path `file` reaches, and the lines
/// where it knows the command line.
fn reaches(file: &[String], src: &str) -> (Vec<Reach>, Vec<(usize, String)>) {
    let t = tokens(src);
    let (mut out, mut clap) = (Vec::new(), Vec::new());
    // Inline modules (`mod tests { … }`): their names and the brace depth inside them.
    let (mut inline, mut depth): (Vec<(String, usize)>, usize) = (Vec::new(), 0);
    let ident = |k: usize| match t.get(k).map(|x| &x.tok) {
        Some(Tok::Ident(w)) => Some(w.as_str()),
        _ => None,
    };
    let is = |k: usize, want: &Tok| t.get(k).map(|x| &x.tok) == Some(want);
    for i in 0..t.len() {
        let after_sep = i > 0 && is(i - 1, &Tok::PathSep);
        match &t[i].tok {
            Tok::Punct('{') => {
                depth += 1;
                if i >= 2 && ident(i - 2) == Some("mod") {
                    if let Some(name) = ident(i - 1) {
                        inline.push((name.to_string(), depth));
                    }
                }
            }
            Tok::Punct('}') => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            Tok::Ident(w) if w == "crate" && !after_sep && is(i + 1, &Tok::PathSep) => {
                from_root(&t, i + 2, &mut out);
            }
            Tok::Ident(w) if w == "super" && !after_sep => {
                let mut here: Vec<&str> = file.iter().map(String::as_str).collect();
                here.extend(inline.iter().map(|(n, _)| n.as_str()));
                let mut k = i;
                while ident(k) == Some("super") && is(k + 1, &Tok::PathSep) {
                    if here.pop().is_none() {
                        break;
                    }
                    k += 2;
                }
                if here.is_empty() && k > i {
                    from_root(&t, k, &mut out);
                }
            }
            Tok::Ident(w) if w == "clap" => clap.push((t[i].line, "clap".to_string())),
            Tok::Punct('#') => {
                let k = if is(i + 1, &Tok::Punct('!')) {
                    i + 2
                } else {
                    i + 1
                };
                if !is(k, &Tok::Punct('[')) {
                    continue;
                }
                match ident(k + 1) {
                    Some(a @ ("arg" | "command" | "clap")) => {
                        clap.push((t[i].line, format!("#[{a}]")));
                    }
                    Some("derive") => {
                        let mut j = k + 2;
                        while j < t.len() && !is(j, &Tok::Punct(']')) {
                            if let Some(d @ ("Args" | "Parser" | "Subcommand" | "ValueEnum")) =
                                ident(j)
                            {
                                clap.push((t[i].line, format!("derive({d})")));
                            }
                            j += 1;
                        }
                    }
                    _ => {}
                }
            }
            _ => {}
        }
    }
    (out, clap)
}

/// The violations in the file `rel` (relative to `src/`) of source `src`, each
/// `src/rel:line: rule (path)`.
fn check_file(rel: &Path, src: &str) -> Vec<String> {
    let file = module_path(rel);
    let Some(layer) = file.first() else {
        return Vec::new(); // lib.rs, main.rs: the roots reach everything.
    };
    let name = format!("src/{}", rel.display());
    let forbidden = RULES
        .iter()
        .find(|(m, _)| m == layer)
        .map_or(&[][..], |(_, f)| *f);
    let (reached, clap) = reaches(&file, src);
    let mut out = Vec::new();
    for r in reached {
        if forbidden.contains(&r.module.as_str()) {
            out.push(format!(
                "{name}:{}: {layer} may not reach {} ({})",
                r.line, r.module, r.path
            ));
        }
    }
    if !COMMAND_LINE.contains(&layer.as_str()) {
        for (line, what) in clap {
            out.push(format!(
                "{name}:{line}: only commands know the command line ({what})"
            ));
        }
    }
    out
}

/// The Rust files under `dir`, sorted.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The violations of the whole source tree.
fn check_tree(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files
        .iter()
        .flat_map(|p| {
            let text = std::fs::read_to_string(p).expect("a source file reads");
            check_file(p.strip_prefix(src).expect("under src"), &text)
        })
        .collect()
}

#[test]
fn no_layer_crosses_a_wall() {
    let crossed = check_tree(&src_dir());
    assert!(
        crossed.is_empty(),
        "walls crossed (docs/src/architecture.md, \"The walls\"):\n{}",
        crossed.join("\n")
    );
}

/// A synthetic engine file that crosses the walls in every form the checker reads, and does
/// the same in comments and strings, which do not count.
#[test]
fn a_crossed_wall_is_reported() {
    let src = r##"//! Mentions crate::driver::simulation in a doc comment.
use crate::problem::grid::Grid;
use crate::{
    engines::Engine,
    output::npy::write_npy,
};
/* crate::commands in a block /* nested */ comment */
fn f<'a>(x: &'a str) -> char {
    let _ = "crate::commands::cli in a string";
    let _ = r#"crate::output in a raw string"#;
    crate::driver::simulation::build_engine(x);
    if x.is_empty() { '\'' } else { '"' }
}
mod tests {
    use super::super::super::super::commands::run;
}
#[derive(Debug, clap::Args)]
struct A {
    #[arg(long)]
    b: bool,
}
"##;
    let got = check_file(Path::new("engines/fd/fake.rs"), src);
    let want = [
        "src/engines/fd/fake.rs:5: engines may not reach output (crate::output::npy::write_npy)",
        "src/engines/fd/fake.rs:11: engines may not reach driver \
         (crate::driver::simulation::build_engine)",
        "src/engines/fd/fake.rs:15: engines may not reach commands (crate::commands::run)",
        "src/engines/fd/fake.rs:17: only commands know the command line (derive(Args))",
        "src/engines/fd/fake.rs:17: only commands know the command line (clap)",
        "src/engines/fd/fake.rs:19: only commands know the command line (#[arg])",
    ];
    assert_eq!(got, want);
    // The same file in commands crosses nothing; `$crate::` in a macro counts as `crate::`.
    assert!(check_file(Path::new("commands/fake.rs"), src).is_empty());
    let got = check_file(
        Path::new("npy/mod.rs"),
        "macro_rules! m { () => { $crate::cpu::x() } }",
    );
    assert_eq!(
        got,
        ["src/npy/mod.rs:1: npy may not reach cpu (crate::cpu::x)"]
    );
}

/// The rules cover every top-level module of `src/`, and each names only modules there.
#[test]
fn every_module_has_a_row() {
    let mut found = BTreeSet::new();
    for e in std::fs::read_dir(src_dir()).expect("src reads") {
        let p = e.expect("an entry").path();
        let name = p
            .file_name()
            .expect("a name")
            .to_string_lossy()
            .into_owned();
        match name.strip_suffix(".rs") {
            Some("lib" | "main") => {}
            Some(stem) => {
                found.insert(stem.to_string());
            }
            None if p.is_dir() => {
                found.insert(name);
            }
            None => {}
        }
    }
    let rows: BTreeSet<String> = RULES.iter().map(|(m, _)| m.to_string()).collect();
    assert_eq!(rows, found, "RULES must have one row per top-level module");
    for (m, forbidden) in RULES {
        for f in *forbidden {
            assert!(rows.contains(*f) && f != m, "{m}: `{f}` is no other module");
        }
    }
}

/// The backticked names in a table cell.
fn names(cell: &str) -> BTreeSet<String> {
    cell.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// The table of "The walls" in the manual states exactly [`RULES`]: each row is
/// `| `module` | modules it may use | modules it may not reach |`.
#[test]
fn the_manual_states_these_walls() {
    let page = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(PAGE))
        .expect("the architecture page reads");
    let section = page
        .split("\n## ")
        .find(|s| s.starts_with("The walls"))
        .expect("a section \"The walls\"");
    let mut rows = Vec::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.trim_matches('|').split('|').collect();
        assert_eq!(cells.len(), 3, "{line}");
        let module = names(cells[0]).into_iter().next().expect("a module");
        rows.push((module, names(cells[1]), names(cells[2])));
    }
    let all: BTreeSet<String> = RULES.iter().map(|(m, _)| m.to_string()).collect();
    assert_eq!(
        rows.iter().map(|r| r.0.as_str()).collect::<Vec<_>>(),
        RULES.iter().map(|r| r.0).collect::<Vec<_>>(),
        "the rows of {PAGE}, in order"
    );
    for ((module, may, may_not), (_, forbidden)) in rows.iter().zip(RULES) {
        let forbidden: BTreeSet<String> = forbidden.iter().map(|f| f.to_string()).collect();
        assert_eq!(*may_not, forbidden, "{PAGE}: what `{module}` may not reach");
        let rest: BTreeSet<String> = all
            .iter()
            .filter(|m| *m != module && !forbidden.contains(*m))
            .cloned()
            .collect();
        assert_eq!(*may, rest, "{PAGE}: what `{module}` may use");
    }
}
