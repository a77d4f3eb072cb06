//! The stability map's spontaneous-curvature axis: at h = ε, from the field prepared there, the
//! fixed-Δt sweep of each spectral scheme with its default stabiliser at each εc0 (c0 uniform),
//! classified as the rest of the map. The bulk term's linearisation f'(±1) = 2 ± 2εC0 (C0 =
//! c0/√2) grows with c0 while the default S does not, so the frontier falls as c0 grows (not
//! necessarily monotonically from one εc0 to the next).
//!
//! Writes `stability_c0.csv` (every run), the frontier table (largest stable Δt per scheme and
//! εc0) and the chart `stability_c0` (PNG and SVG).

use super::{
    at_spacing, class_colour, dt_sweep, edge, prepared, C0Run, C0Sweep, Spec, FRONTIER, METHODS,
};
use crate::commands::study::classify::Class;
use crate::error::{Error, Result};
use crate::output::chart::{Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::{C0Spec, Scene, Scheme};
use crate::problem::model::C0;
use std::fmt::Write as _;

/// Name of `scheme` in the file and the CSV.
fn scheme_name(scheme: Scheme) -> &'static str {
    match scheme {
        Scheme::Sbdf1 => "sbdf1",
        Scheme::Sbdf2 => "sbdf2",
    }
}

/// Every run of the c0 sweep `c0`, at h = ε from the field prepared there.
///
/// # Errors
/// `Error::Config` (field `c0.…`) for an empty or non-finite axis.
pub(super) fn c0_sweep(spec: &Spec, c0: &C0Sweep, base: &Scene) -> Result<Vec<C0Run>> {
    if c0.eps_c0.is_empty() || c0.eps_c0.iter().any(|x| !x.is_finite()) {
        return Err(Error::config("c0.eps_c0", "need at least one finite value"));
    }
    if c0.schemes.is_empty() {
        return Err(Error::config("c0.schemes", "need at least one scheme"));
    }
    let problem = prepared(base, 1.0)?;
    let mut runs = Vec::new();
    for &scheme in &c0.schemes {
        let method = METHODS
            .iter()
            .find(|m| m.scheme == Some(scheme) && !m.no_stabiliser)
            .expect("every scheme has a default-stabiliser method");
        for &eps_c0 in &c0.eps_c0 {
            // The run takes c0 from the problem: the prepared field with this c0.
            let uniform = C0Spec::Uniform(eps_c0 / base.eps);
            let mut at_c0 = problem.clone();
            at_c0.c0 = C0::new(&uniform, &at_c0.grid, base.eps)?;
            let edit = |s: &mut Scene| {
                at_spacing(s, base, 1.0);
                method.apply(s);
                s.c0 = uniform.clone();
            };
            for (dt, r) in dt_sweep(spec, base, &at_c0, &edit)? {
                runs.push(C0Run {
                    scheme: scheme_name(scheme),
                    eps_c0,
                    dt,
                    class: r.0,
                    steps: r.1,
                    max_abs_phi: r.2,
                    max_area_error: r.3,
                });
            }
        }
    }
    Ok(runs)
}

/// Per scheme and εc0: `(scheme, εc0, largest stable Δt, first failure and its class)`.
pub(super) type C0Frontier = Vec<(&'static str, f64, Option<f64>, Option<(f64, Class)>)>;

/// The frontier of the c0 runs, in the order of the file.
pub(super) fn c0_frontier(runs: &[C0Run], c0: &C0Sweep) -> C0Frontier {
    let mut f = Vec::new();
    for &scheme in &c0.schemes {
        let name = scheme_name(scheme);
        for &eps_c0 in &c0.eps_c0 {
            let rs = runs
                .iter()
                .filter(|r| r.scheme == name && r.eps_c0 == eps_c0)
                .map(|r| (r.dt, r.class));
            let (largest, first) = edge(rs);
            f.push((name, eps_c0, largest, first));
        }
    }
    f
}

/// The printed table of the frontier.
pub(super) fn c0_table(f: &C0Frontier) -> String {
    let mut s = format!(
        "\nspontaneous curvature at h = eps, default S, c0 uniform:\n  {:<7} {:>7} {:>14} {:>28}\n",
        "scheme", "eps*c0", "largest stable", "first failure"
    );
    for x in f {
        let _ = writeln!(
            s,
            "  {:<7} {:>7.3} {:>14} {:>28}",
            x.0,
            x.1,
            x.2.map_or("none".into(), |d| format!("{d:.3e}")),
            x.3.map_or("none".into(), |(d, c)| format!("{d:.3e} ({})", c.as_str())),
        );
    }
    s
}

/// The chart: Δt (log) against εc0, a marker per scheme coloured by class, the measured
/// frontier of each scheme.
pub(super) fn c0_chart(runs: &[C0Run], f: &C0Frontier, c0: &C0Sweep) -> Figure {
    let mut fig = Figure::new(
        "Stability against c0 at h = eps, default S (markers by scheme, colour by class)",
        Axis::log("dt [time units]"),
        Axis::linear("eps * c0 (schemes offset vertically)"),
    );
    fig.legend = Corner::LowerLeft;
    let (lo, hi) = c0
        .eps_c0
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let step = if hi > lo { 0.015 * (hi - lo) } else { 0.01 };
    let shapes = [Shape::Triangle, Shape::Diamond];
    for (i, &scheme) in c0.schemes.iter().enumerate() {
        let name = scheme_name(scheme);
        let dy = step * (i as f64 - (c0.schemes.len() as f64 - 1.0) / 2.0);
        let shape = shapes[i % shapes.len()];
        for class in Class::ALL {
            let pts: Vec<(f64, f64)> = runs
                .iter()
                .filter(|r| r.scheme == name && r.class == class)
                .map(|r| (r.dt, r.eps_c0 + dy))
                .collect();
            fig.push(Series::new("", pts, class_colour(class), Mark::Points(shape)).unlisted());
        }
        fig.push(Series::new(
            format!("{}, default S", name.to_uppercase()),
            Vec::new(),
            [90, 90, 90],
            Mark::Points(shape),
        ));
        let frontier: Vec<(f64, f64)> = f
            .iter()
            .filter(|x| x.0 == name)
            .filter_map(|x| x.2.map(|d| (d, x.1 + dy)))
            .collect();
        fig.push(Series::new(
            format!("measured frontier, {}", name.to_uppercase()),
            frontier,
            FRONTIER[i % FRONTIER.len()],
            Mark::Line,
        ));
    }
    for class in Class::ALL {
        fig.push(Series::new(
            class.as_str(),
            Vec::new(),
            class_colour(class),
            Mark::Line,
        ));
    }
    fig
}
