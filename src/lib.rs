//! `vesicle`: shapes and shape instabilities of lipid vesicles with the phase-field model of
//! Campelo & Hernández-Machado (Canham–Helfrich bending energy with spontaneous curvature,
//! conserved dynamics, area held by a Lagrange multiplier).

pub mod cli;
pub mod compare;
pub mod config;
pub mod engine;
pub mod error;
pub mod fd;
pub mod grid;
pub mod levelset;
pub mod model;
pub mod output;
pub mod record;
pub mod relax;
pub mod run;
pub mod setup;
pub mod shapes;
pub mod spectral;
pub mod stencil;
pub mod study;
