//! `vesicle study rates FILE`: the Stokes dynamics' relaxation rates against the sharp
//! theory (docs/src/theory/flow.md; docs/src/validation/flow.md).
//!
//! Each case seeds one mode (a quasi-circle's n, a quasi-sphere's l, a flat membrane's wave)
//! with a small amplitude (twice: +a and −a), runs the Stokes dynamics at fixed tension from
//! it, and fits the decay rate of the difference of the two runs' moments ([`measure`]). The rate is compared with the sharp rate in free space
//! times the periodic box's factor ([`crate::problem::flow::box_factor`]): their ratio
//! should tend to 1 as ε/R → 0. For each (membrane, mode, σ̄) the ratio is extrapolated to
//! ε/R = 0 (ε/λ for the flat membrane, whose cases are its sizes) by the polynomial through
//! the sizes' ratios (linear through two, quadratic through three), and its distance from 1
//! is the error the table reports. A family run in several boxes first takes each size's
//! ratio to L → ∞ ([`free_space_ratio`]): the diffuse vesicle feels its images more than the
//! sharp factor says, by a part that falls with the box as the factor's own shortfall does.
//!
//! Writes `rates.txt`, `cases.csv` (every run), `rates.csv` (per membrane, mode and σ̄: the
//! ratio at each size and extrapolated) and the chart `rates` (ratio against ε/R).

pub mod measure;
pub mod spec;

use super::harness::{Report, Study};
use super::table::{self, Column, Format, Row};
use crate::error::Result;
use crate::output::chart::{colour, Axis, Corner, Figure, Mark, Series, Shape};
use measure::{Case, Kind, Measured};
pub use spec::Spec;
use std::path::Path;
use std::time::Instant;

