//! `vesicle axisym`: the three branches of the c0 = 0 shape diagram of the axisymmetric
//! reference ([`crate::analysis::axisym::diagram`]) on a grid of reduced volumes, written as CSV
//! (energies, contours), a PNG chart, and the transition volumes where the branches cross;
//! with `--c0 LIST`, the (v, c̄0) diagram ([`phase`]); with `--bc --da LIST` or
//! `--ade ALPHA --da0 LIST`, the bilayer-couple or ADE diagram ([`ade`]).

pub mod ade;
pub mod phase;

use crate::analysis::axisym::diagram::{Diagram, Transitions};
use crate::analysis::axisym::{Branch, Options, Solution};
use crate::error::{Error, Result};
use crate::output::{chart, create_file, folder};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `vesicle axisym`.
#[derive(clap::Args, Debug, Clone)]
pub struct AxisymArgs {
    /// Output folder; never overwritten without --force.
    #[arg(long)]
    pub out: PathBuf,
    /// Smallest reduced volume of the grid.
    #[arg(long, default_value_t = 0.5)]
    pub v_min: f64,
    /// Largest reduced volume of the grid (at most 1).
    #[arg(long, default_value_t = 0.99)]
    pub v_max: f64,
    /// Spacing of the grid in v.
    #[arg(long, default_value_t = 0.01)]
    pub dv: f64,
    /// Quadrature nodes (Chebyshev–Lobatto; modes K = (nodes − 1)/3).
    #[arg(long, default_value_t = 241)]
    pub nodes: usize,
    /// Replace an existing output folder.
    #[arg(long)]
    pub force: bool,
    /// Reduced spontaneous curvatures c0·R0, comma separated (e.g. `--c0 0,0.5,1`): the
    /// (v, c0) diagram with the pear branch (`branches_c0_*.csv`, `summary.csv`, `phase.png`)
    /// instead of the c0 = 0 diagram.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub c0: Option<Vec<f64>>,
    /// Area-difference elasticity with α = κ̄/κ = ALPHA: the (v, Δa0) diagram over --da0
    /// (`branches_v*.csv`, `lowest.csv`, `summary.csv`, `limits.csv`, `phase.png`); with
    /// `--c0 X` (one value) at that reduced spontaneous curvature, else c0 = 0.
    #[arg(long, conflicts_with = "bc", requires = "da0")]
    pub ade: Option<f64>,
    /// Preferred reduced area differences Δa0 of --ade, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        requires = "ade"
    )]
    pub da0: Option<Vec<f64>>,
    /// The bilayer-couple model: the (v, Δa) diagram over --da (files as for --ade).
    #[arg(long, requires = "da")]
    pub bc: bool,
    /// Reduced area differences Δa of --bc, comma separated.
    #[arg(long, value_delimiter = ',', requires = "bc")]
    pub da: Option<Vec<f64>>,
}

/// The grid `v_min, v_min + dv, …` up to `v_max` (inclusive within dv/1000), rounded to 1e-9.
fn grid(args: &AxisymArgs) -> Vec<f64> {
    let n = ((args.v_max - args.v_min) / args.dv + 1e-3).floor() as usize;
    (0..=n)
        .map(|i| ((args.v_min + i as f64 * args.dv) * 1e9).round() / 1e9)
        .collect()
}

/// Check the arguments (`Error::Config` naming the argument).
fn check(args: &AxisymArgs) -> Result<()> {
    if !(args.v_min > 0.0 && args.v_min < 1.0) {
        return Err(Error::config(
            "--v-min",
            format!("need 0 < v-min < 1, got {}", args.v_min),
        ));
    }
    if !(args.v_max > args.v_min && args.v_max <= 1.0) {
        return Err(Error::config(
            "--v-max",
            format!("need v-min < v-max ≤ 1, got {}", args.v_max),
        ));
    }
    if !(args.dv > 0.0 && (args.v_max - args.v_min) / args.dv <= 10_000.0) {
        return Err(Error::config(
            "--dv",
            format!(
                "need dv > 0 and at most 10000 steps over [v-min, v-max], got {}",
                args.dv
            ),
        ));
    }
    if !(17..=4097).contains(&args.nodes) {
        return Err(Error::config(
            "--nodes",
            format!("need 17 ≤ nodes ≤ 4097, got {}", args.nodes),
        ));
    }
    Ok(())
}

/// Compute the diagram and write `branches.csv`, `transitions.csv`, `contours/*.csv` and
/// `diagram.png` and `diagram.svg` to `args.out`; print the transition volumes.
///
/// # Errors
/// `Error::Config` for invalid arguments or an existing folder without `--force` (nothing is
/// written); `Error::Io`/`Error::Output` if writing fails.
pub fn run(args: &AxisymArgs) -> Result<()> {
    check(args)?;
    if let (Some(alpha), Some(list)) = (args.ade, &args.da0) {
        let c0 = match args.c0.as_deref() {
            None => 0.0,
            Some([c]) => *c,
            Some(_) => return Err(Error::config("--c0", "give one value with --ade")),
        };
        return ade::run(args, ade::Which::Ade { alpha, c0 }, list, &grid(args));
    }
    if let (true, Some(list)) = (args.bc, &args.da) {
        if args.c0.is_some() {
            return Err(Error::config("--c0", "the bilayer couple takes no c0"));
        }
        return ade::run(args, ade::Which::Bc, list, &grid(args));
    }
    if let Some(list) = &args.c0 {
        return phase::run(args, list, &grid(args));
    }
    if args.out.exists() && !args.force {
        folder::make_out_dir(&args.out, false)?;
    }
    let start = Instant::now();
    let opts = Options::with_nodes(args.nodes);
    let Diagram {
        curves,
        transitions: t,
    } = Diagram::compute(&grid(args), &opts);
    folder::make_out_dir(&args.out, args.force)?;
    // make_out_dir prepares a `snapshots` folder for runs; this command has none.
    write_outputs(&args.out, &curves, &t, decimals(args.dv))?;
    print_summary(&curves, &t, start.elapsed().as_secs_f64(), &args.out);
    Ok(())
}

