//! One case of a diagram: the axisymmetric start of a branch at a reduced volume and reduced
//! spontaneous curvature c̄0, scaled to R0 = `r0` ε (the scene's uniform c0 = c̄0/`r0`), relaxed by L-BFGS on its symmetry-reduced box to the stationarity tolerance,
//! and measured. Every case runs on one thread, so its numbers do not depend on how a sweep
//! is spread over processes.

use super::spec::{Case, Couple, DiagramSpec, SliceAt};
use crate::analysis::axisym::{self, Branch};
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use crate::output::shade::{self, Bounds, View};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

/// What a case measured (`result.json` of its folder).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub struct CaseResult {
    /// The case number.
    pub index: usize,
    /// Branch name.
    pub branch: String,
    /// Target reduced volume (of the sharp start).
    pub v_target: f64,
    /// Reduced spontaneous curvature c̄0 of the sharp start (the scene's c0 is c̄0/`r0`).
    #[serde(default)]
    pub c0: f64,
    /// ADE's α (an ADE diagram's case).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// ADE's Δa0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub da0: Option<f64>,
    /// The Δa the bilayer couple holds (a bilayer-couple diagram's case).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bc_da: Option<f64>,
    /// Δa of the phase field (M/M₁, the record's), with ADE.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub da: Option<f64>,
    /// e alone (the record's `bending_energy`), with ADE; `e` is then w.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending_energy: Option<f64>,
    /// R0/ε.
    pub r0: f64,
    /// Full-box grid.
    pub n: [usize; 3],
    /// Computed points (reduced box).
    pub points: usize,
    /// Reduced volume of the φ = 0 surface ([`crate::analysis::levelset::measure_refined`]).
    pub v: f64,
    /// Δa of the φ = 0 surface ([`crate::analysis::levelset::measure_surface`]); absent from
    /// results written before it was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub da_surface: Option<f64>,
    /// Volume skewness of {φ > 0} along the axis ([`crate::commands::measure::skewness`]): 0 for
    /// an up–down symmetric shape, so it tells a pear or a stomatocyte that kept its asymmetry
    /// from one that relaxed to a symmetric shape; absent from results written before it was
    /// measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skewness: Option<f64>,
    /// Diffuse reduced volume from ∫(1 + φ)/2 and the diffuse area.
    pub v_diffuse: f64,
    /// Reduced bending energy e = ∮(2H − c0)² dA / 16π of the phase field (the record's);
    /// with ADE, w = e + πα(Δa − Δa0)².
    pub e: f64,
    /// σ (the area multiplier), in units of the scene (ε = 1).
    pub sigma: f64,
    /// Final stationarity residual RMS(μ − μ̄).
    pub residual: f64,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// How the relaxation ended (`stationary` when the tolerance was met).
    pub stopped: String,
    /// Wall time of the case (building the field, preparing, relaxing, measuring), seconds.
    pub wall_seconds: f64,
}

impl CaseResult {
    /// The slice the case belongs to.
    pub fn slice(&self) -> SliceAt {
        let ade = self
            .alpha
            .zip(self.da0)
            .map(|(alpha, da0)| Couple::Ade { alpha, da0 });
        SliceAt {
            c0: self.c0,
            couple: ade.or(self.bc_da.map(|da| Couple::Bc { da })),
        }
    }

    /// Whether the relaxation met its tolerance.
    pub fn converged(&self) -> bool {
        self.stopped == "stationary"
    }
}

/// Smallest even `m ≥ n` whose half has no prime factor above 5 (fast transform lengths).
pub(crate) fn transform_friendly(n: usize) -> usize {
    let smooth = |mut k: usize| {
        for p in [2, 3, 5] {
            while k.is_multiple_of(p) {
                k /= p;
            }
        }
        k == 1
    };
    let mut m = n.div_ceil(2);
    while !smooth(m) {
        m += 1;
    }
    2 * m
}

