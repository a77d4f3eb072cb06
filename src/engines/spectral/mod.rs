//! Spectral machinery: planned real transforms on the computational grid.

pub(crate) mod columns;
pub(crate) mod control;
pub mod engine;
pub mod evaluator;
pub(crate) mod kernels;
pub(crate) mod pieces;
pub(crate) mod real_rows;
pub(crate) mod saved;
pub mod stepper;
pub mod transform;
pub mod update;

pub use engine::{stability_bound, CpuPasses, SpectralEngine};
pub use stepper::{DeviceFailure, DeviceState, Passes, States, Stepper};
