//! The onset study's report: the printed tables, `onset_steps.csv`, `onset.csv`, the
//! extrapolation of the shift in ε/R0, and the charts `onset_skewness` and `onset_eps`.
//!
//! **The shift.** The onset is compared with the sharp instability c̄0*(v) at the run's own
//! φ = 0 reduced volume v, as the shift s = onset − c̄0*(v): v is not the same in every run (the
//! area held is the seeded start's, so a stronger seed holds a little more area and a lower v,
//! 0.794 at δ = 0.005 and 0.772 at δ = 0.03 for R0 = 20ε), and c̄0* moves by about 19 per unit of
//! v there, so the onset alone would mix the seed's push with the change of v.
//!
//! **Extrapolation in the seed.** The prolate loses up–down stability subcritically: below the
//! instability an unstable pear of amplitude ∝ √(c̄0* − c̄0) separates it from the budded
//! state, and a seed of strength δ can carry the state across from c̄0* − gδ² on. So at each R0
//! with two or more seeds the shift is fitted as s(δ) = s0 − gδ² by least squares in δ², and s0
//! is the shift of a vanishing seed: the phase field's loss of stability itself ([`SeedLimit`]).
//!
//! **Extrapolation in ε/R0.** The shift is a phase-field error; for each seed, and for s0, it is
//! fitted as s = s_∞ + b ε/R0 by least squares over every R0, and through the two finest R0
//! alone. s_∞ is the extrapolated shift; the two fits' difference shows how far the data are
//! from the linear law.

use super::{Onset, Parameter, Relaxation, Sample, Spec, Step};
use crate::commands::study::fit;
use crate::commands::study::harness::Report;
use crate::commands::study::table::{self, Column, Format};
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use std::fmt::Write as _;

/// A row that carries a [`Relaxation`] (its shared columns, [`relaxation_columns`]).
trait Relaxed {
    fn relaxation(&self) -> &Relaxation;
}

impl Relaxed for Step {
    fn relaxation(&self) -> &Relaxation {
        &self.relaxation
    }
}

impl Relaxed for Sample {
    fn relaxation(&self) -> &Relaxation {
        &self.relaxation
    }
}

/// The columns of a row's [`Relaxation`]: stage, c̄0 (c̄0,eff for the couple), Δa held and of
/// the φ = 0 surface, iterations, how it stopped, residual, e, v.
fn relaxation_columns<R: Relaxed>() -> Vec<Column<R>> {
    vec![
        Column::both("stage", "stage", Format::Plain, |r| {
            r.relaxation().stage.into()
        }),
        Column::both("c0", "c0R0", Format::Fixed(4), |r| r.relaxation().c0.into()),
        Column::both("da", "da", Format::Fixed(4), |r: &R| {
            r.relaxation().da.into()
        })
        .or("-"),
        Column::both("da_surface", "da surface", Format::Fixed(4), |r| {
            r.relaxation().da_surface.into()
        }),
        Column::both("iterations", "iters", Format::Plain, |r| {
            r.relaxation().iterations.into()
        }),
        Column::both("stopped", "stopped", Format::Plain, |r| {
            r.relaxation().stopped.as_str().into()
        }),
        Column::both("residual", "residual", Format::Sci(1), |r| {
            r.relaxation().residual.into()
        }),
        Column::both("e", "e", Format::Fixed(4), |r| r.relaxation().e.into()),
        Column::both("v", "v", Format::Fixed(4), |r| r.relaxation().v.into()),
    ]
}

/// The warning line for the relaxations of `rows` that stopped before `stop_residual` (none
/// when every one is stationary).
fn unconverged<'a>(text: &mut String, rows: impl Iterator<Item = &'a Relaxation>) {
    let n = rows.filter(|r| r.stopped != "stationary").count();
    if n > 0 {
        let _ = writeln!(
            text,
            "warning: {n} relaxations stopped before stop_residual: their state is not a \
             stationary one"
        );
    }
}