/// Full-box grid `[n_ρ, n_ρ, n_z]` (symmetry axis z) for the sharp shape `shape` (R0 = 1)
/// scaled to `r0`: its extent plus `margin + margin_r0·r0` on every side, at h = 1/eps_over_h.
pub fn grid_for(shape: &axisym::Solution, r0: f64, spec: &DiagramSpec) -> [usize; 3] {
    let (zmin, zmax) = shape
        .z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| {
            (a.min(z), b.max(z))
        });
    let rmax = shape.r.iter().cloned().fold(0.0, f64::max);
    let margin = spec.margin + spec.margin_r0 * r0;
    let points = |half: f64| transform_friendly(2 * (half * spec.eps_over_h).ceil() as usize);
    let radial = points(rmax * r0 + margin);
    [radial, radial, points(0.5 * (zmax - zmin) * r0 + margin)]
}

/// Mirror planes a branch keeps about the z axis.
fn mirror_planes(branch: Branch) -> &'static [&'static str] {
    if branch.up_down_symmetric() {
        &["x", "y", "z"]
    } else {
        &["x", "y"]
    }
}

/// Points computed on the reduced box of a `branch` case whose full box is `n`.
pub fn computed_points(branch: Branch, n: [usize; 3]) -> usize {
    n.iter().product::<usize>() >> mirror_planes(branch).len()
}

