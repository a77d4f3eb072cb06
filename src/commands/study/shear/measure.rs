//! One sheared vesicle: its scene, its run under the Stokes dynamics with the area held, and
//! what its steady state measures. In 2D the vesicle is a contour in the shear plane; in 3D a
//! surface on the half box mirrored about the shear plane z = 0 (the imposed shear u_x(y) is
//! even about it and odd about x = 0 and y = 0, so it is the only mirror plane the flow keeps).
//!
//! With I the second-moment tensor about the centroid, in the shear plane, of the region inside
//! the φ = 0 surface (I_xx = ∫(x − x̄)² dV, I_yy, I_xy; in 3D over the whole body), and ω_z the
//! vorticity of the Stokes flow,
//!
//! ```text
//! inclination  ψ = ½ atan2(2I_xy, I_xx − I_yy)                (the long axis against the flow)
//! deformation  D = (L − B)/(L + B),  L, B ∝ √(eigenvalues of I)
//! tank-treading  Ω/(γ̇/2) = −∫ω_z dV/(γ̇ V) = −∮(n_x u_y − n_y u_x) dA/(γ̇ V)
//!                                   (the mean vorticity inside, over that of the imposed shear)
//! ```
//!
//! All three are read from the facets of the φ = 0 surface ([`facets`]), never from the bulk:
//! the mobility lets the bulk's φ drift from ±1 by up to 5e-4 over a long run, and the diffuse
//! indicator (1 + φ)/2 summed over the box turned that into a false, still falling ψ: 18.6°
//! against 33.4° after 24 strains in a box 24 R0 long (start v = 0.95, R0 = 12ε).
//!
//! For a quasi-circle r = R(1 + b cos 2(θ − ψ)) or a quasi-sphere r = R(1 + a sin²θ
//! cos 2(φ − ψ)) these give ψ and D = b (or a) to first order in the amplitude.
//!
//! ψ and D are sampled over the run; the steady values are the means over its last quarter, and
//! the drift is ψ at the end minus ψ three quarters in. Ω is the mean over [`TURNING_SAMPLES`]
//! states of the last quarter, each from the Stokes flow of the state at its σ, recomputed by
//! an evaluator of the same box ([`Evaluator::velocity_at`]).

use super::spec::{Profile, Spec};
use crate::analysis::{drop_flow, facets, levelset};
use crate::commands::measure::{contour_length, inside_area};
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::spectral::evaluator::{Evaluator, ExplicitTerm};
use crate::error::{Error, Result};
use crate::output::image::bilinear;
use crate::problem::config::{self, Laplacian, Scene};
use crate::problem::flow::bending_modulus;
use crate::problem::grid::Grid;
use crate::problem::setup;
use ndarray::{Array3, Axis};
use serde_json::json;
use std::time::Instant;

/// One case: a reduced area and size, the capillary number, the channel, the box's length and
/// the profile.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// The start's reduced area.
    pub reduced_area: f64,
    /// R0/ε.
    pub r0: f64,
    /// Ca = ηγ̇R0³/κ.
    pub capillary: f64,
    /// W/R0.
    pub channel: f64,
    /// L/R0, the periodic box along the flow (and along z in 3D).
    pub length: f64,
    /// How the shear is imposed.
    pub profile: Profile,
    /// η_in/η_out.
    pub viscosity_ratio: f64,
}

impl Case {
    /// The sharp reference's Ω/(γ̇/2) for the contour of `phi` ([`sharp_tank_treading`]) where
    /// it describes this case's flow, simple shear at equal viscosities (walls, λ = 1); NaN
    /// under the Kolmogorov profile or a contrast.
    pub fn sharp_tank_treading(&self, grid: &Grid, phi: &Array3<f64>) -> f64 {
        if self.viscosity_ratio == 1.0 && self.profile == Profile::Walls {
            sharp_tank_treading(grid, phi)
        } else {
            f64::NAN
        }
    }
}

