//! The problem a scene describes, before any engine runs: the strict scene file ([`config`]),
//! the computational [`grid`], the initial [`shapes`] (with [`revolution`] for surfaces of
//! revolution), the phase-field [`model`] (f, f', reduced quantities, c0 fields), the
//! [`area_difference`] term (ADE and the bilayer couple), the Stokes dynamics' sharp [`flow`]
//! figures (rates, the periodic box's factor), the peak-[`memory`] estimate a grid
//! must fit, the measured lattice [`pinning`] of stationary energies at a scene's h/ε, and
//! [`setup`], which turns a validated scene into
//! the grid, initial field and c0 field an engine computes on.

pub mod area_difference;
pub mod config;
pub mod flow;
pub mod grid;
pub mod memory;
pub mod model;
pub mod pinning;
pub mod revolution;
pub mod setup;
pub mod shapes;
