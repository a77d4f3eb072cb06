//! `vesicle study budding FILE`: quasi-static budding under a uniform spontaneous curvature,
//! followed through stationary states by L-BFGS and set beside the sharp-interface pear branch.
//!
//! The start is the axisymmetric prolate of the reference solver at the file's reduced volume
//! `v` and first c̄0 (`c0[0]`), scaled to R0 = `r0` ε, on a box mirrored across x and y only
//! (a pear breaks the up–down mirror). Then for each c̄0 of the path `c0` in turn (up, and
//! down again to see hysteresis), starting from the previous step's state:
//!
//! 1. the state is seeded with a small up–down asymmetry of strength `seed` ([`seed`]), so that
//!    a prolate that has become unstable leaves its stationary symmetric state;
//! 2. c0 = c̄0/R0 is set (uniform) and the field relaxed by L-BFGS (`"dynamics":
//!    "relaxational"`: area held at the first step's A0, volume at the start's) until the
//!    scene's `stop_residual` or `max_steps`;
//! 3. the relaxed state is measured ([`measure::measure_field`] on the unfolded field): e, the
//!    reduced volume of the φ = 0 surface, its neck (the narrowest slice between the two widest
//!    along z, as `vesicle measure`), the skewness of the volume along z and the connected
//!    pieces.
//!
//! The reference ([`mod@reference`]) at each c̄0 is the prolate and the pear branch of
//! [`crate::analysis::axisym`] read at the step's own φ = 0 reduced volume. The dynamics has no
//! hydrodynamics and L-BFGS has no time at all: the path is a sequence of stationary states, not
//! a transient.
//!
//! Writes `budding.csv` (one row per c̄0), `budding.txt`, and the charts `budding_neck_eps`
//! (neck in ε against c̄0, with the reference pear's neck at R0 = `r0` ε) and `budding_neck_r0`
//! (the same in units of R0) and `budding_skewness`.

pub mod reference;
pub mod report;
pub mod seed;

use super::harness::{Report, Study};
use crate::analysis::axisym::{self, Branch, Options};
use crate::commands::measure::{self, ShapeMeasure};
use crate::driver::record::Record;
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use crate::problem::config::{self, C0Spec, Scene};
use crate::problem::grid::Grid;
use crate::problem::model::C0;
use crate::problem::revolution::Meridian;
use crate::problem::setup::{self, Problem, FACE_PHI_MAX};
use crate::problem::shapes::{self, Prepared, Revolution, AXISYM_SPACING};
use ndarray::Array3;
use reference::Reading;
use serde::Deserialize;
use serde_json::{json, Value};
use std::path::Path;
use std::time::Instant;

/// Largest ε|c0| the study accepts: the preferred bud radius 2/c0 stays at ten interface widths
/// or more, where the φ = 0 area and volume hold (the spontaneous-curvature page).
pub const MAX_EPS_C0: f64 = 0.2;

/// Skewness below which a state counts as up–down symmetric (the seed's own skewness, relaxed
/// away on a stable prolate, is about 1e-3 at δ = 0.02).
pub const SYMMETRIC_SKEWNESS: f64 = 0.01;

/// Keys of the scene that the study sets itself.
const STUDY_KEYS: [&str; 5] = ["initial", "c0", "dynamics", "symmetry", "volume"];

/// The study file's keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"budding"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The lattice and the relaxation: a scene object (`dim` 3, `n`, `h`, `eps`, `dt`,
    /// `stop_residual`, `max_steps`, `prepare_steps`, `threads`, …) without `initial`, `c0`,
    /// `dynamics`, `symmetry` and `volume`, which the study sets.
    pub scene: Value,
    /// Reduced volume of the start prolate, in (0, 1).
    pub v: f64,
    /// R0/ε of the start.
    pub r0: f64,
    /// The path in c̄0 = c0 R0 (up, then down again for a hysteresis loop; no value twice in a
    /// row), each with ε|c0| ≤ [`MAX_EPS_C0`].
    pub c0: Vec<f64>,
    /// Strength δ of the asymmetry seeded before each relaxation ([`seed`]), in [0, 0.1].
    pub seed: f64,
}