/// Decimals needed to print grid values of spacing `dv` (at least 2).
fn decimals(dv: f64) -> usize {
    ((-dv.log10() - 1e-9).ceil().max(2.0) as usize).min(9)
}

/// An `Error::Io` on `path`, from the I/O error of writing it.
fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn write_outputs(out: &Path, curves: &[Vec<Solution>], t: &Transitions, dec: usize) -> Result<()> {
    let path = out.join("branches.csv");
    let mut f = create_file(&path)?;
    let err = io_err(&path);
    writeln!(
        f,
        "branch,v,e,sigma,pressure,length,asymmetry,iterations,residual"
    )
    .map_err(&err)?;
    for s in curves.iter().flatten() {
        writeln!(
            f,
            "{},{:.10},{:.12},{:.10e},{:.10e},{:.10},{:.6e},{},{:.3e}",
            s.branch.name(),
            s.v,
            s.e,
            s.sigma,
            s.pressure,
            s.length(),
            s.asymmetry(),
            s.iterations,
            s.residual
        )
        .map_err(&err)?;
    }
    f.flush().map_err(&err)?;

    let path = out.join("transitions.csv");
    let mut f = create_file(&path)?;
    let err = io_err(&path);
    writeln!(f, "transition,v").map_err(&err)?;
    let rows = [
        ("prolate/oblate", &t.prolate_oblate),
        ("oblate/stomatocyte", &t.oblate_stomatocyte),
        ("prolate/stomatocyte", &t.prolate_stomatocyte),
    ];
    for (name, vs) in rows {
        for v in vs {
            writeln!(f, "{name},{v:.6}").map_err(&err)?;
        }
    }
    if let Some(v) = t.stomatocyte_end {
        writeln!(f, "stomatocyte end,{v:.6}").map_err(&err)?;
    }
    if let Some(v) = t.oblate_contact {
        writeln!(f, "oblate self-contact,{v:.6}").map_err(&err)?;
    }
    f.flush().map_err(&err)?;

    let dir = out.join("contours");
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    for s in curves.iter().flatten() {
        let path = dir.join(format!("{}_v{:.*}.csv", s.branch.name(), dec, s.v));
        let mut f = create_file(&path)?;
        let err = io_err(&path);
        writeln!(f, "r,z").map_err(&err)?;
        for (r, z) in s.r.iter().zip(&s.z) {
            writeln!(f, "{r:.12e},{z:.12e}").map_err(&err)?;
        }
        f.flush().map_err(&err)?;
    }

    let mut figure = chart::Figure::new(
        "Shape diagram at c0 = 0: the axisymmetric sharp-interface reference",
        chart::Axis::linear("reduced volume v"),
        chart::Axis::linear("reduced bending energy e = ∮(2H)² dA / 16π"),
    );
    for (i, (c, b)) in curves.iter().zip(Branch::ALL).enumerate() {
        let points = c.iter().map(|s| (s.v, s.e)).collect();
        figure.push(chart::Series::new(
            b.name(),
            points,
            chart::colour(i),
            chart::Mark::Line,
        ));
    }
    figure.write(&out.join("diagram"))?;
    Ok(())
}

fn print_summary(curves: &[Vec<Solution>], t: &Transitions, wall: f64, out: &Path) {
    for (c, b) in curves.iter().zip(Branch::ALL) {
        match (c.first(), c.last()) {
            (Some(lo), Some(hi)) => println!(
                "{:<12} {:>3} shapes, v {:.4}..{:.4}, e {:.6}..{:.6}",
                b.name(),
                c.len(),
                lo.v,
                hi.v,
                lo.e,
                hi.e
            ),
            _ => println!("{:<12} no shapes in the range", b.name()),
        }
    }
    let list = |vs: &[f64]| {
        if vs.is_empty() {
            "none in the range".to_string()
        } else {
            vs.iter()
                .map(|v| format!("v = {v:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    println!("prolate/oblate crossing:      {}", list(&t.prolate_oblate));
    println!(
        "oblate/stomatocyte crossing:  {}",
        list(&t.oblate_stomatocyte)
    );
    println!(
        "prolate/stomatocyte crossing: {}",
        list(&t.prolate_stomatocyte)
    );
    if let Some(v) = t.stomatocyte_end {
        println!("stomatocyte branch ends (limit point) at v = {v:.4}");
    }
    if let Some(v) = t.oblate_contact {
        println!("oblate branch self-contact at v = {v:.4}");
    }
    println!("done in {wall:.2} s -> {}", out.display());
}
