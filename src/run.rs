//! The run driver: builds the problem and engine from a scene, prepares the profile, takes A0,
//! steps until a stop rule fires, records the time series, writes snapshots and the summary.

use crate::config::{AreaMethod, Dynamics, Method, Scene, Symmetry};
use crate::engine::{AreaConstraint, Diverged, Engine};
use crate::error::{Error, Result};
use crate::fd::{self, FdEngine};
use crate::grid::Grid;
use crate::output;
use crate::record::{Record, TimeSeries};
use crate::relax::RelaxEngine;
use crate::setup::{self, Problem};
use crate::spectral::{self, SpectralEngine};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

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

/// Why a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Stopped {
    /// The residual fell below `stop_residual`.
    Stationary,
    /// `t_end` reached.
    TimeEnd,
    /// `max_steps` reached.
    MaxSteps,
    /// The engine could make no further progress (round-off floor).
    Stalled,
}

impl Stopped {
    /// The name written to `summary.json` (`"stopped"`).
    pub fn as_str(&self) -> &'static str {
        match self {
            Stopped::Stationary => "stationary",
            Stopped::TimeEnd => "t_end",
            Stopped::MaxSteps => "max_steps",
            Stopped::Stalled => "stalled",
        }
    }
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
}

/// Stability bound of the scene's method at σ = 0, if it has one: the FD bound of DESIGN.md
/// §2, or the frozen-coefficient bound of the spectral scheme (infinite when the stabiliser
/// makes the bulk linearisation unconditionally stable).
pub fn stability_bound(scene: &Scene, grid: &Grid) -> Option<f64> {
    match (scene.method, scene.dynamics) {
        (Method::Fd, _) => Some(fd::stability_bound(grid, scene.eps, 0.0)),
        (Method::Spectral, Dynamics::Conserved) => {
            let b =
                spectral::stability_bound(grid, scene.eps, &scene.stabilizer(), scene.laplacian);
            b.is_finite().then_some(b)
        }
        (Method::Spectral, Dynamics::Relaxational) => None,
    }
}

/// Refuse a fixed Δt above the method's bound unless the scene allows it.
///
/// # Errors
/// `Error::Config` on field `dt` with the bound.
pub fn check_stability(scene: &Scene, grid: &Grid) -> Result<()> {
    if scene.allow_unstable || scene.adaptive.settings().is_some() {
        return Ok(());
    }
    match stability_bound(scene, grid) {
        Some(bound) if scene.dt >= bound => Err(Error::config(
            "dt",
            format!(
                "{} exceeds the {} stability bound {bound:.4e} (ε = {}, h = {}, dim = {}); \
                 use dt < {bound:.4e}, or set \"allow_unstable\": true for a stability study",
                scene.dt,
                match scene.method {
                    Method::Fd => "finite-difference explicit-Euler",
                    Method::Spectral => "semi-implicit (frozen-coefficient)",
                },
                scene.eps,
                scene.h,
                scene.dim
            ),
        )),
        _ => Ok(()),
    }
}

/// Build the engine a scene asks for, holding `problem.phi` at time 0, no area constraint.
///
/// # Errors
/// `Error::Config` if the initial field is not finite.
fn build_engine(scene: &Scene, problem: &Problem) -> Result<Box<dyn Engine + Send>> {
    let grid = problem.grid.clone();
    let c0 = problem.c0.clone();
    let phi = problem.phi.clone();
    let bad = |d: Diverged| Error::config("initial", d.0);
    Ok(match (scene.method, scene.dynamics) {
        (Method::Fd, _) => Box::new(FdEngine::new(grid, scene.eps, c0, phi, 0.0).map_err(bad)?),
        (Method::Spectral, Dynamics::Conserved) => {
            Box::new(SpectralEngine::new(scene, grid, c0, phi).map_err(bad)?)
        }
        (Method::Spectral, Dynamics::Relaxational) => {
            Box::new(RelaxEngine::new(scene, grid, c0, phi).map_err(bad)?)
        }
    })
}

/// Build the engine, run the unconstrained preparation steps (σ = 0; the conserved spectral
/// SBDF1 stepper when the dynamics is relaxational), then install the area constraint with
/// A0 = the scene's target or the prepared area. Returns the engine and A0.
///
/// # Errors
/// `Error::Config` if the initial field is not finite; `Error::Blowup` if a preparation step
/// diverges.
pub fn start(scene: &Scene, problem: &Problem) -> Result<(Box<dyn Engine + Send>, f64)> {
    let (engine, a0) = prepared(scene, problem)?;
    Ok((engine, a0?))
}