impl table::Row for Step {
    fn columns() -> Vec<Column<Self>> {
        let mut columns = vec![
            Column::both("r0", "R0/eps", Format::Plain, |r: &Self| r.r0.into()),
            Column::both("seed", "seed", Format::Plain, |r| r.seed.into()),
        ];
        columns.extend(relaxation_columns());
        columns.extend([
            Column::both("skewness", "skew", Format::Fixed(4), |r: &Self| {
                r.skewness.into()
            }),
            Column::both("neck", "neck/eps", Format::Fixed(2), |r| r.neck.into()),
            Column::both("pieces", "pieces", Format::Plain, |r| r.pieces.into()),
            Column::both("state", "state", Format::Plain, |r| r.state.as_str().into()),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall_seconds.into()
            })
            .unit("s"),
        ]);
        columns
    }
}

impl table::Row for Onset {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("r0", "R0/eps", Format::Plain, |r| r.r0.into()),
            Column::both("seed", "seed", Format::Plain, |r| r.seed.into()),
            Column::both("below", "symmetric at", Format::Fixed(4), |r| {
                r.below.into()
            }),
            Column::both("above", "asymmetric at", Format::Fixed(4), |r: &Self| {
                r.above.into()
            })
            .or("none"),
            Column::both("onset", "onset", Format::Fixed(4), |r| r.onset.into()),
            Column::both("v", "v", Format::Fixed(4), |r| r.v.into()),
            Column::both("c0", "c0R0", Format::Fixed(4), |r: &Self| r.c0.into()).or("-"),
            Column::both("da_surface", "da surface", Format::Fixed(4), |r: &Self| {
                r.da_surface.into()
            })
            .or("-"),
            Column::both("sharp", "sharp", Format::Fixed(4), |r| r.sharp.into()),
            Column::both("shift", "shift", Format::Fixed(4), |r| r.shift.into()),
            Column::both("sharp_c0", "sharp c0R0", Format::Fixed(4), |r| {
                r.sharp_c0.into()
            }),
            Column::both("shift_c0", "shift c0R0", Format::Fixed(4), |r: &Self| {
                r.shift_c0.into()
            })
            .or("-"),
            Column::both("relaxations", "relax", Format::Plain, |r| {
                r.relaxations.into()
            }),
            Column::both("wall_seconds", "wall", Format::Fixed(0), |r: &Self| {
                r.wall_seconds.into()
            })
            .unit("s"),
        ]
    }
}

/// The shift of one R0 extrapolated to a vanishing seed (see the module docs); a row of
/// `onset_limit.csv`.
#[derive(Clone, Copy, Debug)]
pub struct SeedLimit {
    /// R0/ε.
    pub r0: f64,
    /// Seeds fitted.
    pub seeds: usize,
    /// s0: the shift onset − sharp as δ → 0.
    pub shift: f64,
    /// g of s(δ) = s0 − gδ².
    pub g: f64,
    /// The largest distance of a seed's shift from the fit.
    pub misfit: f64,
}

impl table::Row for SeedLimit {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("r0", "R0/eps", Format::Plain, |r| r.r0.into()),
            Column::both("seeds", "seeds", Format::Plain, |r| r.seeds.into()),
            Column::both("shift", "shift (seed -> 0)", Format::Fixed(4), |r| {
                r.shift.into()
            }),
            Column::both("g", "g", Format::Fixed(1), |r| r.g.into()),
            Column::both("misfit", "misfit", Format::Fixed(4), |r| r.misfit.into()),
        ]
    }
}

