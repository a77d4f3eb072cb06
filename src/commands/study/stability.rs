//! `vesicle study stability FILE`: the stability map (validation ladder rung 7).
//!
//! * **Fixed Δt against h**: at each h of the file (in units of ε; the box kept, n scaled), from
//!   one prepared field (spectral SBDF1 preparation), `steps` fixed steps at each Δt of a
//!   geometric sweep, for FD explicit Euler and spectral SBDF1 and SBDF2, each with S = 0 and
//!   with its default S (area by the exact projection in every method, so that the map is the
//!   time stepper's). Every run is classified
//!   by the criteria of [`super::classify`].
//! * **Adaptive**: spectral SBDF1 with adaptive steps over `[0, t_end]` at several controller
//!   tolerances `energy_alpha` (Δt = dt_max/√(1 + α r²), r the relative energy rate): accepted
//!   steps, rejected attempts and the Δt at which they were tried (an attempt rejected j times
//!   before acceptance at Δt was tried at Δt/shrink^j).
//! * **Lagrangian α**: FD at h = the first h, at fractions of its bound, the area target 1%
//!   below the prepared area, α swept: the run is stable when it does not blow up and
//!   |A − A0|/A0 never exceeds 10 × the initial 1% (a small α lets A drift slowly with the
//!   shape, an unstable one makes it oscillate with growing amplitude; energy rises are
//!   expected while σ moves, so they are not counted).
//! * **Spontaneous curvature** (optional `c0` block): at h = ε, the fixed-Δt sweep of spectral
//!   SBDF1 and/or SBDF2 with the default S at each εc0 of the file, c0 uniform ([`c0`]).
//!
//! Reports the largest stable Δt per method and h (the last stable Δt below the first
//! failure), the spectral/FD ratios and their least-squares scaling with h, the FD bound of
//! docs/src/theory/fd.md. Writes `stability.csv` (every run), `frontier.csv`, `stability.txt`, and the
//! charts `stability_map`, `stability_alpha` (PNG and SVG); with a `c0` block also
//! `stability_c0.csv` and the chart `stability_c0`.

mod c0;

use super::classify::{classify, Class, Criteria, StepSample};
use super::harness::{self, Report, Study};
use super::{file, fit};
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::fd;
use crate::engines::{AreaConstraint, Cause};
use crate::error::{Error, Result};
use crate::output::chart::{Axis, Corner, Figure, Mark, Series, Shape};
use crate::problem::config::{
    AdaptiveSettings, AdaptiveSpec, AreaMethod, Laplacian, Method, Scene, Scheme, StabilizerSpec,
};
use crate::problem::setup::{self, Problem};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"stability"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The base scene at h = ε (its `n` is scaled by ε/h).
    pub scene: Value,
    /// Spacings, in units of ε.
    pub h: Vec<f64>,
    /// Fixed steps per run.
    pub steps: usize,
    /// Smallest Δt of the sweep.
    pub dt_min: f64,
    /// Largest Δt of the sweep.
    pub dt_max: f64,
    /// Δt values per decade.
    pub per_decade: f64,
    /// Adaptive runs.
    pub adaptive: AdaptiveSweep,
    /// The Lagrangian α sweep.
    pub alpha: AlphaSweep,
    /// The spontaneous-curvature axis (optional).
    #[serde(default)]
    pub c0: Option<C0Sweep>,
}

/// The fixed-Δt sweep at h = ε against the spontaneous curvature, default stabiliser.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct C0Sweep {
    /// εc0 values (c0 set uniform to εc0/ε in the scene).
    pub eps_c0: Vec<f64>,
    /// Spectral schemes, each with its default stabiliser.
    pub schemes: Vec<Scheme>,
}

/// One classified run of the c0 sweep; a row of `stability_c0.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct C0Run {
    /// `sbdf1` or `sbdf2` (default stabiliser).
    pub scheme: &'static str,
    /// εc0.
    pub eps_c0: f64,
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
}

/// Adaptive runs at several tolerances.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveSweep {
    /// The controller's `energy_alpha` values.
    pub energy_alpha: Vec<f64>,
    /// End time.
    pub t_end: f64,
    /// First Δt.
    pub dt: f64,
    /// Largest Δt.
    pub dt_max: f64,
}

