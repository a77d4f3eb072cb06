//! `vesicle study ade FILE`: the stability map of the ADE multiplier λ in Δt × α
//! (docs/src/theory/ade.md, "The engines"; docs/src/validation/studies.md, "ADE multiplier:
//! implicit against lagged").
//!
//! From one field prepared without the term (the scene's `prepare_steps` spectral SBDF1 steps),
//! `steps` fixed steps of each spectral scheme of the file (default stabiliser, area by the
//! exact projection) with an ADE term at each α of the file and Δa0 = Δa of the prepared field
//! plus `da0_offset` (so that c̄0,eff starts at c̄0 + 2πα·offset), λ implicit (solved with σ in the
//! step) or lagged (λ of the current state), at each Δt of a geometric sweep. Every run is
//! classified by the criteria of [`crate::commands::study::classify`], with
//! F_eff = F_sc + σⁿA + F_ade: the functional the step decreases at fixed multipliers. The
//! energy guard is off (`allow_unstable`), so a run that rises goes on and is classified by
//! its series.
//!
//! The lagged λ = κ_λ(Mⁿ − M0) is an explicit term whose stiffness κ_λ grows with α: the
//! frontier of the lagged runs falls as α grows, while the implicit λ's denominator is
//! 1 − κ_λ⟨m̂, R̂⟩ ≥ 1 at every α and Δt (docs/src/theory/ade.md).
//!
//! Writes `ade.txt`, `stability_ade.csv` (every run), `frontier_ade.csv` (the largest stable Δt
//! per scheme, multiplier and α) and the chart `stability_ade` (PNG and SVG).

use super::measure::{failure_cause, sweep};
use super::report::{class_colour, Edge, FRONTIER};
use crate::commands::study::classify::{classify, Class, Criteria, StepSample};
use crate::commands::study::file;
use crate::commands::study::harness::{self, Report, Study};
use crate::commands::study::table::{self, Column, Format, Row};
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::Engine;
use crate::error::{Error, Result};
use crate::output::chart::{Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::{
    AdaptiveSpec, AdeMultiplier, AdeSpec, Method, Scene, Scheme, StabilizerSpec,
};
use crate::problem::setup::{self, Problem};
use serde::Deserialize;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"ade"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The 3D scene (inline or a path), without an `ade` block (the study sets it).
    pub scene: Value,
    /// Δa0 − Δa of the prepared field: the map's Δa0 is the start's Δa plus this. Keep
    /// 2πα|offset| small: it is c̄0,eff − c̄0 at the start (docs/src/theory/ade.md, "Measured").
    pub da0_offset: f64,
    /// α values (> 0).
    pub alpha: Vec<f64>,
    /// Smallest Δt of the sweep.
    pub dt_min: f64,
    /// Largest Δt of the sweep.
    pub dt_max: f64,
    /// Δt values per decade.
    pub per_decade: f64,
    /// Spectral schemes, each with its default stabiliser.
    pub schemes: Vec<Scheme>,
    /// λ's treatments: `"implicit"` and/or `"lagged"`.
    pub multipliers: Vec<AdeMultiplier>,
    /// Fixed steps per run.
    pub steps: usize,
}

/// One classified run; a row of `stability_ade.csv`.
#[derive(Clone, Debug)]
pub struct AdeRun {
    /// `sbdf1` or `sbdf2` (default stabiliser).
    pub scheme: &'static str,
    /// `implicit` or `lagged`.
    pub multiplier: &'static str,
    /// α.
    pub alpha: f64,
    /// Δt.
    pub dt: f64,
    /// The class.
    pub class: Class,
    /// Accepted steps.
    pub steps: usize,
    /// Largest max|φ| seen.
    pub max_abs_phi: f64,
    /// Largest |A − A0|/A0 seen.
    pub max_area_error: f64,
    /// Δa of the last state.
    pub da_end: f64,
    /// Largest |c̄0,eff| seen (c̄0 + 2πα(Δa0 − Δa)).
    pub max_abs_c0_eff: f64,
}

