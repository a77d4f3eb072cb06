//! `vesicle study heating FILE`: budding on heating in the ADE model — a quasi-static
//! continuation in the preferred area difference `Δa0` at fixed `v` through stationary states
//! (L-BFGS), set beside the sharp-interface ADE prolate and pear branches ([`reference`]).
//!
//! For each `R0` of the file (`r0`, in ε) the start is the axisymmetric ADE prolate of the
//! reference solver at `v`, `α` and the first `Δa0`, scaled to `R0`, on a box mirrored across x
//! and y only (a pear breaks the up–down mirror), sized to hold the prolate and the budded pear
//! ([`spec::box_size`]). Then for each `Δa0` of the path in turn (heating up, and cooling down again
//! to see the hysteresis of a discontinuous transition), from the previous step's state:
//!
//! 1. the state is seeded with the up–down stretch of strength `seed`
//!    ([`super::budding::seed`]), so that a prolate that has lost stability leaves its
//!    stationary symmetric state;
//! 2. the scene's `ade` is set to `{α, Δa0}` (c0 = 0) and the field relaxed by L-BFGS to the
//!    scene's `stop_residual` (area held at the first step's A0, the volume conserved), which
//!    minimises `w = e + πα(Δa − Δa0)²`;
//! 3. the relaxed state is measured: w, e, Δa and `c̄0,eff = 2πα(Δa0 − Δa)` (the record), the
//!    φ = 0 surface's reduced volume, its neck (the narrowest slice between the two widest,
//!    as `vesicle measure`), the skewness of the volume along z and the connected pieces.
//!
//! Each row is compared with the reference at its own φ = 0 reduced volume (interpolated
//! between the references on a grid of [`V_STEP`] in v; the diffuse surface's `v` sits below
//! the sharp start's, by about 0.24 c̄0,eff ε/R0, and moves along the path): the stable
//! prolate's and stable pear's w and neck at the row's `Δa0`, the pear's bifurcation, fold and
//! the crossing of the energies. The path has no time (L-BFGS): it is a sequence of stationary
//! states, not a transient.
//!
//! Writes `heating.csv` (one row per R0 and Δa0), `heating.txt`, the charts `heating_neck`
//! (neck / R0 against Δa0), `heating_w` (w against Δa0), `heating_w_error` (w against the
//! sharp branch the state is on), `heating_departure` (the phase field's neck against the
//! sharp pear's, in ε) and shaded pictures of the largest R0 at the
//! file's `renders` values of Δa0 (`shape_<i>_da0_<Δa0>.png`).

pub mod reference;
pub mod report;
pub mod spec;

use super::budding::{self, check_fits, relax_seeded, revolved, within};
use super::harness::{Report, Study};
use crate::analysis::axisym::{ade_solution, Branch, Options};
use crate::commands::measure::ShapeMeasure;
use crate::error::{Error, Result};
use crate::output::shade::{Bounds, View};
use crate::output::RgbImage;
use crate::problem::config::{AdeSpec, Scene};
use crate::problem::grid::Grid;
use crate::problem::setup;
use ndarray::Array3;
use rayon::prelude::*;
use reference::Sharp;
pub use spec::Spec;
use spec::{base_scene, check};
use std::path::Path;
use std::time::Instant;

/// One step of a continuation; a row of `heating.csv`.
#[derive(Clone, Debug)]
pub struct Row {
    /// R0/ε of the run.
    pub r0: f64,
    /// Index of the step along the path.
    pub index: usize,
    /// Δa0.
    pub da0: f64,
    /// L-BFGS iterations of this step.
    pub iterations: usize,
    /// How the relaxation ended (`stationary` when `stop_residual` was met).
    pub stopped: String,
    /// Final stationarity residual.
    pub residual: f64,
    /// w = e + πα(Δa − Δa0)².
    pub w: f64,
    /// Reduced bending energy e.
    pub e: f64,
    /// Δa = M/M₁.
    pub da: f64,
    /// c̄0,eff = 2πα(Δa0 − Δa).
    pub c0_eff: f64,
    /// ε c0,eff = c̄0,eff / (R0/ε).
    pub eps_c0_eff: f64,
    /// Reduced volume of the φ = 0 surface.
    pub v: f64,
    /// Neck radius in ε (NaN: no neck).
    pub neck: f64,
    /// Neck radius in units of R0 (the φ = 0 surface's).
    pub neck_r0: f64,
    /// Skewness of the volume along z (0 for an up–down symmetric shape).
    pub skewness: f64,
    /// Connected pieces of {φ > 0}.
    pub pieces: usize,
    /// `symmetric`, `pear`, `necked` or `pieces` ([`budding::state`]).
    pub state: String,
    /// The reference's stable prolate at this Δa0: w (NaN off its stable stretch).
    pub w_prolate_ref: f64,
    /// Its waist (units of R0).
    pub waist_ref: f64,
    /// The reference's stable pear at this Δa0: w.
    pub w_pear_ref: f64,
    /// Its neck (units of R0).
    pub neck_pear_ref: f64,
    /// The reference's Δa0 where the pear leaves the prolate, at `v_ref`.
    pub bifurcation_ref: f64,
    /// The reference's smallest Δa0 of the stable pear (its fold), at `v_ref`.
    pub fold_ref: f64,
    /// The reference's Δa0 where the stable pear's w drops below the stable prolate's.
    pub transition_ref: f64,
    /// Wall seconds of the step.
    pub wall_seconds: f64,
}

