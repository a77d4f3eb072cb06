//! Driving an engine: [`simulation`] (the one step loop: clock, stop rules, observers),
//! [`observers`] (time-series recorder, progress bar, snapshots, checkpoints), the
//! [`schedule`] timers that say when each observer is due, the time series of [`record`],
//! [`checkpoint`] (the file `vesicle resume` continues from), [`signals`] (SIGINT/SIGTERM end
//! a run cleanly) and [`awake`] (rayon workers kept spinning through a step loop). The driver
//! does no I/O of its own; observers call the writers.

pub mod awake;
pub mod checkpoint;
pub mod observers;
pub mod record;
pub mod schedule;
pub mod signals;
pub mod simulation;
