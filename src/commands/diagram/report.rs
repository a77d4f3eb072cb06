//! The merged diagram: `diagram.csv` (one row per point: the extrapolated estimate first, then
//! the finest resolution's raw values), `cases.csv` (every case, with iterations and wall
//! time), `transitions.csv`, `reference.csv`, the chart and the thumbnails, and a printed
//! table against the reference.

use super::case::CaseResult;
use super::extrapolate::{Orders, Point};
use super::reference::{Reference, TRANSITIONS};
use super::spec::{branch_named, Couple, SliceAt, BRANCHES};
use crate::analysis::axisym::Branch;
use crate::analysis::curves::crossings;
use crate::error::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// Relative error `e / e_ref − 1` (NaN when the reference does not reach `v`).
fn error(reference: &Reference, branch: &str, v: f64, e: f64) -> f64 {
    let b = branch_named(branch).expect("a listed branch");
    e / reference.e(b, v) - 1.0
}

/// Per branch of [`BRANCHES`]: its points as `(v, e)` in increasing v, by `coords`.
pub fn branch_points(points: &[Point], coords: fn(&Point) -> (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    BRANCHES
        .iter()
        .map(|b| {
            let mut pts: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.branch == b.name())
                .map(coords)
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            pts
        })
        .collect()
}

/// What a crossing of two branches is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Between the two lowest-energy branches: the ground state changes shape.
    Transition,
    /// Between two branches that a third lies below: both metastable, nothing changes.
    Metastable,
}

impl Kind {
    /// In tables and CSV files.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Transition => "transition",
            Kind::Metastable => "metastable crossing",
        }
    }
}

/// The kind of each pair of [`TRANSITIONS`], at the reference crossing (a transition when the
/// curves do not cross on the computed range: nothing to judge it by).
pub fn kinds(reference: &Reference) -> Vec<Kind> {
    TRANSITIONS
        .iter()
        .map(|&(a, b)| match reference.transition(a, b).as_slice() {
            [v] if !reference.is_transition(a, b, *v) => Kind::Metastable,
            _ => Kind::Transition,
        })
        .collect()
}

/// The crossing volumes of the reference, of the extrapolated points and of the finest
/// resolution, per pair of [`TRANSITIONS`] (NaN where the curves do not cross once).
pub fn transitions(points: &[Point], reference: &Reference) -> Vec<(String, [f64; 3])> {
    let extrapolated = branch_points(points, |p| (p.v, p.e));
    let finest = branch_points(points, |p| (p.finest().v, p.finest().e));
    let index = |b: Branch| BRANCHES.iter().position(|x| *x == b).expect("listed");
    let single = |vs: Vec<f64>| if vs.len() == 1 { vs[0] } else { f64::NAN };
    TRANSITIONS
        .iter()
        .map(|&(a, b)| {
            let (i, j) = (index(a), index(b));
            (
                format!("{}/{}", a.name(), b.name()),
                [
                    single(reference.transition(a, b)),
                    single(crossings(&extrapolated[i], &extrapolated[j])),
                    single(crossings(&finest[i], &finest[j])),
                ],
            )
        })
        .collect()
}

fn write(dir: &Path, name: &str, text: &str) -> Result<()> {
    crate::commands::study::write_text(dir, name, text)
}

