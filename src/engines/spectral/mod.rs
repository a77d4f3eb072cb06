//! Spectral machinery: planned real transforms on the computational grid.

pub(crate) mod control;
pub mod curvature;
pub mod engine;
pub mod evaluator;
pub mod flow;
pub mod inextensible;
pub(crate) mod kernels;
pub(crate) mod pieces;
pub(crate) mod saved;
pub mod stepper;
pub mod tensions;
pub mod update;
pub mod viscous;

pub use engine::{stability_bound, CpuPasses, SpectralEngine};
pub use stepper::{DeviceFailure, DeviceState, Passes, States, Stepper};
/// The planned 3D real transforms: the crate `vesicle-transforms` (`transforms/`).
pub use vesicle_transforms as transform;
