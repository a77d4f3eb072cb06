//! `"device": "gpu"`: the spectral conserved flow on an NVIDIA GPU (docs/src/guide/gpu.md).
//!
//! The engine is compiled with the cargo feature `gpu` only. It loads the CUDA driver, cuFFT
//! and NVRTC at run time (cudarc's dynamic loading), so building it needs no CUDA; a binary
//! without the feature, or a machine without a usable GPU, refuses the scene key with a
//! sentence saying why ([`usable`]).

#[cfg(feature = "gpu")]
mod backend;
#[cfg(feature = "gpu")]
mod engine;
#[cfg(all(feature = "gpu", test))]
mod host;
#[cfg(feature = "gpu")]
mod kernels;

#[cfg(feature = "gpu")]
pub use engine::GpuEngine;

/// Whether `"device": "gpu"` can run here: `Ok`, or why not (a sentence for the user).
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
        Err(
            "this vesicle was built without the GPU engine: build it with \
             `cargo build --release --features gpu` (building needs no CUDA; running needs an \
             NVIDIA GPU with its driver, cuFFT and NVRTC)"
                .to_string(),
        )
    }
}