/// Write the CSV files of the merged diagram to `out`.
///
/// # Errors
/// I/O errors.
pub fn write_csv(
    out: &Path,
    points: &[Point],
    results: &[CaseResult],
    reference: &Reference,
) -> Result<()> {
    let mut s = String::from(
        "branch,v,e,v_target,e_reference,error,r0_finest,v_finest,e_finest,e_reference_finest,\
         error_finest,v_diffuse_finest,sigma_finest,resolutions_used,da,da_surface,da_reference,\
         da_surface_finest,da_reference_finest\n",
    );
    for p in points {
        let f = p.finest();
        let b = branch_named(&p.branch).expect("listed");
        let used: Vec<String> = p.cases.iter().map(|c| c.r0.to_string()).collect();
        let _ = writeln!(
            s,
            "{},{:.6},{:.6},{},{:.6},{:.3e},{},{:.6},{:.6},{:.6},{:.3e},{:.6},{:.6e},{},{:.6},{:.6},{:.6},{:.6},{:.6}",
            p.branch,
            p.v,
            p.e,
            p.v_target,
            reference.e(b, p.v),
            error(reference, &p.branch, p.v, p.e),
            f.r0,
            f.v,
            f.e,
            reference.e(b, f.v),
            error(reference, &p.branch, f.v, f.e),
            f.v_diffuse,
            f.sigma,
            used.join(" "),
            p.da,
            p.da_surface,
            reference.da(b, p.v),
            f.da_surface.unwrap_or(f64::NAN),
            reference.da(b, f.v),
        );
    }
    write(out, "diagram.csv", &s)?;

    let mut s = String::from(
        "index,branch,v_target,r0,n,points,v,v_diffuse,e,e_reference,error,sigma,residual,\
         iterations,stopped,da,da_surface,da_reference,skewness,wall_seconds\n",
    );
    for r in results {
        let b = branch_named(&r.branch).expect("listed");
        let _ = writeln!(
            s,
            "{},{},{},{},{}x{}x{},{},{:.8},{:.8},{:.8},{:.8},{:.3e},{:.8e},{:.3e},{},{},{:.8},{:.8},{:.8},{:.5},{:.2}",
            r.index,
            r.branch,
            r.v_target,
            r.r0,
            r.n[0],
            r.n[1],
            r.n[2],
            r.points,
            r.v,
            r.v_diffuse,
            r.e,
            reference.e(b, r.v),
            error(reference, &r.branch, r.v, r.e),
            r.sigma,
            r.residual,
            r.iterations,
            r.stopped,
            r.da.unwrap_or(f64::NAN),
            r.da_surface.unwrap_or(f64::NAN),
            reference.da(b, r.v),
            r.skewness.unwrap_or(f64::NAN),
            r.wall_seconds,
        );
    }
    write(out, "cases.csv", &s)?;

    let mut s = String::from("transition,reference,extrapolated,finest,kind\n");
    for ((name, [r, e, f]), kind) in transitions(points, reference)
        .into_iter()
        .zip(kinds(reference))
    {
        let _ = writeln!(s, "{name},{r:.5},{e:.5},{f:.5},{}", kind.as_str());
    }
    write(out, "transitions.csv", &s)?;

    let mut s = String::from("branch,v,e\n");
    for (b, c) in BRANCHES.iter().zip(&reference.curves) {
        for (v, e) in c {
            let _ = writeln!(s, "{},{v:.6},{e:.8}", b.name());
        }
    }
    write(out, "reference.csv", &s)
}

/// The printed table: every point against the reference, the orders, the transitions, the
/// worst errors and the cases that did not converge.
pub fn table(
    points: &[Point],
    results: &[CaseResult],
    orders: Orders,
    reference: &Reference,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<12} {:>6} | {:>5} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
        "branch", "v0", "R0/ε", "v", "e", "error", "v∞", "e∞", "error"
    );
    let (mut worst_raw, mut worst_ext) = ((0.0f64, String::new()), (0.0f64, String::new()));
    for p in points {
        let f = p.finest();
        let (er, ee) = (
            error(reference, &p.branch, f.v, f.e),
            error(reference, &p.branch, p.v, p.e),
        );
        let _ = writeln!(
            s,
            "{:<12} {:>6.3} | {:>5} {:>8.5} {:>8.5} {:>+7.3}% | {:>8.5} {:>8.5} {:>+7.3}%",
            p.branch,
            p.v_target,
            f.r0,
            f.v,
            f.e,
            100.0 * er,
            p.v,
            p.e,
            100.0 * ee
        );
        let at = format!("{} v0 = {}", p.branch, p.v_target);
        if er.abs() > worst_raw.0 {
            worst_raw = (er.abs(), at.clone());
        }
        if ee.abs() > worst_ext.0 {
            worst_ext = (ee.abs(), at);
        }
    }
    let _ = writeln!(
        s,
        "orders in ε/R0 (least squares over all points): v {:.2}, e {:.2}",
        orders.v, orders.e
    );
    for p in points.iter().filter(|p| !p.dropped.is_empty()) {
        let r0: Vec<String> = p.dropped.iter().map(|c| c.r0.to_string()).collect();
        let _ = writeln!(
            s,
            "{} v0 = {}: R0/ε = {} left out (e jumps by more than {}% to the next resolution)",
            p.branch,
            p.v_target,
            r0.join(", "),
            100.0 * super::extrapolate::JUMP
        );
    }
    let _ = writeln!(
        s,
        "worst |error|: finest resolution {:.3}% ({}), extrapolated {:.3}% ({})",
        100.0 * worst_raw.0,
        worst_raw.1,
        100.0 * worst_ext.0,
        worst_ext.1
    );
    for ((name, [r, e, f]), kind) in transitions(points, reference)
        .into_iter()
        .zip(kinds(reference))
        .filter(|((_, t), _)| t.iter().any(|x| x.is_finite()))
    {
        let what = match kind {
            Kind::Transition => "transition",
            Kind::Metastable => "crossing",
        };
        let note = match kind {
            Kind::Transition => "",
            Kind::Metastable => "  (two metastable branches: a third is lower; not a transition)",
        };
        let _ = writeln!(
            s,
            "{what} {name:<20} reference {r:.4}  extrapolated {e:.4} ({:+.4})  finest {f:.4} ({:+.4}){note}",
            e - r,
            f - r
        );
    }
    let failed: Vec<String> = results
        .iter()
        .filter(|r| !r.converged())
        .map(|r| format!("{} ({})", r.index, r.stopped))
        .collect();
    if !failed.is_empty() {
        let _ = writeln!(s, "NOT stationary: cases {}", failed.join(", "));
    }
    let wall: f64 = results.iter().map(|r| r.wall_seconds).sum();
    let _ = writeln!(
        s,
        "{} cases; their wall times (one thread each) add up to {:.0} s",
        results.len(),
        wall
    );
    s
}

