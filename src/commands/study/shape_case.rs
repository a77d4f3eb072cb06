//! One stationary shape of the resolution studies (`pinning`, `resolution`), started as a
//! diagram case is ([`crate::commands::diagram::case`]): the axisymmetric reference of a branch
//! at a reduced volume (c0 = 0), scaled to R0 = `r0` ε on the grid a diagram would give it at
//! h = ε/`eps_over_h`, relaxed by L-BFGS on one thread to the stationarity tolerance and
//! measured on its refined φ = 0 surface. A case may be shifted along its axis by a fraction
//! of h (the interface then crosses the lattice elsewhere); a shifted case, and every case
//! it is compared with, runs without the mirror plane across the axis.

use crate::analysis::axisym::{self, Branch, Options};
use crate::commands::diagram::case::grid_for;
use crate::commands::diagram::spec::{branch_named, DiagramSpec};
use crate::commands::diagram::thickness::thinnest;
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use serde::Deserialize;
use serde_json::json;
use std::time::Instant;

/// A shape of a study file: `{"branch": "prolate", "v": 0.75}`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// `prolate`, `oblate` or `stomatocyte`.
    pub branch: String,
    /// Reduced volume of the sharp start.
    pub v: f64,
}

/// How every case of a study is relaxed (the study file's keys, with a diagram's defaults).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Relaxation {
    /// Stationarity tolerance RMS(μ − μ̄).
    #[serde(default = "default_stop_residual")]
    pub stop_residual: f64,
    /// Most L-BFGS iterations per case.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Outside bulk between the shape and the box faces: `margin` ε + `margin_r0` R0.
    #[serde(default = "default_margin")]
    pub margin: f64,
    /// See `margin`.
    #[serde(default = "default_margin_r0")]
    pub margin_r0: f64,
    /// Unconstrained SBDF1 steps that build the profile before A0 is taken.
    #[serde(default = "default_prepare_steps")]
    pub prepare_steps: usize,
    /// Thinnest part (in ε) every start must keep at the smallest R0 of the study.
    #[serde(default = "default_min_width")]
    pub min_width: f64,
}

fn default_stop_residual() -> f64 {
    1e-7
}
fn default_max_iterations() -> usize {
    20_000
}
fn default_margin() -> f64 {
    4.0
}
fn default_margin_r0() -> f64 {
    0.1
}
fn default_prepare_steps() -> usize {
    20
}
fn default_min_width() -> f64 {
    4.0
}

impl Default for Relaxation {
    fn default() -> Self {
        Relaxation {
            stop_residual: default_stop_residual(),
            max_iterations: default_max_iterations(),
            margin: default_margin(),
            margin_r0: default_margin_r0(),
            prepare_steps: default_prepare_steps(),
            min_width: default_min_width(),
        }
    }
}

impl Relaxation {
    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key.
    pub fn validate(&self) -> Result<()> {
        let ranges = [
            ("stop_residual", self.stop_residual, 1e-12, 1e-2),
            ("margin", self.margin, 2.0, 50.0),
            ("margin_r0", self.margin_r0, 0.0, 2.0),
            ("min_width", self.min_width, 0.0, 50.0),
        ];
        for (key, value, lo, hi) in ranges {
            if !(value >= lo && value <= hi) {
                return Err(Error::config(
                    key,
                    format!("need {lo} ≤ {key} ≤ {hi}, got {value}"),
                ));
            }
        }
        if self.max_iterations == 0 {
            return Err(Error::config("max_iterations", "must be at least 1"));
        }
        Ok(())
    }

    /// The diagram file these settings amount to at h = ε/`eps_over_h` (for its grid).
    fn diagram(&self, eps_over_h: f64) -> DiagramSpec {
        DiagramSpec {
            description: String::new(),
            c0: vec![0.0],
            branches: Default::default(),
            branches_by_c0: Default::default(),
            branches_by_da: Default::default(),
            ade: None,
            bilayer_couple: None,
            r0: vec![],
            eps_over_h,
            margin: self.margin,
            margin_r0: self.margin_r0,
            stop_residual: self.stop_residual,
            max_iterations: self.max_iterations,
            prepare_steps: self.prepare_steps,
            thumbnails: vec![],
            min_width: self.min_width,
        }
    }
}

