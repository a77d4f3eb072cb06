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

use crate::error::{Error, Result};
use crate::problem::config::{self, Scene};
use std::path::Path;

/// Refuse a file that is not there: `Error::Config` on `field` (`(scene file)`, `(study
/// file)`) before anything reads it.
///
/// # Errors
/// If `path` does not exist.
pub fn existing(path: &Path, field: &str) -> Result<()> {
    if path.exists() {
        Ok(())
    } else {
        Err(Error::config(
            field,
            format!("{} does not exist", path.display()),
        ))
    }
}

/// The scene file at `path` with the `--set` assignments `set`, as every command reads it:
/// there, valid, and runnable by the engine it asks for
/// ([`crate::driver::simulation::check_engine`]; no hardware touched).
///
/// # Errors
/// `Error::Config` naming the file, the key or the engine's limit.
pub fn load_scene(path: &Path, set: &[String]) -> Result<Scene> {
    existing(path, "(scene file)")?;
    let scene = config::load(path, set)?;
    crate::driver::simulation::check_engine(&scene)?;
    Ok(scene)
}
