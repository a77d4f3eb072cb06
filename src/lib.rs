//! `vesicle`: shapes and shape instabilities of lipid vesicles with the phase-field model of
//! Campelo & Hernández-Machado (Canham–Helfrich bending energy with spontaneous curvature,
//! conserved dynamics, area held by a Lagrange multiplier), as derived in the manual (docs/src/theory/model.md):
//!
//! ```text
//! Φ = (φ + εC0)(φ² − 1) − ε²∇²φ,   F_sc = ∫Φ²,   A = (3/(2√2)) ε ∫|∇φ|²,   V = ∫(1 + φ)/2
//! ∂φ/∂t = ∇²μ,   μ = 2[f'(φ)Φ − ε²∇²Φ] − (3/√2) ε σ ∇²φ
//! ```
//!
//! The source tree follows the layers, from the bottom up (docs/src/architecture.md):
//! * the leaves [`error`], [`cpu`] (the cores and vector instructions, detected once, and the
//!   worker pool a command runs in) and [`npy`] (the `.npy` format);
//! * [`analysis`]: the φ = 0 level set and surface mesh, curves and fits, and the
//!   sharp-interface axisymmetric reference;
//! * [`problem`]: the scene file, grid, initial shapes, model and memory estimate — what is
//!   computed, before any engine runs;
//! * [`engines`] behind [`engines::Engine`]: finite differences (the paper's explicit reference),
//!   spectral (semi-implicit SBDF1/2 with the exact area projection) and relaxational
//!   (preconditioned L-BFGS to stationary states); every engine reports the same Δt-free
//!   stationarity residual RMS(μ − μ̄);
//! * [`output`]: the writers (npy, vti, ply, png, charts, shaded views, gif), the output folder
//!   and its lock;
//! * [`driver`]: the one step loop (clock, stop rules, observers), the time series,
//!   checkpoints and signals;
//! * `commands`: the command line, `run`/`resume`, `compare`, `render`, `measure`, the
//!   sharp-interface and phase-field shape diagrams and the studies. It is public for the
//!   `vesicle` binary and the Python bindings, and hidden from this documentation: it is not
//!   the library's interface (the studies are run through [`run_study`]).
//!
//! Walls (`tests/layers.rs`, the table of docs/src/architecture.md): the leaves use at most
//! [`error`]; each layer reaches only the leaves and the layers listed before it, except that
//! engines and output do not reach each other; only `commands` knows about the command line.
//!
//! The names a library user starts from are re-exported here: [`Scene`] (read by [`load`] or
//! [`load_value`]), [`Problem`] (built by [`build`]), [`Simulation`] and its [`StopRules`],
//! the [`Engine`] it steps, [`Error`], a study by name ([`run_study`], its tables typed as
//! [`StudyTable`]), and the examples in `examples/` (run a scene, read φ, run a study:
//! `cargo run --release --example run_scene`).
//!
//! ```no_run
//! use vesicle::driver::simulation::{Simulation, StopRules};
//! let scene = vesicle::problem::config::load(std::path::Path::new("runs/ellipse2d.json"), &[]).unwrap();
//! let problem = vesicle::problem::setup::build(&scene).unwrap();
//! let (mut sim, _a0) = Simulation::of_scene(&scene, &problem).unwrap();
//! let stopped = sim.run(&StopRules::of(&scene), &mut []).unwrap();
//! let last = sim.record();
//! println!("{}: F = {}, residual = {}", stopped.as_str(), last.energy, last.residual);
//! ```

#![warn(missing_docs)]

pub mod analysis;
#[doc(hidden)]
pub mod commands;
pub mod cpu;
pub mod driver;
pub mod engines;
pub mod error;
pub mod npy;
pub mod output;
pub mod problem;

pub use commands::studies::{
    run as run_study, Args as StudyArgs, Table as StudyTable, Values as StudyValues,
};
pub use driver::simulation::{Simulation, StopRules, Stopped};
pub use engines::{Engine, StepError};
pub use error::{Error, Result};
pub use problem::config::{load, load_value, Scene};
pub use problem::setup::{build, Problem};
