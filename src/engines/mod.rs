//! What the simulation driver needs from an engine (finite differences, spectral,
//! relaxational).
//!
//! Every engine reports the same stationarity measure of its current state (docs/src/reference/outputs.md):
//!
//! ```text
//! residual = ( ∫_Ω (μ − μ̄)² dx / |Ω| )^½,   μ = 2[f'(φ)Φ − ε²∇²Φ] − (3/√2) ε σ ∇²φ,
//! ```
//!
//! over the full box Ω (the same on a reduced box), with σ the engine's current multiplier. It
//! vanishes exactly at the stationary states of the conserved and relaxational flows alike and,
//! unlike max|φ^{n+1} − φ^n|/Δt, it does not shrink as Δt grows.

pub mod failure;
pub mod fd;
pub mod gpu;
pub mod numerics;
pub mod relax;
pub mod spectral;
pub mod stability;
pub mod stencil;

use crate::problem::area_difference::AreaDifference;
use crate::problem::config::AreaMethod;
use crate::problem::model::Measures;
use ndarray::{Array3, ArrayView3, CowArray, Ix3};
use num_complex::Complex64;
use std::borrow::Cow;

/// The area constraint an engine applies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaConstraint {
    /// How σ is chosen.
    pub method: AreaMethod,
    /// α of the Lagrangian update σ^{n+1} = σ^n + α (A^n − A0).
    pub alpha: f64,
    /// Target area A0.
    pub target: f64,
    /// σ of the fixed method (0 otherwise).
    pub sigma: f64,
}

impl AreaConstraint {
    /// No constraint (σ stays 0): used by the preparation steps.
    pub fn none() -> Self {
        AreaConstraint {
            method: AreaMethod::None,
            alpha: 0.0,
            target: 0.0,
            sigma: 0.0,
        }
    }
}

/// What one accepted step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// The step taken (an adaptive engine may take less than it was offered).
    pub dt: f64,
    /// max|φ^{n+1} − φ^n| / Δt of the step (the `rate` column; not a stationarity measure: it
    /// falls as Δt grows).
    pub rate: f64,
    /// Attempts rejected before this step was accepted.
    pub rejected: usize,
}

pub use failure::{Cause, Diverged, Rejection, StepError};

/// A scene key an engine cannot honour ([`supports`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Unsupported {
    /// The dotted scene key.
    pub field: &'static str,
    /// Why, for the user.
    pub why: String,
}

/// Whether the engine `scene` asks for can run it, decided from the scene alone (no hardware
/// is touched: a GPU is probed where its engine is built). Every CPU engine runs every valid
/// scene; the GPU engine states its limits in [`gpu::supports`].
///
/// # Errors
/// The key the engine cannot honour, and why.
pub fn supports(scene: &crate::problem::config::Scene) -> Result<(), Unsupported> {
    match scene.device {
        crate::problem::config::Device::Cpu => Ok(()),
        crate::problem::config::Device::Gpu => gpu::supports(scene),
    }
}

