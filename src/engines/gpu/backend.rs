//! What the GPU engine asks of a device: arrays, the two transforms and the six passes of
//! `kernels.cu`. [`super::kernels::Device`] runs them on a GPU; the tests run the engine on
//! [`super::host::HostDevice`], the same passes in plain Rust on the CPU's transforms, to check
//! the engine's logic against the CPU spectral engine where no GPU is present.
//!
//! Conventions (cuFFT's): spectra are the real-to-complex half spectra of the n0 × n1 × n2
//! periodic box, n0 × n1 × (n2/2 + 1), row-major; `forward` and `inverse` are unnormalised.

use crate::engines::spectral::evaluator::axis_symbol;
use crate::problem::config::Laplacian;
use crate::problem::grid::Grid;
use ndarray::Array3;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The SBDF update's coefficients (the `Update` struct of `kernels.cu`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct UpdateArgs {
    pub a0: f64,
    pub a1: f64,
    pub a2: f64,
    pub b1: f64,
    pub b2: f64,
    pub dt: f64,
    pub s2: f64,
    pub s4e2: f64,
    pub e4x2: f64,
    pub c_sigma: f64,
}

impl UpdateArgs {
    /// (P̂, Q̂) at one mode of |k|² = `k` from φ̂ⁿ = `x`, N̂ⁿ = `n` and the previous step's
    /// `x0`, `n0` (zeros when the formula does not read them): P̂ = h1 x + n1 n + h0 x0 + n0 n0,
    /// Q̂ = q1 x + q0 x0 with the factors of the CPU engine's `ValueFactors`.
    pub fn apply(
        &self,
        k: f64,
        prev: bool,
        [x, n, x0, n0]: [Complex64; 4],
    ) -> (Complex64, Complex64) {
        let s = self.s2 * k + self.s4e2 * k * k;
        let inv = 1.0 / (self.a0 + self.dt * (self.e4x2 * k * k * k + s));
        let qc = -self.dt * self.c_sigma * k * k * inv;
        let (h1, n1, q1) = (
            (-self.a1 + self.dt * self.b1 * s) * inv,
            self.dt * self.b1 * inv,
            self.b1 * qc,
        );
        let (h0, nn0, q0) = if prev {
            (
                (-self.a2 + self.dt * self.b2 * s) * inv,
                self.dt * self.b2 * inv,
                self.b2 * qc,
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        (x * h1 + n * n1 + x0 * h0 + n0 * nn0, x * q1 + x0 * q0)
    }
}

/// |k|² per axis (the spectral symbol or the FD stencil's) and the Parseval weights per axis,
/// the cell volume folded into axis 0's: `[kx2, ky2, kz2, wx, wy, wz]`, so that the integral of
/// u v over the box is Σ w Re(û v̂*) over the half spectrum (`Transform::parseval_weights`).
pub fn tables(grid: &Grid, laplacian: Laplacian) -> [Vec<f64>; 6] {
    let [n0, n1, n2] = grid.shape;
    let s2 = n2 / 2 + 1;
    let k2 = |n: usize, len: usize| -> Vec<f64> {
        (0..len)
            .map(|j| {
                let m = if j <= n / 2 {
                    j as f64
                } else {
                    j as f64 - n as f64
                };
                axis_symbol(2.0 * PI * m / (n as f64 * grid.h), grid.h, laplacian)
            })
            .collect()
    };
    let weights = |n: usize, len: usize, last: bool, scale: f64| -> Vec<f64> {
        (0..len)
            .map(|j| {
                let doubled = last && j > 0 && 2 * j != n;
                scale * if doubled { 2.0 } else { 1.0 } / n as f64
            })
            .collect()
    };
    [
        k2(n0, n0),
        k2(n1, n1),
        k2(n2, s2),
        weights(n0, n0, false, grid.cell_volume()),
        weights(n1, n1, false, 1.0),
        weights(n2, s2, true, 1.0),
    ]
}

/// A device for the GPU engine (see the module documentation). Every method that sums returns
/// its sums added in a fixed order.
pub trait Backend {
    /// A spectrum on the device.
    type Spectrum;
    /// A real field on the device.
    type Field;

    /// The spectral shape n0 × n1 × (n2/2 + 1).
    fn spectral_shape(&self) -> [usize; 3];
    /// Points of a real field.
    fn points(&self) -> usize;
    /// A spectrum of zeros.
    fn spectrum(&self) -> Result<Self::Spectrum, String>;
    /// A real field of zeros.
    fn field(&self) -> Result<Self::Field, String>;
    /// `to` ← the host values `from` (C order).
    fn upload_field(&self, from: &[f64], to: &mut Self::Field) -> Result<(), String>;
    /// The field's values on the host (C order).
    fn download_field(&self, from: &Self::Field) -> Result<Vec<f64>, String>;
    /// A spectrum holding the host spectrum `from`.
    fn upload_spectrum(&self, from: &Array3<Complex64>) -> Result<Self::Spectrum, String>;
    /// The spectrum on the host.
    fn download_spectrum(&self, from: &Self::Spectrum) -> Result<Array3<Complex64>, String>;
    /// `to` ← `from`.
    fn copy_spectrum(&self, from: &Self::Spectrum, to: &mut Self::Spectrum) -> Result<(), String>;

    /// X ← (X + conj X(−k0, −k1))/2 on the self-conjugate planes i2 = 0 and i2 = n2/2.
    fn hermitian(&self, a: &mut Self::Spectrum) -> Result<(), String>;
    /// copy = X̂, lap = −|k|²X̂; returns Σ ap |k|² w |X̂|² (the area, `ap` = (3/(2√2)) ε).
    fn inverse_inputs(
        &self,
        hat: &Self::Spectrum,
        copy: &mut Self::Spectrum,
        lap: &mut Self::Spectrum,
        ap: f64,
    ) -> Result<f64, String>;
    /// The unnormalised inverse transform of `input` (overwritten) into `out`.
    fn inverse(&self, input: &mut Self::Spectrum, out: &mut Self::Field) -> Result<(), String>;
    /// The unnormalised forward transform of `input` into `out`.
    fn forward(&self, input: &Self::Field, out: &mut Self::Spectrum) -> Result<(), String>;
    /// The real-space pass: with N φ in `phi` and N ∇²φ in `lap` (N the points), φ into `phi`,
    /// f(φ) = (φ + εC0)(φ² − 1) into `lap` and f'(φ)Φ into `fphi`, Φ = f − ε²∇²φ; returns
    /// (Σ Φ², Σ φ, max|φ|, max|φ − old|, 0 without `old`).
    fn pointwise(
        &self,
        phi: &mut Self::Field,
        lap: &mut Self::Field,
        fphi: &mut Self::Field,
        old: Option<&Self::Field>,
        e2: f64,
        ec0: f64,
    ) -> Result<[f64; 4], String>;
    /// N̂ = −2k FT[f'Φ] − 2ε²k² FT[f] into `nl` (which holds FT[f'Φ]), `g` = FT[f], k = |k|²;
    /// returns Σ_{k≠0} w |μ̂|², μ̂ = 2 FT[f'Φ] + 2ε²k FT[f] + 2ε⁴k² φ̂ + tension k φ̂, when
    /// `residual` (else 0).
    fn combine(
        &self,
        hat: &Self::Spectrum,
        nl: &mut Self::Spectrum,
        g: &Self::Spectrum,
        e2: f64,
        tension: f64,
        residual: bool,
    ) -> Result<f64, String>;
    /// (A_PP, A_PQ, A_QQ) = Σ ap |k|² w (|P̂|², Re P̂Q̂*, |Q̂|²) of the update `u` from
    /// `cur` = (φ̂ⁿ, N̂ⁿ) and `prev` = (φ̂ⁿ⁻¹, N̂ⁿ⁻¹) when the formula reads them.
    fn area_quadratic(
        &self,
        cur: (&Self::Spectrum, &Self::Spectrum),
        prev: Option<(&Self::Spectrum, &Self::Spectrum)>,
        u: UpdateArgs,
        ap: f64,
    ) -> Result<[f64; 3], String>;
    /// φ̂ⁿ⁺¹ = P̂ + σQ̂ into `out`, with `copy` = φ̂ⁿ⁺¹ and `lap` = −|k|²φ̂ⁿ⁺¹; returns its area.
    #[allow(clippy::too_many_arguments)]
    fn write_update(
        &self,
        cur: (&Self::Spectrum, &Self::Spectrum),
        prev: Option<(&Self::Spectrum, &Self::Spectrum)>,
        u: UpdateArgs,
        ap: f64,
        sigma: f64,
        out: &mut Self::Spectrum,
        copy: &mut Self::Spectrum,
        lap: &mut Self::Spectrum,
    ) -> Result<f64, String>;
}
