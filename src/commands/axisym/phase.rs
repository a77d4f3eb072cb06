//! `vesicle axisym --c0 LIST`: the (v, c̄0) diagram of the axisymmetric reference
//! ([`crate::analysis::axisym::phase`]), one slice per c̄0, written as CSV (`branches_c0_*.csv`,
//! `summary.csv`) and drawn as the phase diagram (`phase.png`, `phase.svg`).

use super::{io_err, AxisymArgs};
use crate::analysis::axisym::phase::{slice, Slice};
use crate::analysis::axisym::{self, Branch, Options, PearEnd, Solution};
use crate::error::{Error, Result};
use crate::output::chart::{colour, Axis, Figure, Mark, Series, Shape};
use crate::output::{create_file, folder};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Check the `--c0` list.
fn check_c0(list: &[f64]) -> Result<()> {
    if list.is_empty() {
        return Err(Error::config("--c0", "list at least one value"));
    }
    if let Some(c) = list.iter().find(|c| !(c.is_finite() && c.abs() <= 10.0)) {
        return Err(Error::config(
            "--c0",
            format!("need finite values with |c0| ≤ 10, got {c}"),
        ));
    }
    Ok(())
}

/// Run `vesicle axisym --c0 LIST`: every slice, then `branches_c0_<c0>.csv`, `summary.csv`,
/// `phase.png` and `phase.svg` in `args.out`.
///
/// # Errors
/// `Error::Config` for invalid arguments or an existing folder without `--force` (nothing is
/// written); `Error::Io`/`Error::Output` if writing fails.
pub fn run(args: &AxisymArgs, list: &[f64], vs: &[f64]) -> Result<()> {
    check_c0(list)?;
    if args.out.exists() && !args.force {
        folder::make_out_dir(&args.out, false)?;
    }
    let start = Instant::now();
    let opts = Options::with_nodes(args.nodes);
    let slices: Vec<Slice> = list.iter().map(|&c| slice(c, vs, &opts)).collect();
    folder::make_out_dir(&args.out, args.force)?;
    for s in &slices {
        write_branches(&args.out, s)?;
    }
    write_summary(&args.out.join("summary.csv"), &slices)?;
    phase_figure(&slices)
        .write(&args.out.join("phase"))
        .map_err(Error::from)?;
    for s in &slices {
        print_slice(s);
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

/// `c0` as it appears in file names (`-0.5` → `m0.50`, `1` → `1.00`, `1.035` → `1.035`): two
/// decimals, or as many as the value needs beyond them (so that 1.03 and 1.035 differ).
pub fn c0_tag(c0: f64) -> String {
    let two = format!("{:.2}", c0.abs());
    let t = if (two.parse::<f64>().unwrap_or(f64::NAN) - c0.abs()).abs() < 1e-12 {
        two
    } else {
        format!("{}", c0.abs())
    };
    if c0 < 0.0 {
        format!("m{t}")
    } else {
        t
    }
}

/// `branches_c0_<tag>.csv`: every shape of every branch (the pear in the order of its path).
fn write_branches(out: &Path, s: &Slice) -> Result<()> {
    let path = out.join(format!("branches_c0_{}.csv", c0_tag(s.c0)));
    let mut f = create_file(&path)?;
    let err = io_err(&path);
    writeln!(
        f,
        "branch,v,e,mean_curvature,sigma,pressure,length,asymmetry,neck,iterations,residual"
    )
    .map_err(&err)?;
    for sol in s.curves.iter().flatten().chain(&s.pear.shapes) {
        let neck = sol.neck().map_or(String::new(), |r| format!("{r:.8}"));
        writeln!(
            f,
            "{},{:.10},{:.12},{:.10},{:.10e},{:.10e},{:.10},{:.6e},{},{},{:.3e}",
            sol.branch.name(),
            sol.v,
            sol.e,
            sol.mean_curvature,
            sol.sigma,
            sol.pressure,
            sol.length(),
            sol.asymmetry(),
            neck,
            sol.iterations,
            sol.residual
        )
        .map_err(&err)?;
    }
    f.flush().map_err(&err)
}

/// The smallest neck over a list of shapes, with its `v`.
fn narrowest(shapes: &[Solution]) -> Option<(f64, f64)> {
    shapes
        .iter()
        .filter_map(|s| s.neck().map(|r| (s.v, r)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// `summary.csv`: per c̄0 and event, `c0,event,v,e,neck,detail`: the changes of the lowest
/// branch (`lowest branch changes` where the energies cross, the transitions; `branch ends`
/// where the lowest changes only because a branch ends or begins inside a grid interval), the
/// pear's bifurcation, fold and end, L_pear, the narrowest necks and the branch ends.
fn write_summary(path: &Path, slices: &[Slice]) -> Result<()> {
    let mut f = create_file(path)?;
    let err = io_err(path);
    writeln!(f, "c0,event,v,e,neck,detail").map_err(&err)?;
    let fmt = |x: Option<f64>, d: usize| x.map_or(String::new(), |x| format!("{x:.d$}"));
    for s in slices {
        let mut row =
            |event: &str, v: Option<f64>, e: Option<f64>, neck: Option<f64>, detail: &str| {
                writeln!(
                    f,
                    "{},{event},{},{},{},{detail}",
                    s.c0,
                    fmt(v, 6),
                    fmt(e, 8),
                    fmt(neck, 5)
                )
            };
        for c in &s.lowest.changes {
            let (event, how) = if c.crossing {
                ("lowest branch changes", "energies cross")
            } else {
                (
                    "branch ends",
                    "grid midpoint: no energy crossing, a branch ends or begins",
                )
            };
            row(
                event,
                Some(c.x),
                None,
                None,
                &format!(
                    "{} below / {} above ({how})",
                    c.below.name(),
                    c.above.name()
                ),
            )
            .map_err(&err)?;
        }
        match &s.pear.bifurcation {
            Some(b) => row(
                "pear bifurcation",
                Some(b.v),
                Some(b.e),
                None,
                "the prolate loses up-down stability (zero of its odd test function); the pear leaves it",
            ),
            None => row(
                "pear bifurcation",
                None,
                None,
                None,
                "none: prolate stable to up-down asymmetry for v >= 0.3",
            ),
        }
        .map_err(&err)?;
        if let Some(top) = s
            .pear
            .shapes
            .iter()
            .max_by(|a, b| a.v.total_cmp(&b.v))
            .filter(|t| {
                s.pear
                    .bifurcation
                    .as_ref()
                    .is_some_and(|b| t.v > b.v + 1e-6)
            })
        {
            row(
                "pear fold",
                Some(top.v),
                Some(top.e),
                top.neck(),
                "largest v on the pear branch (limit point)",
            )
            .map_err(&err)?;
        }
        match &s.pear.end {
            Some(PearEnd::Neck { v, neck }) => {
                let e = s.pear.last.as_ref().map(|l| l.e);
                row(
                    "pear neck stop",
                    Some(*v),
                    e,
                    Some(*neck),
                    &format!(
                        "continuation stopped at neck <= {} (still open; it closes at L_pear)",
                        axisym::NECK_MIN
                    ),
                )
            }
            Some(PearEnd::Stalled { v }) => {
                row("pear stalled", Some(*v), None, None, "continuation failed")
            }
            Some(PearEnd::Grid) => row("pear reaches v-min", None, None, None, ""),
            None => Ok(()),
        }
        .map_err(&err)?;
        match axisym::l_pear_radii(s.c0) {
            Some((r1, r2)) => row(
                "L_pear",
                axisym::l_pear(s.c0),
                None,
                Some(0.0),
                &format!(
                    "two spheres R1 = {r1:.5} and R2 = {r2:.5} (R0 = 1) with 1/R1 + 1/R2 = c0"
                ),
            ),
            None => row("L_pear", None, None, None, "none: c0 < 2*sqrt(2)"),
        }
        .map_err(&err)?;
        if let Some(lim) = axisym::neck_limit(&s.pear) {
            row(
                "L_pear (neck limit)",
                Some(lim.v),
                None,
                Some(0.0),
                &format!(
                    "pear path extrapolated to a closed neck (fit of {} shapes with neck < {}); \
                     pole curvatures sum -> {:.5}",
                    lim.points,
                    axisym::NECK_FIT,
                    lim.pole_sum
                ),
            )
            .map_err(&err)?;
        }
        for (b, c) in Branch::ALL.iter().zip(&s.curves) {
            if let Some((v, r)) = narrowest(c) {
                row("narrowest neck", Some(v), None, Some(r), b.name()).map_err(&err)?;
            }
        }
        if let Some(v) = s.stomatocyte_end {
            row("stomatocyte end", Some(v), None, None, "limit point").map_err(&err)?;
        }
        if let Some(v) = s.oblate_contact {
            row("oblate self-contact", Some(v), None, None, "").map_err(&err)?;
        }
    }
    f.flush().map_err(&err)
}

/// The phase diagram: a marker at every `(v, c̄0)` of the grid coloured by the lowest-energy
/// branch (the pear region among them), the prolate's stability line against up–down
/// asymmetry (the pear bifurcation), the line where the pear's neck reaches
/// [`axisym::NECK_MIN`] and the budding limit L_pear of the two-sphere formula (c̄0 ≥ 2√2).
pub fn phase_figure(slices: &[Slice]) -> Figure {
    let mut fig = Figure::new(
        "lowest-energy shape, spontaneous-curvature model",
        Axis::linear("reduced volume v"),
        Axis::linear("reduced spontaneous curvature c0·R0"),
    );
    let shapes = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    for (i, b) in Branch::WITH_PEAR.iter().enumerate() {
        let pts: Vec<(f64, f64)> = slices
            .iter()
            .flat_map(|s| {
                s.lowest
                    .points
                    .iter()
                    .filter(|(_, lb, _)| lb == b)
                    .map(move |(v, _, _)| (*v, s.c0))
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
    let pear_line: Vec<(f64, f64)> = slices
        .iter()
        .filter_map(|s| s.pear.bifurcation.as_ref().map(|b| (b.v, s.c0)))
        .collect();
    if !pear_line.is_empty() {
        fig.push(Series::new(
            "prolate loses up-down stability",
            pear_line,
            colour(4),
            Mark::LinePoints(Shape::Cross),
        ));
    }
    let limit_line: Vec<(f64, f64)> = slices
        .iter()
        .filter_map(|s| match s.pear.end {
            Some(PearEnd::Neck { v, .. }) => Some((v, s.c0)),
            _ => None,
        })
        .collect();
    if !limit_line.is_empty() {
        fig.push(Series::new(
            "pear neck 0.005 R0",
            limit_line,
            colour(5),
            Mark::Dashed,
        ));
    }
    let l_pear_line: Vec<(f64, f64)> = slices
        .iter()
        .filter_map(|s| axisym::l_pear(s.c0).map(|v| (v, s.c0)))
        .collect();
    if !l_pear_line.is_empty() {
        fig.push(Series::new(
            "L_pear (two-sphere limit)",
            l_pear_line,
            colour(6),
            Mark::LinePoints(Shape::Diamond),
        ));
    }
    fig
}

fn print_slice(s: &Slice) {
    println!("c0 = {}:", s.c0);
    for (b, c) in Branch::ALL.iter().zip(&s.curves) {
        if let (Some(lo), Some(hi)) = (c.first(), c.last()) {
            println!(
                "  {:<12} v {:.3}..{:.3}, e {:.6}..{:.6}",
                b.name(),
                lo.v,
                hi.v,
                lo.e,
                hi.e
            );
        }
    }
    for c in &s.lowest.changes {
        println!(
            "  lowest: {} below / {} above v = {:.4}{}",
            c.below.name(),
            c.above.name(),
            c.x,
            if c.crossing {
                ""
            } else {
                " (grid midpoint: a branch ends, no crossing)"
            }
        );
    }
    match &s.pear.bifurcation {
        Some(b) => println!("  pear bifurcation at v = {:.5} (e = {:.6})", b.v, b.e),
        None => println!("  no pear bifurcation on the prolate for v ≥ 0.3"),
    }
    if let Some(PearEnd::Neck { v, neck }) = &s.pear.end {
        println!("  pear neck {neck:.4} at v = {v:.4} (continuation stopped; the neck is open)");
    }
    if let Some(lim) = axisym::neck_limit(&s.pear) {
        println!(
            "  pear extrapolated to a closed neck: v = {:.5}, pole curvatures sum {:.4}",
            lim.v, lim.pole_sum
        );
    }
    match axisym::l_pear(s.c0) {
        Some(v) => println!("  L_pear (two-sphere limit, 1/R1 + 1/R2 = c0) at v = {v:.5}"),
        None => println!("  no L_pear (c0 < 2√2)"),
    }
}

#[cfg(test)]
mod tests {
    use super::c0_tag;

    /// Two decimals where they suffice (the committed folder names), more where the value has
    /// them: 1.03 and 1.035 (two slices of one bilayer-couple diagram) get different folders.
    #[test]
    fn tags_keep_the_digits_that_tell_values_apart() {
        assert_eq!(c0_tag(-0.5), "m0.50");
        assert_eq!(c0_tag(1.0), "1.00");
        assert_eq!(c0_tag(1.03), "1.03");
        assert_eq!(c0_tag(1.035), "1.035");
        assert_eq!(c0_tag(-1.125), "m1.125");
    }
}