/// What one case measured; a row of `cases.csv`.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The case.
    pub case: Case,
    /// Grid points of the full box along each axis.
    pub points: Vec<usize>,
    /// The reduced area of the final φ = 0 contour (in 3D the reduced volume of the φ = 0
    /// surface).
    pub reduced_area: f64,
    /// The excess Δ of that contour's length (surface's area) over the circle's (sphere's) of
    /// the same enclosed area (volume): 2D v^(−1/2) − 1, 3D v^(−2/3) − 1 ([`excess`]).
    pub excess: f64,
    /// The reduced area (volume) of the phase field's own measures, 4πV/A² (6√π V/A^(3/2)),
    /// V = ∫χ and A = (3/(2√2))ε∫|∇φ|²: what the run holds.
    pub field_reduced_area: f64,
    /// The steady inclination, degrees.
    pub inclination: f64,
    /// ψ at the end minus ψ three quarters through the run, degrees.
    pub drift: f64,
    /// The relative change of the volume (area in 2D) inside the φ = 0 surface from the first
    /// state to the last ([`Inside`]). ∫φ is held to round-off, but the mobility
    /// lets the bulk's φ drift from −1 and take its share: 0.8% (walls 8R0 apart) and 1.6%
    /// (24R0 long) over 24 strains at R0 = 8ε, Ca = 1.
    pub volume_change: f64,
    /// The linear theory's ψ at this reduced area ([`linear_inclination`]), degrees.
    pub linear: f64,
    /// The same theory with the amplitude from v to first order ([`first_order_inclination`]),
    /// degrees: equal to `linear` in 2D; in 3D its distance to `linear` is the theory's own
    /// second-order ambiguity.
    pub linear_first_order: f64,
    /// The steady deformation D.
    pub deformation: f64,
    /// The linear theory's D = b (a in 3D).
    pub linear_deformation: f64,
    /// The mean rotation rate inside over γ̇/2.
    pub tank_treading: f64,
    /// The sharp-interface reference's Ω/(γ̇/2) for the final contour, in free space simple
    /// shear with equal viscosities ([`sharp_tank_treading`]). NaN where that is not the
    /// case's own flow: in 3D, with η_in ≠ η_out, and under the Kolmogorov profile.
    pub sharp_tank_treading: f64,
    /// σ̄ = σR0²/κ at the end.
    pub sigma_bar: f64,
    /// Steps run.
    pub steps: usize,
    /// Wall seconds.
    pub wall: f64,
    /// The final field on the full box (for its picture).
    pub phi: Array3<f64>,
}

/// The excess Δ of a closed contour's length over the circle's of the same area, or of a
/// closed surface's area over the sphere's of the same volume (R the equal-volume radius), in
/// terms of its reduced area (volume) v — exactly:
///
/// ```text
/// 2D: Δ = L/(2πR) − 1 = v^(−1/2) − 1,      3D: Δ = A/(4πR²) − 1 = v^(−2/3) − 1
/// ```
pub fn excess(v: f64, dim: usize) -> f64 {
    if dim == 3 {
        v.powf(-2.0 / 3.0) - 1.0
    } else {
        v.powf(-0.5) - 1.0
    }
}

/// The amplitude of the l = 2 (n = 2) shape at reduced area (volume) v, the linear theory's
/// D: in 2D b = √(2(1 − v)/3) (r = R(1 + b cos 2θ) has v = 1 − 3b²/2 + O(b⁴)); in 3D
/// a = √(15Δ/8) with Δ = [`excess`]`(v, 3)` (r = R(1 + a sin²θ cos 2φ) has Δ = 8a²/15).
pub fn amplitude(v: f64, dim: usize) -> f64 {
    if dim == 3 {
        (15.0 * excess(v, 3) / 8.0).sqrt()
    } else {
        (2.0 * (1.0 - v) / 3.0).sqrt()
    }
}

/// The steady inclination of the linear theory for this model (a global tension;
/// docs/src/theory/flow.md): cos 2ψ = 2b·g in 2D, cos 2ψ = 2a·g = √(15Δ/2)·g in 3D
/// ([`amplitude`]), with g = [`strain_slowing`]`(λ)` the factor by which a viscous inside slows
/// the shape's response to the imposed strain (1 at equal viscosities), in degrees (NaN where
/// the right side exceeds 1: no steady angle, the vesicle tumbles).
pub fn linear_inclination(v: f64, dim: usize, lambda: f64) -> f64 {
    0.5 * (2.0 * amplitude(v, dim) * strain_slowing(dim, lambda))
        .acos()
        .to_degrees()
}

/// 1/(the interface's normal velocity in an imposed linear flow over the flow's own) at
/// λ = η_in/η_out: (1 + λ)/2 in 2D, (2λ + 3)/5 in 3D (the l = 2 drop in a regular incident
/// flow, velocity and tangential stress continuous; docs/src/theory/flow.md). In the linear
/// theory the amplitude is held by the tension, so the relaxation's own factor drops out and
/// cos 2ψ scales by this one.
pub fn strain_slowing(dim: usize, lambda: f64) -> f64 {
    if dim == 3 {
        (2.0 * lambda + 3.0) / 5.0
    } else {
        (1.0 + lambda) / 2.0
    }
}

