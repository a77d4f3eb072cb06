//! One rate: the scene of a seeded mode, its run under the Stokes dynamics at fixed tension,
//! and the mode's amplitude, whose logarithm is fitted against time.
//!
//! The amplitude is a moment of the inside indicator χ = (1 + φ)/2, linear in the mode's
//! amplitude and blind to the others at first order:
//!
//! ```text
//! circle (mode n):   Q = Σ χ Re[(x + iy)^n]            (about the centroid)
//! sphere (mode l):   Q = Σ χ r^l P_l(z/r)              (about the centroid)
//! flat (wave λ):     Q = Σ χ y cos(2πx/λ)              (y across the slab)
//! ```
//!
//! Each case runs twice, seeded with +a and −a, and the rate is fitted to Q(+a) − Q(−a)
//! ([`moments`]).
//!
//! On a mirror-reduced box (the quarter or eighth box, [`Case::symmetry`]) the centroid's
//! coordinate along each mirrored axis is the mirror plane, 0 (the reduced box alone would put
//! it inside itself), and the sum over the computed points is multiplied by
//! [`Grid::mirror_factor`]: the integrand about a centroid on the mirror planes is even across
//! them, so Q is the full box's Q, not only proportional to it.

use super::spec::Spec;
use crate::commands::study::fit;
use crate::driver::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::error::{Error, Result};
use crate::problem::config::{self, Scene};
use crate::problem::flow::{self as theory, bending_modulus};
use crate::problem::grid::Grid;
use crate::problem::setup;
use crate::problem::shapes::legendre;
use ndarray::Array3;
use serde_json::json;
use std::f64::consts::PI;
use std::time::Instant;

/// Which membrane a case seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// The quasi-circle's mode n.
    Circle,
    /// The quasi-sphere's mode l.
    Sphere,
    /// The flat membrane's wave.
    Flat,
}

impl Kind {
    /// The name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Circle => "circle",
            Kind::Sphere => "sphere",
            Kind::Flat => "flat",
        }
    }

    /// The dimension of its box: 3 for the sphere, 2 otherwise.
    pub fn dim(self) -> usize {
        match self {
            Kind::Sphere => 3,
            Kind::Circle | Kind::Flat => 2,
        }
    }
}

/// One case to run: the membrane, its mode (n, l, or λ/ε for the flat one), σ̄ and size.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// The membrane.
    pub kind: Kind,
    /// n or l (0 for the flat membrane).
    pub mode: usize,
    /// σ̄: σR²/κ, or σ/(κk²) for the flat membrane.
    pub sigma_bar: f64,
    /// R/ε, or λ/ε.
    pub size: f64,
    /// L/R (closed vesicles) or the box's height over λ (flat).
    pub box_ratio: f64,
    /// Run on a mirror-reduced box ([`Case::symmetry`]).
    pub mirror: bool,
    /// λ = η_in/η_out.
    pub viscosity_ratio: f64,
    /// A locally inextensible membrane (full periodic box, λ = 1).
    pub inextensible: bool,
    /// M of the diffusive channel.
    pub mobility: f64,
}

impl Case {
    /// "drop" (one global tension) or "inextensible" (a tension field).
    pub fn membrane_model(&self) -> &'static str {
        if self.inextensible {
            "inextensible"
        } else {
            "drop"
        }
    }

    /// The scene's mirrored axes: none on the full box; with [`Case::mirror`] x and y (the
    /// circle's quarter box, or the sphere's with z periodic), and z as well for the sphere's
    /// even modes (the eighth box: P_l(cos θ) is even in z for even l, odd for odd l).
    pub fn symmetry(&self) -> &'static [&'static str] {
        match (self.mirror, self.kind) {
            (false, _) => &[],
            (true, Kind::Sphere) if self.mode.is_multiple_of(2) => &["x", "y", "z"],
            (true, _) => &["x", "y"],
        }
    }
}