/// The Lagrangian α sweep (FD, first h).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct AlphaSweep {
    /// Δt as fractions of the FD bound.
    pub dt_fractions: Vec<f64>,
    /// Smallest α.
    pub alpha_min: f64,
    /// Largest α.
    pub alpha_max: f64,
    /// α values per decade.
    pub per_decade: f64,
    /// Steps per run.
    pub steps: usize,
}

/// One classified run; a row of `stability.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// `fixed`, `adaptive` or `alpha`.
    pub sweep: &'static str,
    /// Method name.
    pub method: &'static str,
    /// h/ε.
    #[serde(rename = "h_over_eps")]
    pub h: f64,
    /// Δt (fixed), or the median accepted Δt (adaptive).
    pub dt: f64,
    /// α (alpha sweep), or the controller's energy_alpha (adaptive), else NaN.
    pub alpha: f64,
    /// The class.
    pub class: Class,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected attempts (adaptive).
    pub rejected: usize,
    /// Largest max|φ| seen.
    #[serde(rename = "max_abs_phi")]
    pub max_phi: f64,
    /// Largest |A − A0|/A0 seen.
    #[serde(rename = "max_area_error")]
    pub area_error: f64,
    /// Δt of each rejected attempt (adaptive; in the table and the map, not the CSV).
    #[serde(skip)]
    pub rejected_dts: Vec<f64>,
}

/// A fixed-Δt method: its name, its marker on the map, and what it sets in the scene.
pub struct FixedMethod {
    /// Name in the tables.
    pub name: &'static str,
    /// Marker on the map.
    pub shape: Shape,
    /// The engine and scheme (`None`: FD explicit Euler).
    pub scheme: Option<Scheme>,
    /// Whether the stabiliser is S = 0 (else the scheme's default).
    pub no_stabiliser: bool,
}

impl FixedMethod {
    /// Set the method in `s`: FD with the exact area projection (so that the map is the time
    /// stepper's), or spectral with its scheme and stabiliser.
    fn apply(&self, s: &mut Scene) {
        match self.scheme {
            None => {
                s.method = Method::Fd;
                s.scheme = Scheme::default();
                s.stabilizer = StabilizerSpec::default();
                s.laplacian = Laplacian::default();
                s.area.method = Some(AreaMethod::Projection);
            }
            Some(scheme) => {
                s.method = Method::Spectral;
                s.scheme = scheme;
                s.stabilizer = if self.no_stabiliser {
                    StabilizerSpec {
                        s2: Some(0.0),
                        s4: Some(0.0),
                    }
                } else {
                    StabilizerSpec::default()
                };
            }
        }
    }
}

/// The fixed-Δt methods.
pub const METHODS: [FixedMethod; 5] = [
    FixedMethod {
        name: "FD explicit Euler",
        shape: Shape::Circle,
        scheme: None,
        no_stabiliser: false,
    },
    FixedMethod {
        name: "SBDF1, S = 0",
        shape: Shape::Square,
        scheme: Some(Scheme::Sbdf1),
        no_stabiliser: true,
    },
    FixedMethod {
        name: "SBDF1, default S",
        shape: Shape::Triangle,
        scheme: Some(Scheme::Sbdf1),
        no_stabiliser: false,
    },
    FixedMethod {
        name: "SBDF2, S = 0",
        shape: Shape::Cross,
        scheme: Some(Scheme::Sbdf2),
        no_stabiliser: true,
    },
    FixedMethod {
        name: "SBDF2, default S",
        shape: Shape::Diamond,
        scheme: Some(Scheme::Sbdf2),
        no_stabiliser: false,
    },
];

/// Geometric sweep with `per_decade` values per decade from `lo` to `hi`.
fn sweep(lo: f64, hi: f64, per_decade: f64) -> Vec<f64> {
    let count = ((hi / lo).log10() * per_decade).round() as i32;
    (0..=count)
        .map(|i| lo * 10f64.powf(i as f64 / per_decade))
        .collect()
}

/// The study: `stability.txt`, `stability.csv` (every run), `frontier.csv` and the charts
/// `stability_map`, `stability_alpha`.
pub struct Stability;

