//! `vesicle study shear FILE`: 2D or 3D vesicles tank-treading in a steady shear, their
//! inclination, deformation and tank-treading rate against the reduced area (volume), beside
//! the linear theory of this model (docs/src/theory/flow.md, "Shear";
//! docs/src/validation/flow.md).
//!
//! Each case runs a vesicle with its area held in plane Couette flow between walls (or the
//! periodic Kolmogorov flow) at one capillary number until it is steady ([`measure`]). Per
//! reduced area the sizes' departures ψ − ψ_lin(v) from the linear theory, cos 2ψ = 2b in 2D
//! and cos 2ψ = √(15Δ/2) in 3D (taken at each run's own reduced area, that of its final φ = 0
//! contour or surface, which differs slightly from the start's), are extrapolated to ε/R0 = 0
//! by the least-squares line through them (the sizes' departures differ by less than the runs'
//! last drift, so a polynomial through them would extrapolate noise).
//!
//! Writes `shear.txt`, `cases.csv` (every run), `angles.csv` (per reduced area), the chart
//! `inclination` (ψ against v with the theory) and `shape_vV.png` (the finest size's steady
//! shape per reduced area; in 3D its three mid-planes).

pub mod measure;
pub mod spec;

use super::fit;
use super::harness::{Report, Study};
use super::table::{self, Column, Format, Row};
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use crate::output::image::slices_image;
use measure::{amplitude, first_order_inclination, linear_inclination, Case, Measured};
pub use spec::Spec;
use std::path::Path;

impl Row for Measured {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("start_v", "start v", Format::Plain, |r: &Self| {
                r.case.reduced_area.into()
            }),
            Column::both("r0", "R0", Format::Plain, |r: &Self| r.case.r0.into()).unit("eps"),
            Column::both("capillary", "Ca", Format::Plain, |r: &Self| {
                r.case.capillary.into()
            }),
            Column::both("channel", "W/R0", Format::Plain, |r: &Self| {
                r.case.channel.into()
            }),
            Column::both("length", "L/R0", Format::Plain, |r: &Self| {
                r.case.length.into()
            }),
            Column::both("profile", "profile", Format::Plain, |r: &Self| {
                r.case.profile.name().into()
            }),
            Column::both(
                "viscosity_ratio",
                "eta_in/eta_out",
                Format::Plain,
                |r: &Self| r.case.viscosity_ratio.into(),
            ),
            Column::csv("points", |r: &Self| {
                r.points.iter().product::<usize>().into()
            }),
            Column::both("reduced_area", "v", Format::Fixed(4), |r: &Self| {
                r.reduced_area.into()
            }),
            Column::both("excess", "Delta", Format::Fixed(4), |r: &Self| {
                r.excess.into()
            }),
            Column::both(
                "field_reduced_area",
                "v field",
                Format::Fixed(4),
                |r: &Self| r.field_reduced_area.into(),
            ),
            Column::both("inclination", "psi", Format::Fixed(2), |r: &Self| {
                r.inclination.into()
            })
            .unit("deg"),
            Column::both("linear", "psi linear", Format::Fixed(2), |r: &Self| {
                r.linear.into()
            })
            .unit("deg"),
            Column::both(
                "linear_first_order",
                "psi linear 1st order",
                Format::Fixed(2),
                |r: &Self| r.linear_first_order.into(),
            )
            .unit("deg"),
            Column::both("drift", "drift", Format::Fixed(3), |r: &Self| {
                r.drift.into()
            })
            .unit("deg"),
            Column::both("volume_change", "dV/V", Format::Sci(2), |r: &Self| {
                r.volume_change.into()
            }),
            Column::both("deformation", "D", Format::Fixed(4), |r: &Self| {
                r.deformation.into()
            }),
            Column::both("linear_deformation", "b", Format::Fixed(4), |r: &Self| {
                r.linear_deformation.into()
            }),
            Column::both(
                "tank_treading",
                "omega/(rate/2)",
                Format::Fixed(4),
                |r: &Self| r.tank_treading.into(),
            ),
            Column::both(
                "sharp_tank_treading",
                "omega sharp",
                Format::Fixed(4),
                |r: &Self| r.sharp_tank_treading.into(),
            ),
            Column::both("sigma_bar", "sigma_bar", Format::Fixed(2), |r: &Self| {
                r.sigma_bar.into()
            }),
            Column::both("steps", "steps", Format::Plain, |r: &Self| r.steps.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// One reduced area's sizes and their extrapolation; a row of `angles.csv`.
#[derive(Clone, Debug)]
pub struct Angle {
    /// The start's reduced area.
    pub start: f64,
    /// The reduced area at the finest size.
    pub reduced_area: f64,
    /// Its excess Δ.
    pub excess: f64,
    /// ψ_lin at it, degrees.
    pub linear: f64,
    /// ψ − ψ_lin per size, coarse to fine: "−0.41 −0.32".
    pub departures: String,
    /// ψ − ψ_lin extrapolated to ε/R0 = 0, degrees.
    pub extrapolated: f64,
    /// ψ_lin + the extrapolated departure, degrees.
    pub inclination: f64,
    /// cos 2ψ/(2b) of that ψ (2a in 3D): 1 where the linear theory holds.
    pub cos_ratio: f64,
    /// cos 2ψ/(2b) (2a) at the finest size, its own ψ and v.
    pub finest_cos_ratio: f64,
    /// Ω/(γ̇/2) at the finest size.
    pub tank_treading: f64,
}

impl Row for Angle {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("start_v", "start v", Format::Plain, |r: &Self| {
                r.start.into()
            }),
            Column::both(
                "reduced_area",
                "v (finest)",
                Format::Fixed(4),
                |r: &Self| r.reduced_area.into(),
            ),
            Column::both("excess", "Delta", Format::Fixed(4), |r: &Self| {
                r.excess.into()
            }),
            Column::both("linear", "psi linear", Format::Fixed(2), |r: &Self| {
                r.linear.into()
            })
            .unit("deg"),
            Column::both(
                "departures",
                "psi - psi linear per size (coarse to fine)",
                Format::Plain,
                |r| r.departures.as_str().into(),
            ),
            Column::both(
                "extrapolated",
                "extrapolated",
                Format::Fixed(2),
                |r: &Self| r.extrapolated.into(),
            )
            .unit("deg"),
            Column::both("inclination", "psi", Format::Fixed(2), |r: &Self| {
                r.inclination.into()
            })
            .unit("deg"),
            Column::both(
                "cos_ratio",
                "cos 2psi/(2b)",
                Format::Fixed(3),
                |r: &Self| r.cos_ratio.into(),
            ),
            Column::both(
                "finest_cos_ratio",
                "cos 2psi/(2b) finest",
                Format::Fixed(3),
                |r: &Self| r.finest_cos_ratio.into(),
            ),
            Column::both(
                "tank_treading",
                "omega/(rate/2)",
                Format::Fixed(4),
                |r: &Self| r.tank_treading.into(),
            ),
        ]
    }
}

