//! The device side of the GPU engine: the context and stream, the kernels of `kernels.cu`
//! (compiled by NVRTC), the cuFFT plans, the wavenumber and weight tables, and the launches,
//! each returning its sums added in block order on the host (deterministic).

use crate::engines::spectral::evaluator::axis_symbol;
use crate::engines::spectral::update::Update;
use crate::engines::spectral::DeviceFailure;
use crate::problem::config::Laplacian;
use crate::problem::grid::Grid;
use cudarc::cufft::sys::{cufftType, double2};
use cudarc::cufft::CudaFft;
use cudarc::driver::{
    CudaContext, CudaFunction, CudaSlice, CudaStream, DeviceRepr, LaunchConfig, PushKernelArg,
};
use ndarray::Array3;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::sync::Arc;

/// The kernels' source.
const SOURCE: &str = include_str!("kernels.cu");
/// Blocks of every launch (grid-stride loops) and threads per block (`THREADS` in the source).
const BLOCKS: u32 = 1024;
const THREADS: u32 = 256;

/// A spectrum on the device (interleaved re, im).
pub type Spectrum = CudaSlice<double2>;
/// A real field on the device.
pub type Field = CudaSlice<f64>;

/// What an update reads: (φ̂ⁿ, N̂ⁿ) and, when it reads two levels, (φ̂ⁿ⁻¹, N̂ⁿ⁻¹).
pub type UpdateInputs<'a> = ([&'a Spectrum; 2], Option<[&'a Spectrum; 2]>);

/// Device results: a failure is fatal to the run (no smaller step mends it).
type Result<T> = std::result::Result<T, DeviceFailure>;

/// Any failure of the device, as a sentence.
fn failed(what: &str) -> impl Fn(cudarc::driver::DriverError) -> DeviceFailure + '_ {
    move |e| DeviceFailure(format!("GPU: {what} failed ({e})"))
}