impl Study for Stability {
    const NAME: &'static str = "stability";
    type Spec = Spec;
    type Output = Vec<Run>;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Vec<Run>, Report)> {
        let base = file::scene(&spec.scene, &[], "scene", dir)?;
        let (runs, bounds) = sweeps(spec, &base)?;
        let frontier = frontier(&runs, &spec.h);
        let mut report = Report {
            text: table(&runs, &frontier, &bounds, spec),
            ..Report::default()
        };
        report.table("stability.csv", &runs)?;
        report.table("frontier.csv", &frontier_rows(&frontier, &bounds))?;
        charts(&mut report, &runs, &frontier, &bounds, (base.dim, base.eps));
        if let Some(c0) = &spec.c0 {
            let c0_runs = c0::c0_sweep(spec, c0, &base)?;
            let edges = c0::c0_frontier(&c0_runs, c0);
            report.text.push_str(&c0::c0_table(&edges));
            report.table("stability_c0.csv", &c0_runs)?;
            report.chart("stability_c0", c0::c0_chart(&c0_runs, &edges, c0));
        }
        Ok((runs, report))
    }
}

/// The FD bound at each h: `(h/ε, Δt bound)`.
type Bounds = Vec<(f64, f64)>;

/// Every run of the three sweeps, and the FD bound at each h.
fn sweeps(spec: &Spec, base: &Scene) -> Result<(Vec<Run>, Bounds)> {
    if !(spec.dt_min > 0.0 && spec.dt_max > spec.dt_min && spec.per_decade > 0.0) {
        return Err(Error::config(
            "dt_min",
            "need 0 < dt_min < dt_max and per_decade > 0",
        ));
    }
    if spec.h.is_empty() || spec.h.iter().any(|h| h.is_nan() || *h <= 0.0) {
        return Err(Error::config("h", "need at least one h > 0"));
    }
    let criteria = Criteria::default();
    let mut runs = Vec::new();
    let mut bounds = Vec::new();
    for &h in &spec.h {
        let grid = |s: &mut Scene| at_spacing(s, base, h);
        let problem = prepared(base, h)?;
        bounds.push((h, fd::stability_bound(&problem.grid, base.eps, 0.0)));
        for m in &METHODS {
            let edit = |s: &mut Scene| {
                grid(s);
                m.apply(s);
            };
            for (dt, r) in dt_sweep(spec, base, &problem, &edit)? {
                runs.push(Run {
                    sweep: "fixed",
                    method: m.name,
                    h,
                    dt,
                    alpha: f64::NAN,
                    class: r.0,
                    steps: r.1,
                    rejected: 0,
                    max_phi: r.2,
                    area_error: r.3,
                    rejected_dts: Vec::new(),
                });
            }
        }
        for &ea in &spec.adaptive.energy_alpha {
            let s = harness::variant(base, "adaptive", |s| {
                grid(s);
                s.method = Method::Spectral;
                s.scheme = Scheme::Sbdf1;
                s.allow_unstable = false;
                s.dt = spec.adaptive.dt;
                s.t_end = Some(spec.adaptive.t_end);
                s.max_steps = None;
                s.adaptive = AdaptiveSpec::Settings(AdaptiveSettings {
                    energy_alpha: ea,
                    dt_max: Some(spec.adaptive.dt_max),
                    ..AdaptiveSettings::default()
                });
            })?;
            runs.push(adaptive_run(&s, &problem, h, ea)?);
        }
        if h == spec.h[0] {
            let bound = bounds[0].1;
            for &frac in &spec.alpha.dt_fractions {
                for alpha in sweep(
                    spec.alpha.alpha_min,
                    spec.alpha.alpha_max,
                    spec.alpha.per_decade,
                ) {
                    let s = harness::variant(base, "alpha", |s| {
                        grid(s);
                        METHODS[0].apply(s);
                        s.dt = frac * bound;
                        s.max_steps = Some(spec.alpha.steps);
                        s.area.method = Some(AreaMethod::Lagrangian);
                        s.area.alpha = Some(alpha);
                    })?;
                    let lagrangian = Criteria {
                        rise: f64::INFINITY,
                        area: 10.0 * ALPHA_OFFSET,
                        max_phi: criteria.max_phi,
                    };
                    let r = fixed_run(&s, &problem, &lagrangian, Some(alpha))?;
                    runs.push(Run {
                        sweep: "alpha",
                        method: "FD explicit Euler, Lagrangian area",
                        h,
                        dt: frac * bound,
                        alpha,
                        class: r.0,
                        steps: r.1,
                        rejected: 0,
                        max_phi: r.2,
                        area_error: r.3,
                        rejected_dts: Vec::new(),
                    });
                }
            }
        }
    }
    Ok((runs, bounds))
}

