//! Run a scene file to its end and print how it ended (the library's `vesicle run` without the
//! output folder): the default scene, a 2D ellipse relaxing to its stationary shape, takes about
//! a second.
//!
//! ```sh
//! cargo run --release --example run_scene [SCENE.json]
//! ```

use std::path::PathBuf;

fn main() -> vesicle::Result<()> {
    let path = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("runs/ellipse2d.json"), PathBuf::from);
    // The scene as `vesicle run` reads it: validated, with `--set`-style overrides (none here).
    let scene = vesicle::load(&path, &[])?;
    // The grid, the initial field and c0; then the preparation steps, the engine the scene
    // asks for and its area constraint (A0).
    let problem = vesicle::build(&scene)?;
    let (mut simulation, a0) = vesicle::Simulation::of_scene(&scene, &problem)?;
    println!(
        "{}: A0 = {a0:.6e}, engine {}",
        path.display(),
        simulation.engine().name()
    );
    // The scene's stop rules (steps, time, stationarity residual, wall time), no observers.
    let stopped = simulation.run(&vesicle::StopRules::of(&scene), &mut [])?;
    let last = simulation.record();
    println!(
        "{} after {} steps at t = {:.4e}: F = {:.6e}, A = {:.6e}, V = {:.6e}, residual {:.3e}",
        stopped.as_str(),
        simulation.clock.step,
        simulation.clock.t,
        last.energy,
        last.area,
        last.volume,
        last.residual
    );
    Ok(())
}
