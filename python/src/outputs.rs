//! The scene's `output.*` schedules in a run from Python, as `vesicle run` keeps them: into a
//! folder, the library's own writers (the time series row by row, snapshots, checkpoints);
//! without one, snapshots kept in memory and checkpoints skipped, their schedules still landing
//! the steps where the command line lands them (so the fields stay the same bit for bit).

use ndarray::Array3;
use std::path::{Path, PathBuf};
use vesicle::driver::observers::{Checkpointer, Recorder, Snapshots};
use vesicle::driver::record::{Record, TimeSeries};
use vesicle::driver::simulation::{Flow, Now, Observer};
use vesicle::error::{Error, Result};
use vesicle::output::lock::RunLock;
use vesicle::problem::config::{Scene, Schedule};
use vesicle::problem::grid::Grid;

/// A snapshot kept in memory: the step, t and φ of the full box.
pub struct Snapshot {
    /// Accepted steps at the snapshot.
    pub step: usize,
    /// Its time.
    pub t: f64,
    /// φ on the full box (internal layout).
    pub phi: Array3<f64>,
}

/// Keeps φ on the scene's snapshot schedule (as [`Snapshots`] writes it, the initial state of
/// a run from step 0 included).
pub struct Kept<'a> {
    schedule: Schedule,
    grid: &'a Grid,
    kept: &'a mut Vec<Snapshot>,
}

impl<'a> Kept<'a> {
    /// Snapshots of `scene` on `grid` into `kept`.
    pub fn new(scene: &Scene, grid: &'a Grid, kept: &'a mut Vec<Snapshot>) -> Self {
        Kept {
            schedule: scene.snapshots(),
            grid,
            kept,
        }
    }

    fn keep(&mut self, now: &Now) {
        self.kept.push(Snapshot {
            step: now.record.step,
            t: now.record.t,
            phi: self.grid.unfold(now.engine.phi()).into_owned(),
        });
    }
}

impl Observer for Kept<'_> {
    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        Some(("snapshots", self.schedule))
    }

    fn start(&mut self, now: &Now) -> Result<()> {
        if !self.schedule.is_never() && now.record.step == 0 {
            self.keep(now);
        }
        Ok(())
    }

    fn step(&mut self, now: &Now) -> Result<Flow> {
        self.keep(now);
        Ok(Flow::Continue)
    }
}

/// The checkpoint schedule without a folder: nothing written, the steps landed as a run that
/// writes them lands them.
pub struct Unwritten(pub Schedule);

impl Observer for Unwritten {
    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        Some(("checkpoints", self.0))
    }
}

/// A run folder written from Python, as `vesicle run` writes it during a run: held by its lock,
/// `timeseries.csv` (the history so far, then a row at a time), `snapshots/` (made by the
/// first snapshot) and `checkpoint.bin`.
pub struct Folder {
    dir: PathBuf,
    _lock: RunLock,
}

impl Folder {
    /// Open `dir` (created if missing; an existing folder is written into, so that successive
    /// runs continue it), refusing one another run holds.
    ///
    /// # Errors
    /// `Error::Config` on field `--out` if another process writes there; `Error::Io`.
    pub fn open(dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        Ok(Folder {
            _lock: RunLock::acquire(dir)?,
            dir: dir.to_path_buf(),
        })
    }

    /// A recorder on `schedule` that takes over `history` (left empty) and writes it to
    /// `timeseries.csv`, then appends each row it keeps; `history` is left as it was if the
    /// file cannot be written.
    ///
    /// # Errors
    /// `Error::Io` if the file cannot be written.
    pub fn recorder(&self, schedule: Schedule, history: &mut Vec<Record>) -> Result<Recorder> {
        let path = self.dir.join("timeseries.csv");
        let mut file = TimeSeries::create(&path)?;
        for r in history.iter() {
            file.push(r)?;
        }
        Ok(Recorder::resuming(schedule, file, std::mem::take(history)))
    }

    /// The snapshot writer of `scene` on `grid`: `snapshots/phi_<step>.npy` (and `.vti`, `.png`
    /// when the scene asks for them).
    pub fn snapshots<'a>(&self, grid: &'a Grid, scene: &'a Scene) -> Snapshots<'a> {
        Snapshots::new(&self.dir.join("snapshots"), grid, scene)
    }

    /// The checkpoint writer of the resolved `scene`: `checkpoint.bin` on its schedule and at
    /// the end of the run.
    pub fn checkpoints(&self, scene: &Scene) -> Checkpointer {
        Checkpointer::new(&self.dir, scene.resolved_value(), scene.checkpoints())
    }
}
