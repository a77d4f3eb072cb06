//! `vesicle study onset FILE`: where the prolate leaves up–down symmetry as c̄0 grows (the
//! onset of budding), converged in ε/R0 and set beside the sharp instability.
//!
//! Two methods. `"method": "hessian"` follows the lowest up–down odd eigenvalue of the
//! symmetric state's second variation to its zero, with no seed ([`hessian`]). The default,
//! `"seeded"`, described below, relaxes seeded states and classifies them by their skewness.
//!
//! For each `R0` of the file (in ε) and each seed strength δ of `seeds`, the start is the
//! axisymmetric prolate of the reference solver at `v` and `c0[0]`, scaled to `R0` on a box
//! mirrored across x and y only (a pear breaks the up–down mirror), sized by the heating
//! study's [`box_size`](super::heating::spec::box_size). Then:
//!
//! 1. **The coarse path.** For each c̄0 of `c0` in turn, from the previous state: the up–down
//!    stretch of strength δ is seeded ([`super::budding::seed`]), c0 = c̄0/R0 set, and the field
//!    relaxed by L-BFGS to the scene's `stop_residual` (area held at the first step's A0, the
//!    volume conserved). A state is symmetric when the skewness of its volume along z is below
//!    [`budding::SYMMETRIC_SKEWNESS`] ([`budding::state`]). The path stops at the first state that is
//!    not.
//! 2. **Bisection.** The bracket (last symmetric c̄0, first asymmetric c̄0) is halved
//!    `bisections` times, each midpoint relaxed from the last symmetric state after the same
//!    seed. The onset is the final bracket's midpoint, its half-width the error of the
//!    bracketing (the stop residual's is not in it: see the docs of the science page).
//! 3. **The sharp instability** at the φ = 0 reduced volume of the last symmetric state: the
//!    zero in c̄0 of the prolate's up–down test function
//!    ([`axisym::prolate_updown_zero`]). The shift onset − sharp is extrapolated in ε/R0
//!    ([`report`]).
//!
//! A seed that is too weak to leave a barely unstable prolate within the stop residual would
//! move the onset up; two seeds per R0 show whether it does. The path has no time (L-BFGS): it
//! is a sequence of stationary states, not a transient.
//!
//! Writes `onset_steps.csv` (every relaxation), `onset.csv` (one row per R0 and seed),
//! `onset.txt`, and the charts `onset_skewness` (|skewness| against c̄0, every run) and
//! `onset_eps` (the onset against ε/R0 beside the sharp instability).
//!
//! **The bilayer couple.** With a path in `da` instead of `c0` ([`Parameter::Couple`], the
//! Hessian method only) the states hold Δa = M/M₁ at c0 = 0, the second variation carries the
//! couple's multiplier, and the sharp instability is the sharp BC prolate's loss of up–down
//! stability at the run's v ([`axisym::bc_bifurcation`]: its Δa and c̄0,eff). Each state also
//! reports its c̄0,eff and the φ = 0 surface's Δa, so that the onset is compared in the held Δa,
//! in the surface's Δa and in c̄0,eff.

pub mod hessian;
pub mod report;
pub mod spec;

use super::budding::{self, check_fits, relax_seeded, revolved, within};
use super::harness::{Report, Study};
use crate::analysis::axisym::{self, Branch, Options};
use crate::error::{Error, Result};
use crate::problem::config::{C0Spec, Scene};
use crate::problem::grid::Grid;
use crate::problem::setup::{self, Problem};
use hessian::EigenRun;
pub use hessian::Sample;
use ndarray::Array3;
use rayon::prelude::*;
use spec::{base_scene, check};
pub use spec::{Method, Parameter, Spec};
use std::path::Path;
use std::time::Instant;

/// What every relaxed state of the study reports, seeded (`Step`) or symmetric (`Sample`): the
/// columns the two tables share.
#[derive(Clone, Debug)]
pub struct Relaxation {
    /// `path` (the coarse path), `bisection` (seeded) or `refine` (hessian).
    pub stage: &'static str,
    /// c̄0 = c0 R0, or the couple's state's effective c̄0,eff = −λR0/(√2ε) (its multiplier λ
    /// read as a uniform spontaneous curvature).
    pub c0: f64,
    /// Δa held by the bilayer couple (NaN for spontaneous curvature).
    pub da: f64,
    /// Δa of the φ = 0 surface.
    pub da_surface: f64,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// How the relaxation ended (`stationary` when `stop_residual` was met).
    pub stopped: String,
    /// Final stationarity residual.
    pub residual: f64,
    /// Reduced bending energy e.
    pub e: f64,
    /// Reduced volume of the φ = 0 surface.
    pub v: f64,
}

