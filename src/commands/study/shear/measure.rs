//! One sheared vesicle: its scene, its run under the Stokes dynamics with the area held, and
//! what its steady state measures.
//!
//! With χ = (1 + φ)/2 the inside indicator and I its second-moment tensor about the centroid,
//!
//! ```text
//! inclination  ψ = ½ atan2(2I_xy, I_xx − I_yy)                (the long axis against the flow)
//! deformation  D = (L − B)/(L + B),  L, B ∝ √(eigenvalues of I)
//! tank-treading  Ω/(γ̇/2) = −Σ(u_x ∂_yχ − u_y ∂_xχ)/(γ̇ Σχ)     (the mean vorticity inside, over
//!                                                              that of the imposed shear)
//! ```
//!
//! ψ and D are sampled over the run; the steady values are the means over its last quarter, and
//! the drift is ψ at the end minus ψ three quarters in. The velocity is the Stokes flow of the
//! final state at its σ, recomputed by an evaluator of the same box ([`Evaluator::velocity_at`]).

use super::spec::{Profile, Spec};
use crate::commands::measure::{contour_length, inside_area};
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::engines::spectral::evaluator::{Evaluator, ExplicitTerm};
use crate::error::{Error, Result};
use crate::problem::config::{self, Laplacian, Scene};
use crate::problem::flow::bending_modulus;
use crate::problem::grid::Grid;
use crate::problem::setup;
use ndarray::{Array3, Axis};
use serde_json::json;
use std::time::Instant;

/// One case: a reduced area and size, the capillary number, the channel and the profile.
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
    /// How the shear is imposed.
    pub profile: Profile,
}

/// What one case measured; a row of `cases.csv`.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The case.
    pub case: Case,
    /// Grid points along x and y.
    pub points: Vec<usize>,
    /// The reduced area of the final φ = 0 contour.
    pub reduced_area: f64,
    /// The steady inclination, degrees.
    pub inclination: f64,
    /// ψ at the end minus ψ three quarters through the run, degrees.
    pub drift: f64,
    /// The linear theory's ψ at this reduced area ([`linear_inclination`]), degrees.
    pub linear: f64,
    /// The steady deformation D.
    pub deformation: f64,
    /// The linear theory's D = b.
    pub linear_deformation: f64,
    /// The mean rotation rate inside over γ̇/2.
    pub tank_treading: f64,
    /// σ̄ = σR0²/κ at the end.
    pub sigma_bar: f64,
    /// Steps run.
    pub steps: usize,
    /// Wall seconds.
    pub wall: f64,
    /// The final field (for its picture).
    pub phi: Array3<f64>,
}

/// The excess amplitude b = √(2(1 − v)/3) of a quasi-circle of reduced area v (r = R(1 +
/// b cos 2θ) has v = 1 − 3b²/2 + O(b⁴)).
pub fn amplitude(v: f64) -> f64 {
    (2.0 * (1.0 - v) / 3.0).sqrt()
}

/// The steady inclination of the linear theory for this model (a global tension, equal
/// viscosities; docs/src/theory/flow.md): cos 2ψ = 2b, in degrees (NaN where 2b > 1, beyond
/// the theory).
pub fn linear_inclination(v: f64) -> f64 {
    0.5 * (2.0 * amplitude(v)).acos().to_degrees()
}

/// The scene of `case`: a 2D ellipse of the reduced area in a box of `length`·R0 along the
/// flow and `channel`·R0 across it, adaptive SBDF2 with the area held, for `strains`/γ̇.
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
    let value = json!({
        "description": format!("shear study: v {} R0 {} Ca {} W/R0 {} {}",
            case.reduced_area, r0, case.capillary, case.channel, case.profile.name()),
        "dim": 2, "n": [points(spec.length), points(case.channel)], "h": h, "eps": 1.0,
        "scheme": "sbdf2", "dt": 0.5, "adaptive": {"dt_max": spec.dt_max},
        "t_end": spec.strains / rate,
        "prepare_steps": 20,
        "dynamics": "stokes",
        "flow": {"viscosity": spec.viscosity, "mobility": spec.mobility, "shear_rate": rate},
        "walls": walls,
        "initial": {"shape": "spheroid", "reduced_volume": case.reduced_area, "r0": r0,
                    "kind": "prolate", "axis": "x"},
    });
    let scene = config::from_value(value)?;
    crate::problem::memory::check(&scene)?;
    Ok(scene)
}

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
    let mut samples: Vec<(f64, f64, f64)> = Vec::new();
    let mut steps = 0;
    let mut probe = Probe(|now: &Now| {
        let (psi, d) = moments(&grid, now.engine.phi());
        samples.push((now.record.t, psi, d));
        steps = now.record.step;
        Ok(Flow::Continue)
    });
    sim.run(&StopRules::of(&scene), &mut [&mut probe])?;
    let engine = sim.engine();
    let (phi, sigma) = (engine.phi().clone(), engine.sigma());
    let v = contour_reduced_area(&grid, &phi);
    let tail: Vec<&(f64, f64, f64)> = samples.iter().filter(|s| s.0 >= 0.75 * t_end).collect();
    if tail.len() < 2 {
        return Err(Error::config(
            "strains",
            "too few states in the run's last quarter; raise strains",
        ));
    }
    let mean =
        |f: fn(&(f64, f64, f64)) -> f64| tail.iter().map(|s| f(s)).sum::<f64>() / tail.len() as f64;
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
    let u = ev
        .velocity_at(&phi, sigma)
        .map_err(|_| Error::config("initial", "the final state is not finite"))?
        .expect("the evaluator has the flow");
    Ok(Measured {
        case: *case,
        points: scene.n.clone(),
        reduced_area: v,
        inclination: mean(|s| s.1),
        drift: tail[tail.len() - 1].1 - tail[0].1,
        linear: linear_inclination(v),
        deformation: mean(|s| s.2),
        linear_deformation: amplitude(v),
        tank_treading: -mean_vorticity(&grid, &phi, &u) / rate,
        sigma_bar: sigma * case.r0 * case.r0 / bending_modulus(1.0),
        steps,
        wall: started.elapsed().as_secs_f64(),
        phi,
    })
}