impl Row for Measured {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("membrane", "membrane", Format::Plain, |r| {
                r.case.kind.name().into()
            }),
            Column::both("model", "model", Format::Plain, |r| {
                r.case.membrane_model().into()
            }),
            Column::both("mode", "mode", Format::Plain, |r| r.case.mode.into()),
            Column::both("sigma_bar", "sigma_bar", Format::Plain, |r| {
                r.case.sigma_bar.into()
            }),
            Column::both("viscosity_ratio", "eta_in/eta_out", Format::Plain, |r| {
                r.case.viscosity_ratio.into()
            }),
            Column::both("mobility", "M", Format::Plain, |r| r.case.mobility.into()),
            Column::both("size", "R or lambda", Format::Plain, |r: &Self| {
                r.case.size.into()
            })
            .unit("eps"),
            Column::both("box", "L/R or H/lambda", Format::Plain, |r| {
                r.case.box_ratio.into()
            }),
            Column::csv("points", |r| r.points.iter().product::<usize>().into()),
            Column::csv("mirrored_axes", |r| r.case.symmetry().len().into()),
            Column::both("dt", "dt", Format::Sci(2), |r| r.dt.into()),
            Column::both("steps", "steps", Format::Plain, |r| r.steps.into()),
            Column::both("rate", "rate", Format::Sci(4), |r| r.rate.into()),
            Column::both("theory", "sharp (free)", Format::Sci(4), |r| {
                r.theory.into()
            }),
            Column::both("box_factor", "box factor", Format::Fixed(4), |r| {
                r.box_factor.into()
            }),
            Column::both("ratio", "rate/(sharp x box)", Format::Fixed(4), |r| {
                r.ratio.into()
            }),
            Column::both("diffusive_share", "diffusive share", Format::Sci(1), |r| {
                r.diffusive_share.into()
            }),
            Column::both("boussinesq", "Bq", Format::Sci(2), |r| r.boussinesq.into()),
            Column::both(
                "dilation_factor",
                "dilation factor",
                Format::Fixed(4),
                |r| r.dilation_factor.into(),
            ),
            Column::both("fit_residual", "fit residual", Format::Sci(1), |r| {
                r.fit_residual.into()
            }),
            Column::both("widening", "profile widening", Format::Fixed(3), |r| {
                r.widening.into()
            }),
            Column::csv("max_speed", |r| r.max_speed.into()),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// The extrapolated ratio of one (membrane, mode, σ̄); a row of `rates.csv`.
#[derive(Clone, Debug)]
pub struct Rate {
    /// `circle`, `sphere` or `flat`.
    pub membrane: &'static str,
    /// `drop` or `inextensible`.
    pub model: &'static str,
    /// n or l (0 flat).
    pub mode: usize,
    /// σ̄.
    pub sigma_bar: f64,
    /// η_in/η_out.
    pub viscosity_ratio: f64,
    /// M of the diffusive channel.
    pub mobility: f64,
    /// Γ η_outR³/κ of the sharp theory (closed vesicles; with the contrast's factor), or Γ/(κk³/4η) − 1 = σ̄ (flat: NaN).
    pub reduced_theory: f64,
    /// L/R of the boxes: "4", or "8 10 -> inf" where each size's ratio is taken to L → ∞.
    pub boxes: String,
    /// (R/ε, ratio) at each size, smallest ε/R last; in free space where several boxes ran.
    pub ratios: Vec<(f64, f64)>,
    /// The ratios as the table prints them: "0.9519 0.9730 0.9829".
    pub ratios_text: String,
    /// The ratio extrapolated to ε/R = 0.
    pub extrapolated: f64,
    /// extrapolated − 1, in percent.
    pub error_percent: f64,
    /// Wall seconds of its cases.
    pub wall: f64,
}

impl Row for Rate {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("membrane", "membrane", Format::Plain, |r| r.membrane.into()),
            Column::both("model", "model", Format::Plain, |r| r.model.into()),
            Column::both("mode", "mode", Format::Plain, |r| r.mode.into()),
            Column::both("sigma_bar", "sigma_bar", Format::Plain, |r| {
                r.sigma_bar.into()
            }),
            Column::both("viscosity_ratio", "eta_in/eta_out", Format::Plain, |r| {
                r.viscosity_ratio.into()
            }),
            Column::both("mobility", "M", Format::Plain, |r| r.mobility.into()),
            Column::both("reduced_theory", "G eta R^3/kappa", Format::Fixed(4), |r| {
                r.reduced_theory.into()
            }),
            Column::both("boxes", "L/R", Format::Plain, |r| r.boxes.as_str().into()),
            Column::both(
                "ratios",
                "ratio per size (coarse to fine)",
                Format::Plain,
                |r| r.ratios_text.as_str().into(),
            ),
            Column::both("extrapolated", "extrapolated", Format::Fixed(4), |r| {
                r.extrapolated.into()
            }),
            Column::both("error_percent", "error", Format::Fixed(2), |r: &Self| {
                r.error_percent.into()
            })
            .unit("%"),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// Every case and every extrapolated rate.
#[derive(Clone, Debug)]
pub struct Output {
    /// Every run.
    pub cases: Vec<Measured>,
    /// Per membrane, mode and σ̄.
    pub rates: Vec<Rate>,
}

/// The study.
pub struct RatesStudy;

impl Study for RatesStudy {
    const NAME: &'static str = "rates";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Output, Report)> {
        spec.validate()?;
        let groups = groups(spec);
        let mut progress = Progress::of(spec, &groups)?;
        let mut cases = Vec::new();
        let mut rates = Vec::new();
        for group in groups {
            let measured = group
                .iter()
                .map(|c| {
                    let m = measure::run(spec, c)?;
                    progress.done(&m);
                    Ok(m)
                })
                .collect::<Result<Vec<_>>>()?;
            rates.push(extrapolate(&measured));
            cases.extend(measured);
        }
        let mut text = String::from("== every case ==\n");
        text.push_str(&table::text(&cases));
        text.push_str(
            "\n== the ratio rate/(sharp free rate x box factor), extrapolated to eps/R = 0 ==\n",
        );
        text.push_str(&table::text(&rates));
        let mut report = Report {
            text,
            ..Report::default()
        };
        report.table("cases.csv", &cases)?;
        report.table("rates.csv", &rates)?;
        report.chart("rates", chart(&rates));
        Ok((Output { cases, rates }, report))
    }
}

/// A line on stderr as each case ends: its rate and ratio, and an ETA from the work done so
/// far ([`measure::work`]: the cases' costs differ by orders of magnitude, as R^6 in 3D).
struct Progress {
    started: Instant,
    /// Each case's work, in the order the cases run.
    work: Vec<f64>,
    finished: usize,
}

impl Progress {
    fn of(spec: &Spec, groups: &[Vec<Case>]) -> Result<Self> {
        Ok(Progress {
            started: Instant::now(),
            work: groups
                .iter()
                .flatten()
                .map(|case| measure::work(spec, case))
                .collect::<Result<_>>()?,
            finished: 0,
        })
    }

