//! `vesicle run` and `vesicle resume`: wire a scene (or a checkpoint) to the simulation driver
//! and its writers. A run builds the problem and prepares the simulation; a resumed run rebuilds
//! the engine from `checkpoint.bin`. Both then run with the recorder, progress bar, snapshot,
//! checkpoint and interrupt observers, holding the folder's lock, and write the final field,
//! images and `summary.json`.

use crate::driver::checkpoint::Checkpoint;
use crate::driver::observers::{Checkpointer, Progress, Recorder, Snapshots};
use crate::driver::record::{Record, TimeSeries};
use crate::driver::signals::Interrupts;
use crate::driver::simulation::{
    build_engine, check_stability, constrain, stability_bound, Prepared, Simulation, StopRules,
    Stopped,
};
use crate::engines::Engine;
use crate::error::{Error, Result};
use crate::output;
use crate::output::folder::{check_out_dir, make_out_dir};
use crate::output::lock::RunLock;
use crate::problem::config::{self, AreaMethod, Scene, Symmetry};
use crate::problem::grid::Grid;
use crate::problem::setup::{self, Problem};
use serde_json::json;
use std::path::{Path, PathBuf};

/// How a run is driven and where it writes.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output folder (created; must not exist unless `force`).
    pub out: PathBuf,
    /// Replace an existing output folder.
    pub force: bool,
    /// Show a progress bar (only drawn on a terminal).
    pub progress: bool,
}

/// The result of a completed run.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The last record.
    pub last: Record,
    /// Why it stopped.
    pub stopped: Stopped,
    /// Wall time of the time loop.
    pub wall_seconds: f64,
    /// The signal that interrupted the run (SIGINT or SIGTERM), if one did.
    pub signal: Option<i32>,
}

/// The scene with every default made explicit, as saved under `"spec"` in `summary.json` (the
/// area target A0 `a0`, except under a fixed tension).
pub fn resolved_scene(scene: &Scene, a0: f64, mirror: &[bool]) -> Scene {
    let mut s = scene.clone();
    s.area.method = Some(scene.area_method());
    // A fixed tension holds σ, not an area: its scene has no target.
    if scene.area_method() != AreaMethod::Fixed {
        s.area.target = Some(a0);
    }
    if scene.area_method() == AreaMethod::Lagrangian {
        s.area.alpha = Some(scene.alpha());
    }
    s.symmetry = Symmetry::Axes(
        mirror
            .iter()
            .zip(["x", "y", "z"])
            .filter(|(m, _)| **m)
            .map(|(_, a)| a.to_string())
            .collect(),
    );
    s.threads = Some(scene.threads());
    if scene.output.records.is_none() {
        s.output.record_every = Some(scene.record_every());
    }
    if scene.output.checkpoints.is_none() {
        s.output.checkpoint_minutes = Some(scene.checkpoints().every_minutes.unwrap_or_default());
    }
    let st = scene.stabilizer();
    s.stabilizer = crate::problem::config::StabilizerSpec {
        s2: Some(st.s2),
        s4: Some(st.s4),
    };
    s
}

/// Run a validated scene and write its outputs to `opts.out`.
///
/// # Errors
/// `Error::Config` for input that only shows up once the field is built (shape outside the
/// box, asymmetric mirror planes, unstable Δt, an output folder that exists or cannot be
/// written, checked first), in which case nothing is written; `Error::Blowup` after writing
/// the last good state and the summary.
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<Outcome> {
    check_out_dir(&opts.out, opts.force)?;
    let mut problem = setup::build(scene)?;
    check_stability(scene, &problem.grid)?;
    let Prepared {
        mut simulation,
        area_target,
    } = Prepared::new(scene, &problem)?;
    // The engine holds its own copy of φ: free the initial field for the run.
    problem.phi = ndarray::Array3::zeros((0, 0, 0));
    make_out_dir(&opts.out, opts.force)?;
    let _lock = RunLock::acquire(&opts.out)?;
    let a0 = area_target
        .as_ref()
        .map_or_else(|_| simulation.engine().measures().area, |a| *a);
    let resolved = resolved_scene(scene, a0, &problem.mirror);
    let mut recorder = Recorder::to_file(scene.records(), &opts.out.join("timeseries.csv"))?;
    match area_target {
        Err(e) => {
            simulation.run(&StopRules::steps(0), &mut [&mut recorder])?;
            finish(
                &opts.out,
                &problem.grid,
                &simulation,
                &resolved,
                &recorder,
                (Err(e), None),
            )
        }
        Ok(_) => {
            eprintln!(
                "{}",
                describe(&resolved, &problem, simulation.engine().name())
            );
            drive(&resolved, &problem.grid, simulation, recorder, opts)
        }
    }
}

