//! `vesicle diagram FILE`: the shape diagram (reduced bending energy e against reduced volume
//! v on the prolate, oblate and stomatocyte branches) from the phase-field model, at one or
//! several reduced spontaneous curvatures c̄0 = c0 R0, against the program's own
//! sharp-interface reference at the same c̄0 ([`crate::analysis::axisym`]).
//!
//! Each point `(branch, v, c̄0)` starts from the reference shape at `(v, c̄0)`
//! ([`crate::problem::revolution`]), scaled to R0 = `r0` ε for every resolution of the diagram
//! file ([`spec`]), its scene's uniform c0 = c̄0/`r0`, and is relaxed by L-BFGS on its
//! symmetry-reduced box (⅛ for prolates and oblates, ¼ for stomatocytes) to the stationarity
//! tolerance ([`case`]). Start shapes thinner than `min_width` ε at the coarsest resolution are
//! refused ([`thickness`]). The φ = 0 surface gives v, and the pair (v, e) is extrapolated to
//! ε/R0 → 0 with orders fitted over the whole diagram ([`extrapolate`]).
//!
//! Cases are independent: `--list` prints them, `--case K` runs one into
//! `OUT/cases/<case>/`, `--merge` collects the folders into the CSV files and charts
//! ([`merge`], [`report`], [`chart`], [`summary`]); without these flags one process runs every
//! case (`--jobs` at a time, one thread each) and merges. Either way the CSV files are the same.

pub mod case;
pub mod chart;
pub mod extrapolate;
pub mod merge;
pub mod reference;
pub mod report;
pub mod spec;
pub mod summary;
pub mod thickness;

use crate::analysis::axisym::{self, Options};
use crate::error::{Error, Result};
use case::{run_case, CaseResult};
use rayon::prelude::*;
use spec::{Case, Couple, DiagramSpec};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Arguments of `vesicle diagram`.
#[derive(clap::Args, Debug, Clone)]
pub struct DiagramArgs {
    /// Diagram file (JSON): branches and reduced volumes, resolutions R0/ε, tolerance.
    pub file: PathBuf,
    /// Output folder (cases go to OUT/cases/); default out/<file stem>.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the cases (number, branch, v, R0/ε, grid) and stop.
    #[arg(long, conflicts_with_all = ["case", "merge"])]
    pub list: bool,
    /// Run case K only, into OUT/cases/<case>/.
    #[arg(long, value_name = "K", conflicts_with = "merge")]
    pub case: Option<usize>,
    /// Collect OUT/cases/ into the CSV files and charts (every case must have finished).
    #[arg(long)]
    pub merge: bool,
    /// Cases run at once by a single-process sweep (default: the number of cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Replace an existing output folder (sweep), case result (--case) or merged files
    /// (--merge).
    #[arg(long)]
    pub force: bool,
}

impl DiagramArgs {
    /// Cases run at once: `--jobs`, else every core.
    pub fn jobs(&self) -> usize {
        self.jobs.unwrap_or_else(crate::cpu::cores).max(1)
    }
}

/// Run the command.
///
/// # Errors
/// `Error::Config` for a bad diagram file or arguments (naming the key or flag; nothing is
/// written), a case that is already done (without `--force`), or a merge with cases missing.
pub fn run(args: &DiagramArgs) -> Result<()> {
    let spec = DiagramSpec::load(&args.file)?;
    let cases = spec.cases();
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args.file.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from("out").join(stem.as_ref())
    });
    if args.list {
        return list(&spec, &cases);
    }
    if let Some(k) = args.case {
        let case = cases.get(k).ok_or_else(|| {
            Error::config(
                "--case",
                format!("the diagram has cases 0..{}, got {k}", cases.len()),
            )
        })?;
        let dir = out.join("cases").join(case.folder());
        if dir.join("result.json").exists() && !args.force {
            return Err(Error::config(
                "--case",
                format!("case {k} is done ({}); --force redoes it", dir.display()),
            ));
        }
        let shape = start_shape(&spec, case)?;
        check_width(&spec, case, &shape)?;
        let r = run_case(&spec, case, &shape, &dir)
            .map_err(|e| e.within(&format!("diagram case {k} ({})", case.folder())))?;
        eprintln!("{}", line(&r, 1, 1));
        return Ok(());
    }
    if args.merge {
        return merge::merge(&spec, &cases, &out, args.force);
    }
    sweep(&spec, &cases, &out, args)?;
    merge::merge(&spec, &cases, &out, true)
}

/// The sharp start of `case`, at its c̄0.
///
/// # Errors
/// `Error::Config` naming the key that lists the point if the branch does not reach `v` at
/// this c̄0.
fn start_shape(spec: &DiagramSpec, case: &Case) -> Result<axisym::Solution> {
    let at = |why: String| {
        Error::config(
            spec.key_of(case),
            format!(
                "no reference shape at v = {}, {}: {why}",
                case.v,
                case.slice().describe()
            ),
        )
    };
    let opts = Options::default().with_c0(case.c0);
    let shape = match case.couple {
        Some(Couple::Ade { alpha, da0 }) => {
            axisym::ade_solution(case.branch, case.v, alpha, da0, &opts)
        }
        Some(Couple::Bc { da }) => axisym::bc_solution(case.branch, case.v, da, &opts),
        None => axisym::solve(case.branch, case.v, &opts),
    }
    .map_err(|e| at(e.to_string()))?;
    if !case.branch.up_down_symmetric() && shape.asymmetry() < reference::ASYMMETRIC {
        return Err(at(format!(
            "the {} branch does not exist here (its continuation is up-down symmetric)",
            case.branch.name()
        )));
    }
    Ok(shape)
}

