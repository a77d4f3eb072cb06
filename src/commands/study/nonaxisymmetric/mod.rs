//! `vesicle study nonaxisymmetric FILE`: a non-axisymmetric ADE state (triaxial, starfish)
//! against the axisymmetric branches at the same (v, α, Δa0).
//!
//! For every h/ε of `eps_over_h`, α of `alpha` and Δa0 of `da0` the study relaxes the file's scene
//! (its non-axisymmetric seed, box and mirror planes, `ade` set, the box kept in units of
//! ε) by L-BFGS, and measures v on the refined φ = 0 surface, w, e, Δa, and the semi-axes of
//! the inside from its second moments,
//!
//! ```text
//! a_i = √(5 ⟨x_i²⟩),   ⟨x_i²⟩ = ∫ x_i² (1 + φ)/2 dx / ∫ (1 + φ)/2 dx   (x about the centroid)
//! ```
//!
//! (exact for a solid ellipsoid), sorted a1 ≥ a2 ≥ a3, and the triaxiality
//! τ = min(a1 − a2, a2 − a3)/a2: zero for a shape of revolution about one of the axes, up to
//! the lattice. Each axisymmetric start of `axisymmetric` (the sharp shape of its branch, an
//! `axisym` initial shape at the R0 of the non-axisymmetric state's A0) runs in the same box
//! and h at seed volumes v_s found by the secant method on the reduced volume reached
//! ([`match_volume`]), and its w is interpolated linearly in v to the non-axisymmetric state's v: the
//! phase field against the phase field at the same v. The sharp reference's stationary ADE
//! shapes (`axisym::ade_solution`) of the `sharp` branches are solved at the same v.
//!
//! Writes `nonaxisymmetric.txt`, `states.csv` (every relaxed state) and `comparison.csv` (per
//! h/ε, α and Δa0: the non-axisymmetric state, the phase-field and sharp axisymmetric w at its v,
//! the lowest, and the lattice pinning bound of e at that h/ε, [`crate::problem::pinning`]).

pub mod spec;

use super::harness::{Report, Study};
use super::table::{self, Column, Format, Row};
use crate::analysis::axisym::{self, Branch, Options};
use crate::commands::diagram::case::transform_friendly;
use crate::driver::simulation::{Simulation, StopRules};
use crate::error::{Error, Result};
use crate::problem::config::{Dynamics, Scene};
use ndarray::Array3;
pub use spec::Spec;
use std::path::Path;
use std::time::Instant;

/// One relaxed state; a row of `states.csv`.
#[derive(Clone, Debug)]
pub struct State {
    /// h/ε.
    pub h_over_eps: f64,
    /// α.
    pub alpha: f64,
    /// Δa0.
    pub da0: f64,
    /// `non-axisymmetric`, or the axisymmetric start and its seed volume (`prolate (x) v_s 0.805`).
    pub start: String,
    /// R0/ε of the area target A0.
    pub r0: f64,
    /// Reduced volume of the refined φ = 0 surface.
    pub v: f64,
    /// w = e + πα(Δa − Δa0)².
    pub w: f64,
    /// Reduced bending energy e.
    pub e: f64,
    /// Reduced area difference Δa.
    pub da: f64,
    /// c̄0,eff = 2πα(Δa0 − Δa).
    pub c0_eff: f64,
    /// Semi-axes from the second moments, a1 ≥ a2 ≥ a3 (in ε).
    pub axes: [f64; 3],
    /// τ = min(a1 − a2, a2 − a3)/a2.
    pub triaxiality: f64,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// Final stationarity residual.
    pub residual: f64,
    /// Wall seconds (the built field to the measured state).
    pub wall: f64,
}