/// What the study returns: the rows and the references.
pub struct Output {
    /// The rows, R0 by R0, in path order.
    pub rows: Vec<Row>,
    /// The reference at each grid v of the rows ([`v_grid`]), in increasing v.
    pub sharp: Vec<Sharp>,
}

/// The study.
pub struct Heating;

impl Study for Heating {
    const NAME: &'static str = "heating";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Output, Report)> {
        check(spec)?;
        let opts = Options::with_nodes(spec.nodes);
        let start = ade_solution(Branch::Prolate, spec.v, spec.alpha, spec.da0[0], &opts)
            .map_err(|e| Error::config("v", format!("the start prolate: {e}")))?;
        let mut rows = Vec::new();
        let mut images = Vec::new();
        let last = spec.r0.len() - 1;
        for (i, &r0) in spec.r0.iter().enumerate() {
            let scene = base_scene(spec, r0, &start.r, &start.z)?;
            let render = if i == last { &spec.renders[..] } else { &[] };
            let (path, pics) = continuation(spec, &scene, r0, (&start.r, &start.z), render)?;
            images.extend(pics);
            rows.extend(path);
        }
        let began = Instant::now();
        let mut vs: Vec<f64> = rows.iter().flat_map(|r| v_grid(r.v)).collect();
        vs.sort_by(f64::total_cmp);
        vs.dedup();
        let sharp: Vec<Sharp> = vs
            .par_iter()
            .map(|&v| Sharp::at(v, spec.alpha, spec.nodes))
            .collect();
        eprintln!(
            "reference at {} reduced volumes in {:.1} s",
            vs.len(),
            began.elapsed().as_secs_f64()
        );
        for row in rows.iter_mut() {
            fill_reference(row, &sharp);
        }
        let mut report = report::report(spec, &rows, &sharp)?;
        report.images = images;
        Ok((Output { rows, sharp }, report))
    }
}

/// Step of the grid of reduced volumes at which the reference is computed; a row reads it
/// interpolated linearly in v between the two grid values around its φ = 0 v.
pub const V_STEP: f64 = 0.005;

/// The grid values of [`V_STEP`] below and above `v` (one value if `v` lies on the grid).
pub fn v_grid(v: f64) -> Vec<f64> {
    let snap = |x: f64| (x * 1e9).round() / 1e9;
    let lo = snap((v / V_STEP).floor() * V_STEP);
    let hi = snap((v / V_STEP).ceil() * V_STEP);
    if lo == hi {
        vec![lo]
    } else {
        vec![lo, hi]
    }
}

/// The reference of `sharp` computed at the grid value `v`.
pub fn sharp_at(sharp: &[Sharp], v: f64) -> Option<&Sharp> {
    sharp.iter().find(|s| (s.v - v).abs() < 1e-9)
}

/// A picture and its file name.
type Picture = (String, RgbImage);