/// Every case and every reduced area's extrapolation.
#[derive(Clone, Debug)]
pub struct Output {
    /// Every run (the main grid's, then the variations).
    pub cases: Vec<Measured>,
    /// Per reduced area of the main grid.
    pub angles: Vec<Angle>,
}

/// The study.
pub struct ShearStudy;

impl Study for ShearStudy {
    const NAME: &'static str = "shear";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Output, Report)> {
        spec.validate()?;
        let (groups, variations) = cases(spec);
        let total = groups.iter().map(Vec::len).sum::<usize>() + variations.len();
        let mut done = 0;
        let mut run = |case: &Case| {
            let m = measure::run(spec, case)?;
            done += 1;
            eprintln!(
                "shear [{done}/{total}] v {:.4} R0 {} Ca {} W/R0 {} L/R0 {} {}: psi {:.2} deg \
                 (linear {:.2}), D {:.4}, omega/(rate/2) {:.4} (sharp {:.4}), dV/V {:.1e}, {} steps, \
                 {:.0} s",
                m.reduced_area,
                case.r0,
                case.capillary,
                case.channel,
                case.length,
                case.profile.name(),
                m.inclination,
                m.linear,
                m.deformation,
                m.tank_treading,
                m.sharp_tank_treading,
                m.volume_change,
                m.steps,
                m.wall
            );
            Ok::<_, crate::error::Error>(m)
        };
        let mut cases = Vec::new();
        let mut angles = Vec::new();
        for group in &groups {
            let measured = group.iter().map(&mut run).collect::<Result<Vec<_>>>()?;
            angles.push(extrapolate(spec.dimension, &measured));
            cases.extend(measured);
        }
        for case in &variations {
            cases.push(run(case)?);
        }
        let mut text = format!("== every case ({}D) ==\n", spec.dimension);
        text.push_str(&table::text(&cases));
        text.push_str(&format!(
            "\n== per reduced area: the departure from the linear theory {}, extrapolated to \
             eps/R0 = 0 ==\n",
            theory(spec.dimension)
        ));
        text.push_str(&table::text(&angles));
        let mut report = Report {
            text,
            ..Report::default()
        };
        report.table("cases.csv", &cases)?;
        report.table("angles.csv", &angles)?;
        report.chart("inclination", chart(spec.dimension, &cases, &angles));
        if cases.iter().any(|m| m.case.viscosity_ratio != 1.0) {
            report.chart(
                "inclination_contrast",
                contrast_chart(spec.dimension, &cases),
            );
        }
        let finest: Vec<&Measured> = groups
            .iter()
            .filter_map(|g| {
                let last = g.last()?;
                cases
                    .iter()
                    .find(|m| m.case.r0 == last.r0 && m.case.reduced_area == last.reduced_area)
            })
            .collect();
        for m in finest {
            let title = format!(
                "v {:.3}, R0 {} eps, Ca {}: psi {:.1} deg",
                m.reduced_area, m.case.r0, m.case.capillary, m.inclination
            );
            let name = format!("shape_v{:.2}.png", m.case.reduced_area);
            let image = slices_image(Path::new(&name), &m.phi, spec.dimension, &title)?;
            report.images.push((name, image));
        }
        Ok((Output { cases, angles }, report))
    }
}