/// The grid at `h` (in units of ε): the box of `base` kept, `n` scaled; no preparation (the
/// field is prepared once), the study's stop rules only.
fn at_spacing(s: &mut Scene, base: &Scene, h: f64) {
    s.h = h * base.eps;
    s.n = base
        .n
        .iter()
        .map(|&m| (m as f64 / h).round() as usize)
        .collect();
    s.prepare_steps = 0;
    s.allow_unstable = true;
    s.adaptive = AdaptiveSpec::Flag(false);
    s.t_end = None;
    s.stop_residual = None;
}

/// The problem of `base` at spacing `h`, its field prepared by `base.prepare_steps` spectral
/// SBDF1 steps (the one starting field of every run at that h).
fn prepared(base: &Scene, h: f64) -> Result<Problem> {
    let prep = harness::variant(base, "scene", |s| {
        at_spacing(s, base, h);
        s.method = Method::Spectral;
        s.scheme = Scheme::Sbdf1;
        s.prepare_steps = base.prepare_steps;
        s.allow_unstable = false;
    })?;
    let mut problem = setup::build(&prep)?;
    problem.phi = super::prepared_field(&prep, &problem)?;
    Ok(problem)
}

/// The fixed-Δt sweep of `spec` (`steps` steps at each Δt, from `problem.phi`) of the scene
/// `edit` makes from `base`, classified by the default criteria: `(Δt, run)` in increasing Δt,
/// stopped after three failures (blown up or constraint lost) in a row, as larger steps fail
/// too.
fn dt_sweep(
    spec: &Spec,
    base: &Scene,
    problem: &Problem,
    edit: &dyn Fn(&mut Scene),
) -> Result<Vec<(f64, Outcome)>> {
    let criteria = Criteria::default();
    let mut out = Vec::new();
    let mut blown = 0;
    for dt in sweep(spec.dt_min, spec.dt_max, spec.per_decade) {
        let s = harness::variant(base, "scene", |s| {
            edit(s);
            s.dt = dt;
            s.max_steps = Some(spec.steps);
        })?;
        let r = fixed_run(&s, problem, &criteria, None)?;
        blown = if matches!(r.0, Class::BlownUp | Class::ConstraintLost) {
            blown + 1
        } else {
            0
        };
        out.push((dt, r));
        if blown == 3 {
            break;
        }
    }
    Ok(out)
}

/// The area target's offset below the prepared area in the α sweep.
const ALPHA_OFFSET: f64 = 0.01;

/// A fixed run's class, steps, largest max|φ| and largest area error.
type Outcome = (Class, usize, f64, f64);

/// `s` from `problem.phi` for its `max_steps`: class, steps, largest max|φ| and area error.
/// With `alpha`, the Lagrangian update with that α toward (1 − [`ALPHA_OFFSET`]) × the
/// prepared area.
fn fixed_run(
    s: &Scene,
    problem: &Problem,
    criteria: &Criteria,
    alpha: Option<f64>,
) -> Result<Outcome> {
    let (mut sim, a0) = Simulation::of_scene(s, problem)?;
    let target = match alpha {
        Some(alpha) => {
            let target = (1.0 - ALPHA_OFFSET) * a0;
            sim.engine_mut().set_area(AreaConstraint {
                method: crate::problem::config::AreaMethod::Lagrangian,
                alpha,
                target,
            });
            target
        }
        None => a0,
    };
    let mut samples = Vec::new();
    let mut before = sim.record();
    let mut watch = Probe(|now: &Now| {
        let after = &now.record;
        let sigma = before.sigma;
        samples.push(StepSample {
            f_before: before.energy + sigma * before.area,
            f_after: after.energy + sigma * after.area,
            area_error: (after.area - target).abs() / target,
            max_phi: now.engine.phi().iter().fold(0.0f64, |m, p| m.max(p.abs())),
        });
        before = *after;
        Ok(Flow::Continue)
    });
    let failure = failure_cause(sim.run(&StopRules::of(s), &mut [&mut watch]))?;
    let class = classify(&samples, failure, criteria);
    let max_phi = samples.iter().fold(0.0f64, |m, x| m.max(x.max_phi));
    let area = samples.iter().fold(0.0f64, |m, x| m.max(x.area_error));
    Ok((class, sim.clock.step, max_phi, area))
}