/// The shift of each R0 of `spec` with two or more seeds bracketed, extrapolated to δ → 0.
pub fn seed_limits(spec: &Spec, onsets: &[Onset]) -> Vec<SeedLimit> {
    spec.r0
        .iter()
        .filter_map(|&r0| {
            let (d2, y): (Vec<f64>, Vec<f64>) = onsets
                .iter()
                .filter(|o| o.r0 == r0 && o.shift.is_finite())
                .map(|o| (o.seed * o.seed, o.shift))
                .unzip();
            let line = fit::linear(&d2, &y)?;
            let misfit = d2
                .iter()
                .zip(&y)
                .map(|(x, y)| (y - line.intercept - line.slope * x).abs())
                .fold(0.0, f64::max);
            Some(SeedLimit {
                r0,
                seeds: line.n,
                shift: line.intercept,
                g: -line.slope,
                misfit,
            })
        })
        .collect()
}

/// The intercepts at ε/R0 = 0 of the lines s = s0 + b ε/R0 through `(r0, s)`: over every
/// point, and through the two of largest R0 (the points in increasing R0; NaN with fewer than
/// two).
fn intercepts(points: &[(f64, f64)]) -> (f64, f64) {
    let (x, s): (Vec<f64>, Vec<f64>) = points
        .iter()
        .filter(|p| p.1.is_finite())
        .map(|&(r0, s)| (1.0 / r0, s))
        .unzip();
    let intercept = |x: &[f64], s: &[f64]| fit::linear(x, s).map_or(f64::NAN, |l| l.intercept);
    let k = x.len().saturating_sub(2);
    (intercept(&x, &s), intercept(&x[k..], &s[k..]))
}

/// The extrapolation of one seed's shifts in ε/R0.
#[derive(Clone, Copy, Debug)]
pub struct Extrapolation {
    /// The seed strength.
    pub seed: f64,
    /// s0 of the least-squares line over every R0 (NaN with fewer than two).
    pub all: f64,
    /// s0 of the line through the two finest R0 (NaN with fewer than two).
    pub finest: f64,
}

/// The extrapolated shift of each seed of `spec` from `onsets` (see the module docs).
pub fn extrapolate(spec: &Spec, onsets: &[Onset]) -> Vec<Extrapolation> {
    spec.seeds
        .iter()
        .map(|&seed| {
            let points: Vec<(f64, f64)> = onsets
                .iter()
                .filter(|o| o.seed == seed)
                .map(|o| (o.r0, o.shift))
                .collect();
            let (all, finest) = intercepts(&points);
            Extrapolation { seed, all, finest }
        })
        .collect()
}

/// The report of the relaxations `steps` and the `onsets` of `spec`.
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn report(spec: &Spec, steps: &[Step], onsets: &[Onset]) -> Result<Report> {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "budding onset: the prolate at v = {} (sharp start at c0 R0 = {}), c0 R0 stepped up \
         until it leaves up-down symmetry, then the bracket bisected {} times; L-BFGS through \
         stationary states",
        spec.v, spec.c0[0], spec.bisections
    );
    text.push_str(&table::text(steps));
    unconverged(&mut text, steps.iter().map(|s| &s.relaxation));
    text.push('\n');
    text.push_str(&table::text(onsets));
    let _ = writeln!(
        text,
        "sharp: the zero in c0 R0 of the axisymmetric prolate's up-down test function at the \
         phase field's phi = 0 v (last symmetric state); shift = onset - sharp"
    );
    for e in extrapolate(spec, onsets) {
        let _ = writeln!(
            text,
            "seed {}: shift extrapolated to eps/R0 -> 0 (linear in eps/R0): {:+.4} over every \
             R0, {:+.4} through the two finest",
            e.seed, e.all, e.finest
        );
    }
    let limits = seed_limits(spec, onsets);
    if !limits.is_empty() {
        let _ = writeln!(
            text,
            "\nthe shift of a vanishing seed at each R0, shift(seed) = s0 - g seed^2 by least \
             squares (a seed can push the state over the subcritical barrier before the \
             prolate loses stability)"
        );
        text.push_str(&table::text(&limits));
        let points: Vec<(f64, f64)> = limits.iter().map(|l| (l.r0, l.shift)).collect();
        let (all, finest) = intercepts(&points);
        let _ = writeln!(
            text,
            "seed -> 0: shift extrapolated to eps/R0 -> 0 (linear in eps/R0): {all:+.4} over \
             every R0, {finest:+.4} through the two finest"
        );
    }
    let mut report = Report {
        text,
        ..Report::default()
    };
    report.table("onset_steps.csv", steps)?;
    report.table("onset.csv", onsets)?;
    if !limits.is_empty() {
        report.table("onset_limit.csv", &limits)?;
    }
    report.chart("onset_skewness", skewness_chart(spec, steps));
    report.chart("onset_eps", onset_chart(spec, onsets, &limits));
    Ok(report)
}