    fn done(&mut self, m: &Measured) {
        let c = &m.case;
        self.finished += 1;
        let done: f64 = self.work[..self.finished].iter().sum();
        let elapsed = self.started.elapsed().as_secs_f64();
        let eta = elapsed * (self.work.iter().sum::<f64>() / done - 1.0);
        eprintln!(
            "rates [{}/{}] {} {} {} sigma_bar {} M {} R {} L/R {}: rate {:.4e}, ratio {:.4}, \
             fit residual {:.1e}, {} steps, {:.0} s | {elapsed:.0} s, ETA {eta:.0} s",
            self.finished,
            self.work.len(),
            c.kind.name(),
            c.mode,
            c.membrane_model(),
            c.sigma_bar,
            c.mobility,
            c.size,
            c.box_ratio,
            m.rate,
            m.ratio,
            m.fit_residual,
            m.steps,
            m.wall
        );
    }
}

/// The cases of the spec, grouped by (membrane, mode, σ̄, λ, model, M), each group's sizes
/// coarse (small R/ε) to fine, and each size's boxes small to large.
fn groups(spec: &Spec) -> Vec<Vec<Case>> {
    let mut out = Vec::new();
    for (kind, family) in [(Kind::Circle, &spec.circle), (Kind::Sphere, &spec.sphere)] {
        let Some(f) = family else { continue };
        for g in &f.groups {
            let mut sizes = g.r0.clone();
            sizes.sort_by(f64::total_cmp);
            for &mode in &g.modes {
                for &sigma_bar in &g.sigma_bar {
                    for &viscosity_ratio in &g.viscosity_ratio {
                        for (&model, &mobility) in pairs(&g.models, &spec.mobility) {
                            out.push(
                                sizes
                                    .iter()
                                    .flat_map(|&size| {
                                        f.boxes.iter().map(move |&box_ratio| Case {
                                            kind,
                                            mode,
                                            sigma_bar,
                                            size,
                                            box_ratio,
                                            mirror: f.mirror,
                                            viscosity_ratio,
                                            inextensible: model == spec::Model::Inextensible,
                                            mobility,
                                        })
                                    })
                                    .collect(),
                            );
                        }
                    }
                }
            }
        }
    }
    if let Some(f) = &spec.flat {
        let mut sizes = f.wavelengths.clone();
        sizes.sort_by(f64::total_cmp);
        for &sigma_bar in &f.sigma_bar {
            for (&viscosity_ratio, &mobility) in pairs(&f.viscosity_ratio, &spec.mobility) {
                out.push(
                    sizes
                        .iter()
                        .map(|&size| Case {
                            kind: Kind::Flat,
                            mode: 0,
                            sigma_bar,
                            size,
                            box_ratio: f.height,
                            mirror: false,
                            viscosity_ratio,
                            inextensible: false,
                            mobility,
                        })
                        .collect(),
                );
            }
        }
    }
    out
}

/// Every (a, b), a the outer loop.
fn pairs<'a, A, B>(a: &'a [A], b: &'a [B]) -> impl Iterator<Item = (&'a A, &'a B)> {
    a.iter().flat_map(move |x| b.iter().map(move |y| (x, y)))
}

/// The value at x = 0 of the polynomial through `(x_i, y_i)`: Σ_i y_i Π_{j≠i} x_j/(x_j − x_i).
pub fn value_at_zero(points: &[(f64, f64)]) -> f64 {
    points
        .iter()
        .enumerate()
        .map(|(i, &(xi, yi))| {
            let weight: f64 = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &(xj, _))| xj / (xj - xi))
                .product();
            yi * weight
        })
        .sum()
}

