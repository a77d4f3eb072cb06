//! What every study shares: read the study file (`--quick` applied), refuse an existing output
//! folder without `--force` before anything is computed, time the study, and write what it
//! produced — the printed table (also `NAME.txt`, closed by the study's wall time), its CSV
//! files (typed rows through [`table`]), its charts (PNG and SVG) and pictures (PNG).
//!
//! A study is a [`Study`]: a name, a spec read from its file, and a `measure` that turns the
//! spec into a [`Report`]. [`run`] does the rest; [`run_with`] does the same for a measurement
//! whose spec does not come from a study file (`vesicle study stationary` on a scene file).

use super::file;
use super::table::{self, Row};
use crate::error::{Error, Result};
use crate::output::chart::Figure;
use crate::output::{folder, RgbImage};
use crate::problem::config::Scene;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A study: its name (the file's `"study"`, the command, the `.txt` file's stem), its spec and
/// what it measures.
pub trait Study {
    /// `"convergence"`, `"stability"`, …
    const NAME: &'static str;
    /// The study file's keys.
    type Spec: DeserializeOwned;
    /// What the study returns to its caller (the rows, for tests and the library).
    type Output;
    /// Run the measurements of `spec` (scene paths relative to `dir`).
    ///
    /// # Errors
    /// `Error::Config` naming the study key; `Error::Blowup` if a run diverges.
    fn measure(spec: &Self::Spec, dir: &Path) -> Result<(Self::Output, Report)>;
}

/// What a study writes: the table, the CSV files, the charts.
#[derive(Default)]
pub struct Report {
    /// The printed table (the study's wall time is appended).
    pub text: String,
    /// `(file name, CSV bytes)`, from [`table::csv`].
    pub tables: Vec<(String, Vec<u8>)>,
    /// The same tables as typed columns ([`table::typed`]), for the library's callers.
    pub typed: Vec<table::Table>,
    /// `(file stem, figure)`: each written as `stem.png` and `stem.svg`.
    pub charts: Vec<(String, Figure)>,
    /// `(file name, picture)`: each written as a PNG file.
    pub images: Vec<(String, RgbImage)>,
}

impl Report {
    /// Add the CSV file `name` holding `rows` ([`table::csv`]).
    ///
    /// # Errors
    /// `Error::Config` if a row cannot be written (a bug).
    pub fn table<R: Row>(&mut self, name: &str, rows: &[R]) -> Result<()> {
        self.tables.push((name.to_string(), table::csv(rows)?));
        self.typed.push(table::typed(name, rows));
        Ok(())
    }

    /// Add the chart `stem`.
    pub fn chart(&mut self, stem: &str, figure: Figure) {
        self.charts.push((stem.to_string(), figure));
    }
}

/// An output folder, checked before a study starts and created when it has a result.
struct Session {
    out: PathBuf,
    force: bool,
    started: Instant,
}

impl Session {
    /// Refuse `out` if it exists without `force`; start the study's clock.
    ///
    /// # Errors
    /// `Error::Config` (field `--out`) for an existing folder without `force`.
    pub fn open(out: &Path, force: bool) -> Result<Self> {
        folder::check_out_dir(out, force)?;
        Ok(Session {
            out: out.to_path_buf(),
            force,
            started: Instant::now(),
        })
    }

    /// Create the folder and write `report` into it as the study `name`: print the table with
    /// the wall time since [`Session::open`], write `name.txt`, the CSV files and the charts.
    ///
    /// # Errors
    /// I/O and drawing errors.
    pub fn finish(self, name: &str, report: Report) -> Result<()> {
        folder::make_out_dir(&self.out, self.force)?;
        let mut text = report.text;
        if !text.ends_with('\n') {
            text.push('\n');
        }
        text.push_str(&format!(
            "study wall time {:.1} s\n",
            self.started.elapsed().as_secs_f64()
        ));
        print!("{text}");
        super::write_text(&self.out, &format!("{name}.txt"), &text)?;
        for (file, bytes) in &report.tables {
            let path = self.out.join(file);
            std::fs::write(&path, bytes).map_err(|source| Error::Io { path, source })?;
        }
        for (stem, figure) in &report.charts {
            figure.write(&self.out.join(stem))?;
        }
        for (file, image) in &report.images {
            image.write_png(&self.out.join(file))?;
        }
        println!("-> {}", self.out.display());
        Ok(())
    }
}

/// Run the study `S` of the file `path` (its quick variant if `quick`) into `out`.
///
/// # Errors
/// `Error::Config` for a bad study file (naming the key) or an existing `out` without `force`;
/// `Error::Blowup` if a run diverges.
pub fn run<S: Study>(path: &Path, quick: bool, out: &Path, force: bool) -> Result<S::Output> {
    let spec: S::Spec = file::load(path, S::NAME, quick)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    run_with::<S>(out, force, || S::measure(&spec, dir))
}

/// Run `measure` as the study `S` into `out`: refuse an existing `out` without `force` first,
/// then measure, then write the report (the table with the wall time, `NAME.txt`, the CSV files
/// and the charts).
///
/// # Errors
/// `Error::Config` for an existing `out` without `force`; the errors of `measure`; I/O and
/// drawing errors.
pub fn run_with<S: Study>(
    out: &Path,
    force: bool,
    measure: impl FnOnce() -> Result<(S::Output, Report)>,
) -> Result<S::Output> {
    let session = Session::open(out, force)?;
    let (output, report) = measure()?;
    session.finish(S::NAME, report)?;
    Ok(output)
}

/// A variant of `base`: `edit` applied to a copy, then validated as a scene file would be and
/// checked against the memory available; errors name `field.<scene key>` (the study key that
/// holds the scene).
///
/// # Errors
/// `Error::Config` for a variant that is not a valid scene.
pub fn variant(base: &Scene, field: &str, edit: impl FnOnce(&mut Scene)) -> Result<Scene> {
    let mut s = base.clone();
    edit(&mut s);
    let within = |e: Error| match e {
        Error::Config { field: f, reason } => Error::config(format!("{field}.{f}"), reason),
        other => other,
    };
    s.validate().map_err(within)?;
    crate::problem::memory::check(&s).map_err(within)?;
    Ok(s)
}
