//! `vesicle compare`: the finite-difference reference and the spectral engine from the same
//! (prepared) initial field, side by side at common times.

use crate::driver::simulation::{check_stability, Simulation, StopRules};
use crate::engines::fd;
use crate::error::{Error, Result};
use crate::output::folder;
use crate::problem::config::{Method, Scene};
use crate::problem::model::Measures;
use crate::problem::setup;
use std::fmt::Write as _;
use std::path::Path;

/// Rows of the comparison table.
pub const ROWS: usize = 10;

/// One engine's state at a common time.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// F_sc, A, V.
    pub measures: Measures,
    /// σ.
    pub sigma: f64,
    /// Steps taken so far.
    pub steps: usize,
    /// Wall seconds so far.
    pub wall: f64,
}

/// The comparison at one time.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    /// Common time.
    pub t: f64,
    /// Finite differences.
    pub fd: Sample,
    /// Spectral.
    pub spectral: Sample,
    /// max |φ_fd − φ_sp|.
    pub max_dphi: f64,
}

/// The FD time step used by `compare`: the scene's `dt` when the scene is an FD scene, else
/// half the FD stability bound.
pub fn fd_dt(scene: &Scene, grid: &crate::problem::grid::Grid) -> f64 {
    match scene.method {
        Method::Fd => scene.dt,
        Method::Spectral => 0.5 * fd::stability_bound(grid, scene.eps, 0.0),
    }
}

/// Run both engines over `[0, t_end]` and compare them at `ROWS` common times.
///
/// # Errors
/// `Error::Config` if the scene has no `t_end` or the output folder exists (without `force`);
/// `Error::Blowup` if either engine diverges.
pub fn run_pair(scene: &Scene) -> Result<Vec<Row>> {
    let t_end = scene
        .t_end
        .ok_or_else(|| Error::config("t_end", "compare needs t_end (the common time span)"))?;
    let problem = setup::build(scene)?;
    let mut sp_scene = scene.clone();
    sp_scene.method = Method::Spectral;
    let mut fd_scene = scene.clone();
    fd_scene.method = Method::Fd;
    fd_scene.adaptive = crate::problem::config::AdaptiveSpec::Flag(false);
    fd_scene.dt = fd_dt(scene, &problem.grid);
    check_stability(&fd_scene, &problem.grid)?;
    // Prepare once (FD), then both engines start from the same field and A0.
    let (prepared_fd, a0) = Simulation::of_scene(&fd_scene, &problem)?;
    let mut prepared = problem.clone();
    prepared.phi = prepared_fd.engine().phi().clone();
    // Both engines hold the area the same way (the scene's method, default projection).
    let method = scene.area_method();
    for s in [&mut sp_scene, &mut fd_scene] {
        s.prepare_steps = 0;
        s.area.method = Some(method);
        s.area.target = Some(a0);
    }
    let (mut fd_sim, _) = Simulation::of_scene(&fd_scene, &prepared)?;
    let (mut sp_sim, _) = Simulation::of_scene(&sp_scene, &prepared)?;
    let mut rows = Vec::with_capacity(ROWS + 1);
    for j in 0..=ROWS {
        let target = t_end * j as f64 / ROWS as f64;
        for (name, sim) in [("fd", &mut fd_sim), ("spectral", &mut sp_sim)] {
            sim.run(&StopRules::until(target), &mut [])
                .map_err(|e| e.within(&format!("{name} engine")))?;
        }
        let max_dphi =
            crate::problem::model::max_abs_diff(fd_sim.engine().phi(), sp_sim.engine().phi());
        let sample = |sim: &Simulation| Sample {
            measures: sim.engine().measures(),
            sigma: sim.engine().sigma(),
            steps: sim.clock.step,
            wall: sim.clock.wall_seconds,
        };
        rows.push(Row {
            t: target,
            fd: sample(&fd_sim),
            spectral: sample(&sp_sim),
            max_dphi,
        });
    }
    Ok(rows)
}

/// CSV of the comparison (one line per common time).
pub fn to_csv(rows: &[Row], dim: usize, eps: f64) -> String {
    let mut s = String::from(
        "t,fd_energy,sp_energy,fd_area,sp_area,fd_volume,sp_volume,fd_reduced_volume,sp_reduced_volume,\
         fd_reduced_energy,sp_reduced_energy,fd_sigma,sp_sigma,max_abs_dphi,fd_steps,sp_steps,fd_wall_seconds,sp_wall_seconds\n",
    );
    for r in rows {
        let (a, b) = (r.fd.measures, r.spectral.measures);
        let (ra, rb) = (a.reduced(dim, eps), b.reduced(dim, eps));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.t,
            a.energy,
            b.energy,
            a.area,
            b.area,
            a.volume,
            b.volume,
            ra.volume,
            rb.volume,
            ra.energy,
            rb.energy,
            r.fd.sigma,
            r.spectral.sigma,
            r.max_dphi,
            r.fd.steps,
            r.spectral.steps,
            r.fd.wall,
            r.spectral.wall
        );
    }
    s
}

/// The printed table.
pub fn to_table(rows: &[Row], dim: usize, eps: f64) -> String {
    let mut s = format!(
        "{:>11} {:>13} {:>13} {:>9} {:>9} {:>9} {:>9} {:>10}\n",
        "t", "F_fd", "F_sp", "e_fd", "e_sp", "v_fd", "v_sp", "max|dphi|"
    );
    for r in rows {
        let (a, b) = (r.fd.measures, r.spectral.measures);
        let (ra, rb) = (a.reduced(dim, eps), b.reduced(dim, eps));
        let _ = writeln!(
            s,
            "{:>11.4e} {:>13.6e} {:>13.6e} {:>9.5} {:>9.5} {:>9.5} {:>9.5} {:>10.3e}",
            r.t, a.energy, b.energy, ra.energy, rb.energy, ra.volume, rb.volume, r.max_dphi
        );
    }
    if let Some(last) = rows.last() {
        let _ = writeln!(
            s,
            "steps: fd {} spectral {}; wall: fd {:.3} s spectral {:.3} s; fd/spectral wall-time ratio {:.1}",
            last.fd.steps,
            last.spectral.steps,
            last.fd.wall,
            last.spectral.wall,
            last.fd.wall / last.spectral.wall.max(1e-12)
        );
    }
    s
}

/// `vesicle compare`: run the pair, print the table, write `compare.csv` and `compare.txt`.
///
/// # Errors
/// As [`run_pair`], plus `Error::Io` when writing.
pub fn compare(scene: &Scene, out: &Path, force: bool) -> Result<()> {
    folder::check_out_dir(out, force)?;
    let rows = run_pair(scene)?;
    folder::make_out_dir(out, force)?;
    let table = to_table(&rows, scene.dim, scene.eps);
    println!("{table}");
    for (name, text) in [
        ("compare.csv", to_csv(&rows, scene.dim, scene.eps)),
        ("compare.txt", table),
    ] {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|source| Error::Io { path, source })?;
    }
    Ok(())
}
