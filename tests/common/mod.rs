//! Shared helpers of the integration tests: scenes from JSON and engines built from them.
#![allow(dead_code)]

use serde_json::{json, Value};
use vesicle::driver::simulation::{Simulation, StopRules, Stopped};
use vesicle::engines::Engine;
use vesicle::problem::config::{self, Scene};
use vesicle::problem::setup::{self, Problem};

/// A validated scene from JSON.
pub fn scene(v: Value) -> Scene {
    let s = config::from_value(v).expect("valid scene");
    s.validate().expect("valid scene");
    s
}

/// The problem and a prepared simulation (area constraint installed) for `scene`.
pub fn simulation(scene: &Scene) -> (Problem, Simulation) {
    let problem = setup::build(scene).expect("problem");
    let (sim, _) = Simulation::of_scene(scene, &problem).expect("simulation");
    (problem, sim)
}

/// The problem and a prepared engine (area constraint installed) for `scene`.
pub fn engine(scene: &Scene) -> (Problem, Box<dyn Engine + Send>) {
    let (problem, sim) = simulation(scene);
    (problem, sim.into_engine())
}

/// Run `sim` to `t_end` (fixed or adaptive steps as its engine does, landing on `t_end`).
pub fn advance(sim: &mut Simulation, t_end: f64) {
    sim.run(&StopRules::until(t_end), &mut [])
        .expect("no blow-up");
}

/// The JSON scene `base` with the entries of `extra` added or replaced.
pub fn with(base: &Value, extra: Value) -> Value {
    let mut v = base.clone();
    v.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    v
}

/// max|φ_fd − φ_sp| at `t_end` from the same field: the FD reference at half its stability
/// bound and spectral SBDF2 at Δt = 2e-4 (time errors far below the O(h²) spatial gap), on the
/// scene `base` (grid, field, c0, area and symmetry; no method or step).
pub fn fd_spectral_gap(base: &Value, t_end: f64) -> f64 {
    let probe = scene(with(base, json!({"method": "fd", "dt": 1e-6})));
    let grid = setup::build(&probe).expect("problem").grid;
    let fd_dt = 0.5 * vesicle::engines::fd::stability_bound(&grid, probe.eps, 0.0);
    let fd = scene(with(base, json!({"method": "fd", "dt": fd_dt})));
    let sp = scene(with(
        base,
        json!({"method": "spectral", "scheme": "sbdf2", "dt": 2e-4}),
    ));
    let (_, mut a) = simulation(&fd);
    let (_, mut b) = simulation(&sp);
    advance(&mut a, t_end);
    advance(&mut b, t_end);
    vesicle::problem::model::max_abs_diff(a.engine().phi(), b.engine().phi())
}

/// Relative difference |a − b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Least-squares slope of log(y) against log(x).
pub fn log_slope(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let n = lx.len() as f64;
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// Relaxed reduced energy of a sphere of radius 6ε on a grid of spacing `h` with the given
/// Laplacian. The FD-discrete energy is relaxed with the semi-implicit engine using the
/// stencil's symbol (`"laplacian": "fd"`): the same discrete energy as the explicit FD
/// reference, whose stability bound (∝ h⁶) makes relaxing at h = ε/4 impractical.
pub fn relaxed_sphere_energy(h: f64, laplacian: &str) -> f64 {
    let n = (22.0 / h).round() as usize;
    let s = scene(json!({
        "dim": 3, "n": [n, n, n], "h": h, "eps": 1.0, "method": "spectral",
        "laplacian": laplacian, "dt": 1e-3, "adaptive": {"dt_max": 50.0},
        "max_steps": 5000, "stop_residual": 1e-8,
        "initial": {"shape": "sphere", "radius": 6.0}, "symmetry": ["x", "y", "z"]
    }));
    let (_, mut sim) = simulation(&s);
    relax(&mut sim, 1e-8, 5000).expect("the sphere relaxes");
    sim.engine().measures().reduced(3, 1.0).energy
}

/// Run `sim` until its residual RMS(μ − μ̄) falls below `tol`; the steps taken, or `None`
/// if `max_steps` did not suffice.
pub fn relax(sim: &mut Simulation, tol: f64, max_steps: usize) -> Option<usize> {
    let rules = StopRules {
        stop_residual: Some(tol),
        max_steps: Some(max_steps),
        ..StopRules::default()
    };
    let stopped = sim.run(&rules, &mut []).expect("no blow-up");
    (stopped == Stopped::Stationary).then_some(sim.clock.step)
}
