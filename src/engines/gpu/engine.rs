//! The spectral step's passes on the GPU ([`GpuPasses`]): the shared [`Stepper`] (the step's
//! logic, the same as on the CPU) over the kernels of `kernels.cu`, on the full periodic 3D box,
//! with every array on the device. The host keeps the scalars; φ and the spectra come back to
//! the host only when they are asked for (outputs, checkpoints).

use super::kernels::{Device, Field, Spectrum};
use crate::engines::spectral::stepper::{Evaluation, SavedSpectra};
use crate::engines::spectral::update::Update;
use crate::engines::spectral::{DeviceFailure, DeviceState, Passes, States, Stepper};
use crate::engines::{Diverged, Saved, SavedArray};
use crate::problem::config::Scene;
use crate::problem::grid::Grid;
use crate::problem::model::{self, Measures, AREA_PREFACTOR, C0};
use ndarray::{Array3, CowArray, Ix3};
use num_complex::Complex64;
use std::cell::OnceCell;

/// A state on the device.
pub struct State {
    hat: Spectrum,
    nonlinear: Spectrum,
    phi: Field,
    measures: Measures,
    residual: f64,
}

impl DeviceState for State {
    type Spectrum = Spectrum;

    fn measures(&self) -> Measures {
        self.measures
    }

    fn residual(&self) -> f64 {
        self.residual
    }

    fn spectra(&self) -> [&Spectrum; 2] {
        [&self.hat, &self.nonlinear]
    }

    fn spectra_mut(&mut self) -> [&mut Spectrum; 2] {
        [&mut self.hat, &mut self.nonlinear]
    }
}

impl State {
    /// A state of zeros on `dev`.
    fn on(dev: &Device) -> Result<Self, DeviceFailure> {
        Ok(State {
            hat: dev.spectrum()?,
            nonlinear: dev.spectrum()?,
            phi: dev.field()?,
            measures: Measures::default(),
            residual: f64::NAN,
        })
    }
}

/// Copies of device arrays, made when the host asks and dropped when the state changes.
#[derive(Default)]
struct HostCopies {
    phi: OnceCell<Array3<f64>>,
    hat: OnceCell<Array3<Complex64>>,
    prev: OnceCell<[Array3<Complex64>; 2]>,
}

/// The spectral conserved flow on the GPU.
pub type GpuEngine = Stepper<GpuPasses>;

impl GpuEngine {
    /// Engine on the first GPU holding `phi` at t = 0, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if the GPU cannot be set up or `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let c0_ramped = c0.is_ramped();
        let passes = GpuPasses::new(scene, grid, c0, &phi)?;
        Ok(Stepper::with_passes(passes, scene, c0_ramped))
    }
}

/// The spectral step's passes on a GPU: the states and the scratch, on the device.
pub struct GpuPasses {
    dev: Device,
    grid: Grid,
    eps: f64,
    /// Uniform εC0 (ramped in time).
    c0: C0,
    states: States<State>,
    /// Scratch: the inverse transforms' second input (−|k|²φ̂), then FT[f].
    spare: Spectrum,
    /// Real scratch: ∇²φ, then f; and f'Φ.
    work: Field,
    work2: Field,
    host: HostCopies,
}

