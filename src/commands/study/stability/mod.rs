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
//! * **The ADE multiplier** (its own study, `vesicle study ade`, [`ade`]): on a 3D scene with
//!   an ADE term, the fixed-Δt sweep of SBDF1 and SBDF2 at each α with λ implicit and lagged.
//!
//! The runs are [`measure`]d from the study file's keys ([`spec`]). The [`report`] gives the
//! largest stable Δt per method and h (the last stable Δt below the first failure), the
//! spectral/FD ratios and their least-squares scaling with h, the FD bound of
//! docs/src/theory/fd.md. Writes `stability.csv` (every run), `frontier.csv`, `stability.txt`,
//! and the charts `stability_map`, `stability_alpha` (PNG and SVG); with a `c0` block also
//! `stability_c0.csv` and the chart `stability_c0`.

pub mod ade;
pub mod c0;
pub mod measure;
pub mod report;
pub mod spec;

pub use ade::{AdeRun, AdeStability};
pub use c0::C0Run;
pub use measure::{FixedMethod, Run, METHODS};
pub use spec::{AdaptiveSweep, AlphaSweep, C0Sweep, Spec};

use super::file;
use super::harness::{Report, Study};
use crate::error::Result;
use std::path::Path;

/// The study: `stability.txt`, `stability.csv` (every run), `frontier.csv` and the charts
/// `stability_map`, `stability_alpha`; with a `c0` block also `stability_c0.csv` and the chart
/// `stability_c0`.
pub struct Stability;

impl Study for Stability {
    const NAME: &'static str = "stability";
    type Spec = Spec;
    type Output = Vec<Run>;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Vec<Run>, Report)> {
        let base = file::scene(&spec.scene, &[], "scene", dir)?;
        let (runs, bounds) = measure::sweeps(spec, &base)?;
        let mut report = report::report(spec, &runs, &bounds, (base.dim, base.eps))?;
        if let Some(c0) = &spec.c0 {
            let c0_runs = c0::c0_sweep(spec, c0, &base)?;
            c0::report(&mut report, &c0_runs, c0)?;
        }
        Ok((runs, report))
    }
}
