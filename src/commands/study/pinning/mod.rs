//! `vesicle study pinning FILE`: how much the lattice pins a stationary shape's reduced energy,
//! against h/ε.
//!
//! At a given h/ε the phase-field energy of a shape is a smooth function of ε/R0 plus a part
//! that depends on where the interface crosses the lattice: moving R0 by ε/4, or the centre by a
//! fraction of h, moves the interface by sub-cell amounts. For each shape of the file (started
//! from the axisymmetric reference as a diagram case is, relaxed by L-BFGS to the file's
//! tolerance: [`super::shape_case`]) and each h/ε the study measures
//!
//! * the **R0 series**: e and v at every R0 of `r0` (on the box a diagram uses), and the largest
//!   residual of the least-squares quadratic in (ε/R0)² through them ([`super::fit::quadratic`]):
//!   what a smooth law does not explain;
//! * the **shift series**: e and v at R0 = `shift_r0` with the centre moved along the axis by
//!   0 and each fraction of h in `shifts` (on the box without the mirror plane across the axis),
//!   and their spread max − min.
//!
//! Every case of a (shape, h/ε) runs on one box, the largest R0's. The same two figures are
//! given for e − e_ref(v), the error against the sharp reference at the v reached (v itself
//! wanders a little with R0 and the lattice, and e with it along the branch).
//!
//! The pinning figure of a (shape, h/ε) is the larger of the two for e; the table of the
//! program ([`crate::problem::pinning`]) holds the largest over the shapes. Writes
//! `pinning.txt`, `cases.csv` (every case), `pinning.csv` (per shape and h/ε), `bound.csv` (per
//! h/ε) and the chart `pinning` (the figure against h/ε, log–log).

pub mod spec;

use super::fit;
use super::harness::{Report, Study};
use super::shape_case::{self, Placement, Start};
use super::table::{self, Column, Format, Row};
use crate::error::{Error, Result};
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
pub use spec::Spec;
use std::path::Path;

/// One relaxed case; a row of `cases.csv`.
#[derive(Clone, Debug)]
pub struct Case {
    /// The shape (`prolate v0 = 0.75`).
    pub shape: String,
    /// `r0` (the R0 series) or `shift` (the shift series).
    pub series: &'static str,
    /// h/ε.
    pub h_over_eps: f64,
    /// R0/ε.
    pub r0: f64,
    /// Shift of the centre along the axis, in h.
    pub shift: f64,
    /// Reduced volume of the φ = 0 surface.
    pub v: f64,
    /// Reduced energy.
    pub e: f64,
    /// e − e_ref(v): the error against the sharp reference at the v reached.
    pub de: f64,
    /// Residual of the quadratic fit of e in (ε/R0)² (R0 series; NaN in the shift series).
    pub e_fit_residual: f64,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// Final stationarity residual.
    pub residual: f64,
    /// Points computed.
    pub points: usize,
    /// Wall seconds.
    pub wall: f64,
}

impl Row for Case {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("shape", "shape", Format::Plain, |r| r.shape.as_str().into()),
            Column::both("series", "series", Format::Plain, |r| r.series.into()),
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| {
                r.h_over_eps.into()
            }),
            Column::both("r0", "R0/eps", Format::Plain, |r| r.r0.into()),
            Column::both("shift", "shift/h", Format::Plain, |r| r.shift.into()),
            Column::both("v", "v", Format::Fixed(6), |r| r.v.into()),
            Column::both("e", "e", Format::Fixed(7), |r| r.e.into()),
            Column::both("e_minus_e_ref", "e - e_ref(v)", Format::Sci(4), |r| {
                r.de.into()
            }),
            Column::both("e_fit_residual", "e - fit", Format::Sci(2), |r| {
                r.e_fit_residual.into()
            }),
            Column::both("iterations", "iterations", Format::Plain, |r| {
                r.iterations.into()
            }),
            Column::both("residual", "residual", Format::Sci(1), |r| {
                r.residual.into()
            }),
            Column::csv("points", |r| r.points.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// The pinning figures of one shape at one h/ε; a row of `pinning.csv`.
#[derive(Clone, Debug)]
pub struct Pinning {
    /// The shape.
    pub shape: String,
    /// h/ε.
    pub h_over_eps: f64,
    /// Largest |residual| of the quadratic fit of e in (ε/R0)² over the R0 series.
    pub e_fit: f64,
    /// The same for v.
    pub v_fit: f64,
    /// max − min of e over the shifts.
    pub e_shift: f64,
    /// max − min of v over the shifts.
    pub v_shift: f64,
    /// Largest |residual| of the quadratic fit of e − e_ref(v) over the R0 series (the error
    /// at the v reached: what is left once v's own wander along the branch is taken out).
    pub de_fit: f64,
    /// max − min of e − e_ref(v) over the shifts.
    pub de_shift: f64,
    /// The pinning figure: the larger of `e_fit` and `e_shift`.
    pub bound: f64,
    /// Wall seconds of the shape's cases at this h/ε.
    pub wall: f64,
}

impl Row for Pinning {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("shape", "shape", Format::Plain, |r| r.shape.as_str().into()),
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| {
                r.h_over_eps.into()
            }),
            Column::both("e_fit_residual", "e: fit residual", Format::Sci(2), |r| {
                r.e_fit.into()
            }),
            Column::both("e_shift_spread", "e: shift spread", Format::Sci(2), |r| {
                r.e_shift.into()
            }),
            Column::both("v_fit_residual", "v: fit residual", Format::Sci(2), |r| {
                r.v_fit.into()
            }),
            Column::both("v_shift_spread", "v: shift spread", Format::Sci(2), |r| {
                r.v_shift.into()
            }),
            Column::both(
                "de_fit_residual",
                "e-e_ref: fit res.",
                Format::Sci(2),
                |r| r.de_fit.into(),
            ),
            Column::both(
                "de_shift_spread",
                "e-e_ref: shift spr.",
                Format::Sci(2),
                |r| r.de_shift.into(),
            ),
            Column::both("e_pinning", "e pinning", Format::Sci(2), |r| r.bound.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// The largest pinning figure over the shapes at one h/ε; a row of `bound.csv` (the table
/// of [`crate::problem::pinning`]).
#[derive(Clone, Debug)]
pub struct Bound {
    /// h/ε.
    pub h_over_eps: f64,
    /// The largest pinning figure of e over the shapes.
    pub e: f64,
    /// Relative to the shape's e: `e` over the smallest e of the shapes.
    pub relative: f64,
    /// The shape it comes from.
    pub shape: String,
}

impl Row for Bound {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| {
                r.h_over_eps.into()
            }),
            Column::both("e_pinning", "e pinning (all shapes)", Format::Sci(2), |r| {
                r.e.into()
            }),
            Column::both("relative", "relative", Format::Sci(2), |r| {
                r.relative.into()
            }),
            Column::both("shape", "worst shape", Format::Plain, |r| {
                r.shape.as_str().into()
            }),
        ]
    }
}