/// A time stepper holding the current state φ, σ and its measures.
pub trait Engine {
    /// Current φ on the computed grid.
    fn phi(&self) -> &Array3<f64>;
    /// Current σ (the multiplier that produced the current state).
    fn sigma(&self) -> f64;
    /// F_sc, A, V of the current state (full-box values).
    fn measures(&self) -> Measures;
    /// The stationarity residual RMS_Ω(μ − μ̄) of the current state at the current σ (module
    /// docs).
    fn residual(&self) -> f64;
    /// Replace the area constraint (σ is reset to 0 when the method changes to none, and set
    /// to the constraint's σ by the fixed method).
    fn set_area(&mut self, area: AreaConstraint);
    /// Advance from time `t` by at most `dt`.
    ///
    /// # Errors
    /// [`StepError`] if the state diverged, broke a constraint or the device failed; the
    /// engine then still holds the last good state.
    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, StepError>;
    /// Hold the area-difference term (ADE or the bilayer couple) at its reference area; the
    /// driver calls it after [`Engine::set_area`]. Engines without the term refuse its scenes
    /// in [`supports`].
    ///
    /// # Errors
    /// A sentence if the engine cannot hold the term.
    fn set_area_difference(&mut self, term: AreaDifference) -> Result<(), String>;
    /// What the current state's Stokes flow measured (the Stokes dynamics only).
    fn flow(&self) -> Option<spectral::flow::FlowStats> {
        None
    }
    /// The area-difference term the engine holds, if any.
    fn area_difference(&self) -> Option<AreaDifference> {
        None
    }
    /// The area-difference multiplier λ of the current state (μ holds λ δM/δφ); 0 without
    /// the term.
    fn lambda(&self) -> f64 {
        0.0
    }
    /// The step the engine proposes next (adaptive engines), or `dt` unchanged.
    fn next_dt(&self, dt: f64) -> f64 {
        dt
    }
    /// True when the engine can make no further progress (a line search found no decrease at
    /// round-off level); the driver then stops.
    fn stalled(&self) -> bool {
        false
    }
    /// Turn on or off the check that a step does not raise F_eff where the scheme guarantees a
    /// decrease (on by default; off for stability studies, which classify rises themselves).
    fn guard_energy(&mut self, _on: bool) {}
    /// The largest Δt / (stability bound at the current σ) taken so far, for engines with a
    /// bound (FD); `None` otherwise.
    fn max_dt_over_bound(&self) -> Option<f64> {
        None
    }
    /// Short name for logs and tables.
    fn name(&self) -> &'static str;
    /// Everything needed to continue exactly from the current state (checkpoints): the state
    /// arrays as they are held (spectra, not their transforms), borrowed, not copied, and the
    /// scalars that are not recomputed from them.
    fn save(&self) -> Saved<'_>;
    /// Continue from `saved`, the state at time `t` of an engine built for the same scene, with
    /// the same area constraint installed. Afterwards the engine steps bit for bit as the saved
    /// one would have. Arrays the engine keeps as they are (the L-BFGS pairs) are moved out of
    /// `saved`, not copied.
    ///
    /// # Errors
    /// A message naming what is missing or has the wrong shape.
    fn restore(&mut self, saved: &mut Saved<'_>, t: f64) -> Result<(), String>;
}

/// An array of an engine's saved state: borrowed from the engine when it is saved (a checkpoint
/// is written from the engine's own arrays, with no copy beside them), owned when it is read
/// back from a file.
#[derive(Clone, Debug, PartialEq)]
pub enum SavedArray<'a> {
    /// A real field (φ on the grid).
    Real(CowArray<'a, f64, Ix3>),
    /// A spectrum.
    Complex(CowArray<'a, Complex64, Ix3>),
    /// A spectrum of this shape kept in single precision, as interleaved (re, im) reals (the
    /// L-BFGS pairs), stored so in a checkpoint; [`Saved::take_single`] also reads a complex
    /// array (a checkpoint written before the f32 kind).
    Single([usize; 3], Cow<'a, [f32]>),
}

/// An engine's state for a checkpoint: named scalars and arrays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Saved<'a> {
    /// Named scalars (bit-exact; NaN allowed).
    pub scalars: Vec<(String, f64)>,
    /// Named arrays.
    pub arrays: Vec<(String, SavedArray<'a>)>,
}

impl<'a> Saved<'a> {
    /// Add a scalar.
    pub fn scalar(mut self, name: &str, value: f64) -> Self {
        self.scalars.push((name.to_string(), value));
        self
    }

    /// Add an array.
    pub fn array(mut self, name: &str, value: SavedArray<'a>) -> Self {
        self.arrays.push((name.to_string(), value));
        self
    }

    /// The scalar `name`.
    ///
    /// # Errors
    /// If it is missing.
    pub fn get(&self, name: &str) -> Result<f64, String> {
        self.scalars
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| format!("the saved state lacks `{name}`"))
    }

    /// Whether it holds an array `name`.
    pub fn has(&self, name: &str) -> bool {
        self.position(name).is_ok()
    }

    /// The real array `name`, which must have `shape`.
    ///
    /// # Errors
    /// If it is missing, complex or of another shape.
    pub fn real(&self, name: &str, shape: &[usize]) -> Result<ArrayView3<'_, f64>, String> {
        match self.find(name)? {
            SavedArray::Real(a) if a.shape() == shape => Ok(a.view()),
            SavedArray::Real(a) => Err(wrong_shape(name, a.shape(), shape)),
            SavedArray::Complex(_) | SavedArray::Single(..) => {
                Err(format!("saved `{name}` is complex, not real"))
            }
        }
    }

    /// The complex array `name`, which must have `shape`.
    ///
    /// # Errors
    /// If it is missing, real or of another shape.
    pub fn complex(
        &self,
        name: &str,
        shape: &[usize],
    ) -> Result<ArrayView3<'_, Complex64>, String> {
        match self.find(name)? {
            SavedArray::Complex(a) if a.shape() == shape => Ok(a.view()),
            SavedArray::Complex(a) => Err(wrong_shape(name, a.shape(), shape)),
            SavedArray::Single(..) => Err(format!("saved `{name}` is in single precision")),
            SavedArray::Real(_) => Err(format!("saved `{name}` is real, not complex")),
        }
    }

    /// The spectrum `name` of `shape` in single precision as interleaved (re, im) reals, taken
    /// out of `self` (its values moved, not copied; a second call finds it missing): a
    /// [`SavedArray::Single`], or a complex array (from a checkpoint written before the pairs were
    /// stored as f32) rounded to f32, which gives back exactly the values that were widened.
    ///
    /// # Errors
    /// If it is missing, real or of another shape.
    pub fn take_single(&mut self, name: &str, shape: &[usize]) -> Result<Vec<f32>, String> {
        let at = self.position(name)?;
        let got: &[usize] = match &self.arrays[at].1 {
            SavedArray::Single(s, _) => s,
            SavedArray::Complex(a) => a.shape(),
            SavedArray::Real(_) => return Err(format!("saved `{name}` is real, not complex")),
        };
        if got != shape {
            return Err(wrong_shape(name, got, shape));
        }
        Ok(match self.arrays.remove(at).1 {
            SavedArray::Single(_, v) => v.into_owned(),
            SavedArray::Complex(a) => a.iter().flat_map(|c| [c.re as f32, c.im as f32]).collect(),
            SavedArray::Real(_) => unreachable!("refused above"),
        })
    }

    fn find(&self, name: &str) -> Result<&SavedArray<'a>, String> {
        Ok(&self.arrays[self.position(name)?].1)
    }

    /// Index of the array `name`.
    fn position(&self, name: &str) -> Result<usize, String> {
        self.arrays
            .iter()
            .position(|(n, _)| n == name)
            .ok_or_else(|| format!("the saved state lacks `{name}`"))
    }
}

fn wrong_shape(name: &str, got: &[usize], want: &[usize]) -> String {
    format!("saved `{name}` has shape {got:?}, the scene needs {want:?}")
}