/// What one case measured; a row of `cases.csv`.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The case.
    pub case: Case,
    /// Grid points per axis of the box.
    pub points: Vec<usize>,
    /// Δt.
    pub dt: f64,
    /// Steps run.
    pub steps: usize,
    /// Γ measured (the slope of −ln|Q| over the run after its first tenth).
    pub rate: f64,
    /// The sharp rate in free space (flat: of one interface).
    pub theory: f64,
    /// The periodic box's factor ([`theory::box_factor`]; 1 for the flat membrane).
    pub box_factor: f64,
    /// Γ / (theory × box factor).
    pub ratio: f64,
    /// The sharp diffusive channel's rate over the flow's ([`diffusive_rate`] / (theory × box
    /// factor)): the part of `ratio` above 1 the mobility alone explains.
    pub diffusive_share: f64,
    /// Bq = η_d/(ηR), the diffuse membrane's dilational surface viscosity η_d = Cε³/M over ηR
    /// ([`theory::dilational_viscosity_coefficient`]); NaN for the flat membrane.
    pub boussinesq: f64,
    /// The factor Bq puts on the sharp drop's rate in the case's box
    /// ([`theory::dilational_factor`]); 1 for the inextensible membrane (it does not dilate),
    /// NaN where it is not computed (the flat membrane, unequal viscosities).
    pub dilation_factor: f64,
    /// Largest relative deviation of ln|Q| from the fitted line, over the fit.
    pub fit_residual: f64,
    /// δ ≈ σ/(3ε), the relative widening of the interface's profile the fixed tension holds
    /// (docs/src/theory/flow.md): the phase field departs from the sharp membrane once it is
    /// a few percent.
    pub widening: f64,
    /// max|u| at the end.
    pub max_speed: f64,
    /// Wall seconds.
    pub wall: f64,
}

/// κ at ε = 1 (every case has ε = 1: lengths are in ε).
fn kappa() -> f64 {
    bending_modulus(1.0)
}

/// The sharp rate of `case` in free space, in units of 1/time, at the outside viscosity `eta`
/// (η_in = λη): the equal-viscosity rate times the contrast's factor, or for the inextensible
/// membrane times [`theory::inextensible_factor`] (Milner & Safran's rate in 3D).
pub fn sharp_rate(case: &Case, eta: f64) -> f64 {
    let (r, lambda) = (case.size, case.viscosity_ratio);
    let constrained = |dim: usize| {
        if case.inextensible {
            theory::inextensible_factor(dim, case.mode)
        } else {
            1.0
        }
    };
    match case.kind {
        Kind::Circle => {
            theory::circle_rate(case.mode, case.sigma_bar) * kappa() / (eta * r.powi(3))
                * theory::planar_contrast_factor(lambda)
                * constrained(2)
        }
        Kind::Sphere => {
            theory::sphere_rate(case.mode, case.sigma_bar) * kappa() / (eta * r.powi(3))
                * theory::sphere_contrast_factor(case.mode, lambda)
                * constrained(3)
        }
        Kind::Flat => {
            let k = 2.0 * PI / r;
            theory::flat_rate(k, kappa(), case.sigma_bar * kappa() * k * k, eta)
                * theory::planar_contrast_factor(lambda)
        }
    }
}

/// The sharp diffusive channel's rate of `case` in free space, in units of 1/time: the
/// mobility's, in parallel with the flow's [`sharp_rate`] ([`theory::sphere_diffusive_rate`]);
/// it does not depend on the viscosities or the inextensibility.
pub fn diffusive_rate(case: &Case) -> f64 {
    let (r, m) = (case.size, case.mobility);
    let reduced = match case.kind {
        Kind::Circle => theory::circle_diffusive_rate(case.mode, case.sigma_bar),
        Kind::Sphere => theory::sphere_diffusive_rate(case.mode, case.sigma_bar),
        Kind::Flat => return theory::flat_diffusive_rate(2.0 * PI / r, kappa(), tension(case), m),
    };
    reduced * m * kappa() / r.powi(5)
}

/// Bq of `case` at the outside viscosity `eta` and the factor it puts on the drop's rate
/// ([`Measured::boussinesq`], [`Measured::dilation_factor`]).
pub fn dilation(case: &Case, eta: f64) -> (f64, f64) {
    if case.kind == Kind::Flat {
        return (f64::NAN, f64::NAN);
    }
    let bq = theory::dilational_viscosity_coefficient() / (case.mobility * eta * case.size);
    let factor = if case.inextensible {
        1.0
    } else if case.viscosity_ratio != 1.0 {
        f64::NAN
    } else {
        theory::dilational_factor(case.kind.dim(), case.mode, bq, Some(1.0 / case.box_ratio))
    };
    (bq, factor)
}

/// The box factor of `case`.
pub fn box_factor(case: &Case) -> f64 {
    let r_over_l = 1.0 / case.box_ratio;
    match case.kind {
        Kind::Circle if case.inextensible => {
            theory::inextensible_box_factor(2, case.mode, r_over_l)
        }
        Kind::Sphere if case.inextensible => {
            theory::inextensible_box_factor(3, case.mode, r_over_l)
        }
        Kind::Circle => {
            theory::circle_box_factor_with_contrast(case.mode, r_over_l, case.viscosity_ratio)
        }
        Kind::Sphere => theory::box_factor(3, case.mode, r_over_l),
        Kind::Flat => 1.0,
    }
}

