//! `"device": "gpu"`: the spectral conserved flow on an NVIDIA GPU (docs/src/guide/gpu.md): the
//! shared spectral step ([`crate::engines::spectral::Stepper`]) over the kernels of
//! `kernels.cu`.
//!
//! The engine is compiled with the cargo feature `gpu` only. It loads the CUDA driver, cuFFT
//! and NVRTC at run time (cudarc's dynamic loading), so building it needs no CUDA. What a scene
//! may ask of it is decided without touching the hardware ([`supports`]); the hardware is probed
//! where the engine is built, and by `vesicle check` ([`usable`]).

#[cfg(all(feature = "gpu", test))]
mod conformance;
#[cfg(feature = "gpu")]
mod engine;
#[cfg(feature = "gpu")]
mod kernels;

#[cfg(feature = "gpu")]
pub use engine::{GpuEngine, GpuPasses};

use crate::engines::Unsupported;
use crate::problem::config::{C0Spec, Dynamics, Method, Scene, Symmetry};

/// Whether the GPU engine can run `scene`: the spectral conserved flow on the full periodic 3D
/// box with even lengths and a uniform c0, in a binary built with the `gpu` feature. Touches no
/// hardware.
///
/// # Errors
/// The scene key the engine cannot honour, and why.
pub fn supports(scene: &Scene) -> Result<(), Unsupported> {
    let refuse = |field: &'static str, why: &str| {
        Err(Unsupported {
            field,
            why: format!(
                "{why}: \"device\": \"gpu\" runs the spectral conserved flow on the full \
                 periodic 3D box"
            ),
        })
    };
    if scene.method != Method::Spectral {
        return refuse("method", "the GPU engine is spectral");
    }
    if scene.dynamics != Dynamics::Conserved {
        return refuse("dynamics", "the GPU engine runs conserved dynamics only");
    }
    if scene.dim != 3 {
        return refuse("dim", "the GPU engine is 3D only");
    }
    if !matches!(&scene.symmetry, Symmetry::Axes(a) if a.is_empty()) {
        return refuse("symmetry", "the GPU engine has no mirror-reduced boxes");
    }
    if !scene.walls.is_empty() {
        return refuse("walls", "the GPU engine has the periodic box only");
    }
    if scene.n.iter().any(|m| m % 2 != 0) {
        return refuse("n", "the GPU engine needs even lengths");
    }
    if scene.ade.is_some() {
        return refuse("ade", "the GPU engine has no area-difference term yet");
    }
    if scene.bilayer_couple.is_some() {
        return refuse(
            "bilayer_couple",
            "the GPU engine has no area-difference term yet",
        );
    }
    if matches!(scene.c0, C0Spec::Field(_)) {
        return refuse("c0", "the GPU engine takes a uniform c0 only");
    }
    if cfg!(feature = "gpu") {
        Ok(())
    } else {
        Err(Unsupported {
            field: "device",
            why: NOT_BUILT.to_string(),
        })
    }
}

/// Why a binary without the `gpu` feature refuses `"device": "gpu"`.
const NOT_BUILT: &str = "this vesicle was built without the GPU engine: build it with \
     `cargo build --release --features gpu` (building needs no CUDA; running needs an NVIDIA \
     GPU with its driver, cuFFT and NVRTC)";

/// Whether a GPU can be used here: `Ok`, or why not (a sentence for the user). Probes the
/// hardware: loads the libraries, opens the first device, compiles the kernels and plans a
/// transform.
///
/// # Errors
/// Without the `gpu` feature, always; with it, when the CUDA driver, cuFFT or NVRTC cannot be
/// loaded, no GPU is found or the kernels do not compile.
pub fn usable() -> Result<(), String> {
    #[cfg(feature = "gpu")]
    {
        kernels::probe()
    }
    #[cfg(not(feature = "gpu"))]
    {
        Err(NOT_BUILT.to_string())
    }
}