impl Row for AdeRun {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("scheme", |r| r.scheme.into()),
            Column::csv("multiplier", |r| r.multiplier.into()),
            Column::csv("alpha", |r| r.alpha.into()),
            Column::csv("dt", |r| r.dt.into()),
            Column::csv("class", |r| r.class.as_str().into()),
            Column::csv("steps", |r| r.steps.into()),
            Column::csv("max_abs_phi", |r| r.max_abs_phi.into()),
            Column::csv("max_area_error", |r| r.max_area_error.into()),
            Column::csv("da_end", |r| r.da_end.into()),
            Column::csv("max_abs_c0_eff", |r| r.max_abs_c0_eff.into()),
        ]
    }
}

/// The study: `ade.txt`, `stability_ade.csv`, `frontier_ade.csv` and the chart
/// `stability_ade`.
pub struct AdeStability;

impl Study for AdeStability {
    const NAME: &'static str = "ade";
    type Spec = Spec;
    type Output = Vec<AdeRun>;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Vec<AdeRun>, Report)> {
        let base = file::scene(&spec.scene, &[], "scene", dir)?;
        let (runs, start) = runs(spec, &base)?;
        let report = report(spec, &runs, start)?;
        Ok((runs, report))
    }
}

/// Name of `scheme` in the file and the CSV.
fn scheme_name(scheme: Scheme) -> &'static str {
    match scheme {
        Scheme::Sbdf1 => "sbdf1",
        Scheme::Sbdf2 => "sbdf2",
    }
}

/// Name of `m` in the file and the CSV.
fn multiplier_name(m: AdeMultiplier) -> &'static str {
    match m {
        AdeMultiplier::Implicit => "implicit",
        AdeMultiplier::Lagged => "lagged",
    }
}

/// Refuse an empty, non-finite or non-positive axis, or a scene with its own area-difference
/// term, naming the key.
fn check(spec: &Spec, base: &Scene) -> Result<()> {
    if spec.alpha.is_empty() || spec.alpha.iter().any(|a| !(a.is_finite() && *a > 0.0)) {
        return Err(Error::config(
            "alpha",
            "need at least one value, each finite and > 0 (the chart's axis is logarithmic)",
        ));
    }
    if !(spec.dt_min > 0.0
        && spec.dt_max >= spec.dt_min
        && spec.dt_max.is_finite()
        && spec.per_decade > 0.0)
    {
        return Err(Error::config(
            "dt_min",
            "need 0 < dt_min <= dt_max (finite) and per_decade > 0",
        ));
    }
    if spec.schemes.is_empty() {
        return Err(Error::config("schemes", "need at least one scheme"));
    }
    if spec.multipliers.is_empty() {
        return Err(Error::config(
            "multipliers",
            "need \"implicit\" and/or \"lagged\"",
        ));
    }
    if spec.steps == 0 {
        return Err(Error::config("steps", "need at least one step"));
    }
    if !spec.da0_offset.is_finite() {
        return Err(Error::config("da0_offset", "must be finite"));
    }
    if base.ade.is_some() || base.bilayer_couple.is_some() {
        let key = if base.ade.is_some() {
            "scene.ade"
        } else {
            "scene.bilayer_couple"
        };
        return Err(Error::config(
            key,
            "the study sets the ade block (α from alpha, Δa0 = Δa of the prepared field + da0_offset, the multiplier from multipliers): leave it out of the scene",
        ));
    }
    if base.dim != 3 {
        return Err(Error::config("scene.dim", "the ADE term is 3D only"));
    }
    Ok(())
}

/// The scene of one run: `base` with the ADE term `ade`, spectral `scheme` with its default S,
/// `steps` fixed steps of `dt`, energy guard off, no preparation.
fn ade_scene(base: &Scene, scheme: Scheme, ade: AdeSpec, dt: f64, steps: usize) -> Result<Scene> {
    harness::variant(base, "scene", |s| {
        s.prepare_steps = 0;
        s.allow_unstable = true;
        s.adaptive = AdaptiveSpec::Flag(false);
        s.t_end = None;
        s.stop_residual = None;
        s.method = Method::Spectral;
        s.scheme = scheme;
        s.stabilizer = StabilizerSpec::default();
        s.ade = Some(ade);
        s.dt = dt;
        s.max_steps = Some(steps);
    })
}