/// The ratio of a size in free space from its ratios in several boxes, `(L/R, ratio)` small box
/// first: the value at (R/L)^d = 0 of the polynomial in (R/L)^d through them (a line through
/// two). The lowest mode's images fall off as (R/L)^d — the sharp factor's shortfall
/// 1 − [`crate::problem::flow::box_factor`] tends to 6.1 (R/L)² for the circle's n = 2 and
/// 11.1 (R/L)³ for the sphere's l = 2 — and so does the diffuse vesicle's excess over it. One
/// box gives its ratio unchanged.
pub fn free_space_ratio(dim: usize, boxes: &[(f64, f64)]) -> f64 {
    let points: Vec<(f64, f64)> = boxes
        .iter()
        .map(|&(l_over_r, ratio)| (l_over_r.powi(-(dim as i32)), ratio))
        .collect();
    value_at_zero(&points)
}

/// The group's ratios at each size (in free space where several boxes ran) and their
/// extrapolation to ε/R = 0 through the last three sizes (the finest).
fn extrapolate(group: &[Measured]) -> Rate {
    let first = &group[0].case;
    let dim = first.kind.dim();
    let boxes: Vec<f64> = group
        .iter()
        .filter(|m| m.case.size == first.size)
        .map(|m| m.case.box_ratio)
        .collect();
    let ratios: Vec<(f64, f64)> = group
        .chunks(boxes.len())
        .map(|same_size| {
            let per_box: Vec<(f64, f64)> = same_size
                .iter()
                .map(|m| (m.case.box_ratio, m.ratio))
                .collect();
            (same_size[0].case.size, free_space_ratio(dim, &per_box))
        })
        .collect();
    let points: Vec<(f64, f64)> = ratios.iter().map(|&(size, r)| (1.0 / size, r)).collect();
    let tail = &points[points.len().saturating_sub(3)..];
    let extrapolated = value_at_zero(tail);
    let mut boxes_text = boxes
        .iter()
        .map(f64::to_string)
        .collect::<Vec<_>>()
        .join(" ");
    if boxes.len() > 1 {
        boxes_text.push_str(" -> inf");
    }
    Rate {
        membrane: first.kind.name(),
        model: first.membrane_model(),
        mode: first.mode,
        sigma_bar: first.sigma_bar,
        viscosity_ratio: first.viscosity_ratio,
        mobility: first.mobility,
        reduced_theory: match first.kind {
            Kind::Flat => f64::NAN,
            _ => {
                first.size.powi(3) * measure::sharp_rate(first, 1.0)
                    / crate::problem::flow::bending_modulus(1.0)
            }
        },
        boxes: boxes_text,
        ratios_text: ratios
            .iter()
            .map(|(_, ratio)| format!("{ratio:.4}"))
            .collect::<Vec<_>>()
            .join(" "),
        ratios,
        extrapolated,
        error_percent: 100.0 * (extrapolated - 1.0),
        wall: group.iter().map(|m| m.wall).sum(),
    }
}

