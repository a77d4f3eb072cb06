//! The onset without a seed (`"method": "hessian"`): the lowest eigenvalue of the symmetric
//! state's second variation on up–down odd perturbations, followed in c̄0 (or in Δa of the
//! bilayer couple) to its zero.
//!
//! For each value of the path in turn, from the previous state: c0 = c̄0/R0 (or the couple's
//! Δa) is set and the field relaxed by L-BFGS on the box mirrored across x, y *and z* (area
//! held at the first step's A0, volume conserved), so that the state is the up–down symmetric
//! stationary state whether or not it is stable. Its unfolded field is restricted to the box
//! mirrored across x and y only, where up–down odd fields live, and [`OddHessian::lowest`]
//! gives λ, the lowest eigenvalue of the constrained second variation on them, translation
//! removed. λ > 0: the symmetric state is stable against every up–down odd perturbation the box
//! holds; λ < 0: it is not. The path stops at the first λ < 0; the zero is then refined by
//! regula falsi on λ along the path (`bisections` more states, each relaxed from the nearest
//! symmetric state below), and the
//! onset is the last linear root. No seed, no skewness threshold and no early stop of a
//! departing state enter it. With the couple the second variation also carries the state's
//! multiplier of M = Δa M₁ ([`OddHessian`]).

use super::budding::{relax_seeded, within};
use super::{Onset, Relaxation, Spec};
use crate::engines::stability::OddHessian;
use crate::engines::Diverged;
use crate::error::{Error, Result};
use crate::problem::area_difference::AreaDifference;
use crate::problem::config::{Scene, Symmetry};
use crate::problem::grid::Grid;
use crate::problem::model::C0;
use crate::problem::setup::{self, Problem};
use ndarray::Array3;
use num_complex::Complex64;
use std::time::Instant;

/// One symmetric state and its lowest odd eigenvalue; a row of `onset_eigen.csv`.
#[derive(Clone, Debug)]
pub struct Sample {
    /// R0/ε.
    pub r0: f64,
    /// The relaxation of the symmetric state (stage `path` or `refine`).
    pub relaxation: Relaxation,
    /// The area multiplier σ* of the state.
    pub sigma: f64,
    /// λ, the lowest eigenvalue of M⁻¹H on up–down odd fields, translation removed.
    pub eigenvalue: f64,
    /// ‖Bx − θx‖_M of its eigenvector.
    pub eigen_residual: f64,
    /// Products with the second variation taken.
    pub products: usize,
    /// ⟨t, Bt⟩_M of the unit translation along z (the lattice's pinning; 0 in the continuum).
    pub translation: f64,
    /// Wall seconds of the relaxation and the eigenvalue.
    pub wall_seconds: f64,
}

/// One R0 of the Hessian method: the sized scene `base` (mirror planes x and y).
pub struct EigenRun<'a> {
    /// The scene of this R0.
    pub base: &'a Scene,
    /// R0/ε.
    pub r0: f64,
}

/// What the eigenvalue solver keeps from state to state.
struct Path {
    /// The problem on the box mirrored across x, y and z.
    problem: Problem,
    /// The area held (the first relaxation's A0).
    area: Option<f64>,
    /// The last eigenvector (the next solve's start).
    vector: Option<Array3<Complex64>>,
    /// The states computed, as (the path's value, field on the reduced box) for warm starts.
    states: Vec<(f64, Array3<f64>)>,
}