/// Δa of the prepared field `problem.phi` at the area target the runs take.
fn start_da(base: &Scene, problem: &Problem) -> Result<f64> {
    let ade = AdeSpec {
        alpha: 1.0,
        da0: 1.0,
        multiplier: None,
    };
    let s = ade_scene(base, Scheme::Sbdf1, ade, base.dt, 1)?;
    let (sim, _) = Simulation::of_scene(&s, problem)?;
    Ok(sim.record().couple.map_or(f64::NAN, |c| c.da))
}

/// The start of every run: the scene's field after its `prepare_steps` spectral SBDF1 steps
/// without the term (the preparation never has it).
fn prepared(base: &Scene) -> Result<Problem> {
    let prep = harness::variant(base, "scene", |s| {
        s.method = Method::Spectral;
        s.scheme = Scheme::Sbdf1;
        s.adaptive = AdaptiveSpec::Flag(false);
        s.allow_unstable = false;
    })?;
    let mut problem = setup::build(&prep)?;
    problem.phi = crate::commands::study::prepared_field(&prep, &problem)?;
    Ok(problem)
}

/// Every run of the map, and Δa of the prepared field (at the area target of the runs), to
/// which Δa0 is relative.
///
/// # Errors
/// `Error::Config` naming the key of an empty or invalid axis or of an invalid variant scene;
/// `Error::Blowup` if the preparation diverges.
pub fn runs(spec: &Spec, base: &Scene) -> Result<(Vec<AdeRun>, f64)> {
    check(spec, base)?;
    let problem = prepared(base)?;
    let da_start = start_da(base, &problem)?;
    let da0 = da_start + spec.da0_offset;
    let dts = sweep(spec.dt_min, spec.dt_max, spec.per_decade);
    let criteria = Criteria::default();
    let mut runs = Vec::new();
    for &scheme in &spec.schemes {
        for &multiplier in &spec.multipliers {
            for &alpha in &spec.alpha {
                for &dt in &dts {
                    let ade = AdeSpec {
                        alpha,
                        da0,
                        multiplier: Some(multiplier),
                    };
                    let s = ade_scene(base, scheme, ade, dt, spec.steps)?;
                    runs.push(AdeRun {
                        scheme: scheme_name(scheme),
                        multiplier: multiplier_name(multiplier),
                        alpha,
                        dt,
                        ..run(&s, &problem, &criteria)?
                    });
                }
            }
        }
    }
    Ok((runs, da_start))
}

/// F_eff = F_sc + σA + F_ade of the engine's state at multiplier `sigma`, and its Δa and c̄0,eff.
fn state(engine: &dyn Engine, sigma: f64) -> (f64, f64, f64) {
    let m = engine.measures();
    let (f_ade, da, c0_eff) = engine
        .area_difference()
        .map_or((0.0, f64::NAN, f64::NAN), |t| {
            (
                t.energy(m.curvature),
                t.da(m.curvature),
                t.c0_eff(m.curvature, engine.lambda()),
            )
        });
    (m.energy + sigma * m.area + f_ade, da, c0_eff)
}