/// What ended a run: `None` if it ran to its end, the cause of a failed step, or the error of
/// anything else (a failed device, a file), which ends the study.
fn failure_cause<T>(ran: Result<T>) -> Result<Option<Cause>> {
    match ran {
        Ok(_) => Ok(None),
        Err(Error::Blowup { cause, .. }) => Ok(Some(cause)),
        Err(other) => Err(other),
    }
}

/// An adaptive run over `[0, t_end]`: its steps, rejections and where they were tried.
fn adaptive_run(s: &Scene, problem: &Problem, h: f64, energy_alpha: f64) -> Result<Run> {
    let shrink = s.adaptive.settings().map_or(0.5, |a| a.shrink);
    let (mut sim, a0) = Simulation::of_scene(s, problem)?;
    let mut accepted = Vec::new();
    let mut rejected_dts = Vec::new();
    let mut max_phi = 0.0f64;
    let mut area = 0.0f64;
    let mut probe = Probe(|now: &Now| {
        if let Some(rep) = now.report {
            accepted.push(rep.dt);
            for j in 1..=rep.rejected {
                rejected_dts.push(rep.dt / shrink.powi(j as i32));
            }
        }
        max_phi = now.engine.phi().iter().fold(max_phi, |m, p| m.max(p.abs()));
        area = area.max((now.record.area - a0).abs() / a0);
        Ok(Flow::Continue)
    });
    let class = match failure_cause(sim.run(&StopRules::of(s), &mut [&mut probe]))? {
        Some(cause) => classify(&[], Some(cause), &Criteria::default()),
        None => Class::Stable,
    };
    let rejected = sim.clock.rejected;
    accepted.sort_by(f64::total_cmp);
    Ok(Run {
        sweep: "adaptive",
        method: "SBDF1 adaptive",
        h,
        dt: accepted
            .get(accepted.len() / 2)
            .copied()
            .unwrap_or(f64::NAN),
        alpha: energy_alpha,
        class,
        steps: sim.clock.step,
        rejected,
        max_phi,
        area_error: area,
        rejected_dts,
    })
}

