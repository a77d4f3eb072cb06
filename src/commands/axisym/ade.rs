//! `vesicle axisym --bc --da LIST` and `--ade ALPHA --da0 LIST`: the bilayer-couple `(v, Δa)`
//! and ADE `(v, Δa0)` diagrams of the axisymmetric reference
//! ([`crate::analysis::axisym::ade_phase`]): per `v` the BC branches followed in `Δa`
//! (`branches_v<v>.csv`), the lowest branch on the grid and where it changes (`lowest.csv`,
//! `summary.csv`), the limit lines (`limits.csv`) and the phase chart (`phase.png`,
//! `phase.svg`).

use super::{io_err, AxisymArgs};
use crate::analysis::axisym::ade::ADE_WINDOW;
use crate::analysis::axisym::ade_phase::{ade_lowest, bc_lowest, v_slice, VSlice};
use crate::analysis::axisym::lowest::Lowest;
use crate::analysis::axisym::{
    ade_da0, ade_image, l_pear_at, l_sto_at, limit_line, Branch, Limit, LimitShape, Options,
    Solution,
};
use crate::error::{Error, Result};
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use crate::output::{create_file, folder};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Which diagram.
#[derive(Clone, Copy, Debug)]
pub enum Which {
    /// Bilayer couple, over `Δa`.
    Bc,
    /// ADE of `α` at `c̄0`, over `Δa0`.
    Ade {
        /// `α = κ̄/κ`.
        alpha: f64,
        /// Reduced spontaneous curvature.
        c0: f64,
    },
}

impl Which {
    /// The grid's name (`da`, `da0`).
    fn x_name(&self) -> &'static str {
        match self {
            Which::Bc => "da",
            Which::Ade { .. } => "da0",
        }
    }

    /// Where a BC shape lies on the grid's axis: its `Δa`, or the `Δa0` of its ADE image.
    fn x_of_shape(&self, s: &Solution) -> f64 {
        match *self {
            Which::Bc => s.da(),
            Which::Ade { alpha, c0 } => ade_da0(c0, alpha, s.da(), s.c0_eff),
        }
    }

    /// Where a limit shape lies on the grid's axis.
    fn x_of(&self, l: &LimitShape) -> f64 {
        match *self {
            Which::Bc => l.da,
            Which::Ade { alpha, c0 } => l.da0(alpha, c0),
        }
    }
}

/// Check a grid list.
fn check_list(flag: &str, list: &[f64]) -> Result<()> {
    if list.len() < 2 {
        return Err(Error::config(flag, "list at least two values"));
    }
    if let Some(x) = list.iter().find(|x| !(x.is_finite() && x.abs() <= 5.0)) {
        return Err(Error::config(
            flag,
            format!("need finite values with |x| ≤ 5, got {x}"),
        ));
    }
    Ok(())
}