/// One step of the continuation; a row of `budding.csv`.
#[derive(Clone, Debug)]
pub struct Row {
    /// c̄0 = c0 R0 (R0 = `r0` ε).
    pub c0: f64,
    /// ε c0.
    pub eps_c0: f64,
    /// L-BFGS iterations of this step.
    pub iterations: usize,
    /// How the relaxation ended (`stationary` when `stop_residual` was met).
    pub stopped: String,
    /// Final stationarity residual RMS(μ − μ̄).
    pub residual: f64,
    /// Reduced bending energy e of the phase field.
    pub e: f64,
    /// Reduced volume of the φ = 0 surface.
    pub v: f64,
    /// R0 of the φ = 0 surface, √(A/4π), in ε.
    pub r0_surface: f64,
    /// Neck radius in ε (NaN: no neck, the profile has one maximum).
    pub neck: f64,
    /// Neck radius in units of R0 (the φ = 0 surface's).
    pub neck_r0: f64,
    /// Largest slice radius, in ε.
    pub r_max: f64,
    /// Skewness of the volume along z (0 for an up–down symmetric shape).
    pub skewness: f64,
    /// Connected pieces of {φ > 0}.
    pub pieces: usize,
    /// The reference prolate's e at this v and c̄0.
    pub e_prolate_ref: f64,
    /// The reference prolate's waist (narrowest neck, units of R0; NaN: none).
    pub neck_prolate_ref: f64,
    /// The reference pear branch's bifurcation off the prolate (NaN: none down to v = 0.3).
    pub v_bifurcation_ref: f64,
    /// The pear branch's fold (largest v).
    pub v_fold_ref: f64,
    /// v where the reference pear's neck falls below 0.05 R0 (the branch's end).
    pub v_limit_ref: f64,
    /// Neck (units of R0) of the reference's stable pear at this v (NaN: none).
    pub neck_pear_ref: f64,
    /// e of the reference's stable pear at this v.
    pub e_pear_ref: f64,
    /// Neck (units of R0) of the reference's unstable pear at this v.
    pub neck_unstable_ref: f64,
    /// e of the reference's unstable pear at this v.
    pub e_unstable_ref: f64,
    /// What the phase field is: `symmetric`, `pear`, `necked` or `pieces` (see [`state`]).
    pub state: String,
    /// Wall seconds of the step (seed, relaxation, measurement).
    pub wall_seconds: f64,
}

/// The study.
pub struct Budding;

impl Study for Budding {
    const NAME: &'static str = "budding";
    type Spec = Spec;
    type Output = Vec<Row>;

    fn measure(spec: &Spec, _dir: &Path) -> Result<(Vec<Row>, Report)> {
        check(spec)?;
        let base = base_scene(spec)?;
        let sharp = axisym::solve(
            Branch::Prolate,
            spec.v,
            &Options::default().with_c0(spec.c0[0]),
        )
        .map_err(|e| Error::config("v", format!("the start prolate: {e}")))?;
        let mut problem = setup::build(&base).map_err(within("scene"))?;
        let full_grid = Grid::new(&base.n, base.h, &[false; 3]);
        let start = revolved(&sharp.r, &sharp.z, spec.r0 * base.eps, base.eps, &full_grid);
        check_fits(&start)?;
        problem.phi = problem.grid.restrict(&start);
        let mut rows = Vec::new();
        let mut area = None;
        for &c0 in &spec.c0 {
            let began = Instant::now();
            let mut scene = base.clone();
            let c = c0 / (spec.r0 * base.eps);
            scene.c0 = C0Spec::Uniform(c);
            let step = relax_seeded(
                &mut problem,
                scene,
                (spec.r0 * base.eps, spec.seed),
                &mut area,
            )?;
            let last = &step.record;
            let mut row = row_of(c0, c, &step.measure, base.eps);
            row.iterations = last.step;
            row.stopped = step.stopped.to_string();
            row.residual = last.residual;
            row.e = last.reduced_energy;
            row.wall_seconds = began.elapsed().as_secs_f64();
            eprintln!(
                "c0 R0 = {c0}: {} after {} iterations, neck {:.3} eps, skewness {:.4}, pieces {}",
                row.stopped, row.iterations, row.neck, row.skewness, row.pieces
            );
            rows.push(row);
        }
        // The reference, at the phase field's own reduced volumes: one pear path per distinct
        // c̄0, followed to its neck threshold (or v = 0.3).
        let mut distinct = spec.c0.clone();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        let paths = reference::pear_paths(&distinct, 0.3);
        for row in rows.iter_mut() {
            let path = paths
                .iter()
                .find(|p| p.c0 == row.c0)
                .expect("every c0 has a path");
            let (e_prolate, waist) = reference::prolate(row.v, row.c0);
            row.neck_prolate_ref = waist;
            fill_reference(row, &path.read(row.v, e_prolate));
        }
        let report = report::report(spec, &rows, &paths)?;
        Ok((rows, report))
    }
}