/// σ of `case` (ε = 1): σ̄κ/R², or σ̄κk² for the flat membrane.
pub fn tension(case: &Case) -> f64 {
    match case.kind {
        Kind::Flat => case.sigma_bar * kappa() * (2.0 * PI / case.size).powi(2),
        _ => case.sigma_bar * kappa() / (case.size * case.size),
    }
}

/// An even number of points nearest `length / h`.
fn points(length: f64, h: f64) -> usize {
    2 * ((length / h / 2.0).round() as usize).max(2)
}

/// The scene of `case`: the Stokes dynamics with the spec's fluid at σ fixed, SBDF2 with
/// Δt = min(dt_max, step_per_rate/Γ_expected), run for e_folds/Γ_expected.
///
/// # Errors
/// `Error::Config` if the scene is invalid (a bug of the spec's checks) or too large.
pub fn scene(spec: &Spec, case: &Case, expected: f64, sign: f64) -> Result<Scene> {
    let h = spec.h_over_eps;
    let dt = spec.dt_max.min(spec.step_per_rate / expected);
    let t_end = spec.e_folds / expected;
    let r = case.size;
    let sigma = tension(case);
    let (dim, n, initial) = match case.kind {
        Kind::Circle | Kind::Sphere => {
            let dim = case.kind.dim();
            let side = points(case.box_ratio * r, h);
            (
                dim,
                vec![side; dim],
                json!({"shape": "harmonic", "radius": r, "mode": case.mode,
                       "amplitude": sign * spec.amplitude}),
            )
        }
        Kind::Flat => (
            2,
            vec![points(r, h), points(case.box_ratio * r, h)],
            json!({"shape": "slab", "thickness": case.box_ratio * r / 2.0,
                       "wavelength": r, "amplitude": sign * spec.amplitude * r}),
        ),
    };
    let mut value = json!({
        "description": format!("rates study: {} mode {} sigma_bar {} size {} viscosity ratio {} {}",
            case.kind.name(), case.mode, case.sigma_bar, r, case.viscosity_ratio,
            case.membrane_model()),
        "dim": dim, "n": n, "h": h, "eps": 1.0,
        "scheme": "sbdf2", "dt": dt, "t_end": t_end,
        "prepare_steps": spec.prepare_steps,
        "dynamics": "stokes",
        "flow": {"viscosity": spec.viscosity, "mobility": case.mobility,
                 "viscosity_inside": case.viscosity_ratio * spec.viscosity,
                 "inextensible": case.inextensible},
        "area": {"method": "fixed", "sigma": sigma},
        "initial": initial,
    });
    if case.mirror {
        value["symmetry"] = json!(case.symmetry());
    }
    let scene = config::from_value(value)?;
    crate::problem::memory::check(&scene)?;
    Ok(scene)
}

/// The work of `case` in point-steps, for the study's ETA: the points the grid computes times
/// the steps of its two runs (the prepared steps and t_end/Δt each).
///
/// # Errors
/// As [`scene`].
pub fn work(spec: &Spec, case: &Case) -> Result<f64> {
    let scene = scene(
        spec,
        case,
        sharp_rate(case, spec.viscosity) * box_factor(case),
        1.0,
    )?;
    let computed = scene.n.iter().product::<usize>() >> case.symmetry().len();
    let steps = spec.prepare_steps as f64 + scene.t_end.unwrap_or(0.0) / scene.dt;
    Ok(2.0 * computed as f64 * steps)
}