impl GpuPasses {
    /// The passes on the first GPU for `scene`, holding `phi` evaluated at t = 0.
    ///
    /// # Errors
    /// [`Diverged`] if the GPU cannot be set up or `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: &Array3<f64>) -> Result<Self, Diverged> {
        let device = |f: DeviceFailure| Diverged(f.0);
        let dev = Device::new(&grid, scene.laplacian).map_err(device)?;
        let mut cur = State::on(&dev).map_err(device)?;
        dev.upload_field(phi.as_slice().expect("standard layout"), &mut cur.phi)
            .map_err(device)?;
        dev.forward(&cur.phi, &mut cur.hat).map_err(device)?;
        let mut passes = GpuPasses {
            states: States::new(cur, State::on(&dev).map_err(device)?),
            spare: dev.spectrum().map_err(device)?,
            work: dev.field().map_err(device)?,
            work2: dev.field().map_err(device)?,
            eps: scene.eps,
            c0,
            grid,
            dev,
            host: HostCopies::default(),
        };
        passes.evaluate_current(0.0, 0.0).map_err(device)??;
        Ok(passes)
    }

    /// (3/(2√2)) ε: the area weight's prefactor.
    fn area_prefactor(&self) -> f64 {
        AREA_PREFACTOR * self.eps
    }

    /// Evaluate the current state from its φ̂ at time `t` with multiplier `sigma` (the CPU
    /// `Evaluator::evaluate`).
    fn evaluate_current(&mut self, t: f64, sigma: f64) -> Evaluation {
        let (ap, ec0) = (self.area_prefactor(), self.uniform_c0(t));
        let cur = &mut self.states.cur;
        self.dev.hermitian(&mut cur.hat)?;
        let area = self
            .dev
            .inverse_inputs(&cur.hat, &mut cur.nonlinear, &mut self.spare, ap)?;
        finish(
            &self.dev,
            (self.eps, ec0, self.grid.cell_volume()),
            cur,
            (&mut self.spare, &mut self.work, &mut self.work2),
            area,
            None,
            sigma,
        )
    }

    /// εC0 at time `t` (uniform: the GPU engine takes no C0 field).
    fn uniform_c0(&self, t: f64) -> f64 {
        self.c0.parts(self.c0.ramp(t)).0
    }
}

/// The evaluation after its first pass (the CPU `Evaluator::finish`): `state.hat` holds φ̂,
/// `state.nonlinear` a copy of it and `spare` −|k|²φ̂; computes φ, the measures, N̂ (in
/// `state.nonlinear`) and the residual at `sigma`. Returns max|φ − old| (0 without `old`), or
/// that the state diverged; `Err` if the device failed.
fn finish(
    dev: &Device,
    (eps, ec0, cell): (f64, f64, f64),
    state: &mut State,
    (spare, work, work2): (&mut Spectrum, &mut Field, &mut Field),
    area: f64,
    old: Option<&Field>,
    sigma: f64,
) -> Evaluation {
    let e2 = eps * eps;
    dev.inverse(&mut state.nonlinear, &mut state.phi)?;
    dev.inverse(spare, work)?;
    let [phi_sq, phi_sum, max_abs, change] =
        dev.pointwise(&mut state.phi, work, work2, old, e2, ec0)?;
    dev.forward(work2, &mut state.nonlinear)?;
    dev.forward(work, spare)?;
    state.measures = Measures {
        energy: phi_sq * cell,
        area,
        volume: 0.5 * (dev.points() as f64 + phi_sum) * cell,
        curvature: 0.0,
    };
    if model::diverged(max_abs, state.measures.energy) {
        return Ok(Err(Diverged(format!(
            "max|φ| = {max_abs:.3e}, F = {:.3e}: the state diverged",
            state.measures.energy
        ))));
    }
    let tension = 2.0 * AREA_PREFACTOR * eps * sigma;
    let res = dev.combine(&state.hat, &mut state.nonlinear, spare, e2, tension, true)?;
    dev.hermitian(&mut state.nonlinear)?;
    state.residual = (res / (dev.points() as f64 * cell)).sqrt();
    Ok(Ok(change))
}

impl Passes for GpuPasses {
    type State = State;

    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn states(&self) -> &States<State> {
        &self.states
    }

    fn phi(&self) -> &Array3<f64> {
        self.host.phi.get_or_init(|| {
            let v = self
                .dev
                .download_field(&self.states.cur.phi)
                .expect("GPU: reading φ");
            Array3::from_shape_vec(self.grid.shape, v).expect("field shape")
        })
    }

