//! Step a scene by hand and read φ between steps: every 20 steps, the φ = 0 level set's
//! reduced volume (area in 2D) and the range of φ, from the engine's own array; at the end φ on
//! the full box is written as `.npy` (for NumPy: `numpy.load`).
//!
//! ```sh
//! cargo run --release --example read_phi [SCENE.json] [OUT.npy]
//! ```

use std::path::PathBuf;
use vesicle::analysis::levelset;

fn main() -> vesicle::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .map_or_else(|| PathBuf::from("runs/ellipse2d.json"), PathBuf::from);
    let out = args
        .next()
        .map_or_else(|| std::env::temp_dir().join("phi.npy"), PathBuf::from);
    let scene = vesicle::load(&path, &[])?;
    let problem = vesicle::build(&scene)?;
    let (mut simulation, _a0) = vesicle::Simulation::of_scene(&scene, &problem)?;
    for block in 0..5 {
        simulation.run(&vesicle::StopRules::steps(20 * (block + 1)), &mut [])?;
        // φ on the computed grid: a mirror-reduced box holds its part of the full box, so it
        // is unfolded before the whole surface is measured.
        let phi = simulation.engine().phi();
        let full = problem.grid.unfold(phi);
        let level = levelset::measure(&full, scene.dim, scene.h);
        let (lo, hi) = phi
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &p| {
                (a.min(p), b.max(p))
            });
        println!(
            "step {:>3}: reduced {} of φ = 0: {:.5}, φ in [{lo:.4}, {hi:.4}]",
            simulation.clock.step,
            if scene.dim == 2 { "area" } else { "volume" },
            level.reduced_volume
        );
    }
    let full = problem.grid.unfold(simulation.engine().phi());
    vesicle::output::npy::write_npy(&out, &full, scene.dim)?;
    println!("φ written to {}", out.display());
    Ok(())
}