/// Run the BC or ADE diagram over the `v` grid `vs` and the list `xs` (`Δa` or `Δa0`).
///
/// # Errors
/// `Error::Config` for invalid arguments or an existing folder without `--force` (nothing is
/// written); `Error::Io`/`Error::Output` if writing fails.
pub fn run(args: &AxisymArgs, which: Which, xs: &[f64], vs: &[f64]) -> Result<()> {
    let flag = match which {
        Which::Bc => "--da",
        Which::Ade { .. } => "--da0",
    };
    check_list(flag, xs)?;
    if let Which::Ade { alpha, c0 } = which {
        if !(alpha > 0.0 && alpha <= 100.0) {
            return Err(Error::config(
                "--ade",
                format!("need 0 < α ≤ 100, got {alpha}"),
            ));
        }
        if !(c0.is_finite() && c0.abs() <= 10.0) {
            return Err(Error::config("--c0", format!("need |c0| ≤ 10, got {c0}")));
        }
    }
    if args.out.exists() && !args.force {
        folder::make_out_dir(&args.out, false)?;
    }
    let mut xs = xs.to_vec();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let start = Instant::now();
    let c0 = match which {
        Which::Bc => 0.0,
        Which::Ade { c0, .. } => c0,
    };
    let opts = Options::with_nodes(args.nodes).with_c0(c0);
    let window = match which {
        Which::Bc => (xs[0], xs[xs.len() - 1]),
        Which::Ade { .. } => ADE_WINDOW,
    };
    let slices: Vec<VSlice> = vs.iter().map(|&v| v_slice(v, window, &opts)).collect();
    let lows: Vec<Lowest> = slices
        .iter()
        .map(|s| match which {
            Which::Bc => bc_lowest(s, &xs),
            Which::Ade { alpha, .. } => ade_lowest(s, alpha, &xs),
        })
        .collect();
    folder::make_out_dir(&args.out, args.force)?;
    for s in &slices {
        write_branches(&args.out, s, which)?;
    }
    write_lowest(&args.out.join("lowest.csv"), &slices, &lows, which)?;
    write_summary(&args.out.join("summary.csv"), &slices, &lows, which)?;
    write_limits(&args.out.join("limits.csv"), which)?;
    figure(&slices, &lows, which, &xs)
        .write(&args.out.join("phase"))
        .map_err(Error::from)?;
    for (s, l) in slices.iter().zip(&lows) {
        print_slice(s, l, which);
    }
    println!(
        "done in {:.1} s ({} nodes, K = {}) -> {}",
        start.elapsed().as_secs_f64(),
        opts.nodes,
        opts.modes,
        args.out.display()
    );
    Ok(())
}

/// `branches_v<v>.csv`: every BC shape of every branch at `v` in path order, with its ADE
/// image for `--ade`.
fn write_branches(out: &Path, s: &VSlice, which: Which) -> Result<()> {
    let path = out.join(format!("branches_v{:.3}.csv", s.v));
    let mut f = create_file(&path)?;
    let err = io_err(&path);
    write!(f, "branch,v,da,e,c0_eff,pressure,asymmetry,neck,residual").map_err(&err)?;
    if matches!(which, Which::Ade { .. }) {
        write!(f, ",da0,w,stable").map_err(&err)?;
    }
    writeln!(f).map_err(&err)?;
    for c in &s.curves {
        let img = match which {
            Which::Ade { alpha, .. } => ade_image(&c.shapes, alpha),
            Which::Bc => Vec::new(),
        };
        for (i, sol) in c.shapes.iter().enumerate() {
            let neck = sol.neck().map_or(String::new(), |r| format!("{r:.8}"));
            write!(
                f,
                "{},{:.6},{:.12},{:.12},{:.10},{:.10e},{:.6e},{},{:.3e}",
                sol.branch.name(),
                sol.v,
                sol.da(),
                sol.e,
                sol.c0_eff,
                sol.pressure,
                sol.asymmetry(),
                neck,
                sol.residual
            )
            .map_err(&err)?;
            if let Some(p) = img.get(i) {
                write!(f, ",{:.12},{:.12},{}", p.da0, p.w, p.stable).map_err(&err)?;
            }
            writeln!(f).map_err(&err)?;
        }
    }
    f.flush().map_err(&err)
}

/// `lowest.csv`: `v,<x>,branch,energy` at every grid point where a branch exists.
fn write_lowest(path: &Path, slices: &[VSlice], lows: &[Lowest], which: Which) -> Result<()> {
    let mut f = create_file(path)?;
    let err = io_err(path);
    let energy = match which {
        Which::Bc => "e",
        Which::Ade { .. } => "w",
    };
    writeln!(f, "v,{},branch,{energy}", which.x_name()).map_err(&err)?;
    for (s, l) in slices.iter().zip(lows) {
        for (x, b, y) in &l.points {
            writeln!(f, "{:.6},{x:.6},{},{y:.10}", s.v, b.name()).map_err(&err)?;
        }
    }
    f.flush().map_err(&err)
}

