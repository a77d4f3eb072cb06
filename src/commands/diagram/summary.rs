//! The files of a diagram of several c̄0 that span its slices ([`super::merge::Slice`]), in
//! `OUT`: `diagram.csv`, `cases.csv` and `transitions.csv` (the slices' files with a first
//! column `c0`), `table.txt` (every slice's table, then the worst errors, the transitions
//! and the iterations per case against R0 over the whole diagram), `phase.png`/`phase.svg`
//! (the (v, c̄0) phase diagram of the reference, as `vesicle axisym --c0` draws it, with the
//! phase-field transitions on it) and `errors.png` (the error of e against c̄0, per branch).

use super::merge::Slice;
use super::report::Kind;
use super::spec::{branch_named, Couple, BRANCHES};
use crate::analysis::axisym::{phase, Branch, Options};
use crate::commands::axisym::phase::phase_figure;
use crate::error::{Error, Result};
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use std::fmt::Write as _;
use std::path::Path;

/// The lowest branch below and above a transition.
type BranchPair = (Branch, Branch);

/// Grid of reduced volumes of the reference phase diagram (`vesicle axisym`'s default).
const PHASE_V: (f64, f64, f64) = (0.5, 0.99, 0.01);

/// Write the files that span `slices` to `out` and return the printed table.
///
/// # Errors
/// I/O and drawing errors.
pub fn write(out: &Path, slices: &[Slice]) -> Result<String> {
    let column = column(slices);
    for name in ["diagram.csv", "cases.csv"] {
        let mut s = String::new();
        for (k, slice) in slices.iter().enumerate() {
            let path = slice.dir.join(name);
            let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
                path: path.clone(),
                source,
            })?;
            for (i, line) in text.lines().enumerate() {
                match (i, k) {
                    (0, 0) => {
                        let _ = writeln!(s, "{column},{line}");
                    }
                    (0, _) => {}
                    _ => {
                        let _ = writeln!(s, "{},{line}", slice.at.value());
                    }
                }
            }
        }
        crate::commands::study::write_text(out, name, &s)?;
    }
    let mut s = format!("{column},transition,reference,extrapolated,finest,kind\n");
    for slice in slices {
        for (name, [r, e, f], kind) in found(slice) {
            let _ = writeln!(
                s,
                "{},{name},{r:.5},{e:.5},{f:.5},{}",
                slice.at.value(),
                kind.as_str()
            );
        }
    }
    crate::commands::study::write_text(out, "transitions.csv", &s)?;
    let table = table(slices);
    crate::commands::study::write_text(out, "table.txt", &table)?;
    phase_chart(slices)
        .write(&out.join("phase"))
        .map_err(Error::from)?;
    error_chart(slices)
        .write_png(&out.join("errors.png"))
        .map_err(Error::from)?;
    Ok(table)
}

/// The crossings of a slice that exist on either side (reference or phase field).
fn found(slice: &Slice) -> impl Iterator<Item = &(String, [f64; 3], Kind)> {
    slice
        .transitions
        .iter()
        .filter(|(_, t, _)| t.iter().any(|x| x.is_finite()))
}

/// Relative error `e / e_ref(v) − 1` of `branch` in `slice`.
fn error(slice: &Slice, branch: &str, v: f64, e: f64) -> f64 {
    e / slice.reference.e(branch_named(branch).expect("listed"), v) - 1.0
}