/// [`linear_inclination`] with Δ replaced by its first order in 1 − v: in 3D Δ = 2(1 − v)/3 +
/// O((1 − v)²), so cos 2ψ = √(5(1 − v)); in 2D the amplitude is already written so, and this is
/// [`linear_inclination`].
pub fn first_order_inclination(v: f64, dim: usize, lambda: f64) -> f64 {
    if dim == 3 {
        0.5 * ((5.0 * (1.0 - v)).sqrt() * strain_slowing(dim, lambda))
            .acos()
            .to_degrees()
    } else {
        linear_inclination(v, dim, lambda)
    }
}

/// The scene of `case`: a 2D ellipse (3D prolate spheroid along the flow) of the reduced area
/// (volume) in a box of `length`·R0 along the flow (and along z in 3D, mirrored about z = 0)
/// and `channel`·R0 across it, adaptive SBDF2 with the area held, for `strains`/γ̇.
///
/// # Errors
/// `Error::Config` if the scene is invalid or too large.
pub fn scene(spec: &Spec, case: &Case) -> Result<Scene> {
    let (h, r0) = (spec.h_over_eps, case.r0);
    let rate = case.capillary * bending_modulus(1.0) / (spec.viscosity * r0.powi(3));
    let points = |length: f64| 2 * ((length * r0 / h / 2.0).round() as usize);
    let walls: Vec<&str> = match case.profile {
        Profile::Walls => vec!["y"],
        Profile::Kolmogorov => vec![],
    };
    let (n, symmetry) = if spec.dimension == 3 {
        let (x, y) = (points(case.length), points(case.channel));
        (vec![x, y, x], vec!["z"])
    } else {
        (vec![points(case.length), points(case.channel)], vec![])
    };
    let value = json!({
        "description": format!("shear study: {}D v {} R0 {} Ca {} W/R0 {} L/R0 {} {} eta_in/eta_out {}",
            spec.dimension, case.reduced_area, r0, case.capillary, case.channel, case.length,
            case.profile.name(), case.viscosity_ratio),
        "dim": spec.dimension, "n": n, "h": h, "eps": 1.0, "symmetry": symmetry,
        "scheme": "sbdf2", "dt": 0.5, "adaptive": {"dt_max": spec.dt_max},
        "t_end": spec.strains / rate,
        "prepare_steps": 20,
        "dynamics": "stokes",
        "flow": {"viscosity": spec.viscosity, "mobility": spec.mobility, "shear_rate": rate,
                 "viscosity_inside": case.viscosity_ratio * spec.viscosity},
        "walls": walls,
        "initial": {"shape": "spheroid", "reduced_volume": case.reduced_area, "r0": r0,
                    "kind": "prolate", "axis": "x"},
    });
    let scene = config::from_value(value)?;
    crate::problem::memory::check(&scene)?;
    Ok(scene)
}

/// How many states of a run's last quarter the tank-treading rate is averaged over: its value
/// at one state wanders by ±5% about the mean at steady ψ and D (0.85–0.95 against a mean of
/// 0.875 at v = 0.9, R0 = 12ε), so one sample is not the steady value.
const TURNING_SAMPLES: usize = 64;