/// The scene of `case` (contour file `contour.csv` beside it); it sets `c0` = c̄0/`r0` where
/// c̄0 ≠ 0.
pub fn scene_json(spec: &DiagramSpec, case: &Case, n: [usize; 3]) -> serde_json::Value {
    let at_c0 = if case.c0 == 0.0 && case.couple.is_none() {
        String::new()
    } else {
        format!(", {}", case.slice().describe())
    };
    let mut scene = json!({
        "description": format!(
            "diagram case {}: {} branch at v = {}{at_c0}, R0 = {} eps, relaxed by L-BFGS to residual {:e}",
            case.index, case.branch.name(), case.v, case.r0, spec.stop_residual
        ),
        "dim": 3,
        "n": n,
        "h": 1.0 / spec.eps_over_h,
        "eps": 1.0,
        "dynamics": "relaxational",
        "dt": 0.01,
        "max_steps": spec.max_iterations,
        "stop_residual": spec.stop_residual,
        "initial": {"shape": "axisym", "contour": "contour.csv", "r0": case.r0, "axis": "z"},
        "prepare_steps": spec.prepare_steps,
        "symmetry": mirror_planes(case.branch),
        "threads": 1,
        "output": {"png": false, "vti": false}
    });
    if case.c0 != 0.0 {
        scene["c0"] = json!(case.scene_c0());
    }
    if let Some(couple) = case.couple {
        let (key, value) = couple.scene_entry();
        scene[key] = value;
    }
    scene
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Run `case` with the sharp start `shape` (the branch at `case.v` and `case.c0`, R0 = 1) in the folder
/// `dir` (created; it must not hold a result yet): writes `contour.csv`, `scene.json` (which
/// `vesicle run` accepts as it is), `thumbnail.png` when the spec asks for one, and last, by
/// an atomic rename, `result.json`.
///
/// # Errors
/// `Error::Config` if the scene is refused; `Error::Blowup` if the relaxation fails; I/O errors.
pub fn run_case(
    spec: &DiagramSpec,
    case: &Case,
    shape: &axisym::Solution,
    dir: &Path,
) -> Result<CaseResult> {
    let start = Instant::now();
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let contour = dir.join("contour.csv");
    let text: String = std::iter::once("r,z\n".to_string())
        .chain(
            shape
                .r
                .iter()
                .zip(&shape.z)
                .map(|(r, z)| format!("{r:.15e},{z:.15e}\n")),
        )
        .collect();
    std::fs::write(&contour, text).map_err(io(&contour))?;
    let n = grid_for(shape, case.r0, spec);
    let scene_path = dir.join("scene.json");
    let scene_text = serde_json::to_string_pretty(&scene_json(spec, case, n)).expect("json");
    std::fs::write(&scene_path, scene_text).map_err(io(&scene_path))?;
    let scene = crate::problem::config::load(&scene_path, &[])?;
    let problem = crate::problem::setup::build(&scene)?;
    let (mut sim, _a0) = Simulation::of_scene(&scene, &problem)?;
    let stopped = sim.run(&StopRules::of(&scene), &mut [])?;
    let last = sim.record();
    let full = problem.grid.unfold(sim.engine().phi());
    let surface = crate::analysis::levelset::measure_surface(&full, scene.h);
    if spec.thumbnails.iter().any(|v| (v - case.v).abs() < 1e-9) && case.r0 == spec.finest() {
        write_thumbnail(&full, scene.h, case, &dir.join("thumbnail.png"))?;
    }
    let result = CaseResult {
        index: case.index,
        branch: case.branch.name().to_string(),
        v_target: case.v,
        c0: case.c0,
        alpha: match case.couple {
            Some(Couple::Ade { alpha, .. }) => Some(alpha),
            _ => None,
        },
        da0: match case.couple {
            Some(Couple::Ade { da0, .. }) => Some(da0),
            _ => None,
        },
        bc_da: match case.couple {
            Some(Couple::Bc { da }) => Some(da),
            _ => None,
        },
        da: last.couple.map(|c| c.da),
        bending_energy: last.couple.map(|c| c.bending_energy),
        r0: case.r0,
        n,
        points: problem.grid.len(),
        v: surface.level.reduced_volume,
        da_surface: Some(surface.area_difference),
        skewness: Some(skewness_along_axis(&full, scene.h)),
        v_diffuse: last.reduced_volume,
        e: last.reduced_energy,
        sigma: last.sigma,
        residual: last.residual,
        iterations: last.step,
        stopped: stopped.as_str().to_string(),
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    let path = dir.join("result.json");
    let tmp = dir.join("result.json.tmp");
    let json = serde_json::to_string_pretty(&result).expect("json");
    std::fs::write(&tmp, json).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &path).map_err(io(&path))?;
    Ok(result)
}

/// [`crate::commands::measure::skewness`] of the full-box field `full` along the shape's axis z.
fn skewness_along_axis(full: &ndarray::Array3<f64>, h: f64) -> f64 {
    use crate::commands::measure;
    let axis = crate::commands::render::axis_index("z").expect("z is an axis");
    measure::skewness(&measure::radius_profile(full, axis, h), h)
}

/// A small shaded picture of the φ = 0 surface, seen from the side (the stomatocyte cut open
/// across its axis so the invagination shows).
fn write_thumbnail(full: &ndarray::Array3<f64>, h: f64, case: &Case, path: &Path) -> Result<()> {
    let mesh = crate::analysis::surface::extract(full, h);
    let s = full.shape();
    let view = View {
        width: 240,
        height: 240,
        elevation_deg: 15.0,
        cut: (case.branch == Branch::Stomatocyte).then_some(1),
        ..View::default()
    };
    let title = if case.c0 == 0.0 && case.couple.is_none() {
        format!("{} v = {}", case.branch.name(), case.v)
    } else {
        format!(
            "{} v = {}, {}",
            case.branch.name(),
            case.v,
            case.slice().describe()
        )
    };
    let bounds = Bounds::of_grid([s[0], s[1], s[2]], h);
    shade::render(&mesh, &bounds, &view, &title)?.write_png(path)?;
    Ok(())
}

/// Read the result of the case in `dir`, if it finished.
///
/// # Errors
/// `Error::Config` (field `--merge`) if the file exists but cannot be read.
pub fn read_result(dir: &Path) -> Result<Option<CaseResult>> {
    let path = dir.join("result.json");
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).map_err(io(&path))?;
    serde_json::from_str(&text).map(Some).map_err(|e| {
        Error::config(
            "--merge",
            format!("{} is not a case result: {e}", path.display()),
        )
    })
}
