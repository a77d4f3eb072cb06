//! `vesicle`: shapes and shape instabilities of lipid vesicles with the phase-field model of
//! Campelo & Hernández-Machado (Canham–Helfrich bending energy with spontaneous curvature,
//! conserved dynamics, area held by a Lagrange multiplier), as fixed in DESIGN.md:
//!
//! ```text
//! Φ = (φ + εC0)(φ² − 1) − ε²∇²φ,   F_sc = ∫Φ²,   A = (3/(2√2)) ε ∫|∇φ|²,   V = ∫(1 + φ)/2
//! ∂φ/∂t = ∇²μ,   μ = 2[f'(φ)Φ − ε²∇²Φ] − (3/√2) ε σ ∇²φ
//! ```
//!
//! Module map:
//! * scene → problem: [`config`] (the strict scene file), [`setup`] (grid, initial field, c0),
//!   [`grid`], [`shapes`] (with [`revolution`] for surfaces of revolution), [`model`] (f, f', reduced quantities, c0 fields), [`memory`]
//!   (the peak-memory estimate a grid must fit);
//! * engines behind [`engine::Engine`]: [`fd`] (explicit Euler on [`stencil`], the paper's
//!   reference), [`spectral`] (semi-implicit SBDF1/2 with the exact area projection, on
//!   [`spectral::transform`]), [`relax`] (preconditioned L-BFGS to stationary states), with
//!   shared pieces in [`numerics`]; every engine reports the same Δt-free stationarity
//!   residual RMS(μ − μ̄);
//! * driving: [`simulation`] (the one step loop: clock, stop rules, observers), [`observers`]
//!   (time-series recorder, progress bar, snapshots, checkpoints), [`record`], [`checkpoint`]
//!   (the file `vesicle resume` continues from), [`signals`] (SIGINT/SIGTERM end a run cleanly);
//! * commands and output: [`run`] (a scene or a checkpoint wired to the driver and its
//!   writers), [`output`] (npy, vti, png, the folder lock; the φ = 0 mesh, ply, shaded views,
//!   gif), [`levelset`] (sharp φ = 0 measures), [`compare`], [`study`] (stationary routes,
//!   convergence orders, stability map, work–precision; study files, least-squares fits),
//!   [`run_folder`] (a finished run's folder as read back), [`render`] (frames and movie of a
//!   finished run), [`measure`] (radius profile along an axis: neck, pearl wavelength,
//!   skewness), [`cli`];
//! * [`axisym`]: the sharp-interface reference for the c0 = 0 shape diagram (Ritz method on
//!   axisymmetric shapes, continuation along the prolate, oblate and stomatocyte branches);
//!   [`diagram`]: the same diagram from the phase field (independent cases on reduced boxes,
//!   a sweep or a cluster array, merged and extrapolated in ε/R0), with [`curves`] (cubic
//!   interpolation, crossings, power-law fits) and the refined φ = 0 measure of [`levelset`]
//!   on the band-limited interpolant of [`upsample`].
//!
//! ```no_run
//! use vesicle::simulation::{Simulation, StopRules};
//! let scene = vesicle::config::load(std::path::Path::new("runs/ellipse2d.json"), &[]).unwrap();
//! let problem = vesicle::setup::build(&scene).unwrap();
//! let (mut sim, _a0) = Simulation::of_scene(&scene, &problem).unwrap();
//! let stopped = sim.run(&StopRules::of(&scene), &mut []).unwrap();
//! let last = sim.record();
//! println!("{}: F = {}, residual = {}", stopped.as_str(), last.energy, last.residual);
//! ```

pub mod awake;
pub mod axisym;
pub mod checkpoint;
pub mod cli;
pub mod compare;
pub mod config;
pub mod curves;
pub mod diagram;
pub mod engine;
pub mod error;
pub mod fd;
pub mod grid;
pub mod levelset;
pub mod measure;
pub mod memory;
pub mod model;
pub mod numerics;
pub mod observers;
pub mod output;
pub mod private;
pub mod record;
pub mod relax;
pub mod render;
pub mod revolution;
pub mod run;
pub mod run_folder;
pub mod setup;
pub mod shapes;
pub mod signals;
pub mod simulation;
pub mod spectral;
pub mod stencil;
pub mod study;
pub mod upsample;