/// A shape of the study, solved once: its branch, its reduced volume and the sharp start.
#[derive(Clone, Debug)]
pub struct Start {
    /// The branch.
    pub branch: Branch,
    /// Reduced volume of the sharp start.
    pub v: f64,
    /// The sharp start (R0 = 1).
    pub shape: axisym::Solution,
}

impl Start {
    /// The label of the shape in tables (`prolate v0 = 0.75`).
    pub fn label(&self) -> String {
        format!("{} v0 = {}", self.branch.name(), self.v)
    }
}

/// Solve the sharp starts of `shapes` (the study key `field`), each checked to stay at least
/// `min_width` ε thick at `r0_min`.
///
/// # Errors
/// `Error::Config` naming `field[i].branch` or `field[i].v`.
pub fn starts(
    shapes: &[ShapeSpec],
    field: &str,
    r0_min: f64,
    min_width: f64,
) -> Result<Vec<Start>> {
    if shapes.is_empty() {
        return Err(Error::config(field, "list at least one shape"));
    }
    shapes
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let at = |k: &str| format!("{field}[{i}].{k}");
            let branch = branch_named(&s.branch).ok_or_else(|| {
                Error::config(at("branch"), "unknown branch (prolate, oblate or stomatocyte)")
            })?;
            if !(s.v > 0.3 && s.v < 1.0) {
                return Err(Error::config(at("v"), format!("need 0.3 < v < 1, got {}", s.v)));
            }
            let shape = axisym::solve(branch, s.v, &Options::default())
                .map_err(|e| Error::config(at("v"), format!("no {} shape: {e}", s.branch)))?;
            let w = thinnest(&shape) * r0_min;
            if w < min_width {
                return Err(Error::config(
                    at("v"),
                    format!(
                        "the {} at v = {} is {w:.2} ε thick at its thinnest part at R0 = {r0_min} ε, \
                         below min_width = {min_width} ε: raise the smallest r0 or choose another v",
                        s.branch, s.v
                    ),
                ));
            }
            Ok(Start {
                branch,
                v: s.v,
                shape,
            })
        })
        .collect()
}

/// Where a case sits on the lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// R0/ε.
    pub r0: f64,
    /// ε/h.
    pub eps_over_h: f64,
    /// Shift of the shape's centre along its axis, in units of h (0: on the box centre).
    pub shift: f64,
    /// Keep the mirror plane across the axis (up–down symmetric branches only, no shift).
    pub z_mirror: bool,
    /// R0/ε whose diagram grid the case uses, if not its own: a series on one box, so that
    /// the box's size (rounded to fast transform lengths) does not jump between its cases.
    pub grid_r0: Option<f64>,
}

impl Placement {
    /// The case at R0 = `r0`, h = ε/`eps_over_h`, centred, on its own diagram box.
    pub fn centred(r0: f64, eps_over_h: f64) -> Self {
        Placement {
            r0,
            eps_over_h,
            shift: 0.0,
            z_mirror: true,
            grid_r0: None,
        }
    }
}

/// What a case measured.
#[derive(Clone, Debug)]
pub struct Relaxed {
    /// Reduced volume of the refined φ = 0 surface.
    pub v: f64,
    /// Reduced bending energy of the phase field.
    pub e: f64,
    /// The sharp reference's e at the reduced volume reached, `v` (the diagram's comparison).
    pub e_ref: f64,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// Final residual.
    pub residual: f64,
    /// Whether the tolerance was met.
    pub converged: bool,
    /// Points computed (the reduced box).
    pub points: usize,
    /// Wall seconds of the case from its built initial field: preparing, relaxing, measuring
    /// the φ = 0 surface (not the sharp start's solve, which a diagram does once per shape).
    pub wall: f64,
}

