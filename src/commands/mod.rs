//! What the command line reaches: [`cli`] (parsing, dispatch, exit codes), [`run`] (`run` and
//! `resume`), [`compare`], the after-the-run commands [`render`] and [`measure`] over a
//! [`run_folder`], the shape diagram of the axisymmetric reference ([`axisym`]), the
//! phase-field shape [`diagram`] and the [`study`] commands (listed, and run by name, by
//! [`studies`]). Only this layer knows about the command line.

pub mod axisym;
pub mod cli;
pub mod compare;
pub mod diagram;
pub mod measure;
pub mod render;
pub mod run;
pub mod run_folder;
pub mod studies;
pub mod study;