/// The continuation at `R0 = r0` ε from the revolved contour `(r, z)`: the rows and the
/// pictures at the `Δa0` of `render`.
fn continuation(
    spec: &Spec,
    base: &Scene,
    r0: f64,
    (r, z): (&[f64], &[f64]),
    render: &[f64],
) -> Result<(Vec<Row>, Vec<Picture>)> {
    let mut problem = setup::build(base).map_err(within("scene"))?;
    let full_grid = Grid::new(&base.n, base.h, &[false; 3]);
    let start = revolved(r, z, r0 * base.eps, base.eps, &full_grid);
    check_fits(&start)?;
    problem.phi = problem.grid.restrict(&start);
    let mut rows = Vec::new();
    let mut images = Vec::new();
    let mut area = None;
    for (index, &da0) in spec.da0.iter().enumerate() {
        let began = Instant::now();
        let mut scene = base.clone();
        scene.ade = Some(AdeSpec {
            alpha: spec.alpha,
            da0,
            multiplier: None,
        });
        let step = relax_seeded(&mut problem, scene, (r0 * base.eps, spec.seed), &mut area)?;
        let (rec, m, full) = (&step.record, &step.measure, &step.full);
        let couple = rec.couple.ok_or_else(|| {
            Error::config("scene", "the relaxation reported no ADE columns (a bug)")
        })?;
        let mut row = row_of(r0, index, da0, m, base.eps);
        row.iterations = rec.step;
        row.stopped = step.stopped.to_string();
        row.residual = rec.residual;
        row.w = couple.w;
        row.e = couple.bending_energy;
        row.da = couple.da;
        row.c0_eff = couple.c0_eff;
        row.eps_c0_eff = couple.c0_eff / r0;
        if render.iter().any(|x| (x - da0).abs() < 1e-9) {
            images.push(picture(full, base, &row)?);
        }
        row.wall_seconds = began.elapsed().as_secs_f64();
        eprintln!(
            "R0 = {r0} eps, da0 = {da0}: {} after {} iterations, w {:.5}, da {:.5}, neck {:.3} \
             eps, skewness {:.4}, pieces {}",
            row.stopped, row.iterations, row.w, row.da, row.neck, row.skewness, row.pieces
        );
        rows.push(row);
    }
    Ok((rows, images))
}

/// The shaded picture of the φ = 0 surface of `full` (the unfolded field of `row`'s state).
fn picture(full: &Array3<f64>, scene: &Scene, row: &Row) -> Result<Picture> {
    let mesh = crate::analysis::surface::extract(full, scene.h);
    let (n0, n1, n2) = full.dim();
    let bounds = Bounds::of_grid([n0, n1, n2], scene.h);
    let title = format!(
        "R0 = {} eps   da0 = {:.3}   w = {:.4}   da = {:.4}   neck = {:.2} eps",
        row.r0, row.da0, row.w, row.da, row.neck
    );
    let view = View {
        cut: Some(1),
        ..View::default()
    };
    let image = crate::output::shade::render(&mesh, &bounds, &view, &title)?;
    Ok((
        format!("shape_{:02}_da0_{:.3}.png", row.index, row.da0),
        image,
    ))
}

/// The measured part of a row (the relaxation's and the reference's columns left to fill).
fn row_of(r0: f64, index: usize, da0: f64, m: &ShapeMeasure, eps: f64) -> Row {
    let r0_surface = (m.surface.area / (4.0 * std::f64::consts::PI)).sqrt();
    let neck = m.neck.map_or(f64::NAN, |(r, _)| r);
    Row {
        r0,
        index,
        da0,
        iterations: 0,
        stopped: String::new(),
        residual: f64::NAN,
        w: f64::NAN,
        e: f64::NAN,
        da: f64::NAN,
        c0_eff: f64::NAN,
        eps_c0_eff: f64::NAN,
        v: m.surface.reduced_volume,
        neck: neck / eps,
        neck_r0: neck / r0_surface,
        skewness: m.skewness,
        pieces: m.pieces,
        state: budding::state(m).to_string(),
        w_prolate_ref: f64::NAN,
        waist_ref: f64::NAN,
        w_pear_ref: f64::NAN,
        neck_pear_ref: f64::NAN,
        bifurcation_ref: f64::NAN,
        fold_ref: f64::NAN,
        transition_ref: f64::NAN,
        wall_seconds: 0.0,
    }
}

/// Fill the reference columns of `row` at its Δa0 and φ = 0 v from the references `sharp`
/// at the grid values around v: each quantity interpolated linearly in v where both are
/// finite, else the nearer grid value's.
fn fill_reference(row: &mut Row, sharp: &[Sharp]) {
    let grid = v_grid(row.v);
    let at: Vec<&Sharp> = grid.iter().filter_map(|&g| sharp_at(sharp, g)).collect();
    let (a, b) = (at[0], at[at.len() - 1]);
    let t = if b.v > a.v {
        (row.v - a.v) / (b.v - a.v)
    } else {
        0.0
    };
    let mix = |f: &dyn Fn(&Sharp) -> f64| {
        let (x, y) = (f(a), f(b));
        match (x.is_finite(), y.is_finite()) {
            (true, true) => x + t * (y - x),
            _ if t < 0.5 => x,
            _ => y,
        }
    };
    let da0 = row.da0;
    row.w_prolate_ref = mix(&|s| s.prolate_at(da0).w);
    row.waist_ref = mix(&|s| s.prolate_at(da0).neck);
    row.w_pear_ref = mix(&|s| s.pear_at(da0).w);
    row.neck_pear_ref = mix(&|s| s.pear_at(da0).neck);
    row.bifurcation_ref = mix(&|s| s.bifurcation);
    row.fold_ref = mix(&|s| s.fold);
    row.transition_ref = mix(&|s| s.transition);
}
