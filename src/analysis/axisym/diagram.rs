//! The c0 = 0 shape diagram: the prolate, oblate and stomatocyte branches on a grid of reduced
//! volumes and the transition volumes where they cross or end (the command `vesicle axisym`
//! writes and draws it; with `--c0`, the (v, c̄0) diagram of [`super::phase`]).

use super::{branch_end, crossings, follow, Branch, Options, Solution};
use rayon::prelude::*;

/// The c0 = 0 diagram.
#[derive(Clone, Debug)]
pub struct Diagram {
    /// The shapes of each branch of [`Branch::ALL`] on the grid, increasing `v`.
    pub curves: Vec<Vec<Solution>>,
    /// Where the branches cross and end.
    pub transitions: Transitions,
}

/// Transition volumes of a diagram.
#[derive(Clone, Debug, Default)]
pub struct Transitions {
    /// Where the prolate and oblate energies cross.
    pub prolate_oblate: Vec<f64>,
    /// Where the oblate and stomatocyte energies cross.
    pub oblate_stomatocyte: Vec<f64>,
    /// Where the prolate and stomatocyte energies cross.
    pub prolate_stomatocyte: Vec<f64>,
    /// Upper end (limit point) of the stomatocyte branch.
    pub stomatocyte_end: Option<f64>,
    /// First self-contact of the oblate branch.
    pub oblate_contact: Option<f64>,
}

impl Diagram {
    /// Follow the branches of [`Branch::ALL`] over the grid `vs` (increasing) and find their
    /// transitions.
    pub fn compute(vs: &[f64], opts: &Options) -> Self {
        let followed: Vec<_> = Branch::ALL
            .par_iter()
            .map(|&b| follow(b, vs, opts))
            .collect();
        let end_of = |b: Branch| {
            let i = Branch::ALL.iter().position(|x| *x == b).expect("listed");
            let f = &followed[i];
            f.end.or_else(|| branch_end(b, opts))
        };
        let curves: Vec<Vec<Solution>> = followed.iter().map(|f| f.shapes.clone()).collect();
        let transitions = Transitions {
            prolate_oblate: crossings(&curves[0], &curves[1]),
            oblate_stomatocyte: crossings(&curves[1], &curves[2]),
            prolate_stomatocyte: crossings(&curves[0], &curves[2]),
            stomatocyte_end: end_of(Branch::Stomatocyte),
            oblate_contact: end_of(Branch::Oblate),
        };
        Diagram {
            curves,
            transitions,
        }
    }
}