/// Continue the run in `dir` from its `checkpoint` (read from `dir`), with `scene` its
/// scene after the overrides of [`resumed_scene`]. The time series is cut back to the
/// checkpoint's step and continued; the final field and `summary.json` are rewritten at the end.
///
/// # Errors
/// `Error::Config` if the checkpoint does not fit the scene or another run holds the folder;
/// otherwise as [`run`].
pub fn resume(
    dir: &Path,
    checkpoint: Checkpoint<'static>,
    scene: &Scene,
    progress: bool,
) -> Result<Outcome> {
    let _lock = RunLock::acquire(dir)?;
    let (simulation, problem) = restore(checkpoint, scene)?;
    let clock = simulation.clock;
    let (series, history) = TimeSeries::resume(&dir.join("timeseries.csv"), clock.step)?;
    let recorder = Recorder::resuming(scene.records(), series, history);
    eprintln!(
        "{}\n  resuming at step {} t = {:.6e}",
        describe(scene, &problem, simulation.engine().name()),
        clock.step,
        clock.t
    );
    let opts = RunOptions {
        out: dir.to_path_buf(),
        force: false,
        progress,
    };
    drive(scene, &problem.grid, simulation, recorder, &opts)
}

/// The simulation a `checkpoint` holds, for `scene` (its scene after the overrides of
/// [`resumed_scene`]): the engine rebuilt on the scene's grid (the problem's frame, returned
/// beside it, without an initial field), its area constraint and state restored, and the clock
/// where the checkpoint left it. Stepping it continues the run that wrote the checkpoint exactly.
///
/// # Errors
/// `Error::Config` on field `checkpoint` if the checkpoint does not fit the scene.
pub fn restore(
    mut checkpoint: Checkpoint<'static>,
    scene: &Scene,
) -> Result<(Simulation, Problem)> {
    let problem = setup::frame(scene)?;
    let mut engine = build_engine(scene, &problem)?;
    // A fixed tension has no area target (its constraint ignores it).
    let target = match scene.area_method() {
        AreaMethod::Fixed => f64::NAN,
        _ => scene.area.target.ok_or_else(|| {
            Error::config("checkpoint", "its scene lacks the resolved area.target")
        })?,
    };
    constrain(engine.as_mut(), scene, target)?;
    engine
        .restore(&mut checkpoint.engine, checkpoint.clock.t)
        .map_err(|m| Error::config("checkpoint", m))?;
    let clock = checkpoint.clock;
    let mut simulation = Simulation::new(engine, scene.dt, scene.dim, scene.eps);
    simulation.clock = clock;
    simulation.timers = checkpoint.timers;
    Ok((simulation, problem))
}

/// Top-level keys a resumed run may change.
const RESUMABLE: [&str; 6] = [
    "max_steps",
    "t_end",
    "stop_residual",
    "max_wall_minutes",
    "threads",
    "output",
];

/// The two forms of each output's schedule: setting a key of one form on resume removes the
/// keys of the other.
const OUTPUT_FORMS: [(&str, &[&str]); 3] = [
    ("records", &["record_every"]),
    ("snapshots", &["snapshot_every"]),
    ("checkpoints", &["checkpoint_every", "checkpoint_minutes"]),
];

/// The checkpoint's scene with `overrides` applied, each to a key of [`RESUMABLE`]
/// (`max_steps` counts every step since the start of the run). An output schedule set in one
/// form (`output.snapshots`) replaces the other (`output.snapshot_every`), which the checkpoint's
/// resolved scene may hold.
///
/// # Errors
/// `Error::Config` naming a key that cannot change on resume, or an invalid value.
pub fn resumed_scene(mut value: serde_json::Value, overrides: &[String]) -> Result<Scene> {
    for o in overrides {
        let key = o.split('=').next().unwrap_or_default();
        for (new, old) in OUTPUT_FORMS {
            let replaced: &[&str] = if key.strip_prefix("output.") == Some(new) {
                old
            } else if old.iter().any(|k| key.strip_prefix("output.") == Some(k)) {
                &[new]
            } else {
                &[]
            };
            for k in replaced {
                config::apply_override(&mut value, &format!("output.{k}=null"))?;
            }
        }
        let top = key.split('.').next().unwrap_or_default();
        if !RESUMABLE.contains(&top) {
            return Err(Error::config(
                key,
                format!(
                    "cannot change when resuming (the checkpoint continues the run that wrote it); \
                     only {} can",
                    RESUMABLE.join(", ")
                ),
            ));
        }
        config::apply_override(&mut value, o)?;
    }
    let scene = config::from_value(value)?;
    scene.validate()?;
    Ok(scene)
}