/// Every slice's table, then the whole diagram: the worst errors (relative, and absolute in
/// e), the transitions, the iterations per case against R0 and the summed case times.
fn table(slices: &[Slice]) -> String {
    let mut s = String::new();
    let label = slices.first().map_or("c0R0", |sl| sl.at.label());
    for slice in slices {
        let _ = writeln!(s, "=== {} ===", slice.at.describe());
        s.push_str(&slice.table);
        s.push('\n');
    }
    let _ = writeln!(s, "=== the whole diagram ===");
    let _ = writeln!(
        s,
        "{:>6} {:<12} {:>6} | {:>8} {:>8} {:>8} {:>9} | {:>8} {:>8} {:>8} {:>9}",
        label, "branch", "v0", "e_finest", "e_ref", "error", "Δe", "e∞", "e_ref", "error", "Δe"
    );
    for slice in slices {
        for p in &slice.points {
            let b = branch_named(&p.branch).expect("listed");
            let f = p.finest();
            let (rf, re) = (slice.reference.e(b, f.v), slice.reference.e(b, p.v));
            let _ = writeln!(
                s,
                "{:>6} {:<12} {:>6.3} | {:>8.5} {:>8.5} {:>+7.3}% {:>+9.5} | {:>8.5} {:>8.5} {:>+7.3}% {:>+9.5}",
                slice.at.value(),
                p.branch,
                p.v_target,
                f.e,
                rf,
                100.0 * (f.e / rf - 1.0),
                f.e - rf,
                p.e,
                re,
                100.0 * (p.e / re - 1.0),
                p.e - re
            );
        }
    }
    let worst = |get: &dyn Fn(&Slice, &super::extrapolate::Point) -> f64| {
        slices
            .iter()
            .flat_map(|sl| {
                sl.points.iter().map(move |p| {
                    (
                        get(sl, p).abs(),
                        sl.at.value(),
                        p.branch.clone(),
                        p.v_target,
                    )
                })
            })
            .fold((0.0f64, 0.0, String::new(), 0.0), |a, b| {
                if b.0 > a.0 {
                    b
                } else {
                    a
                }
            })
    };
    for (what, w) in [
        (
            "finest resolution",
            worst(&|sl, p| error(sl, &p.branch, p.finest().v, p.finest().e)),
        ),
        (
            "extrapolated",
            worst(&|sl, p| error(sl, &p.branch, p.v, p.e)),
        ),
    ] {
        let _ = writeln!(
            s,
            "worst |error|, {what}: {:.3}% ({} v0 = {} at {label} = {})",
            100.0 * w.0,
            w.2,
            w.3,
            w.1
        );
    }
    let _ = writeln!(
        s,
        "{:>6} {:<24} {:>9} {:>13} {:>17} {:>17}",
        label, "crossing", "kind", "reference", "extrapolated", "finest"
    );
    for slice in slices {
        for (name, [r, e, f], kind) in found(slice) {
            let _ = writeln!(
                s,
                "{:>6} {:<24} {:>9} {:>13.4} {:>8.4} ({:+.4}) {:>8.4} ({:+.4})",
                slice.at.value(),
                name,
                match kind {
                    Kind::Transition => "lowest",
                    Kind::Metastable => "metastable",
                },
                r,
                e,
                e - r,
                f,
                f - r
            );
        }
    }
    let mut r0: Vec<f64> = slices
        .iter()
        .flat_map(|sl| sl.results.iter().map(|r| r.r0))
        .collect();
    r0.sort_by(f64::total_cmp);
    r0.dedup();
    let heads: Vec<String> = r0.iter().map(|r| format!("R0 = {r}ε")).collect();
    let _ = writeln!(
        s,
        "L-BFGS iterations per case, mean (max), against R0:\n{:>6} {}",
        label,
        heads.iter().map(|h| format!("{h:>16}")).collect::<String>()
    );
    for slice in slices {
        let cells: String = r0
            .iter()
            .map(|&r| {
                let it: Vec<usize> = slice
                    .results
                    .iter()
                    .filter(|c| c.r0 == r)
                    .map(|c| c.iterations)
                    .collect();
                let mean = it.iter().sum::<usize>() as f64 / it.len().max(1) as f64;
                let max = it.iter().copied().max().unwrap_or(0);
                format!("{:>16}", format!("{mean:.0} ({max})"))
            })
            .collect();
        let _ = writeln!(s, "{:>6} {cells}", slice.at.value());
    }
    let cases: usize = slices.iter().map(|sl| sl.results.len()).sum();
    let seconds: f64 = slices
        .iter()
        .flat_map(|sl| sl.results.iter().map(|r| r.wall_seconds))
        .sum();
    let failed = slices
        .iter()
        .flat_map(|sl| sl.results.iter())
        .filter(|r| !r.converged())
        .count();
    let _ = writeln!(
        s,
        "{cases} cases ({failed} not stationary); their wall times (one thread each) add up to {seconds:.0} s"
    );
    s
}

