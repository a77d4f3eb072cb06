//! The heating study's report: the printed table (the rows of `heating.csv`), the reference's
//! transitions per R0, where the phase field's neck departs from the sharp pear's, and the
//! charts `heating_neck`, `heating_w`, `heating_w_error` and `heating_departure`.

use super::reference::Sharp;
use super::{Row, Spec};
use crate::commands::study::budding::SYMMETRIC_SKEWNESS;
use crate::commands::study::harness::Report;
use crate::commands::study::table::{self, Column, Format};
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use std::fmt::Write as _;

/// The phase field's neck departs from the sharp pear's where they differ by more than this
/// fraction of the sharp neck.
pub const DEPARTURE: f64 = 0.2;

/// Δa0 within which the stable pear counts as starting at the bifurcation (continuous).
pub const CONTINUOUS_TOL: f64 = 0.005;

/// |Skewness| above which a state counts as on the pear branch: the sharp pears of this study
/// have |skewness| ≈ 1, the weakly asymmetric prolates the phase field finds near the
/// bifurcation 0.01–0.05.
pub const PEAR_SKEWNESS: f64 = 0.3;

impl table::Row for Row {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("r0", "R0/eps", Format::Fixed(0), |r| r.r0.into()),
            Column::csv("index", |r| r.index.into()),
            Column::both("da0", "da0", Format::Fixed(3), |r| r.da0.into()),
            Column::both("iterations", "iters", Format::Plain, |r| {
                r.iterations.into()
            }),
            Column::both("stopped", "stopped", Format::Plain, |r| {
                r.stopped.as_str().into()
            }),
            Column::csv("residual", |r| r.residual.into()),
            Column::both("w", "w", Format::Fixed(4), |r| r.w.into()),
            Column::csv("e", |r| r.e.into()),
            Column::both("da", "da", Format::Fixed(4), |r| r.da.into()),
            Column::both("c0_eff", "c0eff", Format::Fixed(2), |r| r.c0_eff.into()),
            Column::csv("eps_c0_eff", |r| r.eps_c0_eff.into()),
            Column::both("v", "v", Format::Fixed(4), |r| r.v.into()),
            Column::both("neck", "neck/eps", Format::Fixed(2), |r| r.neck.into()),
            Column::both("neck_r0", "neck/R0", Format::Fixed(4), |r| r.neck_r0.into()),
            Column::both("skewness", "skew", Format::Fixed(4), |r| r.skewness.into()),
            Column::both("pieces", "pc", Format::Plain, |r| r.pieces.into()),
            Column::both("state", "state", Format::Plain, |r| r.state.as_str().into()),
            Column::both("w_prolate_ref", "w_prol", Format::Fixed(4), |r| {
                r.w_prolate_ref.into()
            }),
            Column::csv("waist_ref", |r| r.waist_ref.into()),
            Column::both("w_pear_ref", "w_pear", Format::Fixed(4), |r| {
                r.w_pear_ref.into()
            }),
            Column::both("neck_pear_ref", "neck_ref", Format::Fixed(4), |r| {
                r.neck_pear_ref.into()
            }),
            Column::csv("bifurcation_ref", |r| r.bifurcation_ref.into()),
            Column::csv("fold_ref", |r| r.fold_ref.into()),
            Column::csv("transition_ref", |r| r.transition_ref.into()),
            Column::csv("wall_seconds", |r| r.wall_seconds.into()),
        ]
    }
}

