//! Run a sheared scene (one with `flow.shear_rate`) and print the vesicle's inclination ψ, its
//! deformation D and the reduced area (volume) of the φ = 0 surface as it turns, at strain
//! marks γ̇t = 0.5, 1, 2.5, 5, 7.5, 10, 15, 20, 25, … and at the end; then when ψ came within
//! 1° and 0.5° of its final value. ψ and D come from the second moments of the region inside
//! the φ = 0 surface, the measure of `vesicle study shear`.
//!
//! ```sh
//! cargo run --release --example shear_angle [SCENE.json]     # default runs/couette_peer.json
//! ```

use std::path::PathBuf;
use vesicle::analysis::levelset;
use vesicle::commands::study::shear::measure::moments;
use vesicle::driver::simulation::{Flow, Now, Probe};

fn main() -> vesicle::Result<()> {
    let path = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("runs/couette_peer.json"), PathBuf::from);
    let scene = vesicle::load(&path, &[])?;
    let rate = scene
        .flow
        .as_ref()
        .and_then(|f| f.shear_rate)
        .ok_or_else(|| vesicle::Error::config("flow.shear_rate", "the scene has no shear"))?;
    let problem = vesicle::build(&scene)?;
    let grid = problem.grid.clone();
    let (mut simulation, _) = vesicle::Simulation::of_scene(&scene, &problem)?;
    let marks = [
        0.5, 1.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0, 50.0,
    ];
    let mut next = 0;
    let mut series: Vec<(f64, f64)> = Vec::new();
    let show = |strain: f64, phi: &ndarray::Array3<f64>| {
        let (psi, d) = moments(&grid, phi);
        let v = levelset::measure(&grid.unfold(phi), scene.dim, scene.h).reduced_volume;
        println!("γ̇t {strain:7.3}: ψ {psi:7.3}°, D {d:.4}, v(φ = 0) {v:.4}");
        psi
    };
    let mut probe = Probe(|now: &Now| {
        let strain = rate * now.record.t;
        let phi = now.engine.phi();
        series.push((strain, moments(&grid, phi).0));
        if next < marks.len() && strain >= marks[next] {
            show(strain, phi);
            while next < marks.len() && strain >= marks[next] {
                next += 1;
            }
        }
        Ok(Flow::Continue)
    });
    simulation.run(&vesicle::StopRules::of(&scene), &mut [&mut probe])?;
    let strain = rate * simulation.clock.t;
    let last = show(strain, simulation.engine().phi());
    for within in [1.0, 0.5] {
        // The first strain after which ψ stays within `within` of its final value.
        let settled = series
            .iter()
            .rev()
            .take_while(|(_, psi)| (psi - last).abs() <= within)
            .last()
            .map_or(f64::NAN, |(s, _)| *s);
        println!("within {within}° of the final angle from γ̇t = {settled:.2}");
    }
    Ok(())
}