/// |k|² per axis (the spectral symbol or the FD stencil's) and the Parseval weights per axis,
/// the cell volume folded into axis 0's: `[kx2, ky2, kz2, wx, wy, wz]`, so that the integral of
/// u v over the box is Σ w Re(û v̂*) over the half spectrum n0 × n1 × (n2/2 + 1) of cuFFT's
/// real-to-complex transforms (the CPU's `Symbols` of the same box).
fn tables(grid: &Grid, laplacian: Laplacian) -> [Vec<f64>; 6] {
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

/// The GPU can be used: the libraries load, a device exists and the kernels compile.
///
/// # Errors
/// Which library is missing, or that no device was found or the kernels do not compile.
pub fn probe() -> std::result::Result<(), String> {
    // SAFETY: these only try to open the shared libraries.
    let present = unsafe {
        [
            (
                "the CUDA driver (libcuda)",
                cudarc::driver::sys::is_culib_present(),
            ),
            ("cuFFT (libcufft)", cudarc::cufft::sys::is_culib_present()),
            ("NVRTC (libnvrtc)", cudarc::nvrtc::sys::is_culib_present()),
        ]
    };
    if let Some((name, _)) = present.iter().find(|(_, ok)| !ok) {
        return Err(format!("no usable GPU here: {name} cannot be loaded"));
    }
    let ctx =
        CudaContext::new(0).map_err(|e| format!("no usable GPU here: no CUDA device ({e})"))?;
    cudarc::nvrtc::compile_ptx(SOURCE)
        .map_err(|e| format!("no usable GPU here: NVRTC could not compile the kernels ({e})"))?;
    CudaFft::plan_3d(8, 8, 8, cufftType::CUFFT_D2Z, ctx.default_stream())
        .map_err(|e| format!("no usable GPU here: cuFFT could not plan ({e:?})"))?;
    Ok(())
}

// SAFETY: `Update` is repr(C) and holds ten f64 (a0, a1, a2, b1, b2, dt, s2, s4e2, e4x2,
// c_sigma, in this order): the layout of the kernels' `Update`.
unsafe impl DeviceRepr for Update {}

/// The device, its kernels, plans and tables for one grid.
pub struct Device {
    stream: Arc<CudaStream>,
    hermitian: CudaFunction,
    inverse_inputs: CudaFunction,
    pointwise: CudaFunction,
    combine: CudaFunction,
    area_quadratic: CudaFunction,
    write_update: CudaFunction,
    set_mean_mode: CudaFunction,
    forward: CudaFft,
    inverse: CudaFft,
    /// |k|² per axis (spectral or FD symbol) and Parseval weights per axis (cell volume in
    /// axis 0's).
    tables: [CudaSlice<f64>; 6],
    /// n0, n1, s2 = n2/2 + 1, n2.
    dims: [i32; 4],
    partials: CudaSlice<f64>,
}

impl Device {
    /// The first GPU, set up for the full periodic box `grid` (3D, even lengths).
    ///
    /// # Errors
    /// If the context, the kernels, the plans or the tables cannot be set up.
    pub fn new(grid: &Grid, laplacian: Laplacian) -> Result<Self> {
        let ctx = CudaContext::new(0).map_err(failed("starting the CUDA context"))?;
        let stream = ctx.default_stream();
        let ptx = cudarc::nvrtc::compile_ptx(SOURCE).map_err(|e| {
            DeviceFailure(format!("GPU: NVRTC could not compile the kernels ({e})"))
        })?;
        let module = ctx
            .load_module(ptx)
            .map_err(failed("loading the kernels"))?;
        let f = |name: &str| {
            module
                .load_function(name)
                .map_err(failed("loading a kernel"))
        };
        let [n0, n1, n2] = grid.shape;
        let plan = |kind| {
            CudaFft::plan_3d(n0 as i32, n1 as i32, n2 as i32, kind, stream.clone()).map_err(|e| {
                DeviceFailure(format!("GPU: cuFFT could not plan {n0}×{n1}×{n2} ({e:?})"))
            })
        };
        let s2 = n2 / 2 + 1;
        let host = tables(grid, laplacian);
        let mut tables = Vec::new();
        for t in &host {
            tables.push(stream.clone_htod(t).map_err(failed("copying the tables"))?);
        }
        Ok(Device {
            hermitian: f("hermitian_planes")?,
            inverse_inputs: f("inverse_inputs")?,
            pointwise: f("pointwise")?,
            combine: f("combine")?,
            area_quadratic: f("area_quadratic")?,
            write_update: f("write_update")?,
            set_mean_mode: f("set_mean_mode")?,
            forward: plan(cufftType::CUFFT_D2Z)?,
            inverse: plan(cufftType::CUFFT_Z2D)?,
            tables: tables.try_into().expect("six tables"),
            dims: [n0 as i32, n1 as i32, s2 as i32, n2 as i32],
            partials: stream
                .alloc_zeros::<f64>(4 * BLOCKS as usize)
                .map_err(failed("allocating"))?,
            stream,
        })
    }

    fn config() -> LaunchConfig {
        LaunchConfig {
            grid_dim: (BLOCKS, 1, 1),
            block_dim: (THREADS, 1, 1),
            shared_mem_bytes: 0,
        }
    }

    /// The first `count` sums of the last launch, each added over the blocks in order (or the
    /// maximum, for the sums listed in `max`).
    fn sums<const N: usize>(&self, max: [bool; N]) -> Result<[f64; N]> {
        let mut host = vec![0.0; 4 * BLOCKS as usize];
        self.stream
            .memcpy_dtoh(&self.partials, &mut host)
            .map_err(failed("reading the sums"))?;
        let b = BLOCKS as usize;
        Ok(std::array::from_fn(|s| {
            let part = &host[s * b..(s + 1) * b];
            if max[s] {
                part.iter().cloned().fold(0.0, f64::max)
            } else {
                part.iter().sum()
            }
        }))
    }

    /// Push the tables' arguments (the kernels' `TABLE_ARGS`).
    fn push_tables<'a>(&'a self, b: &mut cudarc::driver::LaunchArgs<'a>) {
        for t in &self.tables {
            b.arg(t);
        }
        b.arg(&self.dims[0]);
        b.arg(&self.dims[1]);
        b.arg(&self.dims[2]);
    }

    /// Push the update kernels' leading arguments: φ̂ⁿ, N̂ⁿ, φ̂ⁿ⁻¹, N̂ⁿ⁻¹ (the current ones again
    /// when the formula does not read them), the flag, the coefficients, the tables and the area
    /// prefactor.
    fn push_update<'a>(
        &'a self,
        b: &mut cudarc::driver::LaunchArgs<'a>,
        (cur, prev): UpdateInputs<'a>,
        u: &'a Update,
        ap: &'a f64,
    ) {
        let [h0, n0] = prev.unwrap_or(cur);
        b.arg(cur[0]);
        b.arg(cur[1]);
        b.arg(h0);
        b.arg(n0);
        b.arg(if prev.is_some() { &2i32 } else { &1i32 });
        b.arg(u);
        self.push_tables(b);
        b.arg(ap);
    }
}

