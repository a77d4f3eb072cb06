//! Shared helpers of the integration tests: scenes from JSON and engines built from them.
#![allow(dead_code)]

use serde_json::Value;
use vesicle::config::{self, Scene};
use vesicle::engine::Engine;
use vesicle::run;
use vesicle::setup::{self, Problem};

/// A validated scene from JSON.
pub fn scene(v: Value) -> Scene {
    let s = config::from_value(v).expect("valid scene");
    s.validate().expect("valid scene");
    s
}

/// The problem and a prepared engine (area constraint installed) for `scene`.
pub fn engine(scene: &Scene) -> (Problem, Box<dyn Engine + Send>) {
    let problem = setup::build(scene).expect("problem");
    let (e, _) = run::start(scene, &problem).expect("engine");
    (problem, e)
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