/// `s` from `problem.phi` for its `max_steps`: the classified run (scheme, multiplier, α and Δt
/// left for the caller).
fn run(s: &Scene, problem: &Problem, criteria: &Criteria) -> Result<AdeRun> {
    let (mut sim, a0) = Simulation::of_scene(s, problem)?;
    let mut samples = Vec::new();
    let mut sigma = sim.engine().sigma();
    let (mut f_before, mut da_end, c0_start) = state(sim.engine(), sigma);
    let mut max_c0 = c0_start.abs();
    let mut watch = Probe(|now: &Now| {
        let (f_after, da, c0_eff) = state(now.engine, sigma);
        samples.push(StepSample {
            f_before,
            f_after,
            area_error: (now.record.area - a0).abs() / a0,
            max_phi: now.engine.phi().iter().fold(0.0f64, |m, p| m.max(p.abs())),
        });
        sigma = now.engine.sigma();
        f_before = state(now.engine, sigma).0;
        da_end = da;
        max_c0 = max_c0.max(c0_eff.abs());
        Ok(Flow::Continue)
    });
    let failure = failure_cause(sim.run(&StopRules::of(s), &mut [&mut watch]))?;
    let class = classify(&samples, failure, criteria);
    let max_abs_phi = samples.iter().fold(0.0f64, |m, x| m.max(x.max_phi));
    let max_area_error = samples.iter().fold(0.0f64, |m, x| m.max(x.area_error));
    Ok(AdeRun {
        scheme: "",
        multiplier: "",
        alpha: f64::NAN,
        dt: f64::NAN,
        class,
        steps: sim.clock.step,
        max_abs_phi,
        max_area_error,
        da_end,
        max_abs_c0_eff: max_c0,
    })
}

/// The edge of one (scheme, multiplier) at one α; a row of `frontier_ade.csv`.
pub struct AdeEdge {
    /// `sbdf1` or `sbdf2`.
    pub scheme: &'static str,
    /// `implicit` or `lagged`.
    pub multiplier: &'static str,
    /// α.
    pub alpha: f64,
    /// Its largest stable Δt and first failure.
    pub edge: Edge,
}

impl Row for AdeEdge {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("scheme", "scheme", Format::Plain, |r| r.scheme.into()),
            Column::both("multiplier", "multiplier", Format::Plain, |r| {
                r.multiplier.into()
            }),
            Column::both("alpha", "alpha", Format::Sci(1), |r| r.alpha.into()),
            Column::both(
                "largest_stable_dt",
                "largest stable dt",
                Format::Sci(3),
                |r: &Self| r.edge.largest_dt().into(),
            )
            .or("none"),
            Column::both(
                "first_failure_dt",
                "first failure dt",
                Format::Sci(3),
                |r: &Self| r.edge.failure_dt().into(),
            )
            .or("none"),
            Column::both("first_failure_class", "its class", Format::Plain, |r| {
                r.edge.failure_class().into()
            }),
        ]
    }
}

/// The (scheme, multiplier) pairs of the file, in its order.
fn pairs(spec: &Spec) -> Vec<(&'static str, &'static str)> {
    spec.schemes
        .iter()
        .flat_map(|&s| {
            spec.multipliers
                .iter()
                .map(move |&m| (scheme_name(s), multiplier_name(m)))
        })
        .collect()
}

/// The edge of every (scheme, multiplier) at every α, in the order of the file.
fn frontier(spec: &Spec, runs: &[AdeRun]) -> Vec<AdeEdge> {
    let mut f = Vec::new();
    for (scheme, multiplier) in pairs(spec) {
        for &alpha in &spec.alpha {
            let rs = runs
                .iter()
                .filter(|r| r.scheme == scheme && r.multiplier == multiplier && r.alpha == alpha)
                .map(|r| (r.dt, r.class));
            f.push(AdeEdge {
                scheme,
                multiplier,
                alpha,
                edge: Edge::of(rs),
            });
        }
    }
    f
}

