//! The study registry: every `vesicle study NAME`, read from the command line's own definition
//! ([`list`]), and the runner of a study by name ([`run`]) that the command line and the Python
//! bindings both call. A study writes its folder (table, CSV files, charts) as the command
//! does and returns its tables as typed columns ([`Table`]), taken from the study's report in
//! memory: the same bytes its CSV files are written from, not read back from the folder.

use crate::commands::cli::Cli;
use crate::commands::study::budding::Budding;
use crate::commands::study::convergence::Convergence;
use crate::commands::study::harness::{self, Report, Study};
use crate::commands::study::precision::Precision;
use crate::commands::study::stability::Stability;
use crate::commands::study::{file, stationary};
use crate::error::{Error, Result};
use crate::problem::config;
use clap::CommandFactory;
use std::path::Path;

/// A study of the command line: `vesicle study NAME`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// The subcommand (and the study file's `"study"`).
    pub name: String,
    /// Its one-line description (the command's help).
    pub about: String,
}

/// Every study the command line runs, in the order of `vesicle study --help`: read from the
/// command line's definition, so that a study added there is listed here.
pub fn list() -> Vec<Entry> {
    let cli = Cli::command();
    let study = cli
        .get_subcommands()
        .find(|c| c.get_name() == "study")
        .expect("the command line has a study command");
    study
        .get_subcommands()
        .filter(|c| c.get_name() != "help")
        .map(|c| Entry {
            name: c.get_name().to_string(),
            about: c
                .get_about()
                .map(|a| a.to_string())
                .unwrap_or_default()
                .lines()
                .next()
                .unwrap_or_default()
                .to_string(),
        })
        .collect()
}

/// The names of [`list`].
pub fn names() -> Vec<String> {
    list().into_iter().map(|e| e.name).collect()
}

/// One column of a study table.
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    /// Counts (every cell an integer).
    Int(Vec<i64>),
    /// Numbers (an empty cell is NaN).
    Float(Vec<f64>),
    /// Names and classes.
    Text(Vec<String>),
}

/// A study table: a CSV file of the study's folder as columns.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The file's stem (`stability` for `stability.csv`).
    pub name: String,
    /// `(header, column)` in the file's order.
    pub columns: Vec<(String, Column)>,
}

/// What a study is run on, as `vesicle study NAME FILE [--quick] [--set K=V] --out OUT
/// [--force]`.
#[derive(Clone, Copy, Debug)]
pub struct Args<'a> {
    /// The study file (or, for `stationary`, a scene file).
    pub file: &'a Path,
    /// Its quick variant.
    pub quick: bool,
    /// Overrides of a scene file (`stationary` on a scene file only).
    pub set: &'a [String],
    /// The output folder.
    pub out: &'a Path,
    /// Replace an existing output folder.
    pub force: bool,
}

/// Run the study `name` as the command line does (its thread pool, its checks, its folder)
/// and return its tables.
///
/// # Errors
/// `Error::Config` on field `study` for a name not in [`list`]; otherwise the study's errors.
pub fn run(name: &str, args: &Args) -> Result<Vec<Table>> {
    match name {
        Convergence::NAME => run_file::<Convergence>(args),
        Precision::NAME => run_file::<Precision>(args),
        Stability::NAME => run_file::<Stability>(args),
        Budding::NAME => run_file::<Budding>(args),
        "stationary" => run_stationary(args),
        _ => Err(Error::config(
            "study",
            format!(
                "unknown study {name:?}: expected one of {}",
                names().join(", ")
            ),
        )),
    }
}

/// A study `S` whose output is its report's tables, beside the rows it returns.
struct Tables<S>(std::marker::PhantomData<S>);

impl<S: Study> Study for Tables<S> {
    const NAME: &'static str = S::NAME;
    type Spec = S::Spec;
    type Output = Vec<(String, Vec<u8>)>;

    fn measure(spec: &S::Spec, dir: &Path) -> Result<(Self::Output, Report)> {
        let (_, report) = S::measure(spec, dir)?;
        Ok((report.tables.clone(), report))
    }
}

/// The study `S` of a study file in one pool of its threads ([`file::threads`]).
fn run_file<S: Study>(args: &Args) -> Result<Vec<Table>> {
    refuse_set(args)?;
    exists(args.file, "(study file)")?;
    let threads = file::threads(args.file, S::NAME, args.quick)?;
    let tables = crate::cpu::in_pool(threads, || {
        harness::run::<Tables<S>>(args.file, args.quick, args.out, args.force)
    })?;
    tables
        .iter()
        .map(|(file, bytes)| table(file, bytes))
        .collect()
}

/// The stationary study, on a study file or on a scene file (with `set` applied, in a pool of
/// the scene's threads).
fn run_stationary(args: &Args) -> Result<Vec<Table>> {
    if file::is_study_file(args.file) {
        refuse_set(args)?;
        stationary::stationary_file(args.file, args.quick, args.out, args.force)?;
    } else {
        if args.quick {
            return Err(Error::config(
                "--quick",
                "applies to a study file (one with a \"study\" key), not a scene file",
            ));
        }
        exists(args.file, "(scene file)")?;
        let scene = config::load(args.file, args.set)?;
        crate::driver::simulation::check_engine(&scene)?;
        crate::cpu::in_pool(scene.threads(), || {
            stationary::stationary(&scene, args.out, args.force)
        })?;
    }
    // The stationary study keeps its report to itself: its tables are read from the folder it
    // has just written (only its CSV files are there).
    folder_tables(args.out)
}