/// |skewness| against c̄0 for every run (R0 by colour, seed by marker), sorted in c̄0, with
/// the symmetric threshold.
fn skewness_chart(spec: &Spec, steps: &[Step]) -> Figure {
    let mut fig = Figure::new(
        "Budding onset: up-down asymmetry of the relaxed states",
        Axis::linear("c0 R0"),
        Axis::log("|skewness| of the volume along z"),
    );
    fig.legend = Corner::UpperLeft;
    let shapes = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    for (i, &r0) in spec.r0.iter().enumerate() {
        for (j, &seed) in spec.seeds.iter().enumerate() {
            let mut pts: Vec<(f64, f64)> = steps
                .iter()
                .filter(|s| s.r0 == r0 && s.seed == seed && s.skewness != 0.0)
                .map(|s| (s.relaxation.c0, s.skewness.abs()))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            fig.push(Series::new(
                format!("R0 = {r0} eps, seed {seed}"),
                pts,
                colour(i),
                Mark::LinePoints(shapes[j % shapes.len()]),
            ));
        }
    }
    let (lo, hi) = (spec.c0[0], spec.c0[spec.c0.len() - 1]);
    fig.push(Series::new(
        "symmetric below",
        vec![
            (lo, super::budding::SYMMETRIC_SKEWNESS),
            (hi, super::budding::SYMMETRIC_SKEWNESS),
        ],
        colour(7),
        Mark::Dashed,
    ));
    fig
}

/// The shift onset − sharp against ε/R0 for each seed and for a vanishing seed (`limits`).
fn onset_chart(spec: &Spec, onsets: &[Onset], limits: &[SeedLimit]) -> Figure {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = spec
        .seeds
        .iter()
        .map(|&seed| {
            let pts = onsets
                .iter()
                .filter(|o| o.seed == seed && o.shift.is_finite())
                .map(|o| (1.0 / o.r0, o.shift))
                .collect();
            (format!("phase field, seed {seed}"), pts)
        })
        .collect();
    if !limits.is_empty() {
        let pts = limits.iter().map(|l| (1.0 / l.r0, l.shift)).collect();
        series.push(("phase field, seed -> 0".to_string(), pts));
    }
    shift_chart(series, onsets, Parameter::C0)
}

/// The shifts of `series` (name, points (ε/R0, onset − sharp)) against ε/R0, each with its
/// least-squares line (dashed, to ε/R0 = 0), and the sharp value 0, up to the largest ε/R0 of
/// `onsets`, in the path's `parameter`.
fn shift_chart(
    series: Vec<(String, Vec<(f64, f64)>)>,
    onsets: &[Onset],
    parameter: Parameter,
) -> Figure {
    let mut fig = Figure::new(
        "Budding onset: shift from the sharp instability against eps/R0",
        Axis::linear("eps / R0"),
        Axis::linear(format!(
            "onset - sharp instability at the run's v ({})",
            parameter.label()
        )),
    );
    fig.legend = Corner::LowerLeft;
    let shapes = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    let top = onsets.iter().map(|o| 1.0 / o.r0).fold(0.0, f64::max);
    for (j, (name, pts)) in series.into_iter().enumerate() {
        let (x, y): (Vec<f64>, Vec<f64>) = pts.iter().copied().unzip();
        fig.push(Series::new(
            name,
            pts,
            colour(j),
            Mark::Points(shapes[j % shapes.len()]),
        ));
        if let Some(line) = fit::linear(&x, &y) {
            fig.push(
                Series::new(
                    "",
                    vec![
                        (0.0, line.intercept),
                        (top, line.intercept + line.slope * top),
                    ],
                    colour(j),
                    Mark::Dashed,
                )
                .unlisted(),
            );
        }
    }
    fig.push(Series::new(
        "sharp instability",
        vec![(0.0, 0.0), (top, 0.0)],
        colour(7),
        Mark::Line,
    ));
    fig
}