/// What the study returns.
#[derive(Clone, Debug)]
pub struct Output {
    /// Every case.
    pub cases: Vec<Case>,
    /// Per shape and h/ε.
    pub pinning: Vec<Pinning>,
    /// Per h/ε.
    pub bounds: Vec<Bound>,
}

/// The study.
pub struct PinningStudy;

impl Study for PinningStudy {
    const NAME: &'static str = "pinning";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Output, Report)> {
        spec.validate()?;
        let relax = &spec.relaxation;
        let starts = shape_case::starts(&spec.shapes, "shapes", spec.r0_min(), relax.min_width)?;
        let mut r0 = spec.r0.clone();
        r0.sort_by(f64::total_cmp);
        let mut cases = Vec::new();
        let mut pinning = Vec::new();
        for start in &starts {
            for &eps_over_h in &spec.eps_over_h {
                let (mut series, p) = measure_one(start, eps_over_h, &r0, spec)?;
                cases.append(&mut series);
                pinning.push(p);
            }
        }
        let bounds = bounds(&pinning, &spec.eps_over_h, &cases);
        let mut text = String::from("== every case ==\n");
        text.push_str(&table::text(&cases));
        text.push_str(
            "\n== pinning per shape and h/eps (e and v: the largest residual of a quadratic fit \
             in (eps/R0)^2 over the R0 series; the spread max - min over the shifts) ==\n",
        );
        text.push_str(&table::text(&pinning));
        text.push_str("\n== the pinning bound of each h/eps (largest over the shapes) ==\n");
        text.push_str(&table::text(&bounds));
        let mut report = Report {
            text,
            ..Report::default()
        };
        report.table("cases.csv", &cases)?;
        report.table("pinning.csv", &pinning)?;
        report.table("bound.csv", &bounds)?;
        report.chart("pinning", chart(&pinning, &bounds));
        Ok((
            Output {
                cases,
                pinning,
                bounds,
            },
            report,
        ))
    }
}