/// Largest stable Δt of each fixed method at each h: `(method, h, largest stable, first
/// failure and its class)`.
type Frontier = Vec<(&'static str, f64, Option<f64>, Option<(f64, Class)>)>;

fn frontier(runs: &[Run], hs: &[f64]) -> Frontier {
    let mut f = Vec::new();
    for name in METHODS.map(|m| m.name) {
        for &h in hs {
            let rs: Vec<&Run> = runs
                .iter()
                .filter(|r| r.sweep == "fixed" && r.method == name && r.h == h)
                .collect();
            let (largest, first_fail) = edge(rs.iter().map(|r| (r.dt, r.class)));
            f.push((name, h, largest, first_fail));
        }
    }
    f
}

/// Of runs `(Δt, class)` in increasing Δt: the last stable Δt below the first failure, and
/// the first failure with its class.
fn edge(runs: impl Iterator<Item = (f64, Class)>) -> (Option<f64>, Option<(f64, Class)>) {
    let mut largest = None;
    for (dt, class) in runs {
        if class != Class::Stable {
            return (largest, Some((dt, class)));
        }
        largest = Some(dt);
    }
    (largest, None)
}

fn largest(f: &Frontier, name: &str, h: f64) -> Option<f64> {
    f.iter().find(|x| x.0 == name && x.1 == h).and_then(|x| x.2)
}

fn table(runs: &[Run], f: &Frontier, bounds: &[(f64, f64)], spec: &Spec) -> String {
    let mut s = format!(
        "{} fixed steps per run, dt from {:.1e} to {:.1e} ({} per decade), from the prepared field\n\
         classes: stable (and energy-decreasing); energy rising (F_eff at the step's sigma rose > 1e-10 relative); \
         constraint lost (a V or A guard failed, or |A - A0|/A0 > 1e-3); blown up (diverged or max|phi| > 1.5)\n\n\
         {:<20} {:>7} {:>14} {:>26} {:>12}\n",
        spec.steps, spec.dt_min, spec.dt_max, spec.per_decade,
        "method", "h/eps", "largest stable", "first failure", "FD bound"
    );
    for x in f {
        let bound = bounds.iter().find(|b| b.0 == x.1).map_or(f64::NAN, |b| b.1);
        let _ = writeln!(
            s,
            "{:<20} {:>7.4} {:>14} {:>26} {:>12.4e}",
            x.0,
            x.1,
            x.2.map_or("none".into(), |d| format!("{d:.3e}")),
            x.3.map_or("none".into(), |(d, c)| format!("{d:.3e} ({})", c.as_str())),
            bound
        );
    }
    let _ = writeln!(s, "\nspectral / FD largest stable dt:");
    for name in METHODS.map(|m| m.name).into_iter().skip(1) {
        let mut hs = Vec::new();
        let mut ratios = Vec::new();
        for &h in &spec.h {
            if let (Some(a), Some(b)) = (largest(f, name, h), largest(f, "FD explicit Euler", h)) {
                hs.push(h);
                ratios.push(a / b);
            }
        }
        let list: Vec<String> = hs
            .iter()
            .zip(&ratios)
            .map(|(h, r)| format!("h = {h}: {r:.3e}"))
            .collect();
        let scaling =
            fit::power(&hs, &ratios).map_or(String::new(), |p| format!("; ratio ∝ h^p, {p}"));
        let _ = writeln!(s, "  {name:<18} {}{scaling}", list.join(", "));
    }
    for name in METHODS.map(|m| m.name) {
        let (hs, dts): (Vec<f64>, Vec<f64>) = spec
            .h
            .iter()
            .filter_map(|&h| largest(f, name, h).map(|d| (h, d)))
            .unzip();
        if let Some(p) = fit::power(&hs, &dts) {
            let _ = writeln!(s, "  largest stable dt of {name} ∝ h^p: {p}");
        }
    }
    let _ = writeln!(
        s,
        "\nadaptive SBDF1 to t = {} (dt_max {}):\n  {:>7} {:>12} {:>7} {:>9} {:>14} {:>16} {:>16}",
        spec.adaptive.t_end,
        spec.adaptive.dt_max,
        "h/eps",
        "energy_alpha",
        "steps",
        "rejected",
        "median dt",
        "median rejected",
        "class"
    );
    for r in runs.iter().filter(|r| r.sweep == "adaptive") {
        let mut rej = r.rejected_dts.clone();
        rej.sort_by(f64::total_cmp);
        let med = rej
            .get(rej.len() / 2)
            .map_or("-".into(), |d| format!("{d:.3e}"));
        let _ = writeln!(
            s,
            "  {:>7.4} {:>12.1e} {:>7} {:>9} {:>14.3e} {:>16} {:>16}",
            r.h,
            r.alpha,
            r.steps,
            r.rejected,
            r.dt,
            med,
            r.class.as_str()
        );
    }
    let _ = writeln!(
        s,
        "\nLagrangian area update (FD, h = {}): largest stable alpha against dt",
        spec.h[0]
    );
    for &frac in &spec.alpha.dt_fractions {
        let rs: Vec<&Run> = runs
            .iter()
            .filter(|r| r.sweep == "alpha" && (r.dt / bounds[0].1 - frac).abs() < 1e-9)
            .collect();
        let first = rs
            .iter()
            .position(|r| r.class != Class::Stable)
            .unwrap_or(rs.len());
        let best = first
            .checked_sub(1)
            .map_or("none".into(), |i| format!("{:.3e}", rs[i].alpha));
        let dt = frac * bounds[0].1;
        let _ = writeln!(
            s,
            "  dt = {dt:.3e} ({frac} of the bound): largest stable alpha {best}"
        );
    }
    s
}

/// A row of `frontier.csv`.
#[derive(Serialize)]
struct FrontierRow {
    method: &'static str,
    h_over_eps: f64,
    largest_stable_dt: f64,
    first_failure_dt: f64,
    first_failure_class: &'static str,
    fd_bound: f64,
}

fn frontier_rows(f: &Frontier, bounds: &[(f64, f64)]) -> Vec<FrontierRow> {
    f.iter()
        .map(|x| FrontierRow {
            method: x.0,
            h_over_eps: x.1,
            largest_stable_dt: x.2.unwrap_or(f64::NAN),
            first_failure_dt: x.3.map_or(f64::NAN, |p| p.0),
            first_failure_class: x.3.map_or("none", |p| p.1.as_str()),
            fd_bound: bounds.iter().find(|b| b.0 == x.1).map_or(f64::NAN, |b| b.1),
        })
        .collect()
}

/// Colour of a class on the map.
fn class_colour(c: Class) -> [u8; 3] {
    match c {
        Class::Stable => [44, 160, 44],
        Class::EnergyRising => [255, 165, 0],
        Class::ConstraintLost => [148, 103, 189],
        Class::BlownUp => [214, 39, 40],
    }
}

/// Colours of the measured frontiers: none of them a class's colour.
const FRONTIER: [[u8; 3]; 3] = [[31, 119, 180], [140, 86, 75], [23, 190, 207]];

fn charts(
    report: &mut Report,
    runs: &[Run],
    f: &Frontier,
    bounds: &[(f64, f64)],
    (dim, eps): (usize, f64),
) {
    let mut map = Figure::new(
        "Stability map: fixed dt against h (markers by method, colour by class)",
        Axis::log("h / eps (methods offset sideways)"),
        Axis::log("dt [time units]"),
    );
    map.legend = Corner::LowerRight;
    let offset = |i: usize| 1.12f64.powf(i as f64 - (METHODS.len() as f64 - 1.0) / 2.0);
    for (i, m) in METHODS.iter().enumerate() {
        for class in Class::ALL {
            let pts: Vec<(f64, f64)> = runs
                .iter()
                .filter(|r| r.sweep == "fixed" && r.method == m.name && r.class == class)
                .map(|r| (r.h * offset(i), r.dt))
                .collect();
            map.push(Series::new("", pts, class_colour(class), Mark::Points(m.shape)).unlisted());
        }
        map.push(Series::new(
            m.name,
            Vec::new(),
            [90, 90, 90],
            Mark::Points(m.shape),
        ));
    }
    for class in Class::ALL {
        map.push(Series::new(
            class.as_str(),
            Vec::new(),
            class_colour(class),
            Mark::Line,
        ));
    }
    let (lo, hi) = bounds.iter().fold((f64::INFINITY, 0.0f64), |(a, b), x| {
        (a.min(x.0), b.max(x.0))
    });
    let curve: Vec<(f64, f64)> = (0..=40)
        .map(|k| lo / 1.5 * (1.5 * 1.5 * hi / lo).powf(k as f64 / 40.0))
        .map(|h| (h, fd_bound(dim, h * eps, eps)))
        .collect();
    map.push(Series::new(
        "FD bound 1/(λ(2 + ε²λ)²), λ = 4d/h²",
        curve,
        [0, 0, 0],
        Mark::Dashed,
    ));
    for (i, name) in ["SBDF1, default S", "SBDF2, default S", "SBDF1, S = 0"]
        .into_iter()
        .enumerate()
    {
        let pts: Vec<(f64, f64)> = f
            .iter()
            .filter(|x| x.0 == name)
            .filter_map(|x| x.2.map(|d| (x.1, d)))
            .collect();
        map.push(Series::new(
            format!("measured frontier, {name}"),
            pts,
            FRONTIER[i],
            Mark::Line,
        ));
    }
    let rejected: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.sweep == "adaptive")
        .flat_map(|r| r.rejected_dts.iter().map(move |d| (r.h * 1.35, *d)))
        .collect();
    map.push(Series::new(
        "adaptive SBDF1: rejected attempts",
        rejected,
        [0, 0, 0],
        Mark::Points(Shape::Cross),
    ));
    report.chart("stability_map", map);

    let mut alpha = Figure::new(
        "Lagrangian area update (FD): stable alpha against dt",
        Axis::log("dt [time units]"),
        Axis::log("alpha"),
    );
    alpha.legend = Corner::LowerLeft;
    for class in Class::ALL {
        let pts: Vec<(f64, f64)> = runs
            .iter()
            .filter(|r| r.sweep == "alpha" && r.class == class)
            .map(|r| (r.dt, r.alpha))
            .collect();
        alpha.push(Series::new(
            class.as_str(),
            pts,
            class_colour(class),
            Mark::Points(Shape::Circle),
        ));
    }
    report.chart("stability_alpha", alpha);
}

/// The FD bound of docs/src/theory/fd.md at σ = 0: Δt = 1 / (λ (2 + ε²λ)²), λ = 4d/h² (the curve on
/// the map; [`fd::stability_bound`] gives the same at the computed grids).
fn fd_bound(dim: usize, h: f64, eps: f64) -> f64 {
    let l = 4.0 * dim as f64 / (h * h);
    1.0 / (l * (2.0 + eps * eps * l).powi(2))
}
