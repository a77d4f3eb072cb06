//! Observers of a [`Simulation`](crate::driver::simulation::Simulation): the time-series recorder, the
//! progress bar, the snapshot writer and the checkpoint writer, each called on its
//! [`Schedule`] (the driver keeps the schedules' state and lands steps on their due times).

use crate::driver::checkpoint::Checkpoint;
use crate::driver::record::{Record, TimeSeries};
use crate::driver::simulation::{Ending, Flow, Now, Observer, StopRules};
use crate::error::{Error, Result};
use crate::output;
use crate::problem::config::{Scene, Schedule};
use crate::problem::grid::Grid;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};

/// Keeps a row on its schedule, the first state and the last one, in memory and (when given a
/// file) in `timeseries.csv`. A state is kept once even when several calls of `Simulation::run`
/// see it.
pub struct Recorder {
    schedule: Schedule,
    file: Option<TimeSeries>,
    /// The rows kept so far.
    pub history: Vec<Record>,
}

impl Recorder {
    /// Rows in memory only.
    pub fn in_memory(schedule: Schedule) -> Self {
        Recorder {
            schedule,
            file: None,
            history: Vec::new(),
        }
    }

    /// Rows in memory and in the CSV file `path` (created with its header).
    ///
    /// # Errors
    /// `Error::Io` if the file cannot be created.
    pub fn to_file(schedule: Schedule, path: &Path) -> Result<Self> {
        Ok(Recorder {
            file: Some(TimeSeries::create(path)?),
            ..Self::in_memory(schedule)
        })
    }

    /// Continue a time series already holding `history` (a resumed run).
    pub fn resuming(schedule: Schedule, file: TimeSeries, history: Vec<Record>) -> Self {
        Recorder {
            schedule,
            file: Some(file),
            history,
        }
    }

    /// The last row kept.
    pub fn last(&self) -> Option<&Record> {
        self.history.last()
    }

    fn keep(&mut self, r: &Record) -> Result<()> {
        if self.last().is_some_and(|l| l.step == r.step) {
            return Ok(());
        }
        if let Some(f) = self.file.as_mut() {
            f.push(r)?;
        }
        self.history.push(*r);
        Ok(())
    }
}

impl Observer for Recorder {
    fn start(&mut self, now: &Now) -> Result<()> {
        self.keep(&now.record)
    }

    fn step(&mut self, now: &Now) -> Result<Flow> {
        self.keep(&now.record)?;
        Ok(Flow::Continue)
    }

    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        Some(("records", self.schedule))
    }

    fn finish(&mut self, now: &Now, _ending: Ending) -> Result<()> {
        self.keep(&now.record)?;
        match self.file.as_mut() {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

/// Seconds between two updates of the progress bar's text.
const PROGRESS_SECONDS: f64 = 0.25;

/// A progress bar on stderr (drawn only on a terminal), updated every [`PROGRESS_SECONDS`] of
/// wall time: step, t, Δt, residual and an ETA from
/// whichever stop rule is nearest (for `stop_residual`, the fraction of the way in
/// log(residual) from the first state's residual to the tolerance).
pub struct Progress {
    bar: ProgressBar,
    rules: StopRules,
    first_residual: f64,
}

/// Positions of the bar: tenths of a per cent.
const BAR_LENGTH: u64 = 1000;

impl Progress {
    /// A bar for a run with `rules`; hidden unless `show`.
    pub fn new(rules: StopRules, show: bool) -> Self {
        let bar = if show {
            let bar = ProgressBar::new(BAR_LENGTH);
            bar.set_draw_target(ProgressDrawTarget::stderr_with_hz(4));
            bar.set_style(
                ProgressStyle::with_template("{bar:30} {percent:>3}% eta {eta:>5} | {msg}")
                    .expect("valid template"),
            );
            bar
        } else {
            ProgressBar::hidden()
        };
        Progress {
            bar,
            rules,
            first_residual: f64::NAN,
        }
    }

    /// Fraction of the run done by the rule nearest to firing.
    fn fraction(&self, r: &Record) -> f64 {
        let by_time = self.rules.t_end.map(|te| r.t / te);
        let by_steps = self.rules.max_steps.map(|m| r.step as f64 / m as f64);
        let by_residual = self.rules.stop_residual.map(|tol| {
            let span = (self.first_residual / tol).ln();
            if span > 0.0 {
                (self.first_residual / r.residual).ln() / span
            } else {
                1.0
            }
        });
        [by_time, by_steps, by_residual]
            .into_iter()
            .flatten()
            .filter(|f| f.is_finite())
            .fold(0.0, f64::max)
            .clamp(0.0, 1.0)
    }
}

impl Observer for Progress {
    fn start(&mut self, now: &Now) -> Result<()> {
        self.first_residual = now.record.residual;
        Ok(())
    }

    fn step(&mut self, now: &Now) -> Result<Flow> {
        if !self.bar.is_hidden() {
            let r = &now.record;
            self.bar
                .set_position((BAR_LENGTH as f64 * self.fraction(r)) as u64);
            self.bar.set_message(format!(
                "step {}  t {:.4e}  dt {:.3e}  residual {:.3e}",
                r.step, r.t, r.dt, r.residual
            ));
        }
        Ok(Flow::Continue)
    }

    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        let every = if self.bar.is_hidden() {
            Schedule::NEVER
        } else {
            Schedule::minutes(PROGRESS_SECONDS / 60.0)
        };
        Some(("progress", every))
    }

    fn finish(&mut self, _now: &Now, ending: Ending) -> Result<()> {
        match ending {
            Ending::Stopped(_) => self.bar.finish_and_clear(),
            Ending::Failed(_) => self.bar.abandon(),
        }
        Ok(())
    }
}

/// Writes φ of the full box on the scene's snapshot schedule to
/// `DIR/snapshots/phi_<step>.npy` (and `.vti`, `.png` when the scene asks for them).
pub struct Snapshots<'a> {
    dir: PathBuf,
    grid: &'a Grid,
    scene: &'a Scene,
}