impl Row for State {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| {
                r.h_over_eps.into()
            }),
            Column::both("alpha", "alpha", Format::Plain, |r| r.alpha.into()),
            Column::both("da0", "da0", Format::Plain, |r| r.da0.into()),
            Column::both("start", "start", Format::Plain, |r| r.start.as_str().into()),
            Column::both("r0", "R0/eps", Format::Fixed(3), |r| r.r0.into()),
            Column::both("v", "v", Format::Fixed(5), |r| r.v.into()),
            Column::both("w", "w", Format::Fixed(6), |r| r.w.into()),
            Column::both("e", "e", Format::Fixed(6), |r| r.e.into()),
            Column::both("da", "da", Format::Fixed(5), |r| r.da.into()),
            Column::both("c0_eff", "c0_eff", Format::Fixed(3), |r| r.c0_eff.into()),
            Column::both("a1", "a1", Format::Fixed(2), |r| r.axes[0].into()),
            Column::both("a2", "a2", Format::Fixed(2), |r| r.axes[1].into()),
            Column::both("a3", "a3", Format::Fixed(2), |r| r.axes[2].into()),
            Column::both("triaxiality", "tau", Format::Sci(2), |r| {
                r.triaxiality.into()
            }),
            Column::both("iterations", "iterations", Format::Plain, |r| {
                r.iterations.into()
            }),
            Column::both("residual", "residual", Format::Sci(1), |r| {
                r.residual.into()
            }),
            Column::both("wall_seconds", "wall", Format::Fixed(1), |r: &Self| {
                r.wall.into()
            })
            .unit("s"),
        ]
    }
}

/// The non-axisymmetric state of one (h/ε, Δa0) against the axisymmetric branches at its v;
/// a row of `comparison.csv`. NaN where a branch was not run or has no stable sharp shape.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// α.
    pub alpha: f64,
    /// Δa0.
    pub da0: f64,
    /// h/ε.
    pub h_over_eps: f64,
    /// R0/ε.
    pub r0: f64,
    /// The non-axisymmetric state's v.
    pub v: f64,
    /// Its w, e, Δa and τ.
    pub w: f64,
    /// See `w`.
    pub e: f64,
    /// See `w`.
    pub da: f64,
    /// See `w`.
    pub triaxiality: f64,
    /// Phase-field w of the prolate, oblate and stomatocyte starts, interpolated to `v`.
    pub w_pf: [f64; 3],
    /// Sharp w of the prolate, oblate, stomatocyte and pear at `v`.
    pub w_sharp: [f64; 4],
    /// The lowest phase-field state (`non-axisymmetric` or a branch).
    pub lowest_pf: &'static str,
    /// w − the lowest phase-field axisymmetric w (negative: the non-axisymmetric state is lower).
    pub margin_pf: f64,
    /// The lattice pinning bound of e at this h/ε.
    pub pinning: f64,
}

/// The phase-field branches of [`Comparison::w_pf`], in its order.
const PF: [Branch; 3] = [Branch::Prolate, Branch::Oblate, Branch::Stomatocyte];

impl Row for Comparison {
    fn columns() -> Vec<Column<Self>> {
        let mut c: Vec<Column<Self>> = vec![
            Column::both("alpha", "alpha", Format::Plain, |r| r.alpha.into()),
            Column::both("da0", "da0", Format::Plain, |r| r.da0.into()),
            Column::both("h_over_eps", "h/eps", Format::Fixed(4), |r| {
                r.h_over_eps.into()
            }),
            Column::both("r0", "R0/eps", Format::Fixed(2), |r| r.r0.into()),
            Column::both("v", "v", Format::Fixed(5), |r| r.v.into()),
            Column::both("w", "w", Format::Fixed(5), |r| r.w.into()),
            Column::both("e", "e", Format::Fixed(5), |r| r.e.into()),
            Column::both("da", "da", Format::Fixed(4), |r| r.da.into()),
            Column::both("triaxiality", "tau", Format::Fixed(3), |r| {
                r.triaxiality.into()
            }),
        ];
        c.push(Column::both(
            "w_pf_prolate",
            "pf prolate",
            Format::Fixed(5),
            |r| r.w_pf[0].into(),
        ));
        c.push(Column::both(
            "w_pf_oblate",
            "pf oblate",
            Format::Fixed(5),
            |r| r.w_pf[1].into(),
        ));
        c.push(Column::both(
            "w_pf_stomatocyte",
            "pf stomatocyte",
            Format::Fixed(5),
            |r| r.w_pf[2].into(),
        ));
        c.push(Column::both(
            "w_sharp_prolate",
            "sharp prolate",
            Format::Fixed(5),
            |r| r.w_sharp[0].into(),
        ));
        c.push(Column::both(
            "w_sharp_oblate",
            "sharp oblate",
            Format::Fixed(5),
            |r| r.w_sharp[1].into(),
        ));
        c.push(Column::both(
            "w_sharp_stomatocyte",
            "sharp stomatocyte",
            Format::Fixed(5),
            |r| r.w_sharp[2].into(),
        ));
        c.push(Column::both(
            "w_sharp_pear",
            "sharp pear",
            Format::Fixed(5),
            |r| r.w_sharp[3].into(),
        ));
        c.push(Column::both(
            "lowest_pf",
            "lowest (pf)",
            Format::Plain,
            |r| r.lowest_pf.into(),
        ));
        c.push(Column::both(
            "margin_pf",
            "w - pf axisym",
            Format::Sci(2),
            |r| r.margin_pf.into(),
        ));
        c.push(Column::both(
            "pinning",
            "pinning of e",
            Format::Sci(1),
            |r| r.pinning.into(),
        ));
        c
    }
}

