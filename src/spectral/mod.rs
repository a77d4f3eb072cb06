//! Spectral machinery: planned real transforms on the computational grid.

pub mod engine;
pub mod evaluator;
pub mod transform;

pub use engine::{stability_bound, SpectralEngine};