impl EigenRun<'_> {
    /// The path, the refinement and the onset (its sharp columns NaN) from the revolved start
    /// contour `(r, z)`.
    ///
    /// # Errors
    /// `Error::Config` for a start that does not fit, an unstable first state or a box that
    /// cannot hold the odd fields; `Error::Blowup` if a relaxation diverges; `Error::Study` if a
    /// second variation cannot be formed.
    pub fn onset(&self, spec: &Spec, (r, z): (&[f64], &[f64])) -> Result<(Vec<Sample>, Onset)> {
        let began = Instant::now();
        let mut scene = self.base.clone();
        scene.symmetry = Symmetry::Axes(vec!["x".into(), "y".into(), "z".into()]);
        let mut problem = setup::build(&scene).map_err(within("scene"))?;
        let full_grid = Grid::new(&scene.n, scene.h, &[false; 3]);
        let start = super::budding::revolved(r, z, self.r0 * scene.eps, scene.eps, &full_grid);
        super::budding::check_fits(&start)?;
        problem.phi = problem.grid.restrict(&start);
        let mut path = Path {
            problem,
            area: None,
            vector: None,
            states: Vec::new(),
        };
        let mut samples: Vec<Sample> = Vec::new();
        let parameter = spec.parameter();
        for &value in spec.path() {
            let s = self.sample(&scene, &mut path, value, "path", spec)?;
            let unstable = s.eigenvalue < 0.0;
            samples.push(s);
            if unstable {
                break;
            }
        }
        if samples[0].eigenvalue < 0.0 {
            return Err(Error::config(
                parameter.key(),
                format!(
                    "the first symmetric state ({} = {}, R0 = {} eps) is already unstable \
                     to up-down odd perturbations (lowest eigenvalue {:.3e}): start the path \
                     lower",
                    parameter.label(),
                    spec.path()[0],
                    self.r0,
                    samples[0].eigenvalue
                ),
            ));
        }
        let n = samples.len();
        let mut bracket = (samples[n - 1].clone(), samples[n - 1].clone());
        if samples[n - 1].eigenvalue < 0.0 {
            bracket.0 = samples[n - 2].clone();
            for _ in 0..spec.bisections {
                let value = linear_root(&bracket.0, &bracket.1, |s| s.relaxation.value(parameter));
                let value = (value * 1e9).round() / 1e9;
                path.warm_start_below(value);
                let s = self.sample(&scene, &mut path, value, "refine", spec)?;
                if s.eigenvalue < 0.0 {
                    bracket.1 = s.clone();
                } else {
                    bracket.0 = s.clone();
                }
                samples.push(s);
            }
        }
        let (lo, hi) = &bracket;
        let crossed = hi.eigenvalue < 0.0;
        let at_root = |of: &dyn Fn(&Sample) -> f64| {
            if crossed {
                linear_root(lo, hi, of)
            } else {
                of(lo)
            }
        };
        let result = Onset {
            r0: self.r0,
            seed: 0.0,
            below: lo.relaxation.value(parameter),
            above: if crossed {
                hi.relaxation.value(parameter)
            } else {
                f64::NAN
            },
            onset: if crossed {
                at_root(&|s| s.relaxation.value(parameter))
            } else {
                f64::NAN
            },
            v: at_root(&|s| s.relaxation.v),
            c0: at_root(&|s| s.relaxation.c0),
            da_surface: at_root(&|s| s.relaxation.da_surface),
            sharp: f64::NAN,
            shift: f64::NAN,
            sharp_c0: f64::NAN,
            shift_c0: f64::NAN,
            relaxations: samples.len(),
            wall_seconds: began.elapsed().as_secs_f64(),
        };
        Ok((samples, result))
    }

    /// Relax the symmetric state at the path's value `value` from `path`'s current field and
    /// find its lowest odd eigenvalue (from the last eigenvector).
    fn sample(
        &self,
        scene: &Scene,
        path: &mut Path,
        value: f64,
        stage: &'static str,
        spec: &Spec,
    ) -> Result<Sample> {
        let began = Instant::now();
        let eps = scene.eps;
        let parameter = spec.parameter();
        let mut at = scene.clone();
        parameter.set(&mut at, value, self.r0 * eps);
        let relaxed = relax_seeded(
            &mut path.problem,
            at.clone(),
            (self.r0 * eps, 0.0),
            &mut path.area,
        )?;
        path.states.push((value, path.problem.phi.clone()));
        let odd_box = Grid::new(&scene.n, scene.h, &[true, true, false]);
        let phi = odd_box.restrict(&relaxed.full);
        let c0_field = C0::new(&at.c0, &odd_box, eps)?;
        let area_difference = path.area.and_then(|a0| AreaDifference::of(&at, a0));
        let failed = |d: Diverged| {
            Error::Study(format!(
                "the second variation at {} = {value}: {}",
                parameter.label(),
                d.0
            ))
        };
        let mut hessian = OddHessian::new(
            odd_box,
            (eps, c0_field, scene.laplacian),
            area_difference,
            &phi,
            scene.threads(),
        )
        .map_err(failed)?;
        let translation = hessian.translation_stiffness().map_err(failed)?;
        let lowest = hessian
            .lowest(
                path.vector.as_ref(),
                spec.eigen_tolerance,
                spec.eigen_products,
            )
            .map_err(failed)?;
        let sample = Sample {
            r0: self.r0,
            relaxation: Relaxation::of(stage, (parameter, value), &relaxed),
            sigma: hessian.sigma(),
            eigenvalue: lowest.value,
            eigen_residual: lowest.residual,
            products: lowest.products,
            translation,
            wall_seconds: began.elapsed().as_secs_f64(),
        };
        path.vector = Some(lowest.vector);
        eprintln!(
            "R0 = {} eps, {} = {value} ({stage}): {} after {} iterations, lowest odd eigenvalue \
             {:.4e} (residual {:.1e}, {} products), translation {:.1e}",
            self.r0,
            parameter.label(),
            sample.relaxation.stopped,
            sample.relaxation.iterations,
            sample.eigenvalue,
            sample.eigen_residual,
            sample.products,
            sample.translation
        );
        Ok(sample)
    }
}