/// The report of `rows` (all R0) with the references `sharp` (one per grid v).
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn report(spec: &Spec, rows: &[Row], sharp: &[Sharp]) -> Result<Report> {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "budding on heating: ADE alpha = {}, start v = {}, seed {}; L-BFGS through stationary \
         states in da0 (no time: the path is not a transient)",
        spec.alpha, spec.v, spec.seed
    );
    text.push_str(&table::text(rows));
    let _ = writeln!(
        text,
        "reference: the stable ADE prolate (w_prol) and pear (w_pear, neck_ref in R0) at each \
         row's phi = 0 v; - off a stable stretch"
    );
    for &r0 in &spec.r0 {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.r0 == r0).collect();
        let _ = writeln!(text, "  R0 = {r0} eps: {}", summary(&mine, sharp));
    }
    let mut report = Report {
        text,
        ..Report::default()
    };
    report.table("heating.csv", rows)?;
    let chart_ref = rows
        .iter()
        .rev()
        .find(|r| on_pear(r))
        .or(rows.last())
        .and_then(|r| nearest(sharp, r.v));
    report.chart("heating_neck", neck_chart(spec, rows, chart_ref));
    report.chart("heating_w", w_chart(spec, rows, chart_ref));
    report.chart("heating_w_error", w_error_chart(spec, rows));
    report.chart("heating_departure", departure_chart(spec, rows));
    Ok(report)
}

/// The reference of `sharp` nearest in v to `v`.
pub fn nearest(sharp: &[Sharp], v: f64) -> Option<&Sharp> {
    sharp
        .iter()
        .min_by(|a, b| (a.v - v).abs().total_cmp(&(b.v - v).abs()))
}

/// The rows of the way up (up to the first step down).
pub fn way_up<'a>(rows: &[&'a Row]) -> Vec<&'a Row> {
    let up = rows.windows(2).take_while(|w| w[1].da0 > w[0].da0).count() + 1;
    rows.iter().take(up).copied().collect()
}

/// Whether `row` is on the pear: |skewness| above [`PEAR_SKEWNESS`] and one piece.
pub fn on_pear(row: &Row) -> bool {
    row.skewness.abs() > PEAR_SKEWNESS && row.pieces == 1
}

/// The sharp w of the branch `row` is on: the pear's if [`on_pear`], else the prolate's.
pub fn w_ref(row: &Row) -> f64 {
    if on_pear(row) {
        row.w_pear_ref
    } else {
        row.w_prolate_ref
    }
}

/// The Δa0 interval `(a, b)` between the rows `i − 1` and `i` of `rows` (a NaN for `i = 0`).
fn between(rows: &[&Row], i: usize) -> (f64, f64) {
    let a = if i > 0 { rows[i - 1].da0 } else { f64::NAN };
    (a, rows[i].da0)
}

/// One run's transitions and departure: on the way up the first weakly asymmetric state
/// (|skewness| ≥ 0.01) and the jump to the pear ([`on_pear`]), on the way down the return to
/// the prolate, each as the Δa0 interval between two steps; the reference at the v of the
/// last state before the jump (bifurcation, fold, crossing of the energies, whether
/// continuous); and on the pear the phase field's neck against the sharp pear's: the range of
/// their ratio and the largest sharp neck (in ε) at which the phase field's is more than
/// [`DEPARTURE`] wider.
pub fn summary(rows: &[&Row], sharp: &[Sharp]) -> String {
    let up = way_up(rows);
    let down = &rows[up.len().saturating_sub(1)..];
    let mut s = String::new();
    if let Some(i) = up
        .iter()
        .position(|r| r.skewness.abs() >= SYMMETRIC_SKEWNESS)
    {
        let (a, b) = between(&up, i);
        let _ = write!(
            s,
            "weakly asymmetric between da0 = {a:.3} and {b:.3} (skewness {:.3}); ",
            up[i].skewness
        );
    }
    let Some(i) = up.iter().position(|r| on_pear(r)) else {
        s.push_str("no pear on the way up");
        return s;
    };
    let (a, b) = between(&up, i);
    let _ = write!(
        s,
        "jumps to the pear between da0 = {a:.3} and {b:.3} (da {:.4} -> {:.4}, neck {:.2} eps)",
        if i > 0 { up[i - 1].da } else { f64::NAN },
        up[i].da,
        up[i].neck
    );
    if let Some(j) = down.iter().position(|r| !on_pear(r)) {
        let (a, b) = between(down, j);
        let _ = write!(s, ", back to the prolate between da0 = {a:.3} and {b:.3}");
    }
    if let Some(h) = nearest(sharp, if i > 0 { up[i - 1].v } else { up[i].v }) {
        let _ = write!(
            s,
            "; sharp at v = {:.4}: pear bifurcation da0 = {:.4}, stable pear from {:.4}, \
             energies cross at {:.4} ({}), L_pear at {:.4}",
            h.v,
            h.bifurcation,
            h.fold,
            h.transition,
            if h.continuous(CONTINUOUS_TOL) {
                "continuous"
            } else {
                "discontinuous"
            },
            h.l_pear
        );
    }
    let pears: Vec<&Row> = rows
        .iter()
        .copied()
        .filter(|r| on_pear(r) && r.neck_pear_ref > 0.0)
        .collect();
    let ratio = |r: &Row| r.neck_r0 / r.neck_pear_ref;
    if !pears.is_empty() {
        let lo = pears.iter().map(|r| ratio(r)).fold(f64::MAX, f64::min);
        let hi = pears.iter().map(|r| ratio(r)).fold(f64::MIN, f64::max);
        let _ = write!(
            s,
            "; on the pear the phase-field neck is {lo:.2}-{hi:.2} times the sharp one"
        );
    }
    if let Some(r) = pears
        .iter()
        .filter(|r| ratio(r) > 1.0 + DEPARTURE)
        .max_by(|a, b| a.neck_pear_ref.total_cmp(&b.neck_pear_ref))
    {
        let _ = write!(
            s,
            ", more than {:.0}% wider up to a sharp neck of {:.2} eps ({:.4} R0, da0 = {:.3}: \
             {:.2} eps)",
            100.0 * DEPARTURE,
            r.neck_pear_ref * r.r0,
            r.neck_pear_ref,
            r.da0,
            r.neck
        );
    }
    s
}