impl Relaxation {
    /// The path's value at this state: c̄0, or the couple's Δa.
    pub fn value(&self, parameter: Parameter) -> f64 {
        match parameter {
            Parameter::C0 => self.c0,
            Parameter::Couple => self.da,
        }
    }

    /// The relaxation `relaxed` at the value `value` of the path's `parameter`, in `stage`.
    fn of(
        stage: &'static str,
        (parameter, value): (Parameter, f64),
        relaxed: &budding::Relaxed,
    ) -> Self {
        let rec = &relaxed.record;
        let (c0, da) = match parameter {
            Parameter::C0 => (value, f64::NAN),
            Parameter::Couple => (rec.couple.as_ref().map_or(f64::NAN, |c| c.c0_eff), value),
        };
        Relaxation {
            stage,
            c0,
            da,
            da_surface: relaxed.measure.surface_da,
            iterations: rec.step,
            stopped: relaxed.stopped.to_string(),
            residual: rec.residual,
            e: rec.reduced_energy,
            v: relaxed.measure.surface.reduced_volume,
        }
    }
}

/// One seeded relaxation; a row of `onset_steps.csv`.
#[derive(Clone, Debug)]
pub struct Step {
    /// R0/ε of the run.
    pub r0: f64,
    /// Seed strength δ.
    pub seed: f64,
    /// The relaxation.
    pub relaxation: Relaxation,
    /// Skewness of the volume along z.
    pub skewness: f64,
    /// Neck radius in ε (NaN: none).
    pub neck: f64,
    /// Connected pieces of {φ > 0}.
    pub pieces: usize,
    /// `symmetric`, `pear`, `necked` or `pieces` ([`budding::state`]).
    pub state: String,
    /// Wall seconds of the relaxation and measurement.
    pub wall_seconds: f64,
}

impl Step {
    /// Whether the state kept its up–down symmetry.
    pub fn symmetric(&self) -> bool {
        self.state == "symmetric"
    }
}

/// The onset of one run; a row of `onset.csv`. Its values are the path's ([`Parameter`]).
#[derive(Clone, Debug)]
pub struct Onset {
    /// R0/ε.
    pub r0: f64,
    /// Seed strength δ.
    pub seed: f64,
    /// Last value whose state stayed symmetric.
    pub below: f64,
    /// First value whose state left symmetry (NaN: none on the path).
    pub above: f64,
    /// The onset, the bracket's midpoint (NaN without a bracket).
    pub onset: f64,
    /// φ = 0 reduced volume of the last symmetric state.
    pub v: f64,
    /// c̄0 at the onset: the onset itself for spontaneous curvature, the state's c̄0,eff for the
    /// bilayer couple (interpolated like `v`; NaN for seeded runs).
    pub c0: f64,
    /// Δa of the φ = 0 surface at the onset (interpolated like `v`; NaN for seeded runs).
    pub da_surface: f64,
    /// The sharp prolate's loss of up–down stability at `v`, in the path's parameter (NaN: not
    /// in the bracket searched).
    pub sharp: f64,
    /// onset − sharp.
    pub shift: f64,
    /// The same instability in c̄0: c̄0*(v) for spontaneous curvature (`sharp` itself), the
    /// sharp BC bifurcation's c̄0,eff for the couple.
    pub sharp_c0: f64,
    /// `c0` − `sharp_c0`: the shift in c̄0 (c̄0,eff for the couple).
    pub shift_c0: f64,
    /// Relaxations of the run.
    pub relaxations: usize,
    /// Wall seconds of the run.
    pub wall_seconds: f64,
}

/// What the study returns.
pub struct Output {
    /// Every relaxation, run by run, in the order computed (`seeded`).
    pub steps: Vec<Step>,
    /// Every symmetric state and its eigenvalue, run by run (`hessian`).
    pub samples: Vec<Sample>,
    /// One onset per R0 and seed.
    pub onsets: Vec<Onset>,
}