/// The main grid's cases grouped by reduced area (sizes coarse to fine), and the variations.
fn cases(spec: &Spec) -> (Vec<Vec<Case>>, Vec<Case>) {
    let mut sizes = spec.r0.clone();
    sizes.sort_by(f64::total_cmp);
    let case = |reduced_area, r0| Case {
        reduced_area,
        r0,
        capillary: spec.capillary,
        channel: spec.channel,
        length: spec.length,
        profile: spec.profile,
        viscosity_ratio: 1.0,
    };
    let groups = spec
        .reduced_areas
        .iter()
        .map(|&v| sizes.iter().map(|&r| case(v, r)).collect())
        .collect();
    let variations = spec
        .variations
        .iter()
        .map(|v| Case {
            capillary: v.capillary.unwrap_or(spec.capillary),
            channel: v.channel.unwrap_or(spec.channel),
            length: v.length.unwrap_or(spec.length),
            profile: v.profile.unwrap_or(spec.profile),
            viscosity_ratio: v.viscosity_ratio.unwrap_or(1.0),
            ..case(v.reduced_area, v.r0)
        })
        .collect();
    (groups, variations)
}

/// The drift of ψ over a run's last quarter (degrees) above which it has no steady angle.
const UNSTEADY_DRIFT: f64 = 1.0;

/// ψ against λ = η_in/η_out for the reduced area of the first case with unequal viscosities:
/// each size's steady cases at that start (equal viscosities included), the unsteady ones
/// (|drift| above [`UNSTEADY_DRIFT`]) at ψ = 0, and the linear theory
/// cos 2ψ = 2b(1 + λ)/2 (3D √(15Δ/2)(2λ + 3)/5) at their mean φ = 0 reduced area, which ends
/// at ψ = 0 where the vesicle should start to tumble.
fn contrast_chart(dim: usize, cases: &[Measured]) -> Figure {
    let start = cases
        .iter()
        .find(|m| m.case.viscosity_ratio != 1.0)
        .map_or(f64::NAN, |m| m.case.reduced_area);
    let at_start: Vec<&Measured> = cases
        .iter()
        .filter(|m| m.case.reduced_area == start)
        .collect();
    let mut fig = Figure::new(
        format!("Inclination against the viscosity ratio ({dim}D, start v {start})"),
        Axis::linear("eta_in / eta_out"),
        Axis::linear("inclination psi (degrees)"),
    );
    fig.legend = Corner::UpperRight;
    let mut sizes: Vec<f64> = at_start.iter().map(|m| m.case.r0).collect();
    sizes.sort_by(f64::total_cmp);
    sizes.dedup();
    // A case whose angle still moves by more than a degree over the last quarter has no steady
    // angle: it is drawn at ψ = 0 apart, not joined to the steady ones.
    let steady = |m: &&&Measured| m.drift.abs() <= UNSTEADY_DRIFT;
    for (i, &r0) in sizes.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = at_start
            .iter()
            .filter(|m| m.case.r0 == r0)
            .filter(steady)
            .map(|m| (m.case.viscosity_ratio, m.inclination))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        fig.push(Series::new(
            format!("R0 = {r0} eps"),
            pts,
            colour(i),
            Mark::LinePoints(Shape::Circle),
        ));
    }
    let unsteady: Vec<(f64, f64)> = at_start
        .iter()
        .filter(|m| !steady(m))
        .map(|m| (m.case.viscosity_ratio, 0.0))
        .collect();
    if !unsteady.is_empty() {
        fig.push(Series::new(
            format!("no steady angle (drift > {UNSTEADY_DRIFT} deg): tumbling"),
            unsteady,
            [0, 0, 0],
            Mark::Points(Shape::Diamond),
        ));
    }
    let v = at_start.iter().map(|m| m.reduced_area).sum::<f64>() / at_start.len() as f64;
    let top = at_start
        .iter()
        .map(|m| m.case.viscosity_ratio)
        .fold(1.0, f64::max);
    let theory = (0..=100)
        .map(|i| top * i as f64 / 100.0)
        .map(|lambda| (lambda, linear_inclination(v, dim, lambda)))
        .filter(|p| p.1.is_finite())
        .collect();
    fig.push(Series::new(
        format!("linear theory at v = {v:.3}"),
        theory,
        [0, 0, 0],
        Mark::Dashed,
    ));
    fig
}

