//! The Stokes dynamics (docs/src/theory/flow.md): the diffusive channel's mobility in the
//! implicit step, the energy falling at fixed tension, the flow vanishing at equilibrium, the
//! periodic box, and a mode's rate against the sharp theory.

mod common;

use common::{relax, scene, simulation};
use serde_json::{json, Value};
use vesicle::commands::study::rates::measure::{self, Case, Kind};
use vesicle::commands::study::rates::{value_at_zero, Spec};
use vesicle::driver::record::Record;
use vesicle::driver::simulation::{Flow, Now, Probe, StopRules};
use vesicle::problem::setup;

/// The record of every state of a run of `s`, the prepared start first.
fn recorded(s: &vesicle::problem::config::Scene) -> Vec<Record> {
    let (_, mut sim) = simulation(s);
    let mut rows = vec![sim.record()];
    let mut probe = Probe(|now: &Now| {
        rows.push(now.record);
        Ok(Flow::Continue)
    });
    sim.run(&StopRules::of(s), &mut [&mut probe]).expect("runs");
    rows
}

/// An ellipse in a 64² box at h = ε/2, with the entries of `extra`.
fn ellipse(extra: Value) -> Value {
    common::with(
        &json!({
            "dim": 2, "n": [64, 64], "h": 0.5, "dt": 0.2, "max_steps": 40,
            "initial": {"shape": "ellipsoid", "axes": [9.0, 7.0]},
            "area": {"method": "fixed", "sigma": 0.02}
        }),
        extra,
    )
}

/// With a fluid too viscous to move (η = 1e15), the Stokes dynamics at mobility M is the
/// conserved flow in the time Mt: 40 SBDF1 steps of Δt = 0.2 at M = 0.5 give the field of 40
/// steps of Δt = 0.1 without a fluid, to 1e-11 (the flow's own contribution is ~1e-15). A
/// mobility left out of one of the implicit operator's terms, or of N̂, misses by O(Δt).
#[test]
fn the_mobility_scales_the_conserved_flow() {
    let stokes = scene(ellipse(json!({
        "dynamics": "stokes", "flow": {"viscosity": 1e15, "mobility": 0.5}
    })));
    let conserved = scene(ellipse(json!({"dt": 0.1})));
    let (_, mut a) = simulation(&stokes);
    let (_, mut b) = simulation(&conserved);
    a.run(&StopRules::of(&stokes), &mut []).expect("runs");
    b.run(&StopRules::of(&conserved), &mut []).expect("runs");
    let diff = (a.engine().phi() - b.engine().phi())
        .iter()
        .fold(0.0f64, |m, d| m.max(d.abs()));
    assert!(diff < 1e-11, "max|Δφ| = {diff:e}");
}

/// At fixed tension the Stokes flow lowers F_eff = F_sc + σA every step (the energy guard
/// would stop the run otherwise; the series is checked too), holds σ at its value, conserves
/// the volume to round-off (the advection's k = 0 coefficient is zero), and the fluid works:
/// the dissipation η∫|∇u|² is positive on every row.
#[test]
fn the_flow_lowers_the_energy_at_fixed_tension() {
    let s = scene(ellipse(json!({
        "dynamics": "stokes", "flow": {"viscosity": 1.0, "mobility": 0.01},
        "dt": 0.5, "max_steps": 60
    })));
    let rows = recorded(&s);
    let first = rows[0];
    let f = |r: &Record| r.energy + 0.02 * r.area;
    for w in rows.windows(2) {
        assert!(f(&w[1]) <= f(&w[0]) * (1.0 + 1e-12), "step {}", w[1].step);
    }
    for r in &rows {
        assert_eq!(r.sigma, 0.02);
        assert!((r.volume - first.volume).abs() <= 1e-12 * first.volume);
        assert!(r.flow.expect("flow columns").dissipation > 0.0);
    }
}

/// At equilibrium the force μ∇φ is a gradient (μ uniform) and the exact projection removes
/// it: the flow is driven only by what is left of μ − μ̄. A circle (R = 8ε, σ = 0, M = 1)
/// relaxed to a residual of 1e-10 has max|u| below 1e-9, where a velocity of the bending
/// forces' own scale, κ/(ηR), would be 0.24: no spurious currents beyond the residual's
/// (measured max|u| ≈ residual on the way down).
#[test]
fn spurious_currents_vanish_with_the_residual() {
    let s = scene(json!({
        "dim": 2, "n": [64, 64], "h": 0.5, "dt": 2.0, "scheme": "sbdf2", "max_steps": 2000,
        "dynamics": "stokes", "flow": {"viscosity": 1.0, "mobility": 1.0},
        "area": {"method": "fixed", "sigma": 0.0},
        "initial": {"shape": "sphere", "radius": 8.0}
    }));
    let (_, mut sim) = simulation(&s);
    relax(&mut sim, 1e-10, 2000).expect("the circle relaxes");
    let speed = sim.engine().flow().expect("a flow").max_speed;
    assert!(speed < 1e-9, "max|u| = {speed:e}");
}

/// The flow is solved on the periodic box: `"symmetry": "auto"` keeps every axis whole under
/// the Stokes dynamics (a mirror plane would need sine transforms for the normal velocity),
/// where the conserved flow mirrors the same circle about both.
#[test]
fn the_stokes_box_has_no_mirror() {
    let base = json!({
        "dim": 2, "n": [32, 32], "dt": 0.1, "max_steps": 1, "symmetry": "auto",
        "initial": {"shape": "sphere", "radius": 8.0}
    });
    let conserved = setup::build(&scene(base.clone())).expect("problem");
    assert_eq!(conserved.mirror, vec![true, true]);
    let stokes = common::with(
        &base,
        json!({"dynamics": "stokes", "flow": {"viscosity": 1.0, "mobility": 0.01},
               "area": {"method": "fixed", "sigma": 0.0}}),
    );
    let stokes = setup::build(&scene(stokes)).expect("problem");
    assert_eq!(stokes.mirror, vec![false, false]);
}