/// Run `case` to its steady state and measure it.
///
/// # Errors
/// `Error::Config` for an invalid scene; `Error::Blowup` if the run diverges.
pub fn run(spec: &Spec, case: &Case) -> Result<Measured> {
    let started = Instant::now();
    let scene = scene(spec, case)?;
    let problem = setup::build(&scene)?;
    let grid = problem.grid.clone();
    let (mut sim, _) = Simulation::of_scene(&scene, &problem)?;
    let t_end = scene.t_end.unwrap_or(f64::NAN);
    let flow = scene.flow.expect("a stokes scene");
    let rate = flow.shear_rate.expect("a sheared scene");
    let mut ev = Evaluator::new(
        grid.clone(),
        scene.eps,
        problem.c0.clone(),
        Laplacian::Spectral,
        ExplicitTerm::ConservedRhs,
        1,
    )
    .with_flow(flow);
    let mut samples: Vec<(f64, f64, f64)> = Vec::new();
    let mut turning: Vec<f64> = Vec::new();
    let mut steps = 0;
    let mut start_volume = None;
    let mut probe = Probe(|now: &Now| {
        let phi = now.engine.phi();
        start_volume.get_or_insert_with(|| Inside::of(&grid, phi).volume);
        let (psi, d) = moments(&grid, phi);
        samples.push((now.record.t, psi, d));
        steps = now.record.step;
        // Ω at TURNING_SAMPLES times evenly spread over the last quarter (the first state at or
        // past each).
        let next = 0.75 * t_end + 0.25 * t_end * turning.len() as f64 / TURNING_SAMPLES as f64;
        if now.record.t >= next && turning.len() < TURNING_SAMPLES {
            let u = ev
                .velocity_at(phi, now.engine.sigma())
                .map_err(|_| Error::config("initial", "a state of the run is not finite"))?
                .expect("the evaluator has the flow");
            turning.push(-mean_vorticity(&grid, phi, &u) / rate);
        }
        Ok(Flow::Continue)
    });
    sim.run(&StopRules::of(&scene), &mut [&mut probe])?;
    let engine = sim.engine();
    let (phi, sigma) = (engine.phi().clone(), engine.sigma());
    let field_reduced_area = engine.measures().reduced(grid.dim, scene.eps).volume;
    let v = surface_reduced_area(&grid, &phi);
    let tail: Vec<&(f64, f64, f64)> = samples.iter().filter(|s| s.0 >= 0.75 * t_end).collect();
    if tail.len() < 2 {
        return Err(Error::config(
            "strains",
            "too few states in the run's last quarter; raise strains",
        ));
    }
    let mean =
        |f: fn(&(f64, f64, f64)) -> f64| tail.iter().map(|s| f(s)).sum::<f64>() / tail.len() as f64;
    Ok(Measured {
        case: *case,
        points: scene.n.clone(),
        reduced_area: v,
        excess: excess(v, grid.dim),
        field_reduced_area,
        inclination: mean(|s| s.1),
        drift: tail[tail.len() - 1].1 - tail[0].1,
        volume_change: Inside::of(&grid, &phi).volume / start_volume.unwrap_or(f64::NAN) - 1.0,
        linear: linear_inclination(v, grid.dim, case.viscosity_ratio),
        linear_first_order: first_order_inclination(v, grid.dim, case.viscosity_ratio),
        deformation: mean(|s| s.2),
        linear_deformation: amplitude(v, grid.dim),
        tank_treading: turning.iter().sum::<f64>() / turning.len() as f64,
        sharp_tank_treading: case.sharp_tank_treading(&grid, &phi),
        sigma_bar: sigma * case.r0 * case.r0 / bending_modulus(1.0),
        steps,
        wall: started.elapsed().as_secs_f64(),
        phi: grid.unfold(&phi).into_owned(),
    })
}

/// The reduced area 4πS/P² of the φ = 0 contour (its enclosed area S and length P by
/// marching squares, [`inside_area`] and [`contour_length`]), or in 3D the reduced volume
/// 6√π V₀/A₀^(3/2) of the φ = 0 surface ([`levelset::measure_refined`] on the unfolded box):
/// the shape's own, which the phase field's measures read higher by O((ε/R0)²) — 0.941
/// against 0.900 at R0 = 8ε in 2D.
fn surface_reduced_area(grid: &Grid, phi: &Array3<f64>) -> f64 {
    if grid.dim == 3 {
        return levelset::measure_refined(&grid.unfold(phi), 3, grid.h).reduced_volume;
    }
    let slice = phi.index_axis(Axis(0), 0);
    let (s, p) = (inside_area(slice, grid.h), contour_length(slice, grid.h));
    4.0 * std::f64::consts::PI * s / (p * p)
}

/// The internal axes of x and y (the shear plane): 1 and 2 of a 2D field `[1, nx, ny]`, 0
/// and 1 of a 3D one.
fn plane_axes(grid: &Grid) -> (usize, usize) {
    let x = 3 - grid.dim;
    (x, x + 1)
}