/// The linear theory's formula in dimension `dim`, for the tables.
fn theory(dim: usize) -> &'static str {
    if dim == 3 {
        "cos 2psi = sqrt(15 Delta/2), Delta = v^(-2/3) - 1"
    } else {
        "cos 2psi = 2b, b = sqrt(2(1 - v)/3)"
    }
}

/// One reduced area's departures ψ − ψ_lin(v) and their extrapolation to ε/R0 = 0 by the
/// least-squares line in ε/R0 through every size.
fn extrapolate(dim: usize, group: &[Measured]) -> Angle {
    let finest = group.last().expect("at least two sizes");
    let points: Vec<(f64, f64)> = group
        .iter()
        .map(|m| (1.0 / m.case.r0, m.inclination - m.linear))
        .collect();
    let (x, y): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    let extrapolated = fit::linear(&x, &y).map_or(f64::NAN, |line| line.intercept);
    let inclination = finest.linear + extrapolated;
    let cos_ratio =
        |psi: f64| (2.0 * psi.to_radians()).cos() / (2.0 * amplitude(finest.reduced_area, dim));
    Angle {
        start: finest.case.reduced_area,
        reduced_area: finest.reduced_area,
        excess: finest.excess,
        linear: finest.linear,
        departures: points
            .iter()
            .map(|p| format!("{:+.2}", p.1))
            .collect::<Vec<_>>()
            .join(" "),
        extrapolated,
        inclination,
        cos_ratio: cos_ratio(inclination),
        finest_cos_ratio: cos_ratio(finest.inclination),
        tank_treading: finest.tank_treading,
    }
}

/// ψ against v: every size of the main grid, the extrapolation, and the linear theory (in 3D
/// also its first-order form in 1 − v).
fn chart(dim: usize, cases: &[Measured], angles: &[Angle]) -> Figure {
    let mut fig = Figure::new(
        format!(
            "Inclination of a vesicle tank-treading in shear ({dim}D, area held, equal viscosities)"
        ),
        Axis::linear(if dim == 3 {
            "reduced volume v"
        } else {
            "reduced area v"
        }),
        Axis::linear("inclination psi (degrees)"),
    );
    fig.legend = Corner::LowerRight;
    let marks = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    let mut sizes: Vec<f64> = angles
        .iter()
        .flat_map(|a| {
            cases
                .iter()
                .filter(move |m| m.case.reduced_area == a.start)
                .map(|m| m.case.r0)
        })
        .collect();
    sizes.sort_by(f64::total_cmp);
    sizes.dedup();
    for (i, &r0) in sizes.iter().enumerate() {
        let pts = angles
            .iter()
            .filter_map(|a| {
                cases
                    .iter()
                    .find(|m| m.case.reduced_area == a.start && m.case.r0 == r0)
            })
            .map(|m| (m.reduced_area, m.inclination))
            .collect();
        fig.push(Series::new(
            format!("R0 = {r0} eps"),
            pts,
            colour(i),
            Mark::LinePoints(marks[i % marks.len()]),
        ));
    }
    fig.push(Series::new(
        "extrapolated to eps/R0 = 0",
        angles
            .iter()
            .map(|a| (a.reduced_area, a.inclination))
            .collect(),
        [0, 0, 0],
        Mark::LinePoints(Shape::Diamond),
    ));
    // Where each form of the theory ends (its right side reaches 1).
    let ends = if dim == 3 {
        [(17.0f64 / 15.0).powf(-1.5), 0.8]
    } else {
        [0.625; 2]
    };
    let lo = angles.iter().map(|a| a.reduced_area).fold(1.0, f64::min);
    let curve = |end: f64, f: fn(f64, usize, f64) -> f64| {
        let lo = lo.max(end);
        (0..=50)
            .map(|i| lo + (1.0 - lo) * i as f64 / 50.0)
            .map(|v| (v, f(v, dim, 1.0)))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let label = if dim == 3 {
        "linear theory cos 2psi = sqrt(15 Delta/2)"
    } else {
        "linear theory cos 2psi = 2b"
    };
    fig.push(Series::new(
        label,
        curve(ends[0], linear_inclination),
        [0, 0, 0],
        Mark::Dashed,
    ));
    if dim == 3 {
        fig.push(Series::new(
            "to first order in 1 - v: cos 2psi = sqrt(5(1 - v))",
            curve(ends[1], first_order_inclination),
            [120, 120, 120],
            Mark::Dashed,
        ));
    }
    fig
}