/// The passes of `kernels.cu` and the transforms, each returning its sums added in block order.
/// Spectra are cuFFT's half spectra n0 × n1 × (n2/2 + 1), row-major; `forward` and `inverse`
/// are unnormalised.
impl Device {
    /// The spectral shape n0 × n1 × (n2/2 + 1).
    pub fn spectral_shape(&self) -> [usize; 3] {
        [
            self.dims[0] as usize,
            self.dims[1] as usize,
            self.dims[2] as usize,
        ]
    }

    pub fn points(&self) -> usize {
        self.dims[0] as usize * self.dims[1] as usize * self.dims[3] as usize
    }

    pub fn spectrum(&self) -> Result<Spectrum> {
        self.stream
            .alloc_zeros::<double2>(self.spectral_shape().iter().product())
            .map_err(failed("allocating a spectrum"))
    }

    pub fn field(&self) -> Result<Field> {
        self.stream
            .alloc_zeros::<f64>(self.points())
            .map_err(failed("allocating a field"))
    }

    pub fn upload_field(&self, from: &[f64], to: &mut Field) -> Result<()> {
        self.stream
            .memcpy_htod(from, to)
            .map_err(failed("copying a field"))
    }

    pub fn download_field(&self, from: &Field) -> Result<Vec<f64>> {
        self.stream
            .clone_dtoh(from)
            .map_err(failed("reading a field"))
    }

    pub fn upload_spectrum(&self, from: &Array3<Complex64>) -> Result<Spectrum> {
        let host: Vec<double2> = from.iter().map(|c| double2 { x: c.re, y: c.im }).collect();
        self.stream
            .clone_htod(&host)
            .map_err(failed("copying a spectrum"))
    }

    pub fn download_spectrum(&self, from: &Spectrum) -> Result<Array3<Complex64>> {
        let host = self
            .stream
            .clone_dtoh(from)
            .map_err(failed("reading a spectrum"))?;
        let values = host.iter().map(|v| Complex64::new(v.x, v.y)).collect();
        Ok(Array3::from_shape_vec(self.spectral_shape(), values).expect("spectrum shape"))
    }

    pub fn copy_spectrum(&self, from: &Spectrum, to: &mut Spectrum) -> Result<()> {
        self.stream
            .memcpy_dtod(from, to)
            .map_err(failed("copying a spectrum"))
    }

    /// X ← (X + conj X(−k0, −k1))/2 on the self-conjugate planes (see
    /// `Transform::hermitian_symmetrize`).
    pub fn hermitian(&self, a: &mut Spectrum) -> Result<()> {
        let mut b = self.stream.launch_builder(&self.hermitian);
        b.arg(a);
        b.arg(&self.dims[0]);
        b.arg(&self.dims[1]);
        b.arg(&self.dims[2]);
        b.arg(&self.dims[3]);
        // SAFETY: the arguments match the kernel's signature; the arrays have `modes()` values.
        unsafe { b.launch(Self::config()) }.map_err(failed("hermitian_planes"))?;
        Ok(())
    }

    /// copy = X̂, lap = −|k|²X̂; returns A = Σ (3/(2√2)) ε |k|² w |X̂|² (`ap` the prefactor).
    pub fn inverse_inputs(
        &self,
        hat: &Spectrum,
        copy: &mut Spectrum,
        lap: &mut Spectrum,
        ap: f64,
    ) -> Result<f64> {
        let mut b = self.stream.launch_builder(&self.inverse_inputs);
        b.arg(hat);
        b.arg(copy);
        b.arg(lap);
        self.push_tables(&mut b);
        b.arg(&ap);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`.
        unsafe { b.launch(Self::config()) }.map_err(failed("inverse_inputs"))?;
        Ok(self.sums([false])?[0])
    }

    /// The unnormalised inverse transform of `input` (overwritten) into `out`.
    pub fn inverse(&self, input: &mut Spectrum, out: &mut Field) -> Result<()> {
        self.inverse
            .exec_z2d(input, out)
            .map_err(|e| DeviceFailure(format!("GPU: cuFFT inverse failed ({e:?})")))
    }

    /// The forward transform of `input` into `out`.
    pub fn forward(&self, input: &Field, out: &mut Spectrum) -> Result<()> {
        self.forward
            .exec_d2z(input, out)
            .map_err(|e| DeviceFailure(format!("GPU: cuFFT forward failed ({e:?})")))
    }

    /// The real-space pass (see `pointwise` in `kernels.cu`); returns (Σ Φ², Σ φ, max|φ|,
    /// max|φ − old|).
    #[allow(clippy::too_many_arguments)]
    pub fn pointwise(
        &self,
        phi: &mut Field,
        lap: &mut Field,
        fphi: &mut Field,
        old: Option<&Field>,
        e2: f64,
        ec0: f64,
    ) -> Result<[f64; 4]> {
        let len = self.points() as i64;
        let inv_n = 1.0 / len as f64;
        let has_old = i32::from(old.is_some());
        let mut b = self.stream.launch_builder(&self.pointwise);
        b.arg(&*phi);
        b.arg(lap);
        b.arg(fphi);
        match old {
            Some(o) => b.arg(o),
            None => b.arg(&*phi),
        };
        b.arg(&has_old);
        b.arg(&inv_n);
        b.arg(&e2);
        b.arg(&ec0);
        b.arg(&len);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`; `phi` is read and written by the same thread only.
        unsafe { b.launch(Self::config()) }.map_err(failed("pointwise"))?;
        self.sums([false, false, true, true])
    }