    fn area_quadratic(&self, u: &Update) -> Result<[f64; 3], DeviceFailure> {
        let States { cur, prev, .. } = &self.states;
        let history = prev.as_ref().filter(|_| u.levels() > 1);
        let inputs = ([&cur.hat, &cur.nonlinear], history.map(|[h, n]| [h, n]));
        self.dev.area_quadratic(inputs, u, self.area_prefactor())
    }

    fn write_update(&mut self, u: &Update, sigma: f64) -> Result<f64, DeviceFailure> {
        let ap = self.area_prefactor();
        let States { cur, next, prev } = &mut self.states;
        let history = prev.as_ref().filter(|_| u.levels() > 1);
        let inputs = ([&cur.hat, &cur.nonlinear], history.map(|[h, n]| [h, n]));
        let out = [&mut next.hat, &mut next.nonlinear, &mut self.spare];
        self.dev.write_update(inputs, u, ap, sigma, out)
    }

    fn set_mean_mode(&mut self, value: f64) -> Result<(), DeviceFailure> {
        let next = &mut self.states.next;
        self.dev
            .set_mean_mode(&mut next.hat, &mut next.nonlinear, value)
    }

    fn finish_next(&mut self, area: f64, t: f64, sigma: f64) -> Evaluation {
        let ec0 = self.uniform_c0(t);
        let States { cur, next, .. } = &mut self.states;
        finish(
            &self.dev,
            (self.eps, ec0, self.grid.cell_volume()),
            next,
            (&mut self.spare, &mut self.work, &mut self.work2),
            area,
            Some(&cur.phi),
            sigma,
        )
    }

    fn accept(&mut self, keep_history: bool) -> Result<(), DeviceFailure> {
        let dev = &self.dev;
        self.states.accept(keep_history, |s| {
            let mut copy = dev.spectrum()?;
            dev.copy_spectrum(s, &mut copy)?;
            Ok(copy)
        })?;
        self.host = HostCopies::default();
        Ok(())
    }

    fn spectra(&self) -> (SavedArray<'_>, Option<[SavedArray<'_>; 2]>) {
        let download = |s: &Spectrum| {
            self.dev
                .download_spectrum(s)
                .expect("GPU: reading a spectrum")
        };
        fn complex(a: &Array3<Complex64>) -> CowArray<'_, Complex64, Ix3> {
            a.view().into()
        }
        let hat = self.host.hat.get_or_init(|| download(&self.states.cur.hat));
        let history = self.states.prev.as_ref().map(|[h, n]| {
            let [hat, nonlinear] = self.host.prev.get_or_init(|| [download(h), download(n)]);
            [
                SavedArray::Complex(complex(hat)),
                SavedArray::Complex(complex(nonlinear)),
            ]
        });
        (SavedArray::Complex(complex(hat)), history)
    }

    fn read_spectrum<'s>(
        &self,
        saved: &'s Saved<'_>,
        name: &str,
    ) -> Result<CowArray<'s, Complex64, Ix3>, String> {
        saved
            .complex(name, &self.dev.spectral_shape())
            .map(CowArray::from)
    }

    fn restore(&mut self, saved: SavedSpectra<'_, '_>, t: f64, sigma: f64) -> Result<(), String> {
        let SavedSpectra { hat, history, .. } = saved;
        let upload = |a: &CowArray<'_, Complex64, Ix3>| {
            self.dev.upload_spectrum(&a.to_owned()).map_err(|f| f.0)
        };
        self.states.cur.hat = upload(&hat)?;
        self.states.prev = match history {
            Some([h, n]) => Some([upload(&h)?, upload(&n)?]),
            None => None,
        };
        self.host = HostCopies::default();
        self.evaluate_current(t, sigma)
            .map_err(|f| f.0)?
            .map_err(|d| d.0)?;
        Ok(())
    }

    fn name(&self) -> &'static str {
        "spectral (GPU)"
    }
}