/// The study.
pub struct OnsetStudy;

impl Study for OnsetStudy {
    const NAME: &'static str = "onset";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Output, Report)> {
        check(spec)?;
        let parameter = spec.parameter();
        let first = spec.path()[0];
        let start = match parameter {
            Parameter::C0 => {
                axisym::solve(Branch::Prolate, spec.v, &Options::default().with_c0(first))
            }
            Parameter::Couple => {
                axisym::bc_solution(Branch::Prolate, spec.v, first, &Options::default())
            }
        }
        .map_err(|e| Error::config(parameter.key(), format!("the start prolate: {e}")))?;
        let mut steps = Vec::new();
        let mut samples = Vec::new();
        let mut onsets = Vec::new();
        for &r0 in &spec.r0 {
            let scene = base_scene(spec, r0, &start.r, &start.z)?;
            if spec.method == Method::Hessian {
                let run = EigenRun { base: &scene, r0 };
                let (path, onset) = run.onset(spec, (&start.r, &start.z))?;
                eprintln!(
                    "R0 = {r0} eps: lowest odd eigenvalue crosses 0 at {} = {:.4} (v = {:.4}; \
                     {} states, {:.0} s)",
                    parameter.label(),
                    onset.onset,
                    onset.v,
                    onset.relaxations,
                    onset.wall_seconds
                );
                samples.extend(path);
                onsets.push(onset);
                continue;
            }
            for &delta in &spec.seeds {
                let began = Instant::now();
                let run = Run {
                    base: &scene,
                    r0,
                    seed: delta,
                };
                let (path, onset) = run.bracket(spec, (&start.r, &start.z))?;
                let mut onset = onset;
                onset.wall_seconds = began.elapsed().as_secs_f64();
                eprintln!(
                    "R0 = {r0} eps, seed {delta}: onset between c0 R0 = {} and {} ({} \
                     relaxations, {:.0} s)",
                    onset.below, onset.above, onset.relaxations, onset.wall_seconds
                );
                steps.extend(path);
                onsets.push(onset);
            }
        }
        onsets.par_iter_mut().for_each(|o| {
            (o.sharp, o.sharp_c0) = match parameter {
                Parameter::C0 => {
                    let c0 = sharp_onset(o.v, first).unwrap_or(f64::NAN);
                    (c0, c0)
                }
                Parameter::Couple => axisym::bc_bifurcation(o.v, &Options::default())
                    .map_or((f64::NAN, f64::NAN), |b| (b.da(), b.c0_eff)),
            };
            o.shift = o.onset - o.sharp;
            o.shift_c0 = o.c0 - o.sharp_c0;
        });
        let report = match spec.method {
            Method::Hessian => report::eigen_report(spec, &samples, &onsets)?,
            Method::Seeded => report::report(spec, &steps, &onsets)?,
        };
        Ok((
            Output {
                steps,
                samples,
                onsets,
            },
            report,
        ))
    }
}

/// The sharp prolate's loss of up–down stability at reduced volume `v`: the first zero of its
/// test function above `from` (where it must be stable), bracketed in steps of
/// [`SHARP_STEP`] up to [`SHARP_MAX`], then located by [`axisym::prolate_updown_zero`].
/// `None` if the prolate is unstable at `from` or stable up to [`SHARP_MAX`].
pub fn sharp_onset(v: f64, from: f64) -> Option<f64> {
    let opts = Options::default();
    let mu = |c0: f64| axisym::prolate_updown(v, &opts.with_c0(c0));
    if mu(from)? <= 0.0 {
        return None;
    }
    let mut lo = from;
    while lo < SHARP_MAX {
        let hi = lo + SHARP_STEP;
        if mu(hi)? < 0.0 {
            return axisym::prolate_updown_zero(v, (lo, hi), &opts);
        }
        lo = hi;
    }
    None
}

/// Step in c̄0 of the search for the sharp instability's bracket.
pub const SHARP_STEP: f64 = 0.25;

/// Largest c̄0 searched for the sharp instability.
pub const SHARP_MAX: f64 = 6.0;

