//! The study registry: every `vesicle study NAME`, read from the command line's own definition
//! ([`list`]), and the runner of a study by name ([`run`]) that the command line and the Python
//! bindings both call. A study writes its folder (table, CSV files, charts) as the command
//! does and returns its tables as typed columns ([`Table`]), taken from the study's report in
//! memory: the same bytes its CSV files are written from, not read back from the folder.

use crate::commands::cli::Cli;
use crate::commands::study::budding::Budding;
use crate::commands::study::convergence::Convergence;
use crate::commands::study::file;
use crate::commands::study::harness::{self, Report, Study};
use crate::commands::study::heating::Heating;
use crate::commands::study::nonaxisymmetric::Nonaxisymmetric;
use crate::commands::study::onset::OnsetStudy;
use crate::commands::study::pinning::PinningStudy;
use crate::commands::study::precision::Precision;
use crate::commands::study::rates::RatesStudy;
use crate::commands::study::resolution::ResolutionStudy;
use crate::commands::study::shear::ShearStudy;
use crate::commands::study::stability::{AdeStability, Stability};
use crate::commands::study::stationary::{self, Stationary};
use crate::error::{Error, Result};
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

pub use super::study::table::{Table, Values};

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
        Heating::NAME => run_file::<Heating>(args),
        OnsetStudy::NAME => run_file::<OnsetStudy>(args),
        PinningStudy::NAME => run_file::<PinningStudy>(args),
        ResolutionStudy::NAME => run_file::<ResolutionStudy>(args),
        AdeStability::NAME => run_file::<AdeStability>(args),
        RatesStudy::NAME => run_file::<RatesStudy>(args),
        ShearStudy::NAME => run_file::<ShearStudy>(args),
        Nonaxisymmetric::NAME => run_file::<Nonaxisymmetric>(args),
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

/// A study `S` whose output is its report's tables as typed columns, from the same rows as its
/// CSV files.
struct Tables<S>(std::marker::PhantomData<S>);

impl<S: Study> Study for Tables<S> {
    const NAME: &'static str = S::NAME;
    type Spec = S::Spec;
    type Output = Vec<Table>;

    fn measure(spec: &S::Spec, dir: &Path) -> Result<(Self::Output, Report)> {
        let (_, report) = S::measure(spec, dir)?;
        Ok((report.typed.clone(), report))
    }
}

/// The study `S` of a study file in one pool of its threads ([`file::threads`]).
fn run_file<S: Study>(args: &Args) -> Result<Vec<Table>> {
    refuse_set(args)?;
    super::existing(args.file, "(study file)")?;
    let threads = file::threads(args.file, S::NAME, args.quick)?;
    crate::cpu::in_pool(threads, || {
        harness::run::<Tables<S>>(args.file, args.quick, args.out, args.force)
    })
}

/// The stationary study, on a study file or on a scene file (with `set` applied, in a pool of
/// the scene's threads).
fn run_stationary(args: &Args) -> Result<Vec<Table>> {
    if file::is_study_file(args.file) {
        refuse_set(args)?;
        harness::run::<Tables<Stationary>>(args.file, args.quick, args.out, args.force)
    } else {
        if args.quick {
            return Err(Error::config(
                "--quick",
                "applies to a study file (one with a \"study\" key), not a scene file",
            ));
        }
        let scene = super::load_scene(args.file, args.set)?;
        crate::cpu::in_pool(scene.threads(), || {
            harness::run_with::<Tables<Stationary>>(args.out, args.force, || {
                let (_, report) = stationary::on_scene(&scene)?;
                Ok((report.typed.clone(), report))
            })
        })
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
            "heating",
            "onset",
            "pinning",
            "resolution",
            "ade",
            "rates",
            "shear",
            "nonaxisymmetric",
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
}