impl<'a> Snapshots<'a> {
    /// Snapshots of a run of `scene` on `grid` into `dir`, on [`Scene::snapshots`].
    pub fn new(dir: &Path, grid: &'a Grid, scene: &'a Scene) -> Self {
        Snapshots {
            dir: dir.to_path_buf(),
            grid,
            scene,
        }
    }
}

impl Snapshots<'_> {
    /// φ of `now` into `phi_<step>` (full box); the folder is made with the first snapshot, so
    /// a run without snapshots has none.
    fn write(&self, now: &Now) -> Result<()> {
        std::fs::create_dir_all(&self.dir).map_err(|source| Error::Io {
            path: self.dir.clone(),
            source,
        })?;
        let step = now.record.step;
        let full = self.grid.unfold(now.engine.phi());
        let (dim, s) = (self.scene.dim, self.scene);
        let base = self.dir.join(format!("phi_{step:08}"));
        output::npy::write_npy(&base.with_extension("npy"), &full, dim)?;
        if s.output.vti {
            output::vti::write_vti(&base.with_extension("vti"), &full, dim, s.h, "phi")?;
        }
        if s.output.png {
            let title = format!("step {step}");
            output::image::write_slices_png(&base.with_extension("png"), &full, dim, &title)?;
        }
        Ok(())
    }
}

impl Observer for Snapshots<'_> {
    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        Some(("snapshots", self.scene.snapshots()))
    }

    /// The initial state (step 0) of a new run, so that a movie starts at t = 0; a resumed run
    /// starts from a state whose snapshot, if due, was written before it stopped.
    fn start(&mut self, now: &Now) -> Result<()> {
        if !self.scene.snapshots().is_never() && now.record.step == 0 {
            self.write(now)?;
        }
        Ok(())
    }

    fn step(&mut self, now: &Now) -> Result<Flow> {
        self.write(now)?;
        Ok(Flow::Continue)
    }
}

/// Writes `checkpoint.bin` into a run folder on its schedule and at the end (also after a
/// failed step: the engine then holds the last good state).
pub struct Checkpointer {
    dir: PathBuf,
    scene: serde_json::Value,
    schedule: Schedule,
}

impl Checkpointer {
    /// Checkpoints of a run of the resolved `scene` (its JSON value) into `dir`.
    pub fn new(dir: &Path, scene: serde_json::Value, schedule: Schedule) -> Self {
        Checkpointer {
            dir: dir.to_path_buf(),
            scene,
            schedule,
        }
    }

    fn write(&mut self, now: &Now) -> Result<()> {
        Checkpoint {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: self.scene.clone(),
            clock: now.clock,
            timers: now.timers.to_vec(),
            engine: now.engine.save(),
        }
        .write(&self.dir)
    }
}

impl Observer for Checkpointer {
    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        Some(("checkpoints", self.schedule))
    }

    fn step(&mut self, now: &Now) -> Result<Flow> {
        self.write(now)?;
        Ok(Flow::Continue)
    }

    fn finish(&mut self, now: &Now, _ending: Ending) -> Result<()> {
        self.write(now)
    }
}