/// (ψ in degrees, D) of the field `phi` on `grid` (module documentation), from the second
/// moments in the shear plane of the region inside its φ = 0 surface ([`Inside`]).
pub fn moments(grid: &Grid, phi: &Array3<f64>) -> (f64, f64) {
    let [ixx, ixy, iyy] = Inside::of(grid, phi).second;
    let psi = 0.5 * (2.0 * ixy).atan2(ixx - iyy);
    let (half_sum, half_diff) = (
        0.5 * (ixx + iyy),
        (0.25 * (ixx - iyy).powi(2) + ixy * ixy).sqrt(),
    );
    let (long, short) = ((half_sum + half_diff).sqrt(), (half_sum - half_diff).sqrt());
    (psi.to_degrees(), (long - short) / (long + short))
}

/// The region inside the φ = 0 surface of `phi` (unfolded to the full box), in the shear
/// plane: its volume (area in 2D), centroid and second moments about the centroid.
struct Inside {
    /// V.
    volume: f64,
    /// (x̄, ȳ) at grid point (i, j) ↦ (i h, j h) of the unfolded box.
    centroid: [f64; 2],
    /// [I_xx, I_xy, I_yy].
    second: [f64; 3],
}

impl Inside {
    /// One pass over the facets of [`facets`], by the divergence theorem
    ///
    /// ```text
    /// V = ∮ x n_x,  V x̄ = ∮ (x²/2) n_x,  V ȳ = ∮ (y²/2) n_y,
    /// ∫x² = ∮ (x³/3) n_x,  ∫xy = ∮ (x²y/2) n_x,  ∫y² = ∮ (y³/3) n_y
    /// ```
    ///
    /// (x, y measured from the box's centre). Exact for the piecewise-linear surface, and blind
    /// to φ away from it: the bulk's small departures from ±1, which the mobility lets grow
    /// over the whole box (by 5e-4 over 24 strains at R0 = 8ε, Ca = 1), would weigh
    /// Σ(1 + φ)/2 by the box's size.
    fn of(grid: &Grid, phi: &Array3<f64>) -> Self {
        let (ax, ay) = plane_axes(grid);
        let full = grid.unfold(phi);
        let centre = |a: usize| 0.5 * (full.shape()[a] - 1) as f64 * grid.h;
        let (x0, y0) = (centre(ax), centre(ay));
        let mut m = [0.0; 6];
        facets::for_each(&full, grid.h, |f| {
            let (nx, ny) = (f.normal[ax], f.normal[ay]);
            let terms = [
                nx * f.mean(|p, _| p[ax] - x0),
                nx * f.mean(|p, _| (p[ax] - x0).powi(2) / 2.0),
                ny * f.mean(|p, _| (p[ay] - y0).powi(2) / 2.0),
                nx * f.mean(|p, _| (p[ax] - x0).powi(3) / 3.0),
                nx * f.mean(|p, _| (p[ax] - x0).powi(2) * (p[ay] - y0) / 2.0),
                ny * f.mean(|p, _| (p[ay] - y0).powi(3) / 3.0),
            ];
            m.iter_mut().zip(terms).for_each(|(s, t)| *s += t);
        });
        let [v, sx, sy, sxx, sxy, syy] = m;
        let (cx, cy) = (sx / v, sy / v);
        Inside {
            volume: v,
            centroid: [x0 + cx, y0 + cy],
            second: [sxx - v * cx * cx, sxy - v * cx * cy, syy - v * cy * cy],
        }
    }
}

/// How many angles the final contour is sampled at for [`sharp_tank_treading`].
const CONTOUR_SAMPLES: usize = 128;

/// Ω/(γ̇/2) of the sharp-interface drop-like membrane with the final φ = 0 contour's shape
/// ([`drop_flow::tank_treading`]: free space, equal viscosities), or NaN in 3D. The contour is
/// sampled as r(θ) about the inside's centroid at [`CONTOUR_SAMPLES`] angles: the first zero
/// of φ's bilinear interpolant along each ray, found by steps of h/4 and bisection (NaN when
/// the centroid lies outside, as between two pieces, or the inside reaches the box's edge).
pub fn sharp_tank_treading(grid: &Grid, phi: &Array3<f64>) -> f64 {
    if grid.dim != 2 {
        return f64::NAN;
    }
    let h = grid.h;
    // The centroid is placed on the unfolded box, so the rays read the unfolded field.
    let full = grid.unfold(phi);
    let slice = full.index_axis(Axis(0), 0);
    let [cx, cy] = Inside::of(grid, phi).centroid;
    // No ray runs farther than the box's diagonal.
    let longest = h * (slice.shape()[0] as f64).hypot(slice.shape()[1] as f64);
    let radius: Vec<f64> = (0..CONTOUR_SAMPLES)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / CONTOUR_SAMPLES as f64;
            let along = |r: f64| bilinear(slice, (cx + r * t.cos()) / h, (cy + r * t.sin()) / h);
            let mut r = 0.0;
            while along(r + 0.25 * h) > 0.0 && r < longest {
                r += 0.25 * h;
            }
            let (mut lo, mut hi) = (r, r + 0.25 * h);
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                if along(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        })
        .collect();
    // A ray that leaves the inside at once (the centroid is outside), or never (the inside
    // reaches the box's edge).
    if radius.iter().any(|&r| r < h || r >= longest) {
        return f64::NAN;
    }
    drop_flow::tank_treading(&radius).rate
}