/// Refuse a bad study file, naming the key.
fn check(spec: &Spec) -> Result<()> {
    if !(spec.v > 0.0 && spec.v < 1.0) {
        return Err(Error::config(
            "v",
            format!("must lie in (0, 1), got {}", spec.v),
        ));
    }
    if !(spec.r0.is_finite() && spec.r0 > 0.0) {
        return Err(Error::config("r0", format!("must be > 0, got {}", spec.r0)));
    }
    if spec.c0.is_empty() {
        return Err(Error::config("c0", "needs at least one value"));
    }
    if let Some(w) = spec.c0.windows(2).find(|w| w[1] == w[0]) {
        return Err(Error::config(
            "c0",
            format!("a path of steps: {} twice in a row", w[0]),
        ));
    }
    if let Some(c) = spec
        .c0
        .iter()
        .find(|c| !c.is_finite() || c.abs() / spec.r0 > MAX_EPS_C0 + 1e-12)
    {
        return Err(Error::config(
            "c0",
            format!(
                "c0 R0 = {c} at R0 = {} eps is eps|c0| = {:.3}, above {MAX_EPS_C0}: the preferred \
                 bud radius 2/c0 would come within ten interface widths",
                spec.r0,
                c.abs() / spec.r0
            ),
        ));
    }
    if !(0.0..=0.1).contains(&spec.seed) {
        return Err(Error::config(
            "seed",
            format!("must lie in [0, 0.1], got {}", spec.seed),
        ));
    }
    Ok(())
}

/// Errors of a scene built from the study key `key`, renamed `key.<field>`.
pub fn within(key: &'static str) -> impl Fn(Error) -> Error {
    move |e| match e {
        Error::Config { field, reason } => Error::config(format!("{key}.{field}"), reason),
        other => other,
    }
}

/// The scene of the study: the file's `scene` with L-BFGS, mirror planes x and y, c0 = 0 and a
/// placeholder initial shape (the spheroid of the same v and R0; the start field replaces it).
///
/// # Errors
/// `Error::Config` naming `scene.<key>` for a key the study sets or an invalid scene.
fn base_scene(spec: &Spec) -> Result<Scene> {
    let Value::Object(obj) = &spec.scene else {
        return Err(Error::config("scene", "must be a scene object"));
    };
    if let Some(k) = STUDY_KEYS.iter().find(|k| obj.contains_key(**k)) {
        return Err(Error::config(
            format!("scene.{k}"),
            "is set by the study (initial: the axisymmetric prolate at v and c0[0]; c0: the \
             path; dynamics: relaxational; symmetry: x and y); remove it",
        ));
    }
    let mut value = spec.scene.clone();
    value["initial"] = json!({
        "shape": "spheroid", "reduced_volume": spec.v, "kind": "prolate", "axis": "z",
        "r0": spec.r0 * obj.get("eps").and_then(Value::as_f64).unwrap_or(1.0)
    });
    value["dynamics"] = json!("relaxational");
    value["symmetry"] = json!(["x", "y"]);
    let scene = config::load_value(value, &[], None).map_err(within("scene"))?;
    if scene.dim != 3 {
        return Err(Error::config("scene.dim", "the budding study is 3D"));
    }
    if scene.stop_residual.is_none() && scene.max_steps.is_none() {
        return Err(Error::config(
            "scene.stop_residual",
            "each relaxation needs a stop: stop_residual (and max_steps as a cap)",
        ));
    }
    Ok(scene)
}

/// One relaxed state of a continuation through stationary states ([`relax_seeded`]).
pub struct Relaxed {
    /// How the relaxation ended (`stationary` when `stop_residual` was met).
    pub stopped: &'static str,
    /// The last record (iterations, residual, energies, the ADE columns).
    pub record: Record,
    /// The state on the full box (unfolded).
    pub full: Array3<f64>,
    /// Its shape measured ([`measure::measure_field`] along z).
    pub measure: ShapeMeasure,
}

/// One step of the budding, heating and onset continuations: the state of `problem` seeded with
/// the up–down stretch of strength `seed` at radius `r0` (length units, [`seed::seeded`]), its
/// c0 set from `scene`, then relaxed under `scene` to its stop rules, with the area held at
/// `area`. The first step (`area` `None`) runs the scene's `prepare_steps` and sets `area` to
/// its A0; later steps prepare nothing. The relaxed state is left in `problem.phi`.
///
/// # Errors
/// `Error::Config` for a c0 that does not fit the grid; `Error::Blowup` if the relaxation
/// diverges.
pub fn relax_seeded(
    problem: &mut Problem,
    mut scene: Scene,
    (r0, seed): (f64, f64),
    area: &mut Option<f64>,
) -> Result<Relaxed> {
    scene.area.target = *area;
    if area.is_some() {
        scene.prepare_steps = 0;
    }
    let full = problem.grid.unfold(&problem.phi).into_owned();
    problem.phi = problem
        .grid
        .restrict(&seed::seeded(&full, scene.h, r0, seed));
    problem.c0 = C0::new(&scene.c0, &problem.grid, scene.eps)?;
    let (mut sim, a0) = Simulation::of_scene(&scene, problem)?;
    *area = Some(a0);
    let stopped = sim.run(&StopRules::of(&scene), &mut [])?;
    let record = sim.record();
    problem.phi = sim.engine().phi().clone();
    let full = problem.grid.unfold(&problem.phi).into_owned();
    let measure = measure::measure_field(&full, 2, scene.h, record.step, record.t);
    Ok(Relaxed {
        stopped: stopped.as_str(),
        record,
        full,
        measure,
    })
}