/// As [`start`], but a divergence during preparation still returns the engine (holding its
/// last good state) beside the error.
fn prepared(scene: &Scene, problem: &Problem) -> Result<(Box<dyn Engine + Send>, Result<f64>)> {
    let relaxational = scene.dynamics == Dynamics::Relaxational;
    let mut prep_scene = scene.clone();
    if relaxational {
        prep_scene.dynamics = Dynamics::Conserved;
        prep_scene.scheme = crate::config::Scheme::Sbdf1;
        prep_scene.adaptive = crate::config::AdaptiveSpec::Flag(false);
    }
    let mut engine = build_engine(&prep_scene, problem)?;
    engine.set_area(AreaConstraint::none());
    for i in 0..scene.prepare_steps {
        if let Err(d) = engine.step(0.0, scene.dt) {
            let reason = format!("during preparation step {}: {}", i + 1, d.0);
            return Ok((
                engine,
                Err(Error::Blowup {
                    step: 0,
                    t: 0.0,
                    reason,
                }),
            ));
        }
    }
    if relaxational {
        let mut prepared = problem.clone();
        prepared.phi = engine.phi().clone();
        engine = build_engine(scene, &prepared)?;
    }
    let a0 = scene.area.target.unwrap_or(engine.measures().area);
    engine.set_area(AreaConstraint {
        method: scene.area_method(),
        alpha: scene.alpha(),
        target: a0,
    });
    Ok((engine, Ok(a0)))
}

/// The scene with every default made explicit, as saved under `"spec"` in `summary.json`.
pub fn resolved_scene(scene: &Scene, a0: f64, mirror: &[bool]) -> Scene {
    let mut s = scene.clone();
    s.area.method = Some(scene.area_method());
    s.area.target = Some(a0);
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
    s.threads = Some(rayon::current_num_threads());
    s.output.record_every = Some(scene.record_every());
    let st = scene.stabilizer();
    s.stabilizer = crate::config::StabilizerSpec {
        s2: Some(st.s2),
        s4: Some(st.s4),
    };
    s
}

/// Prepare the output folder: refuse an existing one unless `force`.
///
/// # Errors
/// `Error::Config` on field `--out` if it exists without `force`; `Error::Io` on failure.
pub fn make_out_dir(out: &Path, force: bool) -> Result<()> {
    if out.exists() {
        if !force {
            return Err(Error::config(
                "--out",
                format!(
                    "{} already exists; results are never overwritten silently (pass --force to replace it)",
                    out.display()
                ),
            ));
        }
        std::fs::remove_dir_all(out).map_err(|source| Error::Io {
            path: out.to_path_buf(),
            source,
        })?;
    }
    std::fs::create_dir_all(out.join("snapshots")).map_err(|source| Error::Io {
        path: out.to_path_buf(),
        source,
    })
}