/// Refuse `case` if its start's thinnest part ([`thickness::thinnest`]) is narrower than
/// `min_width` ε at the coarsest resolution.
///
/// # Errors
/// `Error::Config` naming the key that lists the point, the point and its width.
fn check_width(spec: &DiagramSpec, case: &Case, shape: &axisym::Solution) -> Result<()> {
    let w = thickness::thinnest(shape);
    let r0 = spec.coarsest();
    if w * r0 >= spec.min_width {
        return Ok(());
    }
    Err(Error::config(
        spec.key_of(case),
        format!(
            "the {} at v = {}, c0 = {} is {w:.3} R0 thick at its thinnest part: {:.2} ε at the \
             coarsest R0 = {r0} ε, below min_width = {} ε (two interfaces would merge); \
             leave the point out or raise the coarsest r0 to {:.0}",
            case.branch.name(),
            case.v,
            case.c0,
            w * r0,
            spec.min_width,
            (spec.min_width / w).ceil()
        ),
    ))
}

/// The sharp starts of every `(branch, v, c̄0)` of `cases`, in parallel, in the order of
/// `cases`, each checked by [`check_width`].
fn start_shapes(spec: &DiagramSpec, cases: &[Case]) -> Result<Vec<axisym::Solution>> {
    let same = |a: &Case, b: &Case| a.branch == b.branch && a.v == b.v && a.slice() == b.slice();
    let mut keys: Vec<&Case> = Vec::new();
    for c in cases {
        if !keys.iter().any(|k| same(k, c)) {
            keys.push(c);
        }
    }
    let solved: Vec<axisym::Solution> = keys
        .par_iter()
        .map(|c| {
            let shape = start_shape(spec, c)?;
            check_width(spec, c, &shape)?;
            Ok(shape)
        })
        .collect::<Result<_>>()?;
    Ok(cases
        .iter()
        .map(|c| {
            let k = keys.iter().position(|k| same(k, c)).expect("listed");
            solved[k].clone()
        })
        .collect())
}

fn list(spec: &DiagramSpec, cases: &[Case]) -> Result<()> {
    use std::fmt::Write as _;
    let shapes = start_shapes(spec, cases)?;
    let mut text = String::from(
        "case  branch        v     slice   R0/ε  grid (full box)    computed points  thinnest (ε)\n",
    );
    let mut total = 0usize;
    for (c, s) in cases.iter().zip(&shapes) {
        let n = case::grid_for(s, c.r0, spec);
        let points = case::computed_points(c.branch, n);
        total += points;
        let _ = writeln!(
            text,
            "{:>4}  {:<12} {:>6} {:>6} {:>6}  {:>4}x{:>4}x{:>4}  {:>10}  {:>12.1}",
            c.index,
            c.branch.name(),
            c.v,
            c.slice().value(),
            c.r0,
            n[0],
            n[1],
            n[2],
            points,
            thickness::thinnest(s) * c.r0
        );
    }
    let _ = writeln!(
        text,
        "{} cases, {} computed points in all",
        cases.len(),
        total
    );
    // A reader that stops early (`| head`) closes the pipe: that is not an error of the listing.
    match std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(Error::Io {
            path: "(standard output)".into(),
            source: e,
        }),
        _ => Ok(()),
    }
}

/// One line about a finished case.
fn line(r: &CaseResult, done: usize, of: usize) -> String {
    format!(
        "[{done}/{of}] case {} {} v0 = {} {} R0 = {}ε: v {:.5} e {:.5} ({}, {} iterations, residual {:.1e}, {:.1} s)",
        r.index, r.branch, r.v_target, r.slice().describe(), r.r0, r.v, r.e, r.stopped, r.iterations, r.residual, r.wall_seconds
    )
}

/// Run every case in `out/cases/`, `args.jobs` at a time, the largest first.
fn sweep(spec: &DiagramSpec, cases: &[Case], out: &Path, args: &DiagramArgs) -> Result<()> {
    if out.exists() {
        if !args.force {
            return Err(Error::config(
                "--out",
                format!("{} exists; --force replaces it", out.display()),
            ));
        }
        std::fs::remove_dir_all(out).map_err(|source| Error::Io {
            path: out.to_path_buf(),
            source,
        })?;
    }
    let start = Instant::now();
    let shapes = start_shapes(spec, cases)?;
    let mut order: Vec<(usize, usize)> = cases
        .iter()
        .zip(&shapes)
        .map(|(c, s)| (c.index, case::grid_for(s, c.r0, spec).iter().product()))
        .collect();
    order.sort_by_key(|&(_, points)| std::cmp::Reverse(points));
    let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let jobs = args.jobs();
    // Plain threads, each taking the next case and running it on a pool of one thread: a
    // rayon pool here would start more cases while one waits on its own pool.
    let worker = || -> Result<()> {
        let single = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("thread pool");
        while let Some(&(k, _)) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
            let c = &cases[k];
            let dir = out.join("cases").join(c.folder());
            let r = single
                .install(|| run_case(spec, c, &shapes[k], &dir))
                .map_err(|e| e.within(&format!("diagram case {k} ({})", c.folder())))?;
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            let elapsed = start.elapsed().as_secs_f64();
            let eta = elapsed / n as f64 * (cases.len() - n) as f64;
            eprintln!(
                "{} | {elapsed:.0} s, ETA {eta:.0} s",
                line(&r, n, cases.len())
            );
        }
        Ok(())
    };
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..jobs).map(|_| scope.spawn(worker)).collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a sweep worker panicked"))
            .collect::<Result<Vec<()>>>()
    })?;
    eprintln!(
        "{} cases in {:.0} s on {jobs} job(s)",
        cases.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