/// The points `start` placed as `at` computes (its reduced box), without running it.
pub fn points(start: &Start, at: Placement, relax: &Relaxation) -> usize {
    let n = grid_for(
        &start.shape,
        at.grid_r0.unwrap_or(at.r0),
        &relax.diagram(at.eps_over_h),
    );
    let planes = if mirrored(start, at) { 3 } else { 2 };
    n.iter().product::<usize>() >> planes
}

/// Whether the case keeps the mirror plane across the axis.
fn mirrored(start: &Start, at: Placement) -> bool {
    at.z_mirror && start.branch.up_down_symmetric() && at.shift == 0.0
}

/// Relax `start` placed as `at` with the settings `relax`, on one thread, by L-BFGS, or by the
/// route the scene keys of `route` choose (merged into the case's scene: `{"dynamics":
/// "conserved", "scheme": "sbdf2", "adaptive": {...}}`).
///
/// # Errors
/// `Error::Config` for a scene that cannot be built; `Error::Blowup` if a step diverges.
pub fn relax(
    start: &Start,
    at: Placement,
    relax: &Relaxation,
    route: Option<&serde_json::Value>,
) -> Result<Relaxed> {
    let spec = relax.diagram(at.eps_over_h);
    let n = grid_for(&start.shape, at.grid_r0.unwrap_or(at.r0), &spec);
    let h = 1.0 / at.eps_over_h;
    let symmetry: &[&str] = if mirrored(start, at) {
        &["x", "y", "z"]
    } else {
        &["x", "y"]
    };
    let mut scene = json!({
        "description": format!("{} at R0 = {} eps, h = eps/{}, shifted {} h", start.label(), at.r0, at.eps_over_h, at.shift),
        "dim": 3,
        "n": n,
        "h": h,
        "eps": 1.0,
        "dynamics": "relaxational",
        "dt": 0.01,
        "max_steps": relax.max_iterations,
        "stop_residual": relax.stop_residual,
        "initial": {"shape": "axisym", "branch": start.branch.name(), "reduced_volume": start.v,
                    "r0": at.r0, "axis": "z", "center": [0.0, 0.0, at.shift * h]},
        "prepare_steps": relax.prepare_steps,
        "symmetry": symmetry,
        "threads": 1,
        "output": {"png": false, "vti": false}
    });
    if let Some(patch) = route {
        super::file::merge(&mut scene, patch);
    }
    let scene = crate::problem::config::from_value(scene)?;
    scene.validate()?;
    let problem = crate::problem::setup::build(&scene)?;
    // Timed from the built field: the sharp start is solved once per shape (a diagram reads it
    // from a file), and e_ref below is the study's, not the route's.
    let clock = Instant::now();
    let (mut sim, _a0) = Simulation::of_scene(&scene, &problem)?;
    let stopped = sim.run(&StopRules::of(&scene), &mut [])?;
    let last = sim.record();
    let full = problem.grid.unfold(sim.engine().phi());
    let level = crate::analysis::levelset::measure_refined(&full, 3, scene.h);
    let v = level.reduced_volume;
    let wall = clock.elapsed().as_secs_f64();
    Ok(Relaxed {
        v,
        e: last.reduced_energy,
        e_ref: e_ref(start, v)?,
        iterations: last.step,
        residual: last.residual,
        converged: stopped.as_str() == "stationary",
        points: problem.grid.len(),
        wall,
    })
}

/// The sharp reference's e at `v` on `start`'s branch (c0 = 0).
///
/// # Errors
/// `Error::Config` (field `shapes`) if the branch has no shape at `v`.
pub fn e_ref(start: &Start, v: f64) -> Result<f64> {
    axisym::solve(start.branch, v, &Options::default())
        .map(|s| s.e)
        .map_err(|e| {
            Error::config(
                "shapes",
                format!(
                    "no sharp {} at the reduced volume reached, v = {v}: {e}",
                    start.branch.name()
                ),
            )
        })
}