/// `phase.png`: the reference's lowest-energy branch on the (v, c̄0) grid with its pear lines
/// ([`phase_figure`]), the reference transitions of the listed c̄0 as dashed lines,
/// and the phase-field transitions as markers (extrapolated: black crosses; finest
/// resolution: grey diamonds).
fn phase_chart(slices: &[Slice]) -> Figure {
    if slices.first().is_some_and(|s| s.at.couple.is_some()) {
        return ade_phase_chart(slices);
    }
    let (lo, hi, dv) = PHASE_V;
    let n = ((hi - lo) / dv).round() as usize;
    let vs: Vec<f64> = (0..=n).map(|i| lo + dv * i as f64).collect();
    let opts = Options::default();
    let reference: Vec<phase::Slice> = slices
        .iter()
        .map(|s| phase::slice(s.at.c0, &vs, &opts))
        .collect();
    let mut fig = phase_figure(&reference);
    fig.title = "lowest-energy shape: axisymmetric reference, phase-field transitions".into();
    fig.legend = Corner::UpperRight;
    // The reference transitions (energy crossings, not branch ends) between the same two
    // branches, joined across c̄0.
    let mut lines: Vec<(BranchPair, Vec<(f64, f64)>)> = Vec::new();
    for r in &reference {
        for t in r.lowest.changes.iter().filter(|c| c.crossing) {
            let key = (t.below, t.above);
            match lines.iter_mut().find(|(k, _)| *k == key) {
                Some((_, pts)) => pts.push((t.x, r.c0)),
                None => lines.push((key, vec![(t.x, r.c0)])),
            }
        }
    }
    for (k, ((below, above), pts)) in lines.into_iter().enumerate() {
        fig.push(Series::new(
            format!("{}/{} (reference)", below.name(), above.name()),
            pts,
            colour(6 + k),
            Mark::DashedPoints(Shape::Circle),
        ));
    }
    let markers = |which: usize| -> Vec<(f64, f64)> {
        slices
            .iter()
            .flat_map(|s| {
                s.transitions
                    .iter()
                    .filter(|(_, _, kind)| *kind == Kind::Transition)
                    .map(move |(_, t, _)| (t[which], s.at.value()))
            })
            .filter(|(v, _)| v.is_finite())
            .collect()
    };
    fig.push(Series::new(
        "phase field, finest R0",
        markers(2),
        [150, 150, 150],
        Mark::Points(Shape::Diamond),
    ));
    fig.push(Series::new(
        "phase field, extrapolated ε/R0 → 0",
        markers(1),
        [0, 0, 0],
        Mark::Points(Shape::Cross),
    ));
    fig
}

/// The first column of the merged CSV files: `c0`, `da0` for an ADE diagram, `da` for a
/// bilayer-couple one.
fn column(slices: &[Slice]) -> &'static str {
    match slices.first().and_then(|s| s.at.couple) {
        Some(Couple::Ade { .. }) => "da0",
        Some(Couple::Bc { .. }) => "da",
        None => "c0",
    }
}