/// Run `simulation` with the writers of a run folder until a stop rule of `resolved` fires, an
/// interrupt arrives or a step fails, then write the final outputs.
fn drive(
    resolved: &Scene,
    grid: &Grid,
    mut simulation: Simulation,
    mut recorder: Recorder,
    opts: &RunOptions,
) -> Result<Outcome> {
    let rules = StopRules::of(resolved);
    let mut progress = Progress::new(rules, opts.progress);
    let mut snapshots = Snapshots::new(&opts.out.join("snapshots"), grid, resolved);
    let mut checkpoints =
        Checkpointer::new(&opts.out, resolved.resolved_value(), resolved.checkpoints());
    let mut interrupts = Interrupts::install();
    let result = simulation.run(
        &rules,
        &mut [
            &mut recorder,
            &mut progress,
            &mut snapshots,
            &mut interrupts,
            &mut checkpoints,
        ],
    );
    let ending = (result, interrupts.received());
    finish(&opts.out, grid, &simulation, resolved, &recorder, ending)
}

/// Write the final outputs and turn how the step loop ended (its result, and the signal that
/// interrupted it) into the run's result.
fn finish(
    out: &Path,
    grid: &Grid,
    simulation: &Simulation,
    resolved: &Scene,
    recorder: &Recorder,
    (result, signal): (Result<Stopped>, Option<i32>),
) -> Result<Outcome> {
    let last = *recorder.last().expect("the recorder keeps the last state");
    let text = match &result {
        Ok(stopped) => stopped.as_str().to_string(),
        Err(e @ Error::Device { .. }) => format!("device failed: {e}"),
        Err(e) => format!("blew up: {e}"),
    };
    let summary = End {
        last: &last,
        stopped: &text,
        history: &recorder.history,
    };
    write_final(out, grid, simulation.engine(), resolved, &summary)?;
    result.map(|stopped| Outcome {
        last,
        stopped,
        wall_seconds: last.wall_seconds,
        signal,
    })
}

/// How a run ended, for the final outputs.
struct End<'a> {
    last: &'a Record,
    stopped: &'a str,
    history: &'a [Record],
}

fn write_final(
    out: &Path,
    grid: &Grid,
    engine: &dyn Engine,
    resolved: &Scene,
    end: &End,
) -> Result<()> {
    let (last, stopped) = (end.last, end.stopped);
    let full = grid.unfold(engine.phi());
    output::npy::write_npy(&out.join("phi_final.npy"), &full, resolved.dim)?;
    if resolved.output.vti {
        output::vti::write_vti(
            &out.join("phi_final.vti"),
            &full,
            resolved.dim,
            resolved.h,
            "phi",
        )?;
    }
    if resolved.output.png {
        let title = format!("step {} t = {:.4e} ({stopped})", last.step, last.t);
        output::image::write_slices_png(&out.join("shape_final.png"), &full, resolved.dim, &title)?;
        write_charts(out, end.history)?;
    }
    let mut last_json = serde_json::to_value(last).expect("serialisable");
    last_json["steps"] = json!(last.step);
    last_json["stopped"] = json!(stopped);
    let summary = json!({
        "spec": resolved.resolved_value(),
        "final": last_json,
        "levelset": crate::analysis::levelset::measure(&full, resolved.dim, resolved.h),
        "max_dt_over_bound": engine.max_dt_over_bound(),
        "steps": last.step,
        "rejected_steps": last.rejected,
        "wall_seconds": last.wall_seconds,
        "stopped": stopped,
        "computed_shape": grid.shape[3 - resolved.dim..],
        "version": env!("CARGO_PKG_VERSION"),
    });
    let path = out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).expect("serialisable");
    std::fs::write(&path, text).map_err(|source| Error::Io { path, source })
}

/// The charts of a run's time series `history` into the folder `out`: `energy.png` (e(t)) and
/// `residual.png` (RMS(μ − μ̄) against t, log scale).
///
/// # Errors
/// `Error::Output` if a chart cannot be written.
pub fn write_charts(out: &Path, history: &[Record]) -> Result<()> {
    let series = |f: fn(&Record) -> f64| history.iter().map(|r| (r.t, f(r))).collect::<Vec<_>>();
    output::chart::write_timeseries_png(
        &out.join("energy.png"),
        &[("reduced energy e", series(|r| r.reduced_energy))],
        "t",
        "e",
        false,
    )?;
    output::chart::write_timeseries_png(
        &out.join("residual.png"),
        &[("RMS(μ − mean μ)", series(|r| r.residual))],
        "t",
        "residual",
        true,
    )?;
    Ok(())
}