/// The report: the frontier table, both CSV files and the chart.
fn report(spec: &Spec, runs: &[AdeRun], da_start: f64) -> Result<Report> {
    let edges = frontier(spec, runs);
    let da0 = da_start + spec.da0_offset;
    let mut text = format!(
        "ADE multiplier: {} fixed steps per run (default S, area by projection, energy guard off), \
         dt from {:.1e} to {:.1e} ({} per decade), from the field prepared without the term\n\
         da of the start = {da_start:.6}, da0 = {da0:.6} (offset {})\n\
         classes as the stability map, F_eff = F_sc + sigma^n A + F_ade\n\n",
        spec.steps, spec.dt_min, spec.dt_max, spec.per_decade, spec.da0_offset,
    );
    text.push_str(&table::text(&edges));
    let _ = writeln!(
        text,
        "\nlargest stable dt against alpha (> : stable to the end of the sweep):"
    );
    let _ = writeln!(
        text,
        "  {:<20} {}",
        "scheme, multiplier",
        spec.alpha
            .iter()
            .map(|a| format!("{:>10}", format!("{a:.0e}")))
            .collect::<String>()
    );
    for (scheme, multiplier) in pairs(spec) {
        let cells: String = edges
            .iter()
            .filter(|e| e.scheme == scheme && e.multiplier == multiplier)
            .map(|e| {
                let cell = match (e.edge.largest_stable, e.edge.first_failure) {
                    (None, _) => "none".to_string(),
                    (Some(d), None) => format!(">{d:.2e}"),
                    (Some(d), Some(_)) => format!("{d:.2e}"),
                };
                format!("{cell:>10}")
            })
            .collect();
        let _ = writeln!(text, "  {:<20} {cells}", format!("{scheme}, {multiplier}"));
    }
    let mut report = Report {
        text,
        ..Report::default()
    };
    report.table("stability_ade.csv", runs)?;
    report.table("frontier_ade.csv", &edges)?;
    report.chart("stability_ade", chart(spec, runs, &edges));
    Ok(report)
}

/// The chart: Δt (log) against α (log), a marker per (scheme, multiplier) coloured by class and
/// offset sideways, the measured frontier of each pair (implicit solid, lagged dashed; one
/// legend entry per pair), three empty decades above the sweep for the legend.
fn chart(spec: &Spec, runs: &[AdeRun], edges: &[AdeEdge]) -> Figure {
    let mut fig = Figure::new(
        "ADE multiplier: stability in dt x alpha (markers by scheme and multiplier, colour by class)",
        Axis::log("alpha (pairs offset sideways)"),
        Axis::log("dt [time units]"),
    );
    fig.legend = Corner::UpperLeft;
    let ps = pairs(spec);
    let shapes = [
        (Shape::Triangle, "triangles"),
        (Shape::Square, "squares"),
        (Shape::Diamond, "diamonds"),
        (Shape::Cross, "crosses"),
    ];
    let offset = |i: usize| 1.25f64.powf(i as f64 - (ps.len() as f64 - 1.0) / 2.0);
    for (i, &(scheme, multiplier)) in ps.iter().enumerate() {
        let (shape, shape_name) = shapes[i % shapes.len()];
        for class in Class::ALL {
            let pts: Vec<(f64, f64)> = runs
                .iter()
                .filter(|r| r.scheme == scheme && r.multiplier == multiplier && r.class == class)
                .map(|r| (r.alpha * offset(i), r.dt))
                .collect();
            fig.push(Series::new("", pts, class_colour(class), Mark::Points(shape)).unlisted());
        }
        let frontier: Vec<(f64, f64)> = edges
            .iter()
            .filter(|e| e.scheme == scheme && e.multiplier == multiplier)
            .filter_map(|e| e.edge.largest_stable.map(|d| (e.alpha * offset(i), d)))
            .collect();
        let colour = FRONTIER[usize::from(scheme == "sbdf2") % FRONTIER.len()];
        let line = if multiplier == "lagged" {
            Mark::Dashed
        } else {
            Mark::Line
        };
        fig.push(Series::new(
            format!(
                "{}, {multiplier} ({shape_name}): largest stable dt",
                scheme.to_uppercase()
            ),
            frontier,
            colour,
            line,
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
    // One point of a line draws nothing: it only widens the Δt axis to make room for the legend.
    let room = vec![(spec.alpha[0], 1e3 * spec.dt_max)];
    fig.push(Series::new("", room, [255, 255, 255], Mark::Line).unlisted());
    fig
}
