//! Spectral machinery: planned real transforms on the computational grid.
/// Elements per parallel task in the passes over a spectrum or a field (smaller tasks cost more
/// in rayon's scheduling than they gain).
pub const PAR_CHUNK: usize = 8192;

pub mod engine;
pub mod evaluator;
pub mod transform;

pub use engine::{stability_bound, SpectralEngine};