/// Run a validated scene and write its outputs to `opts.out`.
///
/// # Errors
/// `Error::Config` for input that only shows up once the field is built (shape outside the
/// box, asymmetric mirror planes, unstable Δt, existing output folder), in which case nothing
/// is written; `Error::Blowup` after writing the last good state and the summary.
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<Outcome> {
    let mut problem = setup::build(scene)?;
    check_stability(scene, &problem.grid)?;
    if opts.out.exists() && !opts.force {
        make_out_dir(&opts.out, false)?;
    }
    let (mut engine, a0) = prepared(scene, &problem)?;
    // The engine holds its own copy of φ: free the initial field for the run.
    problem.phi = ndarray::Array3::zeros((0, 0, 0));
    make_out_dir(&opts.out, opts.force)?;
    let a0 = match a0 {
        Ok(a0) => a0,
        Err(e) => {
            let target = scene.area.target.unwrap_or(engine.measures().area);
            let resolved = resolved_scene(scene, target, &problem.mirror);
            let last = Record::new(0, 0.0, 0.0, engine.measures(), 0.0, scene.dim, scene.eps);
            let mut series = TimeSeries::create(&opts.out.join("timeseries.csv"))?;
            series.push(&last)?;
            series.flush()?;
            let stopped = format!("blew up: {e}");
            let end = End {
                last: &last,
                stopped: &stopped,
                wall: 0.0,
                history: &[last],
            };
            write_final(&opts.out, &problem.grid, engine.as_ref(), &resolved, &end)?;
            return Err(e);
        }
    };
    let resolved = resolved_scene(scene, a0, &problem.mirror);
    eprintln!("{}", describe(&resolved, &problem, engine.name()));
    let mut series = TimeSeries::create(&opts.out.join("timeseries.csv"))?;
    let mut history = Vec::new();
    let result = time_loop(
        scene,
        &problem.grid,
        engine.as_mut(),
        &mut series,
        &mut history,
        opts,
    );
    series.flush()?;
    let (last, wall, ended) = match result {
        Ok((last, stopped, wall)) => (last, wall, Ok(stopped)),
        Err(failed) => {
            let (last, wall, e) = *failed;
            (last, wall, Err(e))
        }
    };
    let text = match &ended {
        Ok(stopped) => stopped.as_str().to_string(),
        Err(e) => format!("blew up: {e}"),
    };
    let end = End {
        last: &last,
        stopped: &text,
        wall,
        history: &history,
    };
    write_final(&opts.out, &problem.grid, engine.as_ref(), &resolved, &end)?;
    ended.map(|stopped| Outcome {
        last,
        stopped,
        wall_seconds: wall,
    })
}

/// How a run ended, for the final outputs.
struct End<'a> {
    last: &'a Record,
    stopped: &'a str,
    wall: f64,
    history: &'a [Record],
}

type LoopResult = std::result::Result<(Record, Stopped, f64), Box<(Record, f64, Error)>>;

/// Step until a stop rule fires. On divergence returns the last good record and the error.
fn time_loop(
    scene: &Scene,
    grid: &Grid,
    engine: &mut dyn Engine,
    series: &mut TimeSeries,
    history: &mut Vec<Record>,
    opts: &RunOptions,
) -> LoopResult {
    let start = Instant::now();
    let record = |step, t, dt, e: &dyn Engine| {
        Record::new(step, t, dt, e.measures(), e.sigma(), scene.dim, scene.eps)
    };
    let mut last = record(0, 0.0, 0.0, engine);
    let fail = |last: Record, e: Error| Box::new((last, start.elapsed().as_secs_f64(), e));
    series.push(&last).map_err(|e| fail(last, e))?;
    history.push(last);
    let bar = progress_bar(scene, opts.progress);
    let (mut t, mut step, mut dt, mut rejected) = (0.0, 0usize, scene.dt, 0usize);
    let record_every = scene.record_every();
    let stopped = loop {
        dt = engine.next_dt(dt);
        if let Some(t_end) = scene.t_end {
            dt = dt.min(t_end - t);
        }
        let report = match engine.step(t, dt) {
            Ok(r) => r,
            Err(Diverged(reason)) => {
                bar.abandon();
                let err = Error::Blowup {
                    step: step + 1,
                    t: t + dt,
                    reason,
                };
                if last.step != step {
                    // Record the last good state, which the engine still holds.
                    last = record(step, t, dt, engine);
                    last.rejected = rejected;
                    last.wall_seconds = start.elapsed().as_secs_f64();
                    let _ = series.push(&last);
                    history.push(last);
                }
                return Err(fail(last, err));
            }
        };
        t += report.dt;
        dt = report.dt;
        step += 1;
        rejected += report.rejected;
        let stop = if engine.stalled() {
            Some(Stopped::Stalled)
        } else {
            stop_rule(scene, t, dt, step, report.residual)
        };
        if step % record_every == 0 || stop.is_some() {
            last = record(step, t, dt, engine);
            last.residual = report.residual;
            last.rejected = rejected;
            last.wall_seconds = start.elapsed().as_secs_f64();
            series.push(&last).map_err(|e| fail(last, e))?;
            history.push(last);
        }
        if scene.output.snapshot_every > 0 && step % scene.output.snapshot_every == 0 {
            write_snapshot(&opts.out, grid, engine.phi(), scene, step)
                .map_err(|e| fail(last, e))?;
        }
        update_bar(&bar, scene, t, step, dt, report.residual);
        if let Some(s) = stop {
            break s;
        }
    };
    bar.finish_and_clear();
    Ok((last, stopped, start.elapsed().as_secs_f64()))
}