impl Path {
    /// Start the next relaxation from the computed state of largest value below `value` (the
    /// path rises, so that is the nearest from below).
    fn warm_start_below(&mut self, value: f64) {
        if let Some((_, phi)) = self
            .states
            .iter()
            .filter(|(c, _)| *c < value)
            .max_by(|a, b| a.0.total_cmp(&b.0))
        {
            self.problem.phi.assign(phi);
        }
    }
}

/// The root of the line through (the path's value, λ) of `lo` and `hi`, read in `of` (the
/// value, or another column interpolated to the root).
fn linear_root(lo: &Sample, hi: &Sample, of: impl Fn(&Sample) -> f64) -> f64 {
    let t = lo.eigenvalue / (lo.eigenvalue - hi.eigenvalue);
    of(lo) + t * (of(hi) - of(lo))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::axisym::{self, Branch, Options};
    use crate::commands::study::onset::spec::base_scene;
    use crate::problem::config::C0Spec;

    /// The sign of the lowest odd eigenvalue is the symmetric state's stability. The symmetric
    /// prolate (v = 0.8, R0 = 20ε, h = ε, relaxed to 1e-6) displaced along its lowest odd
    /// eigenvector by 0.02 at most and relaxed on the box mirrored across x and y only: at
    /// c̄0 = 3 (λ < 0, measured −7.6e-6) it leaves the symmetric state (|skewness| above the
    /// budding study's threshold 0.01; measured 0.062, a pear), at c̄0 = 2 (λ = +1.7e-5) it comes
    /// back (|skewness| below 1e-3; measured 3.5e-5).
    #[test]
    fn a_negative_eigenvalue_is_a_state_that_departs() {
        let spec: Spec = serde_json::from_value(serde_json::json!({
            "study": "onset", "method": "hessian",
            "scene": {"dim": 3, "h": 1.0, "eps": 1.0, "dt": 0.01, "stop_residual": 1e-6,
                      "max_steps": 4000, "prepare_steps": 20, "threads": 1},
            "v": 0.8, "r0": [20.0], "c0": [2.0, 3.0], "bisections": 0
        }))
        .expect("a spec");
        let start = axisym::solve(Branch::Prolate, spec.v, &Options::default().with_c0(2.0))
            .expect("the start prolate");
        let base = base_scene(&spec, 20.0, &start.r, &start.z).expect("a scene");
        for (c0, departs) in [(2.0, false), (3.0, true)] {
            let mut scene = base.clone();
            scene.symmetry = Symmetry::Axes(vec!["x".into(), "y".into(), "z".into()]);
            scene.c0 = C0Spec::Uniform(c0 / 20.0);
            let mut problem = setup::build(&scene).expect("a problem");
            let full = Grid::new(&scene.n, scene.h, &[false; 3]);
            let prolate = super::super::budding::revolved(&start.r, &start.z, 20.0, 1.0, &full);
            problem.phi = problem.grid.restrict(&prolate);
            let mut area = None;
            let symmetric =
                relax_seeded(&mut problem, scene.clone(), (20.0, 0.0), &mut area).expect("relaxed");
            let odd_box = Grid::new(&scene.n, scene.h, &[true, true, false]);
            let phi = odd_box.restrict(&symmetric.full);
            let c = C0::new(&scene.c0, &odd_box, 1.0).expect("c0");
            let mut hessian =
                OddHessian::new(odd_box.clone(), (1.0, c, scene.laplacian), None, &phi, 1)
                    .expect("H");
            let lowest = hessian.lowest(None, 1e-9, 2000).expect("an eigenvalue");
            assert_eq!(
                lowest.value < 0.0,
                departs,
                "c0 R0 = {c0}: {}",
                lowest.value
            );
            let x = hessian.field(&lowest.vector);
            let top = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let mut displaced = scene.clone();
            displaced.symmetry = Symmetry::Axes(vec!["x".into(), "y".into()]);
            let mut problem = setup::build(&displaced).expect("a problem");
            problem.phi = &phi + &(x * (0.02 / top));
            let relaxed =
                relax_seeded(&mut problem, displaced, (20.0, 0.0), &mut area).expect("relaxed");
            let skew = relaxed.measure.skewness.abs();
            if departs {
                assert!(skew > 0.01, "c0 R0 = {c0}: skewness {skew}");
            } else {
                assert!(skew < 1e-3, "c0 R0 = {c0}: skewness {skew}");
            }
        }
    }
}