/// What the study returns.
#[derive(Clone, Debug)]
pub struct Output {
    /// Every relaxed state.
    pub states: Vec<State>,
    /// Per h/ε and Δa0.
    pub comparison: Vec<Comparison>,
}

/// The study.
pub struct Nonaxisymmetric;

impl Study for Nonaxisymmetric {
    const NAME: &'static str = "nonaxisymmetric";
    type Spec = Spec;
    type Output = Output;

    fn measure(spec: &Spec, dir: &Path) -> Result<(Output, Report)> {
        spec.validate()?;
        let sharp = spec.sharp_branches()?;
        let base = super::file::scene(&spec.scene, &[], "scene", dir)?;
        let alphas = if spec.alpha.is_empty() {
            vec![check_scene(&base)?]
        } else {
            check_scene(&base)?;
            spec.alpha.clone()
        };
        let mut states = Vec::new();
        let mut comparison = Vec::new();
        for &eps_over_h in &spec.eps_over_h {
            for &alpha in &alphas {
                for &da0 in &spec.da0 {
                    let (mut s, c) = one_case(spec, &base, dir, eps_over_h, alpha, da0, &sharp)?;
                    states.append(&mut s);
                    comparison.push(c);
                }
            }
        }
        let mut text = String::from("== every relaxed state ==\n");
        text.push_str(&table::text(&states));
        text.push_str(
            "\n== the non-axisymmetric state against the axisymmetric branches at its v \
             (pf: phase field, same box and h, interpolated in v; sharp: axisym::ade_solution) ==\n",
        );
        text.push_str(&table::text(&comparison));
        let mut report = Report {
            text,
            ..Report::default()
        };
        report.table("states.csv", &states)?;
        report.table("comparison.csv", &comparison)?;
        Ok((Output { states, comparison }, report))
    }
}

/// α of the base scene, after checking that it is a 3D relaxational ADE scene at ε = 1.
fn check_scene(s: &Scene) -> Result<f64> {
    let ade = s.ade.as_ref().ok_or_else(|| {
        Error::config(
            "scene.ade",
            "the study compares ADE states: give an ade block",
        )
    })?;
    if s.dim != 3 {
        return Err(Error::config("scene.dim", "must be 3"));
    }
    if s.eps != 1.0 {
        return Err(Error::config(
            "scene.eps",
            "must be 1 (the box is scaled in units of ε)",
        ));
    }
    if s.dynamics != Dynamics::Relaxational {
        return Err(Error::config(
            "scene.dynamics",
            "must be \"relaxational\" (the study compares L-BFGS end states)",
        ));
    }
    Ok(ade.alpha)
}

