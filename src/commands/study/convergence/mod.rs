//! `vesicle study convergence FILE`: observed orders in Δt, h and ε/R0 (validation ladder rungs
//! 2, 4 and 5), each from a least-squares fit printed beside it ([`super::fit`]).
//!
//! * **time**: from one field, SBDF1 and SBDF2 at Δt, Δt/2, … (fixed steps, the scene's
//!   stabiliser and area constraint) to the time `t`; error max|φ − φ_ref| against SBDF2 at
//!   `reference_dt`. Once from the field after the scene's `prepare_steps` (the smooth start),
//!   once from the raw tanh field (the order reduction of an unprepared start). Fit:
//!   error = C Δt^p.
//! * **space**: the stationary reduced energy e(h) at fixed ε on boxes of edge `length`, with
//!   the FD stencil's symbol (the FD discretisation, relaxed semi-implicitly; docs/src/theory/fd.md) and
//!   with the spectral symbol; error |e(h) − e_ref| against spectral at `reference_h`. Fits:
//!   FD error = C h^p; spectral error = C exp(b ε/h) (straight on a semi-log chart).
//! * **eps**: shapes of the c0 = 0 diagram (axisymmetric starts at the branch's v, R0 = ε/x)
//!   relaxed to the scene's `stop_residual` at ε/R0 = x; v from the φ = 0 surface
//!   ([`crate::analysis::levelset::measure_refined`]), e_ref(v) from [`crate::analysis::axisym::solve`] at that v
//!   (1 for a sphere).
//!   Fits: |e − e_ref| = C x^p; e = e0 + c x^p (the extrapolated limit; also for v); for the
//!   sphere |e − 1| = C exp(b R0/ε).
//!
//! The study file's keys are in [`spec`], the runs in [`measure`], the laws in [`fits`], the
//! tables, CSV files and charts in [`report`].

pub mod fits;
pub mod measure;
pub mod report;
pub mod spec;

pub use fits::Quoted;
pub use measure::Row;
pub use spec::{EpsSpec, ShapeSpec, SpaceSpec, Spec, TimeSpec};

use super::harness::{Report, Study};
use crate::error::Result;
use std::path::Path;

/// The study: `convergence.txt`, `convergence.csv`, `fits.csv` and the charts
/// `convergence_time`, `convergence_space`, `convergence_space_semilog`, `convergence_eps`,
/// `convergence_sphere`.
pub struct Convergence;

impl Study for Convergence {
    const NAME: &'static str = "convergence";
    type Spec = Spec;
    type Output = Vec<Row>;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Vec<Row>, Report)> {
        let mut rows = measure::time_part(&spec.time, dir)?;
        rows.extend(measure::space_part(&spec.space, dir)?);
        rows.extend(measure::eps_part(&spec.eps, dir)?);
        let fits = fits::fits(&rows);
        let report = report::report(&rows, &fits)?;
        Ok((rows, report))
    }
}