impl table::Row for Sample {
    fn columns() -> Vec<Column<Self>> {
        let mut columns = vec![Column::both("r0", "R0/eps", Format::Plain, |r: &Self| {
            r.r0.into()
        })];
        columns.extend(relaxation_columns());
        columns.extend([
            Column::both("sigma", "sigma", Format::Sci(3), |r: &Self| r.sigma.into()),
            Column::both("eigenvalue", "lowest odd eigenvalue", Format::Sci(4), |r| {
                r.eigenvalue.into()
            }),
            Column::both("eigen_residual", "eig. residual", Format::Sci(1), |r| {
                r.eigen_residual.into()
            }),
            Column::both("products", "products", Format::Plain, |r| r.products.into()),
            Column::both("translation", "translation", Format::Sci(1), |r| {
                r.translation.into()
            }),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall_seconds.into()
            })
            .unit("s"),
        ]);
        columns
    }
}

/// A number read from an onset row (a shift to extrapolate).
type Reading = fn(&Onset) -> f64;

/// The report of the Hessian method (`"method": "hessian"`): the symmetric states `samples`
/// with their eigenvalues, the `onsets`, the shift's extrapolation in ε/R0, and the charts
/// `onset_eigenvalue` and `onset_eps`.
///
/// # Errors
/// `Error::Config` if a CSV row cannot be written (a bug).
pub fn eigen_report(spec: &Spec, samples: &[Sample], onsets: &[Onset]) -> Result<Report> {
    let mut text = String::new();
    let label = spec.parameter().label();
    let model = match spec.parameter() {
        Parameter::C0 => "",
        Parameter::Couple => " (bilayer couple, c0 = 0)",
    };
    let _ = writeln!(
        text,
        "budding onset without a seed{model}: the up-down symmetric stationary state of the \
         prolate at v = {} (sharp start at {label} = {}), relaxed by L-BFGS on the box mirrored \
         across x, y and z, and the lowest eigenvalue of its second variation on up-down odd \
         fields (translation removed), {label} stepped up until it is negative, then {} regula \
         falsi steps",
        spec.v,
        spec.path()[0],
        spec.bisections
    );
    text.push_str(&table::text(samples));
    unconverged(&mut text, samples.iter().map(|s| &s.relaxation));
    let loose = samples
        .iter()
        .filter(|s| s.eigen_residual > spec.eigen_tolerance)
        .count();
    if loose > 0 {
        let _ = writeln!(
            text,
            "warning: {loose} eigenvalues stopped at eigen_products before eigen_tolerance"
        );
    }
    text.push('\n');
    text.push_str(&table::text(onsets));
    let sharp = match spec.parameter() {
        Parameter::C0 => {
            "the zero in c0 R0 of the axisymmetric prolate's up-down test function at that v; \
             sharp c0R0: the same"
        }
        Parameter::Couple => {
            "da where the axisymmetric bilayer-couple prolate at that v, walked in da, first \
             loses up-down stability (its test function, that of the spontaneous-curvature \
             prolate at its c0,eff, crosses zero); sharp c0R0: its c0,eff there; c0R0: the \
             state's c0,eff = -lambda R0/(sqrt 2 eps) of its multiplier lambda"
        }
    };
    let _ = writeln!(
        text,
        "onset: the root of the line through the last bracket's ({label}, eigenvalue); v, c0R0 \
         and da surface: the phi = 0 reduced volume, c0 and da interpolated to it; sharp: \
         {sharp}; shift = onset - sharp; shift c0R0 = c0R0 - sharp c0R0"
    );
    let mut shifts: Vec<(&str, Reading)> = vec![("shift", |o| o.shift)];
    if spec.parameter() == Parameter::Couple {
        shifts.push(("da surface - sharp", |o| o.da_surface - o.sharp));
        shifts.push(("shift c0R0 (of c0,eff)", |o| o.shift_c0));
    }
    for (name, of) in shifts {
        let points: Vec<(f64, f64)> = onsets.iter().map(|o| (o.r0, of(o))).collect();
        let (all, finest) = intercepts(&points);
        if all.is_finite() {
            let _ = writeln!(
                text,
                "{name} extrapolated to eps/R0 -> 0 (linear in eps/R0): {all:+.4} over every \
                 R0, {finest:+.4} through the two finest"
            );
        }
    }
    let mut report = Report {
        text,
        ..Report::default()
    };
    report.table("onset_eigen.csv", samples)?;
    report.table("onset.csv", onsets)?;
    report.chart("onset_eigenvalue", eigenvalue_chart(spec, samples, onsets));
    let pts = onsets
        .iter()
        .filter(|o| o.shift.is_finite())
        .map(|o| (1.0 / o.r0, o.shift))
        .collect();
    report.chart(
        "onset_eps",
        shift_chart(
            vec![("phase field, no seed".to_string(), pts)],
            onsets,
            spec.parameter(),
        ),
    );
    Ok(report)
}