/// The reduced area 4πS/P² of the φ = 0 contour (its enclosed area S and length P by
/// marching squares, [`inside_area`] and [`contour_length`]): the shape's own, which the
/// phase field's measures (4πV/A², A = c∫|∇φ|²) read higher by O((ε/R0)²) — 0.941 against
/// 0.900 at R0 = 8ε.
fn contour_reduced_area(grid: &Grid, phi: &Array3<f64>) -> f64 {
    let slice = phi.index_axis(Axis(0), 0);
    let (s, p) = (inside_area(slice, grid.h), contour_length(slice, grid.h));
    4.0 * std::f64::consts::PI * s / (p * p)
}

/// (ψ in degrees, D) of the field `phi` on `grid` (module documentation); 2D fields run along
/// internal axes 1 (x) and 2 (y).
pub fn moments(grid: &Grid, phi: &Array3<f64>) -> (f64, f64) {
    let (x, y) = (grid.coords(1), grid.coords(2));
    let chi = |v: f64| 0.5 * (1.0 + v);
    let (mut m, mut mx, mut my) = (0.0, 0.0, 0.0);
    for ((_, i, j), &v) in phi.indexed_iter() {
        m += chi(v);
        mx += chi(v) * x[i];
        my += chi(v) * y[j];
    }
    let (cx, cy) = (mx / m, my / m);
    let (mut ixx, mut iyy, mut ixy) = (0.0, 0.0, 0.0);
    for ((_, i, j), &v) in phi.indexed_iter() {
        let (dx, dy) = (x[i] - cx, y[j] - cy);
        ixx += chi(v) * dx * dx;
        iyy += chi(v) * dy * dy;
        ixy += chi(v) * dx * dy;
    }
    let psi = 0.5 * (2.0 * ixy).atan2(ixx - iyy);
    let (half_sum, half_diff) = (
        0.5 * (ixx + iyy),
        (0.25 * (ixx - iyy).powi(2) + ixy * ixy).sqrt(),
    );
    let (long, short) = ((half_sum + half_diff).sqrt(), (half_sum - half_diff).sqrt());
    (psi.to_degrees(), (long - short) / (long + short))
}

/// The mean vorticity inside, Σχ(∂_x u_y − ∂_y u_x)/Σχ = Σ(u_x ∂_yχ − u_y ∂_xχ)/Σχ (by parts;
/// χ vanishes at the box's edges), with χ's derivatives by central differences.
fn mean_vorticity(grid: &Grid, phi: &Array3<f64>, u: &[Array3<f64>]) -> f64 {
    let [_, nx, ny] = grid.shape;
    let chi = |i: usize, j: usize| 0.5 * (1.0 + phi[[0, i % nx, j.min(ny - 1)]]);
    let h2 = 2.0 * grid.h;
    let (mut circulation, mut mass) = (0.0, 0.0);
    for i in 0..nx {
        for j in 0..ny {
            let dx = (chi(i + 1, j) - chi(i + nx - 1, j)) / h2;
            let dy = (chi(i, j + 1) - chi(i, j.max(1) - 1)) / h2;
            circulation += u[0][[0, i, j]] * dy - u[1][[0, i, j]] * dx;
            mass += chi(i, j);
        }
    }
    circulation / mass
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The linear theory's figures: v = 0.9 gives b = 0.2582 and ψ = ½ arccos(0.5164) = 29.45°;
    /// 2b reaches 1 at v = 5/8, where the formula ends.
    #[test]
    fn the_linear_theory_gives_its_figures() {
        assert!((amplitude(0.9) - 0.258_198_9).abs() < 1e-6);
        assert!((linear_inclination(0.9) - 29.45).abs() < 0.01);
        assert!(linear_inclination(0.625).abs() < 1e-6);
        assert!(linear_inclination(0.6).is_nan());
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
}