/// φ = tanh(d/(√2 ε)) of the surface of revolution about z through the contour `(r, z)` (R0 = 1)
/// scaled to `r0`, centred in the box of `grid`.
pub fn revolved(r: &[f64], z: &[f64], r0: f64, eps: f64, grid: &Grid) -> Array3<f64> {
    let shape = Prepared::Revolution(Revolution {
        meridian: Meridian::new(r, z, r0, AXISYM_SPACING * eps),
        axis: 2,
        center: [0.0; 3],
    });
    grid.par_field_from(|p| shapes::profile(shape.signed_distance(p, 3), eps))
}

/// The start must keep bulk outside on the box's faces (φ ≤ [`FACE_PHI_MAX`]).
pub fn check_fits(phi: &Array3<f64>) -> Result<()> {
    let (n0, n1, n2) = phi.dim();
    let on_face = |(i, j, k): (usize, usize, usize)| {
        i == 0 || j == 0 || k == 0 || i == n0 - 1 || j == n1 - 1 || k == n2 - 1
    };
    let worst = phi
        .indexed_iter()
        .filter(|(ix, _)| on_face(*ix))
        .map(|(_, p)| *p)
        .fold(f64::NEG_INFINITY, f64::max);
    if worst > FACE_PHI_MAX {
        return Err(Error::config(
            "scene.n",
            format!(
                "the start prolate does not fit the box: φ = {worst:.3} on a face (at most \
                 {FACE_PHI_MAX}); enlarge n"
            ),
        ));
    }
    Ok(())
}

/// What the phase field is at a step: `pieces` (more than one connected piece), `symmetric`
/// (|skewness| below [`SYMMETRIC_SKEWNESS`]: the prolate, with or without a waist), `necked`
/// (asymmetric, a neck between the two widest slices) or `pear` (asymmetric, no neck).
pub fn state(m: &ShapeMeasure) -> &'static str {
    if m.pieces > 1 {
        "pieces"
    } else if m.skewness.abs() < SYMMETRIC_SKEWNESS {
        "symmetric"
    } else if m.neck.is_some() {
        "necked"
    } else {
        "pear"
    }
}

/// The measured part of a row (the relaxation's and the reference's columns left to fill).
fn row_of(c0: f64, c: f64, m: &ShapeMeasure, eps: f64) -> Row {
    let r0_surface = (m.surface.area / (4.0 * std::f64::consts::PI)).sqrt();
    let neck = m.neck.map_or(f64::NAN, |(r, _)| r);
    Row {
        c0,
        eps_c0: eps * c,
        iterations: 0,
        stopped: String::new(),
        residual: f64::NAN,
        e: f64::NAN,
        v: m.surface.reduced_volume,
        r0_surface: r0_surface / eps,
        neck: neck / eps,
        neck_r0: neck / r0_surface,
        r_max: m.r_max / eps,
        skewness: m.skewness,
        pieces: m.pieces,
        e_prolate_ref: f64::NAN,
        neck_prolate_ref: f64::NAN,
        v_bifurcation_ref: f64::NAN,
        v_fold_ref: f64::NAN,
        v_limit_ref: f64::NAN,
        neck_pear_ref: f64::NAN,
        e_pear_ref: f64::NAN,
        neck_unstable_ref: f64::NAN,
        e_unstable_ref: f64::NAN,
        state: state(m).to_string(),
        wall_seconds: 0.0,
    }
}

/// Fill the reference columns of `row` from the reading `r` at its v.
fn fill_reference(row: &mut Row, r: &Reading) {
    row.e_prolate_ref = r.e_prolate;
    row.v_bifurcation_ref = r.v_bifurcation;
    row.v_fold_ref = r.v_fold;
    row.v_limit_ref = r.v_limit;
    (row.neck_pear_ref, row.e_pear_ref) = r.stable;
    (row.neck_unstable_ref, row.e_unstable_ref) = r.unstable;
}

#[cfg(test)]
mod tests;