/// The lowest odd eigenvalue scaled by (R0/ε)⁴ against the path's value for every R0 (by
/// colour), sorted, with the sharp instability at each run's v (a vertical line in its colour) and the zero.
/// The shape modes' eigenvalues fall about like (ε/R0)⁴ (measured at c̄0 = 3, h = 2ε/3: λ (R0/ε)⁴
/// = 0.72, 0.75, 0.75, 0.76, 0.87 at R0 = 20, 24, 28, 32, 40ε), so the scaled curves compare.
fn eigenvalue_chart(spec: &Spec, samples: &[Sample], onsets: &[Onset]) -> Figure {
    let mut fig = Figure::new(
        "Budding onset: lowest up-down odd eigenvalue of the symmetric state",
        Axis::linear(spec.parameter().label()),
        Axis::linear("lowest odd eigenvalue of M^-1 H x (R0/eps)^4"),
    );
    fig.legend = Corner::LowerLeft;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, &r0) in spec.r0.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = samples
            .iter()
            .filter(|s| s.r0 == r0)
            .map(|s| {
                (
                    s.relaxation.value(spec.parameter()),
                    s.eigenvalue * r0.powi(4),
                )
            })
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        for p in &pts {
            (lo, hi) = (lo.min(p.1), hi.max(p.1));
        }
        fig.push(Series::new(
            format!("R0 = {r0} eps"),
            pts,
            colour(i),
            Mark::LinePoints(Shape::Circle),
        ));
    }
    for (i, o) in onsets.iter().enumerate() {
        if o.sharp.is_finite() && lo < hi {
            fig.push(
                Series::new(
                    "",
                    vec![(o.sharp, lo), (o.sharp, hi)],
                    colour(i),
                    Mark::Dashed,
                )
                .unlisted(),
            );
        }
    }
    let path = spec.path();
    let (first, last) = (path[0], path[path.len() - 1]);
    fig.push(Series::new(
        "zero (dashed: sharp instability)",
        vec![(first, 0.0), (last, 0.0)],
        colour(7),
        Mark::Line,
    ));
    fig
}
