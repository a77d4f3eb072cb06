//! The stability study's measurement: the fixed-Δt sweeps of every method at every h, the
//! adaptive runs and the Lagrangian α sweep, each run classified ([`classify`]).

use super::spec::Spec;
use crate::commands::study::classify::{classify, Class, Criteria, StepSample};
use crate::commands::study::harness;
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::fd;
use crate::engines::{AreaConstraint, Cause};
use crate::error::{Error, Result};
use crate::output::chart::Shape;
use crate::problem::config::{
    AdaptiveSettings, AdaptiveSpec, AreaMethod, Laplacian, Method, Scene, Scheme, StabilizerSpec,
};
use crate::problem::setup::{self, Problem};

/// One classified run; a row of `stability.csv`.
#[derive(Clone, Debug)]
pub struct Run {
    /// `fixed`, `adaptive` or `alpha`.
    pub sweep: &'static str,
    /// Method name.
    pub method: &'static str,
    /// h/ε.
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
    pub max_phi: f64,
    /// Largest |A − A0|/A0 seen.
    pub area_error: f64,
    /// Δt of each rejected attempt (adaptive; in the table and the map, not the CSV).
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
    pub(super) fn apply(&self, s: &mut Scene) {
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
pub(super) fn sweep(lo: f64, hi: f64, per_decade: f64) -> Vec<f64> {
    let count = ((hi / lo).log10() * per_decade).round() as i32;
    (0..=count)
        .map(|i| lo * 10f64.powf(i as f64 / per_decade))
        .collect()
}

/// The FD bound at each h: `(h/ε, Δt bound)`.
pub type Bounds = Vec<(f64, f64)>;

/// Every run of the three sweeps, and the FD bound at each h.
///
/// # Errors
/// `Error::Config` naming the key of an empty or inverted sweep or of an invalid variant scene;
/// `Error::Blowup` if a preparation diverges.
pub fn sweeps(spec: &Spec, base: &Scene) -> Result<(Vec<Run>, Bounds)> {
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
pub(super) fn at_spacing(s: &mut Scene, base: &Scene, h: f64) {
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
pub(super) fn prepared(base: &Scene, h: f64) -> Result<Problem> {
    let prep = harness::variant(base, "scene", |s| {
        at_spacing(s, base, h);
        s.method = Method::Spectral;
        s.scheme = Scheme::Sbdf1;
        s.prepare_steps = base.prepare_steps;
        s.allow_unstable = false;
    })?;
    let mut problem = setup::build(&prep)?;
    problem.phi = crate::commands::study::prepared_field(&prep, &problem)?;
    Ok(problem)
}

/// The fixed-Δt sweep of `spec` (`steps` steps at each Δt, from `problem.phi`) of the scene
/// `edit` makes from `base`, classified by the default criteria: `(Δt, run)` in increasing Δt,
/// stopped after three failures (blown up or constraint lost) in a row, as larger steps fail
/// too.
pub(super) fn dt_sweep(
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
pub(super) type Outcome = (Class, usize, f64, f64);

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
                sigma: 0.0,
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
pub(super) fn failure_cause<T>(ran: Result<T>) -> Result<Option<Cause>> {
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