/// The non-axisymmetric state at (h = ε/`eps_over_h`, Δa0), the axisymmetric starts at its v,
/// and the sharp branches.
fn one_case(
    spec: &Spec,
    base: &Scene,
    dir: &Path,
    eps_over_h: f64,
    alpha: f64,
    da0: f64,
    sharp: &[Branch],
) -> Result<(Vec<State>, Comparison)> {
    let h = 1.0 / eps_over_h;
    let n: Vec<usize> = base
        .n
        .iter()
        .map(|&k| transform_friendly((k as f64 * base.h / h).round() as usize))
        .collect();
    let at = serde_json::json!({
        "h": h, "n": n, "ade": {"alpha": alpha, "da0": da0},
        "output": {"png": false, "vti": false}
    });
    let label = format!("h = eps/{eps_over_h}, alpha = {alpha}, da0 = {da0}");
    let scene = super::file::scene(&spec.scene, std::slice::from_ref(&at), "scene", dir)?;
    let na = relax(&scene, "non-axisymmetric", eps_over_h, alpha, da0)
        .map_err(|e| e.within(&format!("non-axisymmetric start, {label}")))?;
    eprintln!(
        "nonaxisymmetric: {label}: w {:.6} v {:.5} tau {:.3} ({} iterations, {:.1} s)",
        na.w, na.v, na.triaxiality, na.iterations, na.wall
    );
    let mut states = vec![na.clone()];
    let mut w_pf = [f64::NAN; 3];
    for a in &spec.axisymmetric {
        let branch = PF
            .into_iter()
            .find(|b| b.name() == a.branch)
            .expect("validated");
        let run = |v_seed: f64| -> Result<State> {
            let start = serde_json::json!({"initial": {
                "shape": "axisym", "branch": a.branch, "reduced_volume": v_seed,
                "r0": na.r0, "axis": a.axis}});
            let s = super::file::scene(
                &spec.scene,
                &[at.clone(), serde_json::json!({"initial": null}), start],
                "scene",
                dir,
            )?;
            let name = format!("{} ({}) v_s {v_seed:.5}", a.branch, a.axis);
            let st = relax(&s, &name, eps_over_h, alpha, da0)
                .map_err(|e| e.within(&format!("{name}, {label}")))?;
            eprintln!(
                "nonaxisymmetric: {label}: {name}: w {:.6} v {:.5} tau {:.3} ({} iterations, {:.1} s)",
                st.w, st.v, st.triaxiality, st.iterations, st.wall
            );
            Ok(st)
        };
        let runs = match_volume(na.v, run)?;
        w_pf[PF.iter().position(|b| *b == branch).expect("a PF branch")] = at_volume(&runs, na.v);
        states.extend(runs);
    }
    let mut w_sharp = [f64::NAN; 4];
    for b in sharp {
        let i = Branch::WITH_PEAR
            .iter()
            .position(|x| x == b)
            .expect("a branch");
        match axisym::ade_solution(*b, na.v, alpha, da0, &Options::with_nodes(SHARP_NODES)) {
            Ok(s) => w_sharp[i] = s.w,
            Err(e) => eprintln!("nonaxisymmetric: {label}: no sharp {} ({e})", b.name()),
        }
    }
    let (lowest_axi, w_axi) = PF
        .iter()
        .zip(w_pf)
        .filter(|(_, w)| w.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(("none", f64::NAN), |(b, w)| (b.name(), w));
    let lowest_pf = if w_axi.is_nan() || w_axi > na.w {
        "non-axisymmetric"
    } else {
        lowest_axi
    };
    let c = Comparison {
        alpha,
        da0,
        h_over_eps: h,
        r0: na.r0,
        v: na.v,
        w: na.w,
        e: na.e,
        da: na.da,
        triaxiality: na.triaxiality,
        w_pf,
        w_sharp,
        lowest_pf,
        margin_pf: na.w - w_axi,
        pinning: crate::problem::pinning::bound(h).value(),
    };
    Ok((states, c))
}

/// The runs of an axisymmetric start whose seed volumes v_s approach the target `v` by the
/// secant method on the reduced volume reached, v(v_s) (first v_s = v, then
/// v_s + (v − v(v_s))): at least two, at most [`VOLUME_RUNS`], stopping once [`bracket`]
/// finds runs on both sides of `v` within [`VOLUME_TOL`] of it.
///
/// # Errors
/// Those of `run`.
fn match_volume(v: f64, run: impl Fn(f64) -> Result<State>) -> Result<Vec<State>> {
    let mut seeds = vec![v];
    let mut runs: Vec<State> = vec![run(v)?];
    while runs.len() < VOLUME_RUNS {
        let k = runs.len();
        if k >= 2 {
            let (p, q) = bracket(&runs, v);
            if (p.v - v) * (q.v - v) <= 0.0 && (p.v - v).abs().max((q.v - v).abs()) < VOLUME_TOL {
                break;
            }
        }
        let slope = if k >= 2 && (runs[k - 1].v - runs[k - 2].v).abs() > 1e-9 {
            (runs[k - 1].v - runs[k - 2].v) / (seeds[k - 1] - seeds[k - 2])
        } else {
            1.0
        };
        let next = seeds[k - 1] + (v - runs[k - 1].v) / slope.clamp(0.2, 5.0);
        seeds.push(next);
        runs.push(run(next)?);
    }
    Ok(runs)
}

/// The two runs of `runs` (at least two) that interpolate best to `v`: the nearest below and
/// the nearest above it where both exist, else the two nearest.
fn bracket(runs: &[State], v: f64) -> (&State, &State) {
    let nearest = |side: f64| {
        runs.iter()
            .filter(|r| (r.v - v) * side >= 0.0)
            .min_by(|a, b| (a.v - v).abs().total_cmp(&(b.v - v).abs()))
    };
    if let (Some(p), Some(q)) = (nearest(-1.0), nearest(1.0)) {
        if !std::ptr::eq(p, q) {
            return (p, q);
        }
    }
    let mut by = runs.iter().collect::<Vec<_>>();
    by.sort_by(|a, b| (a.v - v).abs().total_cmp(&(b.v - v).abs()));
    (by[0], by[1])
}

/// w at `v`, linear in v between the two runs of [`bracket`]:
/// w = w_p + (w_q − w_p)(v − v_p)/(v_q − v_p).
fn at_volume(runs: &[State], v: f64) -> f64 {
    let (p, q) = bracket(runs, v);
    if (q.v - p.v).abs() > 1e-12 {
        p.w + (q.w - p.w) * (v - p.v) / (q.v - p.v)
    } else {
        q.w
    }
}

/// Quadrature nodes of the sharp solves: 121 (K = 40) resolve the smooth ADE shapes to
/// round-off (docs/src/science/ade.md), four times faster than the default 241.
const SHARP_NODES: usize = 121;

/// Most runs of one axisymmetric start in [`match_volume`].
const VOLUME_RUNS: usize = 4;

/// How close to the non-axisymmetric state's v the two runs that interpolate w must end.
const VOLUME_TOL: f64 = 3e-3;

/// Relax `scene` by its own rules and measure the end state.
///
/// # Errors
/// `Error::Config` for a scene that cannot be built, one without ADE columns, or a relaxation
/// that stops before the scene's `stop_residual` (field `scene.max_steps`);
/// `Error::Blowup` if a step diverges.
fn relax(scene: &Scene, start: &str, eps_over_h: f64, alpha: f64, da0: f64) -> Result<State> {
    let problem = crate::problem::setup::build(scene)?;
    let clock = Instant::now();
    let (mut sim, a0) = Simulation::of_scene(scene, &problem)?;
    let stopped = sim.run(&StopRules::of(scene), &mut [])?;
    let last = sim.record();
    if stopped.as_str() != "stationary" {
        return Err(Error::config(
            "scene.max_steps",
            format!(
                "{start} stopped ({}) at residual {:.2e} after {} iterations, before the \
                 scene's stop_residual: raise max_steps",
                stopped.as_str(),
                last.residual,
                last.step
            ),
        ));
    }
    let couple = last
        .couple
        .ok_or_else(|| Error::config("scene.ade", "the run has no ADE record"))?;
    let full = problem.grid.unfold(sim.engine().phi());
    let v = crate::analysis::levelset::measure_refined(&full, 3, scene.h).reduced_volume;
    let axes = semi_axes(&full, scene.h);
    Ok(State {
        h_over_eps: 1.0 / eps_over_h,
        alpha,
        da0,
        start: start.to_string(),
        r0: (a0 / (4.0 * std::f64::consts::PI)).sqrt() / scene.eps,
        v,
        w: couple.w,
        e: couple.bending_energy,
        da: couple.da,
        c0_eff: couple.c0_eff,
        axes,
        triaxiality: triaxiality(axes),
        iterations: last.step,
        residual: last.residual,
        wall: clock.elapsed().as_secs_f64(),
    })
}

/// The semi-axes a_i = √(5⟨x_i²⟩) of the inside of `phi` (weight (1 + φ)/2, clamped to
/// [0, 1]; x about the centroid, in units of the grid spacing `h`), sorted a1 ≥ a2 ≥ a3.
pub fn semi_axes(phi: &Array3<f64>, h: f64) -> [f64; 3] {
    let mut m = 0.0;
    let mut first = [0.0; 3];
    let mut second = [0.0; 3];
    for ((i, j, k), &p) in phi.indexed_iter() {
        let wgt = ((1.0 + p) / 2.0).clamp(0.0, 1.0);
        let x = [i as f64 * h, j as f64 * h, k as f64 * h];
        m += wgt;
        for a in 0..3 {
            first[a] += wgt * x[a];
            second[a] += wgt * x[a] * x[a];
        }
    }
    let mut axes: [f64; 3] = std::array::from_fn(|a| {
        let mean = first[a] / m;
        (5.0 * (second[a] / m - mean * mean)).max(0.0).sqrt()
    });
    axes.sort_by(|a, b| b.total_cmp(a));
    axes
}

/// τ = min(a1 − a2, a2 − a3)/a2 of sorted semi-axes a1 ≥ a2 ≥ a3: zero for a shape of
/// revolution about a coordinate axis.
pub fn triaxiality(a: [f64; 3]) -> f64 {
    (a[0] - a[1]).min(a[1] - a[2]) / a[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(v: f64, w: f64) -> State {
        State {
            h_over_eps: 1.0,
            alpha: 1.0,
            da0: 1.0,
            start: String::new(),
            r0: 1.0,
            v,
            w,
            e: w,
            da: 1.0,
            c0_eff: 0.0,
            axes: [1.0; 3],
            triaxiality: 0.0,
            iterations: 0,
            residual: 0.0,
            wall: 0.0,
        }
    }

    /// The second-moment semi-axes of a sharp solid ellipsoid (φ = ±1, semi-axes 12, 8 and
    /// 5 h) are its semi-axes to the lattice's O(h/a) (within 2%), sorted; τ is then
    /// min(4, 3)/8; a ball reads τ = 0 to round-off.
    #[test]
    fn semi_axes_of_a_solid_ellipsoid() {
        let n = [40, 32, 24];
        let c = |i: usize, k: usize| i as f64 + 0.5 - n[k] as f64 / 2.0;
        let inside = |a: [f64; 3]| {
            Array3::from_shape_fn((n[0], n[1], n[2]), |(i, j, k)| {
                let r =
                    (c(i, 0) / a[0]).powi(2) + (c(j, 1) / a[1]).powi(2) + (c(k, 2) / a[2]).powi(2);
                if r <= 1.0 {
                    1.0
                } else {
                    -1.0
                }
            })
        };
        let axes = semi_axes(&inside([8.0, 12.0, 5.0]), 1.0);
        for (got, want) in axes.iter().zip([12.0, 8.0, 5.0]) {
            assert!((got / want - 1.0).abs() < 0.02, "{axes:?}");
        }
        assert!((triaxiality(axes) - 3.0 / 8.0).abs() < 0.02, "{axes:?}");
        let ball = semi_axes(&inside([7.0, 7.0, 7.0]), 1.0);
        assert!(triaxiality(ball).abs() < 1e-12, "{ball:?}");
    }

    /// w at v interpolates between the nearest runs on either side of it (not the last two),
    /// and extrapolates from the two nearest when all lie on one side.
    #[test]
    fn w_interpolates_between_the_bracketing_runs() {
        let runs = [
            state(0.79, 2.0),
            state(0.83, 0.0),
            state(0.80, 1.0),
            state(0.82, 3.0),
        ];
        assert!((at_volume(&runs, 0.81) - 2.0).abs() < 1e-12);
        let one_side = [state(0.82, 3.0), state(0.83, 4.0), state(0.85, 9.0)];
        assert!((at_volume(&one_side, 0.81) - 2.0).abs() < 1e-12);
    }
}