/// One run: a lattice (`base`, sized for `r0`) and a seed strength.
struct Run<'a> {
    base: &'a Scene,
    r0: f64,
    seed: f64,
}

impl Run<'_> {
    /// The coarse path from the revolved start contour `(r, z)` up to the first asymmetric
    /// state, then the bisections: every relaxation and the onset (its sharp columns NaN).
    fn bracket(&self, spec: &Spec, (r, z): (&[f64], &[f64])) -> Result<(Vec<Step>, Onset)> {
        let mut problem = setup::build(self.base).map_err(within("scene"))?;
        let full_grid = Grid::new(&self.base.n, self.base.h, &[false; 3]);
        let start = revolved(r, z, self.r0 * self.base.eps, self.base.eps, &full_grid);
        check_fits(&start)?;
        problem.phi = problem.grid.restrict(&start);
        let mut steps: Vec<Step> = Vec::new();
        let mut area = None;
        let mut symmetric: Option<(f64, Array3<f64>, f64)> = None;
        let mut above = f64::NAN;
        for &c0 in &spec.c0 {
            let step = self.relax(&mut problem, c0, "path", &mut area)?;
            let keep = step.symmetric();
            if keep {
                symmetric = Some((c0, problem.phi.clone(), step.relaxation.v));
            }
            steps.push(step);
            if !keep {
                above = c0;
                break;
            }
        }
        let Some((mut below, mut phi_below, mut v_below)) = symmetric else {
            return Err(Error::config(
                "c0",
                format!(
                    "the first state (c0 R0 = {}, R0 = {} eps, seed {}) is not up-down \
                     symmetric: start the path lower",
                    spec.c0[0], self.r0, self.seed
                ),
            ));
        };
        if above.is_finite() {
            for _ in 0..spec.bisections {
                // Rounded to 1e-9 so that the printed and written midpoints read as decimals.
                let mid = (0.5 * (below + above) * 1e9).round() / 1e9;
                problem.phi.assign(&phi_below);
                let step = self.relax(&mut problem, mid, "bisection", &mut area)?;
                if step.symmetric() {
                    (below, v_below) = (mid, step.relaxation.v);
                    phi_below = problem.phi.clone();
                } else {
                    above = mid;
                }
                steps.push(step);
            }
        }
        let onset = Onset {
            r0: self.r0,
            seed: self.seed,
            below,
            above,
            onset: 0.5 * (below + above),
            v: v_below,
            c0: f64::NAN,
            da_surface: f64::NAN,
            sharp: f64::NAN,
            shift: f64::NAN,
            sharp_c0: f64::NAN,
            shift_c0: f64::NAN,
            relaxations: steps.len(),
            wall_seconds: 0.0,
        };
        Ok((steps, onset))
    }

    /// Seed the state of `problem`, set c̄0 = `c0` and relax it by L-BFGS
    /// ([`budding::relax_seeded`]: the first relaxation of a run prepares the field and fixes
    /// the area target `area`); the state is left in `problem.phi`.
    fn relax(
        &self,
        problem: &mut Problem,
        c0: f64,
        stage: &'static str,
        area: &mut Option<f64>,
    ) -> Result<Step> {
        let began = Instant::now();
        let eps = self.base.eps;
        let mut scene = self.base.clone();
        scene.c0 = C0Spec::Uniform(c0 / (self.r0 * eps));
        let relaxed = relax_seeded(problem, scene, (self.r0 * eps, self.seed), area)?;
        let m = &relaxed.measure;
        let step = Step {
            r0: self.r0,
            seed: self.seed,
            relaxation: Relaxation::of(stage, (Parameter::C0, c0), &relaxed),
            skewness: m.skewness,
            neck: m.neck.map_or(f64::NAN, |(r, _)| r / eps),
            pieces: m.pieces,
            state: budding::state(m).to_string(),
            wall_seconds: began.elapsed().as_secs_f64(),
        };
        eprintln!(
            "R0 = {} eps, seed {}, c0 R0 = {c0} ({stage}): {} after {} iterations, skewness \
             {:.4}, {}",
            self.r0,
            self.seed,
            step.relaxation.stopped,
            step.relaxation.iterations,
            step.skewness,
            step.state
        );
        Ok(step)
    }
}

#[cfg(test)]
mod tests;
