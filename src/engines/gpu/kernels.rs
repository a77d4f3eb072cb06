//! The device side of the GPU engine: the context and stream, the kernels of `kernels.cu`
//! (compiled by NVRTC), the cuFFT plans, the wavenumber and weight tables, and the launches,
//! each returning its sums added in block order on the host (deterministic).

use super::backend::{tables, Backend, UpdateArgs};
use crate::problem::config::Laplacian;
use crate::problem::grid::Grid;
use cudarc::cufft::sys::{cufftType, double2};
use cudarc::cufft::CudaFft;
use cudarc::driver::{
    CudaContext, CudaFunction, CudaSlice, CudaStream, DeviceRepr, LaunchConfig, PushKernelArg,
};
use ndarray::Array3;
use num_complex::Complex64;
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

/// Any failure of the device, as a sentence.
pub fn failed(what: &str) -> impl Fn(cudarc::driver::DriverError) -> String + '_ {
    move |e| format!("GPU: {what} failed ({e})")
}

/// The GPU can be used: the libraries load, a device exists and the kernels compile.
pub fn probe() -> Result<(), String> {
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

// SAFETY: ten f64 fields, repr(C): the layout of the kernels' `Update`.
unsafe impl DeviceRepr for UpdateArgs {}

/// The device, its kernels, plans and tables for one grid.
pub struct Device {
    stream: Arc<CudaStream>,
    hermitian: CudaFunction,
    inverse_inputs: CudaFunction,
    pointwise: CudaFunction,
    combine: CudaFunction,
    area_quadratic: CudaFunction,
    write_update: CudaFunction,
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
    pub fn new(grid: &Grid, laplacian: Laplacian) -> Result<Self, String> {
        let ctx = CudaContext::new(0).map_err(failed("starting the CUDA context"))?;
        let stream = ctx.default_stream();
        let ptx = cudarc::nvrtc::compile_ptx(SOURCE)
            .map_err(|e| format!("GPU: NVRTC could not compile the kernels ({e})"))?;
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
            CudaFft::plan_3d(n0 as i32, n1 as i32, n2 as i32, kind, stream.clone())
                .map_err(|e| format!("GPU: cuFFT could not plan {n0}×{n1}×{n2} ({e:?})"))
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
    fn sums<const N: usize>(&self, max: [bool; N]) -> Result<[f64; N], String> {
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
        cur: (&'a Spectrum, &'a Spectrum),
        prev: Option<(&'a Spectrum, &'a Spectrum)>,
        u: &'a UpdateArgs,
        ap: &'a f64,
    ) {
        let (h0, n0) = prev.unwrap_or(cur);
        b.arg(cur.0);
        b.arg(cur.1);
        b.arg(h0);
        b.arg(n0);
        b.arg(if prev.is_some() { &1i32 } else { &0i32 });
        b.arg(u);
        self.push_tables(b);
        b.arg(ap);
    }
}

impl Backend for Device {
    type Spectrum = Spectrum;
    type Field = Field;

    fn spectral_shape(&self) -> [usize; 3] {
        [
            self.dims[0] as usize,
            self.dims[1] as usize,
            self.dims[2] as usize,
        ]
    }

    fn points(&self) -> usize {
        self.dims[0] as usize * self.dims[1] as usize * self.dims[3] as usize
    }

    fn spectrum(&self) -> Result<Spectrum, String> {
        self.stream
            .alloc_zeros::<double2>(self.spectral_shape().iter().product())
            .map_err(failed("allocating a spectrum"))
    }

    fn field(&self) -> Result<Field, String> {
        self.stream
            .alloc_zeros::<f64>(self.points())
            .map_err(failed("allocating a field"))
    }

    fn upload_field(&self, from: &[f64], to: &mut Field) -> Result<(), String> {
        self.stream
            .memcpy_htod(from, to)
            .map_err(failed("copying a field"))
    }

    fn download_field(&self, from: &Field) -> Result<Vec<f64>, String> {
        self.stream
            .clone_dtoh(from)
            .map_err(failed("reading a field"))
    }

    fn upload_spectrum(&self, from: &Array3<Complex64>) -> Result<Spectrum, String> {
        let host: Vec<double2> = from.iter().map(|c| double2 { x: c.re, y: c.im }).collect();
        self.stream
            .clone_htod(&host)
            .map_err(failed("copying a spectrum"))
    }

    fn download_spectrum(&self, from: &Spectrum) -> Result<Array3<Complex64>, String> {
        let host = self
            .stream
            .clone_dtoh(from)
            .map_err(failed("reading a spectrum"))?;
        let values = host.iter().map(|v| Complex64::new(v.x, v.y)).collect();
        Ok(Array3::from_shape_vec(self.spectral_shape(), values).expect("spectrum shape"))
    }

    fn copy_spectrum(&self, from: &Spectrum, to: &mut Spectrum) -> Result<(), String> {
        self.stream
            .memcpy_dtod(from, to)
            .map_err(failed("copying a spectrum"))
    }

    /// X ← (X + conj X(−k0, −k1))/2 on the self-conjugate planes (see
    /// `Transform::hermitian_symmetrize`).
    fn hermitian(&self, a: &mut Spectrum) -> Result<(), String> {
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
    fn inverse_inputs(
        &self,
        hat: &Spectrum,
        copy: &mut Spectrum,
        lap: &mut Spectrum,
        ap: f64,
    ) -> Result<f64, String> {
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
    fn inverse(&self, input: &mut Spectrum, out: &mut Field) -> Result<(), String> {
        self.inverse
            .exec_z2d(input, out)
            .map_err(|e| format!("GPU: cuFFT inverse failed ({e:?})"))
    }

    /// The forward transform of `input` into `out`.
    fn forward(&self, input: &Field, out: &mut Spectrum) -> Result<(), String> {
        self.forward
            .exec_d2z(input, out)
            .map_err(|e| format!("GPU: cuFFT forward failed ({e:?})"))
    }

    /// The real-space pass (see `pointwise` in `kernels.cu`); returns (Σ Φ², Σ φ, max|φ|,
    /// max|φ − old|).
    #[allow(clippy::too_many_arguments)]
    fn pointwise(
        &self,
        phi: &mut Field,
        lap: &mut Field,
        fphi: &mut Field,
        old: Option<&Field>,
        e2: f64,
        ec0: f64,
    ) -> Result<[f64; 4], String> {
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
    fn combine(
        &self,
        hat: &Spectrum,
        nl: &mut Spectrum,
        g: &Spectrum,
        e2: f64,
        tension: f64,
        residual: bool,
    ) -> Result<f64, String> {
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
    fn area_quadratic(
        &self,
        cur: (&Spectrum, &Spectrum),
        prev: Option<(&Spectrum, &Spectrum)>,
        u: UpdateArgs,
        ap: f64,
    ) -> Result<[f64; 3], String> {
        let mut b = self.stream.launch_builder(&self.area_quadratic);
        self.push_update(&mut b, cur, prev, &u, &ap);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`.
        unsafe { b.launch(Self::config()) }.map_err(failed("area_quadratic"))?;
        self.sums([false; 3])
    }

    /// φ̂ⁿ⁺¹ = P̂ + σQ̂ into `out`, with the inverse transforms' inputs; returns its area.
    #[allow(clippy::too_many_arguments)]
    fn write_update(
        &self,
        cur: (&Spectrum, &Spectrum),
        prev: Option<(&Spectrum, &Spectrum)>,
        u: UpdateArgs,
        ap: f64,
        sigma: f64,
        out: &mut Spectrum,
        copy: &mut Spectrum,
        lap: &mut Spectrum,
    ) -> Result<f64, String> {
        let mut b = self.stream.launch_builder(&self.write_update);
        self.push_update(&mut b, cur, prev, &u, &ap);
        b.arg(&sigma);
        b.arg(out);
        b.arg(copy);
        b.arg(lap);
        b.arg(&self.partials);
        // SAFETY: as in `hermitian`.
        unsafe { b.launch(Self::config()) }.map_err(failed("write_update"))?;
        Ok(self.sums([false])?[0])
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
