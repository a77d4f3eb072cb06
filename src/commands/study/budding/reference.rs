//! The sharp-interface reference of the budding continuation: at each c̄0 of the path, the
//! prolate and the pear branch of [`crate::analysis::axisym`] read at a fixed reduced volume.
//!
//! The pear branch of [`pear::follow_pear`] is a path in the coefficients that may fold in v:
//! from the bifurcation at v_b it rises to its largest v (the fold; at once when the pitchfork
//! is supercritical), then comes down to the limit shape where the neck closes. The stretch
//! before the fold is unstable (a subcritical pitchfork), the stretch after it the locally
//! stable pear. At a reduced volume v each stretch is read by linear interpolation between the
//! two path states on either side of v; a stretch that does not reach v reads NaN.

use crate::analysis::axisym::{self, pear, Branch, Options};
use rayon::prelude::*;

/// The pear branch stops when its narrowest neck is below this many R0 (the Ritz modes stop
/// resolving it closer to the limit shape): the reference neck is not given below it.
pub const NECK_MIN: f64 = 0.05;

/// The reference at one c̄0, read at one reduced volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// Reduced bending energy of the prolate at v (NaN where the solver fails).
    pub e_prolate: f64,
    /// Where the pear branch leaves the prolate (NaN: the prolate keeps its up–down symmetry
    /// down to v = 0.3); the prolate is stable to asymmetry above it.
    pub v_bifurcation: f64,
    /// Largest v on the pear branch (its fold; NaN without a branch).
    pub v_fold: f64,
    /// v of the last pear state reached, whose neck is below [`NECK_MIN`] (NaN if the branch
    /// ended otherwise): between it and `v_fold` the stable pear exists.
    pub v_limit: f64,
    /// Neck (units of R0) and e of the stable pear at v (NaN off that stretch).
    pub stable: (f64, f64),
    /// Neck (units of R0) and e of the unstable pear at v (NaN off that stretch).
    pub unstable: (f64, f64),
}

/// The pear path at one c̄0: `(v, e, neck)` of each state in path order, and the bifurcation.
#[derive(Clone, Debug)]
pub struct PearPath {
    /// c̄0.
    pub c0: f64,
    /// v of the bifurcation off the prolate (NaN if none).
    pub v_bifurcation: f64,
    /// The states, in the order of the path (neck NaN where the shape has none).
    pub states: Vec<(f64, f64, f64)>,
    /// Whether the path ended at the neck threshold.
    pub reached_limit: bool,
}

impl PearPath {
    /// Follow the pear branch at `c0` down to `v_floor` with the solver's default
    /// discretisation (241 nodes, K = 80).
    pub fn follow(c0: f64, v_floor: f64) -> Self {
        let mut opts = Options::default().with_c0(c0);
        opts.neck_min = NECK_MIN;
        let branch = pear::follow_pear(v_floor, &opts);
        PearPath {
            c0,
            v_bifurcation: branch.bifurcation.as_ref().map_or(f64::NAN, |b| b.v),
            states: branch
                .shapes
                .iter()
                .map(|s| (s.v, s.e, s.neck().unwrap_or(f64::NAN)))
                .collect(),
            reached_limit: matches!(branch.end, Some(pear::PearEnd::Neck { .. })),
        }
    }

    /// Index of the fold: the state of largest v.
    fn fold(&self) -> Option<usize> {
        (0..self.states.len()).max_by(|&a, &b| self.states[a].0.total_cmp(&self.states[b].0))
    }

    /// The reading at `v`, with `e_prolate` the prolate's energy there.
    pub fn read(&self, v: f64, e_prolate: f64) -> Reading {
        let fold = self.fold();
        let v_fold = fold.map_or(f64::NAN, |i| self.states[i].0);
        let v_limit = match (self.reached_limit, self.states.last()) {
            (true, Some(s)) => s.0,
            _ => f64::NAN,
        };
        let (unstable, stable) = match fold {
            Some(i) => (at_v(&self.states[..=i], v), at_v(&self.states[i..], v)),
            None => ((f64::NAN, f64::NAN), (f64::NAN, f64::NAN)),
        };
        Reading {
            e_prolate,
            v_bifurcation: self.v_bifurcation,
            v_fold,
            v_limit,
            stable,
            unstable,
        }
    }
}

/// `(neck, e)` at `v` on a monotone-in-v stretch of `(v, e, neck)` states: linear
/// interpolation between the first two consecutive states that bracket v; NaN if none do.
pub fn at_v(states: &[(f64, f64, f64)], v: f64) -> (f64, f64) {
    states
        .windows(2)
        .find(|w| (w[0].0 - v) * (w[1].0 - v) <= 0.0 && w[0].0 != w[1].0)
        .map_or((f64::NAN, f64::NAN), |w| {
            let s = (v - w[0].0) / (w[1].0 - w[0].0);
            let lerp = |a: f64, b: f64| a + s * (b - a);
            (lerp(w[0].2, w[1].2), lerp(w[0].1, w[1].1))
        })
}

/// The reduced energy of the prolate at `(v, c0)` and its waist (narrowest neck, units of R0;
/// NaN without one); both NaN where the solver does not reach v.
pub fn prolate(v: f64, c0: f64) -> (f64, f64) {
    axisym::solve(Branch::Prolate, v, &Options::default().with_c0(c0))
        .map_or((f64::NAN, f64::NAN), |s| {
            (s.e, s.neck().unwrap_or(f64::NAN))
        })
}

/// The pear paths of every c̄0 of `c0s` (in parallel), each followed down to `v_floor`.
pub fn pear_paths(c0s: &[f64], v_floor: f64) -> Vec<PearPath> {
    c0s.par_iter()
        .map(|&c| PearPath::follow(c, v_floor))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path that rises from v = 0.70 to a fold at 0.80 and comes back down to 0.72: at
    /// v = 0.75 the rising (unstable) stretch reads halfway between its ends (neck 0.30,
    /// e 1.5) and the falling (stable) one a quarter of the way from 0.76 to 0.72 (neck 0.09,
    /// e 1.5); v = 0.81 is off both.
    #[test]
    fn the_stretches_before_and_after_the_fold_are_read_apart() {
        let path = PearPath {
            c0: 3.0,
            v_bifurcation: 0.70,
            states: vec![
                (0.70, 1.0, 0.40),
                (0.80, 2.0, 0.20),
                (0.76, 1.6, 0.10),
                (0.72, 1.2, 0.06),
            ],
            reached_limit: true,
        };
        let r = path.read(0.75, 0.5);
        assert!((r.unstable.0 - 0.30).abs() < 1e-12 && (r.unstable.1 - 1.5).abs() < 1e-12);
        assert!((r.stable.0 - 0.09).abs() < 1e-12 && (r.stable.1 - 1.5).abs() < 1e-12);
        assert_eq!((r.v_fold, r.v_limit, r.e_prolate), (0.80, 0.72, 0.5));
        let off = path.read(0.81, 0.5);
        assert!(off.stable.0.is_nan() && off.unstable.0.is_nan());
    }
}