/// Run `case` and fit its rate.
///
/// # Errors
/// `Error::Config` for an invalid scene; `Error::Blowup` if the run diverges.
pub fn run(spec: &Spec, case: &Case) -> Result<Measured> {
    let started = Instant::now();
    let theory = sharp_rate(case, spec.viscosity);
    let factor = box_factor(case);
    let (boussinesq, dilation_factor) = dilation(case, spec.viscosity);
    let (plus, scene, max_speed) = moments(spec, case, theory * factor, 1.0)?;
    let (minus, _, _) = moments(spec, case, theory * factor, -1.0)?;
    let t_end = scene.t_end.unwrap_or(f64::NAN);
    let series: Vec<(f64, f64)> = plus
        .iter()
        .zip(&minus)
        .map(|(&(t, qp), &(_, qm))| (t, (qp - qm).abs().ln()))
        .collect();
    let kept: Vec<(f64, f64)> = series
        .iter()
        .copied()
        .filter(|(t, _)| *t >= 0.1 * t_end)
        .collect();
    let (t, y): (Vec<f64>, Vec<f64>) = kept.iter().copied().unzip();
    let line = fit::linear(&t, &y).ok_or_else(|| {
        Error::config(
            "e_folds",
            "too few samples to fit a rate; raise e_folds or lower step_per_rate",
        )
    })?;
    let fit_residual = kept
        .iter()
        .map(|(t, y)| (y - line.intercept - line.slope * t).abs())
        .fold(0.0f64, f64::max);
    let rate = -line.slope;
    Ok(Measured {
        case: *case,
        points: scene.n.clone(),
        dt: scene.dt,
        steps: plus.len() - 1,
        rate,
        theory,
        box_factor: factor,
        ratio: rate / (theory * factor),
        diffusive_share: diffusive_rate(case) / (theory * factor),
        boussinesq,
        dilation_factor,
        fit_residual,
        widening: tension(case) / 3.0,
        max_speed,
        wall: started.elapsed().as_secs_f64(),
    })
}

/// (t, Q) at every state of a run.
type Series = Vec<(f64, f64)>;

/// Run `case` seeded with amplitude `sign` × a (expected rate `expected`): Q at every state
/// (time, Q), the scene, and max|u| at the end. The rate is fitted to Q(+a) − Q(−a), odd in a:
/// what the lattice imposes on any circle or sphere (a cos 4θ on the square grid, the cubic
/// harmonics on the cubic one, which mode 4 and 6 would read as a part that does not decay) and
/// the mode's second-order terms cancel.
fn moments(spec: &Spec, case: &Case, expected: f64, sign: f64) -> Result<(Series, Scene, f64)> {
    let scene = scene(spec, case, expected, sign)?;
    let problem = setup::build(&scene)?;
    let grid = problem.grid.clone();
    let (mut sim, _) = Simulation::of_scene(&scene, &problem)?;
    let mut series = Vec::new();
    let mut max_speed = f64::NAN;
    let mut probe = Probe(|now: &Now| {
        series.push((now.record.t, amplitude(case, &grid, now.engine.phi())));
        max_speed = now.engine.flow().map_or(f64::NAN, |f| f.max_speed);
        Ok(Flow::Continue)
    });
    sim.run(&StopRules::of(&scene), &mut [&mut probe])?;
    Ok((series, scene, max_speed))
}

/// The amplitude moment Q of `case`'s mode in the field `phi` on `grid` (module
/// documentation): the full box's Q also on a mirror-reduced grid. 2D fields run along
/// internal axes 1 (x) and 2 (y).
pub fn amplitude(case: &Case, grid: &Grid, phi: &Array3<f64>) -> f64 {
    let c = [grid.coords(0), grid.coords(1), grid.coords(2)];
    let chi = |v: f64| 0.5 * (1.0 + v);
    let at = |(i, j, k): (usize, usize, usize)| [c[0][i], c[1][j], c[2][k]];
    // The centroid of χ (its mass Σχ and first moments).
    let mut mass = 0.0;
    let mut first = [0.0; 3];
    for (idx, &v) in phi.indexed_iter() {
        let p = at(idx);
        mass += chi(v);
        for a in 0..3 {
            first[a] += chi(v) * p[a];
        }
    }
    // The centroid lies on every mirror plane (coordinate 0): the computed part alone would
    // put it inside the reduced box.
    let centre: [f64; 3] = std::array::from_fn(|a| {
        if grid.mirrored(a) {
            0.0
        } else {
            first[a] / mass
        }
    });
    let mut q = 0.0;
    for (idx, &v) in phi.indexed_iter() {
        let p = at(idx);
        let d = [p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]];
        q += chi(v)
            * match case.kind {
                Kind::Circle => {
                    let (r, theta) = (d[1].hypot(d[2]), d[2].atan2(d[1]));
                    r.powi(case.mode as i32) * (case.mode as f64 * theta).cos()
                }
                Kind::Sphere => {
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if r == 0.0 {
                        0.0
                    } else {
                        r.powi(case.mode as i32) * legendre(case.mode, d[2] / r)
                    }
                }
                Kind::Flat => p[2] * (2.0 * PI * p[1] / case.size).cos(),
            };
    }
    q * grid.mirror_factor()
}