/// The stop rules; `t_end` counts as reached within 1e-6 of the last step (the sum of many
/// steps carries round-off, which must not cost an extra step of ~1e-13).
fn stop_rule(scene: &Scene, t: f64, dt: f64, step: usize, residual: f64) -> Option<Stopped> {
    if scene.stop_residual.is_some_and(|tol| residual < tol) {
        Some(Stopped::Stationary)
    } else if scene.t_end.is_some_and(|te| t >= te - 1e-6 * dt) {
        Some(Stopped::TimeEnd)
    } else if scene.max_steps.is_some_and(|m| step >= m) {
        Some(Stopped::MaxSteps)
    } else {
        None
    }
}

fn progress_bar(scene: &Scene, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = match (scene.t_end, scene.max_steps) {
        (Some(_), _) => ProgressBar::new(1000),
        (None, Some(m)) => ProgressBar::new(m as u64),
        _ => ProgressBar::new_spinner(),
    };
    bar.set_draw_target(ProgressDrawTarget::stderr_with_hz(4));
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {percent:>3}% eta {eta:>5} | {msg}")
            .expect("valid template"),
    );
    bar
}

fn update_bar(bar: &ProgressBar, scene: &Scene, t: f64, step: usize, dt: f64, residual: f64) {
    if bar.is_hidden() {
        return;
    }
    let pos = match (scene.t_end, scene.max_steps) {
        (Some(te), Some(m)) => (1000.0 * (t / te).max(step as f64 / m as f64)) as u64,
        (Some(te), None) => (1000.0 * t / te) as u64,
        (None, Some(_)) => step as u64,
        _ => 0,
    };
    bar.set_position(pos);
    bar.set_message(format!(
        "step {step}  t {t:.4e}  dt {dt:.3e}  residual {residual:.3e}"
    ));
}

fn write_snapshot(
    out: &Path,
    grid: &Grid,
    phi: &ndarray::Array3<f64>,
    scene: &Scene,
    step: usize,
) -> Result<()> {
    let full = grid.unfold(phi);
    let base = out.join("snapshots").join(format!("phi_{step:08}"));
    output::npy::write_npy(&base.with_extension("npy"), &full, scene.dim)?;
    if scene.output.vti {
        output::vti::write_vti(
            &base.with_extension("vti"),
            &full,
            scene.dim,
            scene.h,
            "phi",
        )?;
    }
    if scene.output.png {
        output::image::write_slices_png(
            &base.with_extension("png"),
            &full,
            scene.dim,
            &format!("step {step}"),
        )?;
    }
    Ok(())
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
    let summary = json!({
        "spec": resolved.resolved_value(),
        "final": last,
        "levelset": crate::levelset::measure(&full, resolved.dim, resolved.h),
        "max_dt_over_bound": engine.max_dt_over_bound(),
        "steps": last.step,
        "rejected_steps": last.rejected,
        "wall_seconds": end.wall,
        "stopped": stopped,
        "computed_shape": grid.shape[3 - resolved.dim..],
        "version": env!("CARGO_PKG_VERSION"),
    });
    let path = out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).expect("serialisable");
    std::fs::write(&path, text).map_err(|source| Error::Io { path, source })
}

fn write_charts(out: &Path, history: &[Record]) -> Result<()> {
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
        &[("max|dφ/dt|", series(|r| r.residual))],
        "t",
        "residual",
        true,
    )?;
    Ok(())
}

/// A few lines describing the run, printed at start-up.
pub fn describe(scene: &Scene, problem: &Problem, engine: &str) -> String {
    let g = &problem.grid;
    let bound = stability_bound(scene, g);
    let mut s = format!(
        "vesicle {engine}: dim {} n {:?} (computed {:?}, mirror {:?}) h {} eps {}\n",
        scene.dim,
        scene.n,
        &g.shape[3 - scene.dim..],
        problem.mirror,
        scene.h,
        scene.eps
    );
    s += &format!(
        "  dt {}  scheme {:?}  dynamics {:?}  area {:?} (A0 = {:.6e})",
        scene.dt,
        scene.scheme,
        scene.dynamics,
        scene.area_method(),
        scene.area.target.unwrap_or(f64::NAN)
    );
    if let Some(b) = bound {
        s += &format!(
            "\n  stability bound {b:.4e} (dt/bound = {:.3})",
            scene.dt / b
        );
    }
    s
}