/// Δa rows, under `heading`: per point the finest resolution's Δa (`finest`) and the
/// extrapolated Δa∞ (`extrapolated`) against the reference's Δa at the same v (the finest's v,
/// and v∞).
pub fn da_table(
    heading: &str,
    points: &[Point],
    reference: &Reference,
    finest: fn(&CaseResult) -> f64,
    extrapolated: fn(&Point) -> f64,
) -> String {
    let mut s = format!(
        "{heading}\n{:<12} {:>6} | {:>8} {:>8} {:>9} | {:>8} {:>8} {:>9}\n",
        "branch", "v0", "Δa", "Δa_ref", "error", "Δa∞", "Δa_ref", "error"
    );
    for p in points {
        let b = branch_named(&p.branch).expect("listed");
        let f = p.finest();
        let (fd, rf, pd, rd) = (
            finest(f),
            reference.da(b, f.v),
            extrapolated(p),
            reference.da(b, p.v),
        );
        let _ = writeln!(
            s,
            "{:<12} {:>6.3} | {:>8.5} {:>8.5} {:>+8.3}% | {:>8.5} {:>8.5} {:>+8.3}%",
            p.branch,
            p.v_target,
            fd,
            rf,
            100.0 * (fd / rf - 1.0),
            pd,
            rd,
            100.0 * (pd / rd - 1.0)
        );
    }
    s
}

/// `errors.png` (of the slice `at`): the relative error `e / e_ref(v) − 1` (w with ADE) in percent against v, per branch (in
/// the diagram's colours), of the extrapolated points (solid line, filled circles) and of the
/// finest resolution's raw points (dashed line, squares); a line breaks where the reference
/// does not reach v.
///
/// # Errors
/// `Error::Output` if drawing or writing fails.
pub fn write_error_chart(
    out: &Path,
    at: SliceAt,
    points: &[Point],
    reference: &Reference,
) -> Result<()> {
    use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
    let title = if at.c0 == 0.0 && at.couple.is_none() {
        "Phase-field error against the axisymmetric reference, per branch".to_string()
    } else {
        format!(
            "Phase-field error against the axisymmetric reference at {}, per branch",
            at.describe()
        )
    };
    let energy = if matches!(at.couple, Some(Couple::Ade { .. })) {
        "w"
    } else {
        "e"
    };
    let mut fig = Figure::new(
        title,
        Axis::linear("reduced volume v"),
        Axis::linear(format!("{energy} / {energy}_reference(v) − 1  [%]")),
    );
    fig.legend = Corner::UpperRight;
    for (i, b) in BRANCHES.into_iter().enumerate() {
        let pct = |v: f64, e: f64| 100.0 * (e / reference.e(b, v) - 1.0);
        let mine: Vec<&Point> = points.iter().filter(|p| p.branch == b.name()).collect();
        if mine.is_empty() {
            continue;
        }
        let sorted = |mut pts: Vec<(f64, f64)>| {
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            pts
        };
        // The diagram's branch colours are the palette's first three.
        fig.push(Series::new(
            format!("{}, extrapolated ε/R0 → 0", b.name()),
            sorted(mine.iter().map(|p| (p.v, pct(p.v, p.e))).collect()),
            colour(i),
            Mark::LinePoints(Shape::Circle),
        ));
        fig.push(Series::new(
            format!("{}, finest ε/R0 (raw)", b.name()),
            sorted(
                mine.iter()
                    .map(|p| (p.finest().v, pct(p.finest().v, p.finest().e)))
                    .collect(),
            ),
            colour(i),
            Mark::DashedPoints(Shape::Square),
        ));
    }
    fig.write_png(&out.join("errors.png"))?;
    Ok(())
}

/// Check that `results` cover `expected` cases.
///
/// # Errors
/// `Error::Config` (field `--merge`) listing the cases without a result.
pub fn check_complete(expected: usize, results: &[Option<CaseResult>]) -> Result<()> {
    let missing: Vec<String> = results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.is_none())
        .map(|(k, _)| k.to_string())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(Error::config(
        "--merge",
        format!(
            "{} of {expected} cases have no result yet (run them with --case K): {}",
            missing.len(),
            missing.join(", ")
        ),
    ))
}