/// `summary.csv`: per `v`, `v,event,x,detail`: the changes of the lowest branch (`lowest branch
/// changes` where the energies cross, the transitions; `branch ends` where the lowest changes
/// only because a branch ends or begins inside a grid interval), the pear bifurcation, every
/// change of the prolate's up–down stability along its path (`prolate loses` / `prolate
/// regains up-down stability`: the first loss is the pear bifurcation again), the limit shapes
/// at this `v`.
fn write_summary(path: &Path, slices: &[VSlice], lows: &[Lowest], which: Which) -> Result<()> {
    let mut f = create_file(path)?;
    let err = io_err(path);
    writeln!(f, "v,event,{},detail", which.x_name()).map_err(&err)?;
    for (s, l) in slices.iter().zip(lows) {
        for c in &l.changes {
            let (event, how) = if c.crossing {
                ("lowest branch changes", "energies cross")
            } else {
                (
                    "branch ends",
                    "grid midpoint: no energy crossing, a branch ends or begins",
                )
            };
            writeln!(
                f,
                "{:.6},{event},{:.6},{} below / {} above ({how})",
                s.v,
                c.x,
                c.below.name(),
                c.above.name()
            )
            .map_err(&err)?;
        }
        if let Some(b) = pear_bifurcation_x(s, which) {
            writeln!(f, "{:.6},pear bifurcation,{b:.6},leaves the prolate", s.v).map_err(&err)?;
        }
        for c in &s.updown {
            let (event, sign) = if c.loses {
                ("prolate loses up-down stability", "falls")
            } else {
                ("prolate regains up-down stability", "rises")
            };
            let neck = c
                .shape
                .neck()
                .map_or("no neck".to_string(), |r| format!("neck {r:.4} R0"));
            writeln!(
                f,
                "{:.6},{event},{:.6},mu {sign} through 0 ({neck}; c0_eff = {:.4})",
                s.v,
                which.x_of_shape(&c.shape),
                c.shape.c0_eff
            )
            .map_err(&err)?;
        }
        for (name, l) in [("L_pear", l_pear_at(s.v)), ("L_sto", l_sto_at(s.v))] {
            if let Some(l) = l {
                writeln!(
                    f,
                    "{:.6},{name},{:.6},R1 = {:.5} R2 = {:.5} c0_neck = {:.5}",
                    s.v,
                    which.x_of(&l),
                    l.r1,
                    l.r2,
                    l.c0_neck
                )
                .map_err(&err)?;
            }
        }
    }
    f.flush().map_err(&err)
}

/// The grid coordinate of the pear bifurcation at this `v`.
fn pear_bifurcation_x(s: &VSlice, which: Which) -> Option<f64> {
    let i = Branch::WITH_PEAR.iter().position(|b| *b == Branch::Pear)?;
    let b = s.curves[i].bifurcation.as_ref()?;
    Some(which.x_of_shape(b))
}

/// `limits.csv`: the limit lines `L_pear` and `L_sto` (`kind,r1,r2,v,da,c0_neck` and `da0`
/// for `--ade`).
fn write_limits(path: &Path, which: Which) -> Result<()> {
    let mut f = create_file(path)?;
    let err = io_err(path);
    writeln!(f, "kind,r1,r2,v,da,c0_neck,{}", which.x_name()).map_err(&err)?;
    for (name, kind) in [("L_pear", Limit::Pear), ("L_sto", Limit::Stomatocyte)] {
        for l in limit_line(kind, 40) {
            writeln!(
                f,
                "{name},{:.8},{:.8},{:.8},{:.8},{:.8},{:.8}",
                l.r1,
                l.r2,
                l.v,
                l.da,
                l.c0_neck,
                which.x_of(&l)
            )
            .map_err(&err)?;
        }
    }
    f.flush().map_err(&err)
}