/// `phase.png` of an ADE or bilayer-couple diagram: the transitions on the (v, Δa0) or
/// (v, Δa) plane, the reference's (joined across the slices, dashed) and the phase field's (extrapolated: black crosses; finest:
/// grey diamonds).
fn ade_phase_chart(slices: &[Slice]) -> Figure {
    let (title, y) = match slices.first().and_then(|s| s.at.couple) {
        Some(Couple::Ade { alpha, .. }) => (
            format!("ADE transitions at α = {alpha}: axisymmetric reference and phase field"),
            "preferred area difference Δa0",
        ),
        _ => (
            "Bilayer-couple transitions: axisymmetric reference and phase field".to_string(),
            "reduced area difference Δa",
        ),
    };
    let mut fig = Figure::new(title, Axis::linear("reduced volume v"), Axis::linear(y));
    fig.legend = Corner::UpperRight;
    let names: Vec<String> = slices
        .iter()
        .flat_map(|s| found(s).map(|(n, _, _)| n.clone()))
        .fold(Vec::new(), |mut v, n| {
            if !v.contains(&n) {
                v.push(n);
            }
            v
        });
    for (k, name) in names.iter().enumerate() {
        let pts = |which: usize| -> Vec<(f64, f64)> {
            slices
                .iter()
                .flat_map(|s| {
                    found(s)
                        .filter(|(n, _, _)| n == name)
                        .map(move |(_, t, _)| (t[which], s.at.value()))
                })
                .filter(|(v, _)| v.is_finite())
                .collect()
        };
        fig.push(Series::new(
            format!("{name} (reference)"),
            pts(0),
            colour(6 + k),
            Mark::DashedPoints(Shape::Circle),
        ));
        fig.push(Series::new(
            format!("{name}, phase field extrapolated"),
            pts(1),
            [0, 0, 0],
            Mark::Points(Shape::Cross),
        ));
        fig.push(Series::new(
            format!("{name}, phase field finest R0"),
            pts(2),
            [150, 150, 150],
            Mark::Points(Shape::Diamond),
        ));
    }
    fig
}

/// `errors.png`: `e / e_ref(v) − 1` in percent against c̄0 (or w against Δa0), per branch,
/// extrapolated (filled markers) and at the finest resolution (crosses).
fn error_chart(slices: &[Slice]) -> Figure {
    let (title, x, y) = match slices.first().and_then(|s| s.at.couple) {
        Some(Couple::Ade { .. }) => (
            "Phase-field error of w against the axisymmetric ADE reference, per Δa0",
            "preferred area difference Δa0",
            "w / w_reference(v) − 1  [%]",
        ),
        Some(Couple::Bc { .. }) => (
            "Phase-field error of e against the axisymmetric bilayer-couple reference, per Δa",
            "reduced area difference Δa",
            "e / e_reference(v) − 1  [%]",
        ),
        None => (
            "Phase-field error of e against the axisymmetric reference, per c0 R0",
            "reduced spontaneous curvature c0·R0",
            "e / e_reference(v) − 1  [%]",
        ),
    };
    let mut fig = Figure::new(title, Axis::linear(x), Axis::linear(y));
    fig.legend = Corner::LowerLeft;
    let shapes = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    for (i, b) in BRANCHES.iter().enumerate() {
        let pts = |finest: bool| -> Vec<(f64, f64)> {
            slices
                .iter()
                .flat_map(|sl| {
                    sl.points
                        .iter()
                        .filter(|p| p.branch == b.name())
                        .map(move |p| {
                            let (v, e) = if finest {
                                (p.finest().v, p.finest().e)
                            } else {
                                (p.v, p.e)
                            };
                            (sl.at.value(), 100.0 * error(sl, &p.branch, v, e))
                        })
                })
                .collect()
        };
        let (ext, fin) = (pts(false), pts(true));
        if ext.is_empty() {
            continue;
        }
        fig.push(Series::new(
            format!("{}, extrapolated ε/R0 → 0", b.name()),
            ext,
            colour(i),
            Mark::Points(shapes[i]),
        ));
        fig.push(Series::new(
            format!("{}, finest ε/R0 (raw)", b.name()),
            fin,
            colour(i),
            Mark::Points(Shape::Cross),
        ));
    }
    fig
}