fn refuse_set(args: &Args) -> Result<()> {
    if args.set.is_empty() {
        Ok(())
    } else {
        Err(Error::config(
            "--set",
            "applies to a scene file; a study file sets its scene's keys itself",
        ))
    }
}

fn exists(path: &Path, field: &str) -> Result<()> {
    if path.exists() {
        Ok(())
    } else {
        Err(Error::config(
            field,
            format!("{} does not exist", path.display()),
        ))
    }
}

/// Every `*.csv` of `dir` as a table, by file name.
fn folder_tables(dir: &Path) -> Result<Vec<Table>> {
    let io = |source| Error::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|p| {
            let bytes = std::fs::read(p).map_err(|source| Error::Io {
                path: p.clone(),
                source,
            })?;
            let name = p.file_name().map(|n| n.to_string_lossy().to_string());
            table(&name.unwrap_or_default(), &bytes)
        })
        .collect()
}

/// A study's CSV bytes (a header, then rows) as typed columns: a column whose every cell is an
/// integer is [`Column::Int`] (a study writes its floats with a point, an exponent, `NaN` or
/// `inf`, so no float column reads as one), else one whose every cell is a number or empty is
/// [`Column::Float`], else [`Column::Text`].
///
/// # Errors
/// `Error::Config` on field `(csv)` for bytes that are not CSV (a bug).
pub fn table(file: &str, bytes: &[u8]) -> Result<Table> {
    let bug = |e: csv::Error| Error::config("(csv)", format!("{file}: {e}"));
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .from_reader(bytes);
    let headers: Vec<String> = reader
        .headers()
        .map_err(bug)?
        .iter()
        .map(str::to_string)
        .collect();
    let mut cells: Vec<Vec<String>> = vec![Vec::new(); headers.len()];
    for record in reader.records() {
        let record = record.map_err(bug)?;
        for (i, column) in cells.iter_mut().enumerate() {
            column.push(record.get(i).unwrap_or_default().to_string());
        }
    }
    let name = file.strip_suffix(".csv").unwrap_or(file).to_string();
    let columns = headers
        .into_iter()
        .zip(cells)
        .map(|(h, c)| (h, column(c)))
        .collect();
    Ok(Table { name, columns })
}

fn column(cells: Vec<String>) -> Column {
    if !cells.is_empty() {
        if let Ok(ints) = cells.iter().map(|c| c.parse::<i64>()).collect() {
            return Column::Int(ints);
        }
    }
    let number = |c: &String| {
        if c.is_empty() {
            Some(f64::NAN)
        } else {
            c.parse::<f64>().ok()
        }
    };
    match cells.iter().map(number).collect::<Option<Vec<f64>>>() {
        Some(floats) => Column::Float(floats),
        None => Column::Text(cells),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;

    /// The registry lists the command line's study subcommands, and runs each of them: a name
    /// it lists is never refused as unknown (a missing file is what it reports).
    #[test]
    fn every_study_of_the_command_line_is_listed_and_runs_by_name() {
        let names = names();
        for expected in [
            "convergence",
            "stationary",
            "precision",
            "stability",
            "budding",
        ] {
            assert!(
                names.iter().any(|n| n == expected),
                "{expected} in {names:?}"
            );
        }
        assert!(list().iter().all(|e| !e.about.is_empty()));
        let out = std::env::temp_dir().join("vesicle-registry-test-never-written");
        for name in &names {
            let args = Args {
                file: Path::new("/nonexistent/study.json"),
                quick: false,
                set: &[],
                out: &out,
                force: false,
            };
            match run(name, &args) {
                Err(Error::Config { field, .. }) => {
                    assert_ne!(field, "study", "{name} is listed but has no runner")
                }
                other => panic!("{name}: {other:?}"),
            }
        }
        let args = Args {
            file: Path::new("x.json"),
            quick: false,
            set: &[],
            out: &out,
            force: false,
        };
        match run("speed", &args) {
            Err(Error::Config { field, reason }) => {
                assert_eq!(field, "study");
                assert!(reason.contains("budding"), "{reason}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[derive(Serialize)]
    struct Row {
        series: String,
        x: f64,
        steps: usize,
        maybe: Option<f64>,
    }

    /// Typed columns from a study's CSV bytes: counts as integers, floats (1.0, NaN, empty) as
    /// floats, names as text; the floats read back to the same bits.
    #[test]
    fn rows_come_back_as_typed_columns() {
        let rows = [
            Row {
                series: "FD, h = 1".into(),
                x: 1.0,
                steps: 3,
                maybe: None,
            },
            Row {
                series: "spectral".into(),
                x: f64::NAN,
                steps: 0,
                maybe: Some(0.1 + 0.2),
            },
        ];
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in &rows {
            w.serialize(r).unwrap();
        }
        let bytes = w.into_inner().unwrap();
        let t = table("runs.csv", &bytes).unwrap();
        assert_eq!(t.name, "runs");
        let names: Vec<&str> = t.columns.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["series", "x", "steps", "maybe"]);
        assert_eq!(
            t.columns[0].1,
            Column::Text(vec!["FD, h = 1".into(), "spectral".into()])
        );
        match &t.columns[1].1 {
            Column::Float(x) => assert!(x[0] == 1.0 && x[1].is_nan()),
            other => panic!("{other:?}"),
        }
        assert_eq!(t.columns[2].1, Column::Int(vec![3, 0]));
        match &t.columns[3].1 {
            Column::Float(x) => assert!(x[0].is_nan() && x[1] == 0.1 + 0.2),
            other => panic!("{other:?}"),
        }
        let empty = table("none.csv", b"a,b\n").unwrap();
        assert_eq!(empty.columns[0].1, Column::Float(vec![]));
    }
}