/// The ratio against ε/R per (membrane, mode, σ̄, λ, model), in free space where several boxes
/// ran, with the target 1.
fn chart(rates: &[Rate]) -> Figure {
    let mut fig = Figure::new(
        "Stokes relaxation rates: phase field over sharp theory (times the box factor)",
        Axis::linear("eps / R   (flat membrane: eps / wavelength)"),
        Axis::linear("rate / (sharp rate x box factor)"),
    );
    fig.legend = Corner::LowerLeft;
    let several_mobilities = rates.iter().any(|r| r.mobility != rates[0].mobility);
    let marks = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
    ];
    for (i, r) in rates.iter().enumerate() {
        let pts = r
            .ratios
            .iter()
            .map(|&(size, ratio)| (1.0 / size, ratio))
            .collect();
        let mut label = match r.membrane {
            "flat" => format!("flat, sigma_bar {}", r.sigma_bar),
            name => format!("{name} {}, sigma_bar {}", r.mode, r.sigma_bar),
        };
        if r.model == "inextensible" {
            label.push_str(", inextensible");
        } else if r.viscosity_ratio != 1.0 {
            label.push_str(&format!(", eta_in/eta_out {}", r.viscosity_ratio));
        }
        if several_mobilities {
            label.push_str(&format!(", M {}", r.mobility));
        }
        if r.boxes.contains("inf") {
            label.push_str(&format!(", L/R {}", r.boxes));
        }
        fig.push(Series::new(
            label,
            pts,
            colour(i),
            Mark::LinePoints(marks[i % marks.len()]),
        ));
    }
    let xmax = rates
        .iter()
        .flat_map(|r| &r.ratios)
        .map(|&(size, _)| 1.0 / size)
        .fold(0.0, f64::max);
    fig.push(
        Series::new(
            "sharp limit",
            vec![(0.0, 1.0), (xmax, 1.0)],
            [0, 0, 0],
            Mark::Dashed,
        )
        .unlisted(),
    );
    fig
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The extrapolation is exact for a polynomial of the degree it fits: y = 1 + 2x − 3x²
    /// through three points gives 1, y = 0.5 − x through two gives 0.5.
    #[test]
    fn extrapolation_is_exact_on_polynomials() {
        let q = |x: f64| 1.0 + 2.0 * x - 3.0 * x * x;
        let pts: Vec<(f64, f64)> = [0.1, 0.05, 0.02].iter().map(|&x| (x, q(x))).collect();
        assert!((value_at_zero(&pts) - 1.0).abs() < 1e-12);
        assert!((value_at_zero(&[(0.2, 0.3), (0.1, 0.4)]) - 0.5).abs() < 1e-12);
    }

    /// A list of mobilities makes one family per M (each extrapolated in ε/R on its own), with
    /// every size in each and the scene's `flow.mobility` the case's.
    #[test]
    fn each_mobility_is_a_family_of_its_own() {
        let spec: Spec = serde_json::from_value(serde_json::json!({
            "study": "rates", "h_over_eps": 0.5, "viscosity": 1.0, "mobility": [0.01, 0.16],
            "amplitude": 0.02, "dt_max": 3.0, "step_per_rate": 0.02, "e_folds": 0.5,
            "prepare_steps": 20,
            "circle": {"box": 8, "groups": [{"modes": [2], "sigma_bar": [0], "r0": [8, 12]}]}
        }))
        .expect("spec");
        spec.validate().expect("valid");
        let families = groups(&spec);
        assert_eq!(families.len(), 2);
        for (family, m) in families.iter().zip([0.01, 0.16]) {
            assert_eq!(family.len(), 2);
            assert!(family.iter().all(|c| c.mobility == m));
            let scene = measure::scene(&spec, &family[0], 1e-3, 1.0).expect("scene");
            assert_eq!(scene.flow.as_ref().map(|f| f.mobility), Some(m));
        }
    }

    /// The box extrapolation is in (R/L)^d: it takes the sharp factor's own box series to free
    /// space, from L = 8R and 10R, within 2.2e-4 of 1 for the sphere's l = 2 (where its
    /// shortfall is 2.1e-2 at 8R) and within 1.5e-3 for the circle's n = 2 (9.3e-2 at 8R); a
    /// line in (R/L)^d is exact.
    #[test]
    fn the_box_extrapolation_recovers_free_space() {
        use crate::problem::flow::box_factor;
        for (dim, bound) in [(3, 2.2e-4), (2, 1.5e-3)] {
            let series: Vec<(f64, f64)> = [8.0, 10.0]
                .iter()
                .map(|&l| (l, box_factor(dim, 2, 1.0 / l)))
                .collect();
            let free = free_space_ratio(dim, &series);
            assert!((free - 1.0).abs() < bound, "d = {dim}: {free}");
            assert!(1.0 - series[0].1 > 20.0 * (free - 1.0).abs());
        }
        let line = |l: f64| 0.95 - 3.0 * l.powi(-3);
        let free = free_space_ratio(3, &[(6.0, line(6.0)), (9.0, line(9.0))]);
        assert!((free - 0.95).abs() < 1e-12);
    }
}