/// The stop rules in words.
fn stop_text(scene: &Scene) -> String {
    let mut parts = Vec::new();
    if let Some(r) = scene.stop_residual {
        parts.push(format!("residual < {r:e}"));
    }
    if let Some(t) = scene.t_end {
        parts.push(format!("t = {t}"));
    }
    if let Some(m) = scene.max_steps {
        parts.push(format!("{m} steps"));
    }
    if let Some(m) = scene.max_wall_minutes {
        parts.push(format!("{m} min of wall time"));
    }
    parts.join(" or ")
}

/// A few lines describing the run, printed at start-up.
pub fn describe(scene: &Scene, problem: &Problem, engine: &str) -> String {
    let g = &problem.grid;
    let bound = stability_bound(scene, g);
    let mut s = format!(
        "vesicle {engine}: dim {} n {:?} (computed {:?}, mirror {:?}{}) h {} eps {}\n",
        scene.dim,
        scene.n,
        &g.shape[3 - scene.dim..],
        problem.mirror,
        if scene.walls.is_empty() {
            String::new()
        } else {
            format!(", walls across {}", scene.walls.join(", "))
        },
        scene.h,
        scene.eps
    );
    let stepper = match (scene.method, scene.dynamics) {
        (crate::problem::config::Method::Fd, _) => "explicit Euler".to_string(),
        (_, crate::problem::config::Dynamics::Relaxational) => "L-BFGS".to_string(),
        (_, crate::problem::config::Dynamics::Stokes) => {
            format!("{:?} + stokes flow", scene.scheme).to_lowercase()
        }
        _ => format!("{:?}", scene.scheme).to_lowercase(),
    };
    let area = match scene.area_method() {
        crate::problem::config::AreaMethod::Fixed => {
            format!("fixed (σ = {:e})", scene.area.sigma.unwrap_or(0.0))
        }
        method => format!(
            "{method:?} (A0 = {:.6e})",
            scene.area.target.unwrap_or(f64::NAN)
        ),
    };
    s += &format!(
        "  dt {}  {stepper}  area {area}  stop: {}",
        scene.dt,
        stop_text(scene)
    );
    if let Some(b) = bound {
        s += &format!(
            "\n  stability bound {b:.4e} (dt/bound = {:.3})",
            scene.dt / b
        );
    }
    // The pinning table was measured on the spectral discretisation (FD's own spatial error
    // is far larger at these spacings: the precision study).
    if scene.method == crate::problem::config::Method::Spectral && scene.dim >= 2 {
        s += &format!("\n  {}", crate::problem::pinning::note(scene.h / scene.eps));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::resumed_scene;
    use crate::problem::config::Schedule;
    use serde_json::json;

    /// A checkpoint's resolved scene holds the step-count forms; setting the schedule form of an
    /// output on resume replaces them, and setting a step-count key replaces a schedule.
    #[test]
    fn one_form_of_an_output_schedule_replaces_the_other_on_resume() {
        let resolved = json!({
            "dim": 2, "n": [32, 32], "dt": 0.1, "max_steps": 10,
            "initial": {"shape": "sphere", "radius": 6.0},
            "output": {"record_every": 5, "checkpoint_every": 3, "checkpoint_minutes": 10.0,
                       "snapshots": {"every_time": 2.0}}
        });
        let s = resumed_scene(
            resolved.clone(),
            &[
                r#"output.records={"every_time": 0.5}"#.into(),
                r#"output.checkpoints={"every_minutes": 1}"#.into(),
                "output.snapshot_every=4".into(),
            ],
        )
        .unwrap();
        assert_eq!(s.records(), Schedule::time(0.5));
        assert_eq!(s.checkpoints(), Schedule::minutes(1.0));
        assert_eq!(s.snapshots(), Schedule::steps(4));
        assert_eq!(s.output.record_every, None);
        // Without such overrides the checkpoint's forms stay, and a bad value names its key.
        let s = resumed_scene(resolved.clone(), &[]).unwrap();
        assert_eq!(s.records(), Schedule::steps(5));
        let e = resumed_scene(resolved, &[r#"output.records={"every_steps": 0}"#.into()]);
        assert!(
            e.unwrap_err()
                .to_string()
                .contains("output.records.every_steps"),
            "names the field"
        );
    }
}