/// The mean z-vorticity inside the φ = 0 surface, by Stokes' theorem
/// ∫ ω_z dV = ∮ (n_x u_y − n_y u_x) dA over its facets, divided by the volume ∮ x n_x dA from
/// the same pass (in 2D the circulation around the contour over the area it encloses).
/// u (u_x and u_y first) is read on the facets by the linear interpolation that places them.
fn mean_vorticity(grid: &Grid, phi: &Array3<f64>, u: &[Array3<f64>]) -> f64 {
    let (ax, ay) = plane_axes(grid);
    let (full, ux, uy) = (grid.unfold(phi), grid.unfold(&u[0]), grid.unfold(&u[1]));
    let (mut circulation, mut volume) = (0.0, 0.0);
    facets::for_each(&full, grid.h, |f| {
        let (nx, ny) = (f.normal[ax], f.normal[ay]);
        circulation += f.mean(|_, l| nx * f.read(&uy, l) - ny * f.read(&ux, l));
        volume += nx * f.mean(|p, _| p[ax]);
    });
    circulation / volume
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The linear theory's figures: in 2D v = 0.9 gives b = 0.2582 and ψ = ½ arccos(0.5164) =
    /// 29.45°; 2b reaches 1 at v = 5/8, where the formula ends. In 3D v = 0.9 gives Δ =
    /// 0.9^(−2/3) − 1 = 0.07277, a = √(15Δ/8) = 0.3694 and ψ = 21.19°, and to first order in
    /// 1 − v cos 2ψ = √(5 · 0.1), ψ = 22.5°; 2a reaches 1 at Δ = 2/15, v = (17/15)^(−3/2) =
    /// 0.8288.
    #[test]
    fn the_linear_theory_gives_its_figures() {
        assert!((amplitude(0.9, 2) - 0.258_198_9).abs() < 1e-6);
        assert!((linear_inclination(0.9, 2, 1.0) - 29.45).abs() < 0.01);
        assert_eq!(
            first_order_inclination(0.9, 2, 1.0),
            linear_inclination(0.9, 2, 1.0)
        );
        assert!(linear_inclination(0.625, 2, 1.0).abs() < 1e-6);
        assert!(linear_inclination(0.6, 2, 1.0).is_nan());
        assert!((excess(0.9, 3) - 0.072_766).abs() < 1e-6);
        assert!((amplitude(0.9, 3) - 0.369_373).abs() < 1e-6);
        assert!((linear_inclination(0.9, 3, 1.0) - 21.19).abs() < 0.01);
        assert!((first_order_inclination(0.9, 3, 1.0) - 22.5).abs() < 1e-9);
        let end = (17.0f64 / 15.0).powf(-1.5);
        assert!(linear_inclination(end, 3, 1.0).abs() < 1e-4);
        assert!(linear_inclination(end - 1e-3, 3, 1.0).is_nan());
    }

    /// The excess of a quasi-sphere r = R(1 + a sin²θ cos 2φ) is 8a²/15 to second order (the
    /// relation the 3D amplitude uses): its area and volume, integrated on a (θ, φ) grid, give
    /// Δ = v^(−2/3) − 1 within 2% of 8a²/15 at a = 0.05 (the rest is O(a³)).
    #[test]
    fn a_quasi_sphere_has_the_excess_of_the_theory() {
        use std::f64::consts::PI;
        let a = 0.05;
        let (nt, np) = (400, 400);
        let (mut area, mut volume) = (0.0, 0.0);
        for it in 0..nt {
            let t = (it as f64 + 0.5) * PI / nt as f64;
            for ip in 0..np {
                let p = (ip as f64 + 0.5) * 2.0 * PI / np as f64;
                let r = 1.0 + a * t.sin().powi(2) * (2.0 * p).cos();
                let rt = a * 2.0 * t.sin() * t.cos() * (2.0 * p).cos();
                let rp = -2.0 * a * t.sin().powi(2) * (2.0 * p).sin();
                let d = (PI / nt as f64) * (2.0 * PI / np as f64);
                // |∂_θx × ∂_φx| = r √(r² sin²θ + r_θ² sin²θ + r_φ²).
                area +=
                    r * (r * r * t.sin().powi(2) + rt * rt * t.sin().powi(2) + rp * rp).sqrt() * d;
                volume += r.powi(3) / 3.0 * t.sin() * d;
            }
        }
        let v = 6.0 * PI.sqrt() * volume / area.powf(1.5);
        let expected = 8.0 * a * a / 15.0;
        assert!(
            (excess(v, 3) - expected).abs() < 0.02 * expected,
            "{} against {expected}",
            excess(v, 3)
        );
    }

    /// A prolate ellipsoid of semi-axes 1.2, 0.8, 0.8 turned by 30° about z, on the half box
    /// mirrored about z = 0, reads ψ = 30° and D = 0.2 from its moments in the x–y plane (the
    /// same as the full box's).
    #[test]
    fn moments_read_a_tilted_ellipsoid_on_the_half_box() {
        let grid = Grid::new(&[100, 100, 80], 0.04, &[false, false, true]);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let phi = grid.field_from(|[x, y, z]| {
            let (a, b) = (c * x + s * y, -s * x + c * y);
            if (a / 1.2).powi(2) + (b / 0.8).powi(2) + (z / 0.8).powi(2) < 1.0 {
                1.0
            } else {
                -1.0
            }
        });
        assert_eq!(phi.shape(), &[100, 100, 40]);
        let (psi, d) = moments(&grid, &phi);
        assert!((psi - 30.0).abs() < 0.2, "{psi}");
        assert!((d - 0.2).abs() < 0.005, "{d}");
    }

    /// An ellipse of semi-axes 1.2 and 0.8 turned by 30° reads ψ = 30° and D = 0.2 (the
    /// square roots of I's eigenvalues are in the ratio of the axes).
    #[test]
    fn moments_read_an_ellipse() {
        let grid = Grid::new(&[200, 200], 0.02, &[false, false]);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let phi = grid.field_from(|[x, y, _]| {
            let (a, b) = (c * x + s * y, -s * x + c * y);
            if (a / 1.2).powi(2) + (b / 0.8).powi(2) < 1.0 {
                1.0
            } else {
                -1.0
            }
        });
        let (psi, d) = moments(&grid, &phi);
        assert!((psi - 30.0).abs() < 0.2, "{psi}");
        assert!((d - 0.2).abs() < 0.005, "{d}");
    }

    /// The bulk's φ does not reach the moments: a diffuse ellipse (semi-axes 1.2, 0.8, turned
    /// by 30°, tanh profile of width 0.05) in a box 12 long reads the same ψ and D with the
    /// bulk raised by 1e-3 everywhere (which only moves the φ = 0 contour outward by 6e-5)
    /// to 0.01°. Σ(1 + φ)/2 over the box would add 5e-4 × ∫x² dA = 0.144 to the ellipse's
    /// I_xx = 0.946 and read ψ = 24.9° instead of 30.0°.
    #[test]
    fn moments_ignore_the_bulk() {
        let grid = Grid::new(&[600, 100], 0.02, &[false, false]);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let field = |bulk: f64| {
            grid.field_from(|[x, y, _]| {
                let (a, b) = (c * x + s * y, -s * x + c * y);
                let r = ((a / 1.2).powi(2) + (b / 0.8).powi(2)).sqrt();
                bulk - ((r - 1.0) / 0.05).tanh()
            })
        };
        let (psi, d) = moments(&grid, &field(0.0));
        let (psi_raised, d_raised) = moments(&grid, &field(1e-3));
        assert!((psi - 30.0).abs() < 0.2, "{psi}");
        assert!(
            (psi_raised - psi).abs() < 0.01,
            "{psi_raised} against {psi}"
        );
        assert!((d_raised - d).abs() < 1e-3, "{d_raised} against {d}");
    }

    /// The sharp rate of a diffuse tilted ellipse (semi-axes 1.2 and 0.8 at 30°, tanh width
    /// 0.05, h = 0.02) is that of the exact ellipse (1.032), to 1e-3: the contour is read where
    /// it is.
    #[test]
    fn the_sharp_rate_reads_the_contour() {
        let grid = Grid::new(&[200, 160], 0.02, &[false, false]);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let phi = grid.field_from(|[x, y, _]| {
            let (a, b) = (c * x + s * y, -s * x + c * y);
            -((((a / 1.2).powi(2) + (b / 0.8).powi(2)).sqrt() - 1.0) / 0.05).tanh()
        });
        let exact: Vec<f64> = (0..128)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / 128.0 - 30f64.to_radians();
                1.0 / ((t.cos() / 1.2).powi(2) + (t.sin() / 0.8).powi(2)).sqrt()
            })
            .collect();
        let (read, expected) = (
            sharp_tank_treading(&grid, &phi),
            drop_flow::tank_treading(&exact).rate,
        );
        assert!((read - expected).abs() < 1e-3, "{read} against {expected}");
        assert!(
            (expected - 1.0).abs() > 0.02,
            "a rate unlike a circle's: {expected}"
        );
        // A case reads it between walls at λ = 1 only.
        let case = |profile, viscosity_ratio| Case {
            reduced_area: 0.9,
            r0: 10.0,
            capillary: 1.0,
            channel: 8.0,
            length: 16.0,
            profile,
            viscosity_ratio,
        };
        assert_eq!(
            case(Profile::Walls, 1.0).sharp_tank_treading(&grid, &phi),
            read
        );
        assert!(case(Profile::Walls, 2.0)
            .sharp_tank_treading(&grid, &phi)
            .is_nan());
        assert!(case(Profile::Kolmogorov, 1.0)
            .sharp_tank_treading(&grid, &phi)
            .is_nan());
    }

    /// On a box mirrored about both axes the rays read the unfolded field about the unfolded
    /// box's centroid: the same rate as the full box's for the same ellipse (to 1e-12; rays
    /// on the quarter alone about that centroid would leave it at once and read NaN).
    #[test]
    fn the_sharp_rate_reads_a_mirrored_box_unfolded() {
        let ellipse = |grid: &Grid| {
            grid.field_from(|[x, y, _]| {
                -((((x / 1.2).powi(2) + (y / 0.8).powi(2)).sqrt() - 1.0) / 0.05).tanh()
            })
        };
        let full = Grid::new(&[200, 160], 0.02, &[false, false]);
        let quarter = Grid::new(&[200, 160], 0.02, &[true, true]);
        let (a, b) = (
            sharp_tank_treading(&full, &ellipse(&full)),
            sharp_tank_treading(&quarter, &ellipse(&quarter)),
        );
        assert!(a.is_finite() && (a - b).abs() < 1e-12, "{b} against {a}");
    }

    /// Two separate circles have their centroid outside both: no contour about it, NaN.
    #[test]
    fn the_sharp_rate_needs_the_centroid_inside() {
        let grid = Grid::new(&[200, 100], 0.02, &[false, false]);
        let phi = grid.field_from(|[x, y, _]| {
            let r = ((x.abs() - 1.0).powi(2) + y * y).sqrt();
            -((r - 0.5) / 0.05).tanh()
        });
        assert!(sharp_tank_treading(&grid, &phi).is_nan());
    }

    /// The contrast's slowing of the strain response: at λ = 1 nothing changes (2D and 3D); in
    /// 2D cos 2ψ = 2b(1 + λ)/2, so at v = 0.9 (2b = 0.5164) λ = 2 gives ψ = ½ arccos(0.7746) =
    /// 19.616°, the angle reaches 0 at λ_c = 1/b − 1 = 2.873 and there is none beyond (NaN: the
    /// vesicle tumbles); in 3D the factor is (2λ + 3)/5 (the l = 2 drop's response 5/(2λ + 3)).
    #[test]
    fn a_viscous_inside_lowers_the_angle_to_tumbling() {
        for dim in [2, 3] {
            assert_eq!(strain_slowing(dim, 1.0), 1.0);
        }
        assert!((linear_inclination(0.9, 2, 2.0) - 19.616).abs() < 1e-3);
        let b = amplitude(0.9, 2);
        let critical = 1.0 / b - 1.0;
        assert!((critical - 2.873).abs() < 1e-3, "{critical}");
        assert!(linear_inclination(0.9, 2, critical - 1e-9).abs() < 1e-3);
        assert!(linear_inclination(0.9, 2, critical + 1e-3).is_nan());
        assert!((strain_slowing(3, 4.0) - 11.0 / 5.0).abs() < 1e-15);
    }
}