/// The quasi-circle's mode n = 3 at σ = 0 (R = 10 and 14ε, L = 4R, h = ε/2, M = 0.01):
/// the rate over the sharp rate n(n² − 3/2)/4 · κ/(ηR³) (the box factor is 1.000 for n = 3 at
/// L = 4R) is 0.909 and 0.934 — the phase field's O(ε/R) — and its linear extrapolation to
/// ε/R = 0 is within 1.5% of 1 (measured −0.3%; the quadratic term left in a two-point
/// extrapolation from these sizes is about 1%).
#[test]
fn a_quasi_circle_relaxes_at_the_sharp_rate() {
    let spec: Spec = serde_json::from_value(json!({
        "study": "rates", "h_over_eps": 0.5, "viscosity": 1.0, "mobility": 0.01,
        "amplitude": 0.02, "dt_max": 3.0, "step_per_rate": 0.02, "e_folds": 0.5,
        "prepare_steps": 20,
        "circle": {"box": 4, "groups": [{"modes": [3], "sigma_bar": [0], "r0": [10, 14]}]}
    }))
    .expect("spec");
    let points: Vec<(f64, f64)> = [10.0, 14.0]
        .iter()
        .map(|&size| {
            let case = Case {
                kind: Kind::Circle,
                mode: 3,
                sigma_bar: 0.0,
                size,
                box_ratio: 4.0,
            };
            let m = measure::run(&spec, &case).expect("runs");
            assert!(m.ratio > 0.85 && m.ratio < 1.0, "R {size}: {}", m.ratio);
            (1.0 / size, m.ratio)
        })
        .collect();
    let limit = value_at_zero(&points);
    assert!((limit - 1.0).abs() < 0.015, "extrapolated ratio {limit}");
}

/// The imposed Kolmogorov shear (`flow.shear_rate` γ̇): a circle (R = 8ε, σ̄ = 10, on a 32ε box
/// at h = ε/2) sheared for γ̇t = 0.3 is stretched along the flow's extensional axis, +45° from x
/// for u_x = (γ̇/k₀) sin(k₀y) (shear rate +γ̇ at y = 0); the vorticity turns it toward the flow
/// as it deforms, so it reads between 40° and 45° (linear theory: 45° − O(γ̇t)). A shear along
/// the wrong axis, of the wrong sign, or not applied would read −45°, 135° or no inclination.
#[test]
fn an_imposed_shear_stretches_a_circle_along_its_extensional_axis() {
    let s = scene(json!({
        "dim": 2, "n": [64, 64], "h": 0.5, "dt": 1.0, "scheme": "sbdf2", "t_end": 300.0,
        "dynamics": "stokes",
        "flow": {"viscosity": 1.0, "mobility": 0.01, "shear_rate": 1e-3},
        "area": {"method": "fixed", "sigma": 0.295},
        "initial": {"shape": "sphere", "radius": 8.0}
    }));
    let (problem, mut sim) = simulation(&s);
    sim.run(&StopRules::of(&s), &mut []).expect("runs");
    let (x, y) = (problem.grid.coords(1), problem.grid.coords(2));
    let (mut ixx, mut iyy, mut ixy) = (0.0, 0.0, 0.0);
    for ((_, i, j), &p) in sim.engine().phi().indexed_iter() {
        let c = 0.5 * (1.0 + p);
        ixx += c * x[i] * x[i];
        iyy += c * y[j] * y[j];
        ixy += c * x[i] * y[j];
    }
    let angle = 0.5 * (2.0 * ixy).atan2(ixx - iyy).to_degrees();
    assert!(angle > 40.0 && angle < 45.0, "inclination {angle}°");
}

/// A vesicle in the fluid (reduced area 0.8, R0 = 8ε, h = ε/2, adaptive SBDF2): the exact
/// projection holds the area to round-off every step with the flow's response to σ in the
/// step (φ̂^{n+1} = P̂ + σ(Q̂ + R̂)), σ stays of the bending scale (|σ|R0²/κ < 10; with σ lagged
/// in the flow it ran to ±4 within twelve steps, |σ|R0²/κ ≈ 140), and F_sc falls.
#[test]
fn a_vesicle_in_the_fluid_keeps_its_area() {
    let s = scene(json!({
        "dim": 2, "n": [64, 64], "h": 0.5, "scheme": "sbdf2", "dt": 0.5,
        "adaptive": {"dt_max": 3.0}, "max_steps": 120, "prepare_steps": 20,
        "dynamics": "stokes", "flow": {"viscosity": 1.0, "mobility": 0.01},
        "initial": {"shape": "spheroid", "reduced_volume": 0.8, "r0": 8.0, "kind": "prolate",
                    "axis": "x"}
    }));
    let rows = recorded(&s);
    let first = rows[0];
    let kappa = vesicle::problem::flow::bending_modulus(1.0);
    for r in &rows[1..] {
        assert!(
            (r.area - first.area).abs() <= 1e-12 * first.area,
            "step {}",
            r.step
        );
        assert!(r.sigma.abs() * 64.0 / kappa < 10.0, "σ = {}", r.sigma);
    }
    let last = rows.last().expect("rows");
    assert!(
        last.energy < first.energy,
        "{} {}",
        first.energy,
        last.energy
    );
}
