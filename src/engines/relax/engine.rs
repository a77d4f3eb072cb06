//! The relaxational route as an [`Engine`]: a step is one L-BFGS iteration; saving and
//! restoring the state and the memory.

use super::couple::Couple;
use super::lbfgs::{Pair, ARMIJO, MAX_BACKTRACKS, MAX_MEMORY};
use super::RelaxEngine;
use crate::engines::spectral::saved;
use crate::engines::{AreaConstraint, Engine, Saved, SavedArray, StepError, StepReport};
use crate::problem::area_difference::{AreaDifference, Law};
use crate::problem::model::Measures;
use ndarray::Array3;

impl Engine for RelaxEngine {
    fn phi(&self) -> &Array3<f64> {
        &self.cur.phi
    }

    fn sigma(&self) -> f64 {
        self.sigma
    }

    fn measures(&self) -> Measures {
        self.cur.measures
    }

    /// The residual of the current state; infinite while it is off a constraint (a start that
    /// the first iteration retracts is not stationary, whatever its gradient).
    fn residual(&self) -> f64 {
        match self.off_constraints() {
            (false, false) => self.residual,
            _ => f64::INFINITY,
        }
    }

    fn set_area(&mut self, area: AreaConstraint) {
        self.area = area;
        self.reset_memory();
        self.refresh_gradient();
    }

    /// One L-BFGS iteration (its line search may take several evaluations).
    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, StepError> {
        self.retract_start(t + dt)?;
        let mut d = self.recursion(self.pairs.len());
        self.write_direction(&mut d);
        if d.slope >= 0.0 {
            self.reset_memory();
            d = self.recursion(0);
            self.write_direction(&mut d);
        }
        self.direction = d;
        let f0 = self.objective(&self.cur.measures);
        let mut alpha = 1.0;
        let mut rejected = 0;
        std::mem::swap(&mut self.cur.nonlinear, &mut self.trial.nonlinear);
        loop {
            let accepted = self.try_step(alpha, t + dt).is_ok()
                && self.objective(&self.trial.measures)
                    <= f0 + ARMIJO * alpha * self.direction.slope;
            if accepted {
                break;
            }
            rejected += 1;
            alpha *= 0.5;
            if rejected >= MAX_BACKTRACKS {
                self.stalled = true;
                self.reset_memory();
                self.take_back_gradient(t)?;
                return Ok(StepReport {
                    dt,
                    rate: f64::NAN,
                    rejected,
                });
            }
        }
        self.accept();
        // `t` is nominal here, so max|Δφ|/Δt would mean nothing: the rate column is NaN.
        Ok(StepReport {
            dt,
            rate: f64::NAN,
            rejected,
        })
    }

    fn set_area_difference(&mut self, term: AreaDifference) -> Result<(), String> {
        self.ev.area_difference = Some(term);
        // ADE: ĝ of the current state gains λ m̂ (the state's measures and sums are its own).
        // The bilayer couple: a second constraint, its λ from the Gram system.
        self.ev
            .evaluate(&mut self.cur, 0.0, None, None)
            .map_err(|d| d.0)?;
        self.couple = match term.law {
            Law::Couple { .. } => Some(Couple::new(term.target())),
            Law::Elastic { .. } => None,
        };
        self.reset_memory();
        self.refresh_gradient();
        Ok(())
    }

    fn area_difference(&self) -> Option<AreaDifference> {
        self.ev.area_difference
    }

    fn lambda(&self) -> f64 {
        match (self.couple, self.ev.area_difference) {
            (Some(c), _) => c.lambda,
            (None, Some(t)) => t.multiplier(self.cur.measures.curvature),
            (None, None) => 0.0,
        }
    }

    fn stalled(&self) -> bool {
        self.stalled
    }

    fn name(&self) -> &'static str {
        "relaxational (L-BFGS)"
    }

    fn save(&self) -> Saved<'_> {
        let mut saved = Saved::default()
            .scalar("stalled", if self.stalled { 1.0 } else { 0.0 })
            .scalar("pairs", self.pairs.len() as f64)
            .array("phi_hat", SavedArray::Complex(self.cur.hat.view().into()));
        let (n0, n1, n2) = self.cur.hat.dim();
        let shape = [n0, n1, n2];
        // The Gram entries as they were accumulated, so that a resumed run is bitwise the
        // uninterrupted one (the inner products of the state are recomputed by the same sweep).
        let n = self.pairs.len();
        let gram = Array3::from_shape_fn((2, n, n), |(g, i, j)| {
            [&self.sy, &self.yy][g][i * MAX_MEMORY + j]
        });
        saved = saved.array("gram", SavedArray::Real(gram.into()));
        for (i, p) in self.pairs.iter().enumerate() {
            saved = saved
                .array(&format!("s_{i}"), SavedArray::Single(shape, p.s[..].into()))
                .array(&format!("y_{i}"), SavedArray::Single(shape, p.y[..].into()));
        }
        saved
    }

    fn restore(&mut self, saved: &mut Saved<'_>, t: f64) -> Result<(), String> {
        let transform = &self.ev.transform;
        self.cur
            .hat
            .assign(&saved::spectrum(saved, "phi_hat", transform)?);
        self.stalled = saved.get("stalled")? != 0.0;
        let n = saved.get("pairs")?;
        if !(0.0..=self.memory as f64).contains(&n) || n.fract() != 0.0 {
            return Err(format!(
                "the saved L-BFGS memory holds {n} pairs; lbfgs_memory is {}",
                self.memory
            ));
        }
        self.reset_memory();
        for i in 0..n as usize {
            let transform = &self.ev.transform;
            let pair = Pair {
                s: saved::take_single(saved, &format!("s_{i}"), transform)?,
                y: saved::take_single(saved, &format!("y_{i}"), transform)?,
            };
            self.pairs.push_back(pair);
        }
        let n = n as usize;
        // An older checkpoint may lack the Gram, or hold it with the newest pair's column still
        // to come ("fresh" = 1): recompute it then.
        match saved.real("gram", &[2, n, n]) {
            Ok(gram) if saved.get("fresh").map_or(true, |f| f == 0.0) => {
                for ((g, i, j), v) in gram.indexed_iter() {
                    [&mut self.sy, &mut self.yy][g][i * MAX_MEMORY + j] = *v;
                }
            }
            _ => self.rebuild_gram(),
        }
        self.ev
            .evaluate(&mut self.cur, t, None, None)
            .map_err(|d| d.0)?;
        if let Some(c) = self.couple.as_mut() {
            // The evaluation's ĝ holds no λm̂ yet.
            c.lambda = 0.0;
        }
        self.refresh_gradient();
        Ok(())
    }
}