/// The phase chart: the grid points coloured by the lowest branch, the changes, the pear
/// bifurcation and the limit lines.
fn figure(slices: &[VSlice], lows: &[Lowest], which: Which, xs: &[f64]) -> Figure {
    let (title, ylabel) = match which {
        Which::Bc => (
            "lowest-energy shape, bilayer-couple model".to_string(),
            "reduced area difference Δa",
        ),
        Which::Ade { alpha, c0 } => (
            format!("lowest-energy shape, ADE model (α = {alpha}, c0 = {c0})"),
            "preferred area difference Δa0",
        ),
    };
    let mut fig = Figure::new(
        title,
        Axis::linear("reduced volume v"),
        Axis::linear(ylabel),
    );
    if matches!(which, Which::Bc) {
        // The BC chart leaves its lower left empty (no shapes below L_sto at small v there).
        fig.legend = Corner::LowerLeft;
    }
    let (lo, hi) = (xs[0], xs[xs.len() - 1]);
    let shapes = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    for (i, b) in Branch::WITH_PEAR.iter().enumerate() {
        let pts: Vec<(f64, f64)> = slices
            .iter()
            .zip(lows)
            .flat_map(|(s, l)| {
                l.points
                    .iter()
                    .filter(|(_, lb, _)| lb == b)
                    .map(move |(x, _, _)| (s.v, *x))
            })
            .collect();
        if !pts.is_empty() {
            fig.push(Series::new(
                b.name(),
                pts,
                colour(i),
                Mark::Points(shapes[i]),
            ));
        }
    }
    let changes: Vec<(f64, f64)> = slices
        .iter()
        .zip(lows)
        .flat_map(|(s, l)| {
            l.changes
                .iter()
                .filter(|c| c.crossing)
                .map(move |c| (s.v, c.x))
        })
        .collect();
    if !changes.is_empty() {
        fig.push(Series::new(
            "transition (energies cross)",
            changes,
            colour(4),
            Mark::Points(Shape::Cross),
        ));
    }
    let bif: Vec<(f64, f64)> = slices
        .iter()
        .filter_map(|s| pear_bifurcation_x(s, which).map(|x| (s.v, x)))
        .filter(|(_, x)| *x >= lo && *x <= hi)
        .collect();
    if !bif.is_empty() {
        fig.push(Series::new(
            "pear bifurcation",
            bif,
            colour(5),
            Mark::LinePoints(Shape::Cross),
        ));
    }
    // The prolate's later stability changes: where it regains up–down stability (and near
    // v = 0.70 loses it again).
    let later: Vec<(f64, f64)> = slices
        .iter()
        .flat_map(|s| {
            s.updown
                .iter()
                .skip_while(|c| c.loses)
                .map(move |c| (s.v, which.x_of_shape(&c.shape)))
        })
        .filter(|(_, x)| *x >= lo && *x <= hi)
        .collect();
    if !later.is_empty() {
        fig.push(Series::new(
            "prolate regains up–down stability (or loses it again)",
            later,
            colour(5),
            Mark::Points(Shape::Diamond),
        ));
    }
    for (name, kind, c) in [
        ("L_pear (two spheres)", Limit::Pear, 6),
        ("L_sto (sphere in sphere)", Limit::Stomatocyte, 7),
    ] {
        let line: Vec<(f64, f64)> = limit_line(kind, 200)
            .iter()
            .map(|l| (l.v, which.x_of(l)))
            .filter(|(v, x)| *x >= lo && *x <= hi && *v >= 0.3)
            .collect();
        if line.len() >= 2 {
            fig.push(Series::new(name, line, colour(c), Mark::Dashed));
        }
    }
    fig
}

fn print_slice(s: &VSlice, l: &Lowest, which: Which) {
    println!("v = {}:", s.v);
    for c in &s.curves {
        let (lo, hi) = c
            .shapes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x.da()), b.max(x.da()))
            });
        if c.shapes.is_empty() {
            println!("  {:<12} none", c.branch.name());
        } else {
            println!(
                "  {:<12} {:>3} shapes, Δa {lo:.4}..{hi:.4}",
                c.branch.name(),
                c.shapes.len()
            );
        }
    }
    for c in &l.changes {
        println!(
            "  lowest: {} below / {} above {} = {:.4}{}",
            c.below.name(),
            c.above.name(),
            which.x_name(),
            c.x,
            if c.crossing {
                ""
            } else {
                " (grid midpoint: a branch ends, no crossing)"
            }
        );
    }
    if let Some(b) = pear_bifurcation_x(s, which) {
        println!("  pear bifurcation at {} = {b:.5}", which.x_name());
    }
    for c in &s.updown {
        println!(
            "  prolate {} up-down stability at {} = {:.5}",
            if c.loses { "loses" } else { "regains" },
            which.x_name(),
            which.x_of_shape(&c.shape)
        );
    }
}