    /// N̂ from FT[f'Φ] (in `nl`) and FT[f] (`g`); returns Σ_{k≠0} w |μ̂|² when `residual`.
    pub fn combine(
        &self,
        hat: &Spectrum,
        nl: &mut Spectrum,
        g: &Spectrum,
        e2: f64,
        tension: f64,
        residual: bool,
    ) -> Result<f64> {
        let with = i32::from(residual);
        let mut b = self.stream.launch_builder(&self.combine);
        b.arg(hat);
        b.arg(nl);
        b.arg(g);
        self.push_tables(&mut b);
        b.arg(&e2);
        b.arg(&tension);
        b.arg(&with);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`.
        unsafe { b.launch(Self::config()) }.map_err(failed("combine"))?;
        Ok(self.sums([false])?[0])
    }

    /// (A_PP, A_PQ, A_QQ) of the step (`prev`: φ̂ⁿ⁻¹, N̂ⁿ⁻¹ when the formula reads them).
    pub fn area_quadratic(
        &self,
        inputs: UpdateInputs<'_>,
        u: &Update,
        ap: f64,
    ) -> Result<[f64; 3]> {
        let mut b = self.stream.launch_builder(&self.area_quadratic);
        self.push_update(&mut b, inputs, u, &ap);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`.
        unsafe { b.launch(Self::config()) }.map_err(failed("area_quadratic"))?;
        self.sums([false; 3])
    }

    /// φ̂ⁿ⁺¹ = P̂ + σQ̂ into `out`, with the inverse transforms' inputs; returns its area.
    pub fn write_update(
        &self,
        inputs: UpdateInputs<'_>,
        u: &Update,
        ap: f64,
        sigma: f64,
        [out, copy, lap]: [&mut Spectrum; 3],
    ) -> Result<f64> {
        let mut b = self.stream.launch_builder(&self.write_update);
        self.push_update(&mut b, inputs, u, &ap);
        b.arg(&sigma);
        b.arg(out);
        b.arg(copy);
        b.arg(lap);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`.
        unsafe { b.launch(Self::config()) }.map_err(failed("write_update"))?;
        Ok(self.sums([false])?[0])
    }

    /// The real part of mode 0 of `out` and of `copy` ← `value` (the volume ramp's mean mode).
    pub fn set_mean_mode(&self, out: &mut Spectrum, copy: &mut Spectrum, value: f64) -> Result<()> {
        let mut b = self.stream.launch_builder(&self.set_mean_mode);
        b.arg(out);
        b.arg(copy);
        b.arg(&value);
        // SAFETY: as in `hermitian`; one thread writes mode 0 of two spectra.
        unsafe { b.launch(LaunchConfig::for_num_elems(1)) }.map_err(failed("set_mean_mode"))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernels compile (NVRTC alone: no GPU needed, only libnvrtc), or, where NVRTC cannot
    /// be loaded, [`probe`] says which library is missing instead of panicking.
    #[test]
    fn kernels_compile_where_nvrtc_loads() {
        // SAFETY: only tries to open the shared library.
        if unsafe { cudarc::nvrtc::sys::is_culib_present() } {
            if let Err(e) = cudarc::nvrtc::compile_ptx(SOURCE) {
                panic!("the kernels do not compile: {e}");
            }
        } else {
            let why = probe().expect_err("no NVRTC, so no usable GPU");
            assert!(why.contains("cannot be loaded"), "{why}");
        }
    }
}