/// The R0 series and the shift series of `start` at h = ε/`eps_over_h`, and their figures.
fn measure_one(
    start: &Start,
    eps_over_h: f64,
    r0: &[f64],
    spec: &Spec,
) -> Result<(Vec<Case>, Pinning)> {
    let label = start.label();
    let h_over_eps = 1.0 / eps_over_h;
    // Every case of the shape at this h on one box (the largest R0's), so that the box's size,
    // rounded to fast transform lengths, does not jump along the series: a box 4ε wider moves
    // the reduced volume reached by 5e-4 and e with it along the branch.
    let grid_r0 = r0
        .iter()
        .chain([&spec.shift_r0])
        .cloned()
        .fold(0.0, f64::max);
    let one = |series: &'static str, r0: f64, shift: f64| -> Result<Case> {
        let at = Placement {
            r0,
            eps_over_h,
            shift,
            z_mirror: series == "r0",
            grid_r0: Some(grid_r0),
        };
        let r = shape_case::relax(start, at, &spec.relaxation, None)
            .map_err(|e| e.within(&format!("{label}, R0 = {r0}, h/eps = {h_over_eps}")))?;
        if !r.converged {
            return Err(Error::config(
                "relaxation.max_iterations",
                format!(
                    "{label} at R0 = {r0} ε, h = ε/{eps_over_h}, shift {shift} h did not reach \
                     the residual {:e} in {} iterations (residual {:.2e})",
                    spec.relaxation.stop_residual, r.iterations, r.residual
                ),
            ));
        }
        eprintln!(
            "pinning: {label} h/eps {h_over_eps:.4} R0 {r0} shift {shift}: e {:.7} v {:.6} ({} iterations, {:.1} s)",
            r.e, r.v, r.iterations, r.wall
        );
        Ok(Case {
            shape: label.clone(),
            series,
            h_over_eps,
            r0,
            shift,
            v: r.v,
            e: r.e,
            de: r.e - r.e_ref,
            e_fit_residual: f64::NAN,
            iterations: r.iterations,
            residual: r.residual,
            points: r.points,
            wall: r.wall,
        })
    };
    let mut cases = r0
        .iter()
        .map(|&r| one("r0", r, 0.0))
        .collect::<Result<Vec<_>>>()?;
    let x: Vec<f64> = cases.iter().map(|c| (1.0 / c.r0).powi(2)).collect();
    let worst = |res: Option<Vec<f64>>| {
        res.map_or(f64::NAN, |r| r.iter().fold(0.0f64, |m, v| m.max(v.abs())))
    };
    let e: Vec<f64> = cases.iter().map(|c| c.e).collect();
    let v: Vec<f64> = cases.iter().map(|c| c.v).collect();
    let e_res = fit::quadratic(&x, &e);
    if let Some(res) = &e_res {
        for (c, r) in cases.iter_mut().zip(res) {
            c.e_fit_residual = *r;
        }
    }
    let de: Vec<f64> = cases.iter().map(|c| c.de).collect();
    let (e_fit, v_fit) = (worst(e_res), worst(fit::quadratic(&x, &v)));
    let de_fit = worst(fit::quadratic(&x, &de));
    let shifts = std::iter::once(0.0).chain(spec.shifts.iter().cloned());
    let shifted = shifts
        .map(|s| one("shift", spec.shift_r0, s))
        .collect::<Result<Vec<_>>>()?;
    let spread = |get: fn(&Case) -> f64| {
        let (lo, hi) = shifted
            .iter()
            .map(get)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        hi - lo
    };
    let (e_shift, v_shift, de_shift) = (spread(|c| c.e), spread(|c| c.v), spread(|c| c.de));
    cases.extend(shifted);
    let wall = cases.iter().map(|c| c.wall).sum();
    let pinning = Pinning {
        shape: label,
        h_over_eps,
        e_fit,
        v_fit,
        e_shift,
        v_shift,
        de_fit,
        de_shift,
        bound: e_fit.max(e_shift),
        wall,
    };
    Ok((cases, pinning))
}

/// The largest figure over the shapes at each h/ε, in increasing h/ε.
fn bounds(pinning: &[Pinning], eps_over_h: &[f64], cases: &[Case]) -> Vec<Bound> {
    let e_min = cases.iter().map(|c| c.e).fold(f64::INFINITY, f64::min);
    let mut hs: Vec<f64> = eps_over_h.iter().map(|x| 1.0 / x).collect();
    hs.sort_by(f64::total_cmp);
    hs.into_iter()
        .filter_map(|h| {
            pinning
                .iter()
                .filter(|p| p.h_over_eps == h)
                .max_by(|a, b| a.bound.total_cmp(&b.bound))
                .map(|p| Bound {
                    h_over_eps: h,
                    e: p.bound,
                    relative: p.bound / e_min,
                    shape: p.shape.clone(),
                })
        })
        .collect()
}

/// The pinning figure of e against h/ε per shape (log–log), and the bound over the shapes.
fn chart(pinning: &[Pinning], bounds: &[Bound]) -> Figure {
    let mut fig = Figure::new(
        "Lattice pinning of the stationary energy against the grid spacing",
        Axis::log("h / eps"),
        Axis::log("pinning of e (fit residual or shift spread)"),
    );
    fig.legend = Corner::LowerRight;
    let mut shapes: Vec<&str> = Vec::new();
    for p in pinning {
        if !shapes.contains(&p.shape.as_str()) {
            shapes.push(&p.shape);
        }
    }
    let marks = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    for (i, s) in shapes.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = pinning
            .iter()
            .filter(|p| p.shape == *s && p.bound > 0.0)
            .map(|p| (p.h_over_eps, p.bound))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        fig.push(Series::new(
            *s,
            pts,
            colour(i),
            Mark::LinePoints(marks[i % marks.len()]),
        ));
    }
    let pts = bounds
        .iter()
        .filter(|b| b.e > 0.0)
        .map(|b| (b.h_over_eps, b.e))
        .collect();
    fig.push(Series::new(
        "bound (largest over the shapes)",
        pts,
        [0, 0, 0],
        Mark::Dashed,
    ));
    fig
}