/// `(Δa0, y)` of the finite values of `f` over the rows of `r0`.
fn series(rows: &[Row], r0: f64, f: impl Fn(&Row) -> f64) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.r0 == r0)
        .map(|r| (r.da0, f(r)))
        .filter(|p| p.1.is_finite() && p.1 > 0.0)
        .collect()
}

/// `(Δa0, f(Δa0))` on a grid of step 0.0025 over `(lo, hi)`, the finite positive values.
fn sampled((lo, hi): (f64, f64), f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    let n = ((hi - lo) / 0.0025).ceil() as usize;
    (0..=n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .map(|x| (x, f(x)))
        .filter(|p| p.1.is_finite() && p.1 > 0.0)
        .collect()
}

/// The Δa0 range of the path, widened by 0.02.
fn window(spec: &Spec) -> (f64, f64) {
    let lo = spec.da0.iter().copied().fold(f64::MAX, f64::min) - 0.02;
    let hi = spec.da0.iter().copied().fold(f64::MIN, f64::max) + 0.02;
    (lo, hi)
}

/// Neck / R0 (log scale) against Δa0: each R0's phase field beside the sharp stable pear's
/// neck and the prolate's waist at `sharp`'s v (the last asymmetric row's).
fn neck_chart(spec: &Spec, rows: &[Row], sharp: Option<&Sharp>) -> Figure {
    let mut fig = Figure::new(
        format!(
            "Budding on heating (ADE, alpha = {}): neck against da0 at fixed v",
            spec.alpha
        ),
        Axis::linear("da0"),
        Axis::log("neck radius / R0"),
    );
    fig.legend = Corner::LowerLeft;
    let range = window(spec);
    if let Some(s) = sharp {
        fig.push(Series::new(
            format!("sharp stable pear (v = {:.4})", s.v),
            sampled(range, |x| s.pear_at(x).neck),
            colour(7),
            Mark::Line,
        ));
        fig.push(Series::new(
            "sharp prolate's waist",
            sampled(range, |x| s.prolate_at(x).neck),
            colour(7),
            Mark::Dashed,
        ));
    }
    for (i, &r0) in spec.r0.iter().enumerate() {
        fig.push(Series::new(
            format!("phase field R0 = {r0} eps"),
            series(rows, r0, |r| r.neck_r0),
            colour(i),
            Mark::LinePoints(Shape::Circle),
        ));
    }
    fig
}

/// w against Δa0: each R0's phase field beside the sharp stable prolate and pear.
fn w_chart(spec: &Spec, rows: &[Row], sharp: Option<&Sharp>) -> Figure {
    let mut fig = Figure::new(
        format!(
            "Budding on heating (ADE, alpha = {}): w against da0",
            spec.alpha
        ),
        Axis::linear("da0"),
        Axis::linear("w = e + pi alpha (da - da0)^2"),
    );
    fig.legend = Corner::UpperLeft;
    let range = window(spec);
    if let Some(s) = sharp {
        fig.push(Series::new(
            format!("sharp stable prolate (v = {:.4})", s.v),
            sampled(range, |x| s.prolate_at(x).w),
            colour(7),
            Mark::Dashed,
        ));
        fig.push(Series::new(
            "sharp stable pear",
            sampled(range, |x| s.pear_at(x).w),
            colour(7),
            Mark::Line,
        ));
    }
    for (i, &r0) in spec.r0.iter().enumerate() {
        fig.push(Series::new(
            format!("phase field R0 = {r0} eps"),
            series(rows, r0, |r| r.w),
            colour(i),
            Mark::LinePoints(Shape::Circle),
        ));
    }
    fig
}

/// w/w_sharp − 1 (%) against Δa0 per R0, w_sharp that of the branch the row is on
/// ([`w_ref`]) at the row's own v.
fn w_error_chart(spec: &Spec, rows: &[Row]) -> Figure {
    let mut fig = Figure::new(
        "Budding on heating: w against the sharp branch at the same v",
        Axis::linear("da0"),
        Axis::linear("w / w_sharp - 1 (%)"),
    );
    fig.legend = Corner::LowerRight;
    for (i, &r0) in spec.r0.iter().enumerate() {
        let pts = rows
            .iter()
            .filter(|r| r.r0 == r0)
            .map(|r| (r.da0, 100.0 * (r.w / w_ref(r) - 1.0)))
            .filter(|p| p.1.is_finite())
            .collect();
        fig.push(Series::new(
            format!("R0 = {r0} eps"),
            pts,
            colour(i),
            Mark::LinePoints(Shape::Circle),
        ));
    }
    fig
}

/// The phase field's neck against the sharp pear's at the same Δa0, both in ε, on the rows
/// on the pear ([`on_pear`]) with a sharp pear; the line y = x is agreement.
fn departure_chart(spec: &Spec, rows: &[Row]) -> Figure {
    let mut fig = Figure::new(
        "Budding on heating: phase-field neck against the sharp pear's",
        Axis::log("sharp pear neck / eps"),
        Axis::log("phase-field neck / eps"),
    );
    fig.legend = Corner::UpperLeft;
    let pts: Vec<Vec<(f64, f64)>> = spec
        .r0
        .iter()
        .map(|&r0| {
            rows.iter()
                .filter(|r| r.r0 == r0 && on_pear(r))
                .map(|r| (r.neck_pear_ref * r0, r.neck))
                .filter(|p| p.0.is_finite() && p.1.is_finite() && p.0 > 0.0 && p.1 > 0.0)
                .collect()
        })
        .collect();
    let all: Vec<f64> = pts.iter().flatten().flat_map(|p| [p.0, p.1]).collect();
    let lo = all.iter().copied().fold(f64::MAX, f64::min);
    let hi = all.iter().copied().fold(f64::MIN, f64::max);
    if lo < hi {
        fig.push(Series::new(
            "agreement",
            vec![(lo, lo), (hi, hi)],
            colour(7),
            Mark::Dashed,
        ));
    }
    for (i, (p, &r0)) in pts.into_iter().zip(&spec.r0).enumerate() {
        fig.push(Series::new(
            format!("R0 = {r0} eps"),
            p,
            colour(i),
            Mark::Points(Shape::Circle),
        ));
    }
    fig
}
