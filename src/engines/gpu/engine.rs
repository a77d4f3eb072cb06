//! The GPU engine: the CPU spectral engine's step (`engines::spectral::engine`, the same SBDF
//! formula, exact area projection, Lagrangian update, energy guard and adaptive controller) on
//! the full periodic 3D box, with every array on the device. The host keeps the scalars, takes
//! σ from the area quadratic's three sums and checks the constraints; φ and the spectra come
//! back to the host only when they are asked for (outputs, checkpoints).

use super::backend::{Backend, UpdateArgs};
use crate::engines::numerics::nearest_root;
use crate::engines::spectral::control::{self, Rejection};
use crate::engines::{AreaConstraint, Diverged, Engine, Saved, SavedArray, StepReport};
use crate::problem::config::{AdaptiveSettings, AreaMethod, Scene, Scheme, Stabilizer};
use crate::problem::grid::Grid;
use crate::problem::model::{self, Measures, C0};
use ndarray::Array3;
use num_complex::Complex64;
use std::cell::OnceCell;

/// (3/(2√2)): A = (3/(2√2)) ε ∫|∇φ|².
const AREA_FACTOR: f64 = 1.060_660_171_779_821_2;

/// A state on the device.
struct State<B: Backend> {
    hat: B::Spectrum,
    nonlinear: B::Spectrum,
    phi: B::Field,
    measures: Measures,
    residual: f64,
}

/// Copies of device arrays, made when the host asks and dropped when the state changes.
#[derive(Default)]
struct HostCopies {
    phi: OnceCell<Array3<f64>>,
    hat: OnceCell<Array3<Complex64>>,
    prev: OnceCell<(Array3<Complex64>, Array3<Complex64>)>,
}

/// The spectral conserved flow on the GPU.
pub type GpuEngine = DeviceEngine<super::kernels::Device>;

/// The spectral conserved flow on a [`Backend`].
pub struct DeviceEngine<B: Backend> {
    dev: B,
    grid: Grid,
    eps: f64,
    /// εC0 (uniform).
    ec0: f64,
    stabilizer: Stabilizer,
    scheme: Scheme,
    adaptive: Option<AdaptiveSettings>,
    cur: State<B>,
    next: State<B>,
    prev: Option<(B::Spectrum, B::Spectrum)>,
    /// Scratch: the inverse transforms' second input (−|k|²φ̂), then FT[f].
    spare: B::Spectrum,
    /// Real scratch: ∇²φ, then f; and f'Φ.
    work: B::Field,
    work2: B::Field,
    dt_prev: f64,
    max_change: f64,
    sigma: f64,
    area: AreaConstraint,
    volume0: f64,
    dt_next: Option<f64>,
    energy_guard: bool,
    host: HostCopies,
}

impl GpuEngine {
    /// Engine on the first GPU holding `phi` at t = 0, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if the GPU cannot be set up or `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let dev = super::kernels::Device::new(&grid, scene.laplacian).map_err(Diverged)?;
        Self::on(dev, scene, grid, c0, phi).map_err(Diverged)
    }
}

impl<B: Backend> DeviceEngine<B> {
    /// Engine on `dev` holding `phi` at t = 0, no area constraint yet.
    ///
    /// # Errors
    /// A sentence if the device fails or `phi` is not finite.
    pub fn on(dev: B, scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, String> {
        let state = |dev: &B| -> Result<State<B>, String> {
            Ok(State {
                hat: dev.spectrum()?,
                nonlinear: dev.spectrum()?,
                phi: dev.field()?,
                measures: Measures::default(),
                residual: f64::NAN,
            })
        };
        let mut cur = state(&dev)?;
        dev.upload_field(phi.as_slice().expect("standard layout"), &mut cur.phi)?;
        dev.forward(&cur.phi, &mut cur.hat)?;
        let adaptive = control::adaptive_settings(scene);
        let mut e = DeviceEngine {
            next: state(&dev)?,
            spare: dev.spectrum()?,
            work: dev.field()?,
            work2: dev.field()?,
            cur,
            ec0: c0.parts(c0.ramp(0.0)).0,
            eps: scene.eps,
            grid,
            dev,
            stabilizer: scene.stabilizer(),
            scheme: scene.scheme,
            adaptive,
            prev: None,
            dt_prev: scene.dt,
            max_change: 0.0,
            sigma: 0.0,
            area: AreaConstraint::none(),
            volume0: 0.0,
            dt_next: None,
            energy_guard: true,
            host: HostCopies::default(),
        };
        e.evaluate_current(Some(0.0))?;
        e.volume0 = e.cur.measures.volume;
        Ok(e)
    }

    /// Evaluate the current state from its φ̂ (the CPU `Evaluator::evaluate`).
    fn evaluate_current(&mut self, sigma: Option<f64>) -> Result<(), String> {
        let ap = AREA_FACTOR * self.eps;
        self.dev.hermitian(&mut self.cur.hat)?;
        let area =
            self.dev
                .inverse_inputs(&self.cur.hat, &mut self.cur.nonlinear, &mut self.spare, ap)?;
        self.max_change = finish(
            &self.dev,
            (self.eps, self.ec0, self.grid.cell_volume()),
            &mut self.cur,
            (&mut self.spare, &mut self.work, &mut self.work2),
            area,
            None,
            sigma,
        )?
        .map_err(|d| d.0)?;
        Ok(())
    }

    /// SBDF coefficients (a0, a1, a2, b1, b2) for this step (as the CPU engine's).
    fn coefficients(&self, dt: f64) -> [f64; 5] {
        control::sbdf_coefficients(self.scheme, self.prev.is_some(), dt, self.dt_prev)
    }

    fn update(&self, dt: f64) -> UpdateArgs {
        let e2 = self.eps * self.eps;
        let [a0, a1, a2, b1, b2] = self.coefficients(dt);
        UpdateArgs {
            a0,
            a1,
            a2,
            b1,
            b2,
            dt,
            s2: self.stabilizer.s2,
            s4e2: self.stabilizer.s4 * e2,
            e4x2: 2.0 * e2 * e2,
            c_sigma: 3.0 / std::f64::consts::SQRT_2 * self.eps,
        }
    }

    /// φ̂ⁿ⁻¹, N̂ⁿ⁻¹ when this step's formula reads them.
    fn prev_inputs(&self, dt: f64) -> Option<(&B::Spectrum, &B::Spectrum)> {
        let a2 = self.coefficients(dt)[2];
        self.prev
            .as_ref()
            .filter(|_| a2 != 0.0)
            .map(|(h, n)| (h, n))
    }

    fn choose_sigma(&self, dt: f64) -> Result<Option<f64>, String> {
        Ok(match self.area.method {
            AreaMethod::None => Some(0.0),
            AreaMethod::Lagrangian => Some(self.sigma),
            AreaMethod::Projection => {
                let ap = AREA_FACTOR * self.eps;
                let cur = (&self.cur.hat, &self.cur.nonlinear);
                let [pp, pq, qq] =
                    self.dev
                        .area_quadratic(cur, self.prev_inputs(dt), self.update(dt), ap)?;
                nearest_root(qq, pq, pp - self.area.target, self.sigma)
            }
        })
    }

    /// Try one step of `dt` into `next`: the σ of the update and of the new state, or why the
    /// step was rejected; `Err` if the device failed.
    fn attempt(&mut self, dt: f64) -> Result<Result<(f64, f64), Rejection>, Diverged> {
        let Some(sigma) = self.choose_sigma(dt).map_err(Diverged)? else {
            return Ok(Err(Rejection::NoRealRoot));
        };
        let ap = AREA_FACTOR * self.eps;
        let u = self.update(dt);
        let prev = self.prev.as_ref().filter(|_| u.a2 != 0.0);
        let area = self
            .dev
            .write_update(
                (&self.cur.hat, &self.cur.nonlinear),
                prev.map(|(h, n)| (h, n)),
                u,
                ap,
                sigma,
                &mut self.next.hat,
                &mut self.next.nonlinear,
                &mut self.spare,
            )
            .map_err(Diverged)?;
        let sigma_after =
            control::sigma_after(&self.area, self.sigma, self.cur.measures.area, sigma);
        let finished = finish(
            &self.dev,
            (self.eps, self.ec0, self.grid.cell_volume()),
            &mut self.next,
            (&mut self.spare, &mut self.work, &mut self.work2),
            area,
            Some(&self.cur.phi),
            Some(sigma_after),
        )
        .map_err(Diverged)?;
        self.max_change = match finished {
            Ok(change) => change,
            Err(d) => return Ok(Err(Rejection::Diverged(d))),
        };
        let guard = self.energy_guard && control::dissipative(self.adaptive.as_ref(), self.scheme);
        let (before, after) = (&self.cur.measures, &self.next.measures);
        Ok(
            control::check_step(before, after, sigma, self.volume0, &self.area, guard)
                .map(|()| (sigma, sigma_after)),
        )
    }

    fn accept(&mut self, sigma: f64, dt: f64) -> Result<(), String> {
        std::mem::swap(&mut self.cur, &mut self.next);
        if self.scheme == Scheme::Sbdf2 {
            match &mut self.prev {
                Some((h, n)) => {
                    std::mem::swap(h, &mut self.next.hat);
                    std::mem::swap(n, &mut self.next.nonlinear);
                }
                None => {
                    let mut h = self.dev.spectrum()?;
                    let mut n = self.dev.spectrum()?;
                    self.dev.copy_spectrum(&self.next.hat, &mut h)?;
                    self.dev.copy_spectrum(&self.next.nonlinear, &mut n)?;
                    self.prev = Some((h, n));
                }
            }
        }
        self.dt_prev = dt;
        self.sigma = sigma;
        self.host = HostCopies::default();
        Ok(())
    }
}

/// The evaluation after its first sweep (the CPU `Evaluator::finish`): `state.hat` holds φ̂,
/// `state.nonlinear` a copy of it and `spare` −|k|²φ̂; computes φ, the measures, N̂ (in
/// `state.nonlinear`) and, with `sigma`, the residual. Returns max|φ − old|, or `Diverged` if
/// the state diverged; `Err` if the device failed.
fn finish<B: Backend>(
    dev: &B,
    (eps, ec0, cell): (f64, f64, f64),
    state: &mut State<B>,
    (spare, work, work2): (&mut B::Spectrum, &mut B::Field, &mut B::Field),
    area: f64,
    old: Option<&B::Field>,
    sigma: Option<f64>,
) -> Result<Result<f64, Diverged>, String> {
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
    };
    if model::diverged(max_abs, state.measures.energy) {
        return Ok(Err(Diverged(format!(
            "max|φ| = {max_abs:.3e}, F = {:.3e}: the state diverged",
            state.measures.energy
        ))));
    }
    let tension = 2.0 * AREA_FACTOR * eps * sigma.unwrap_or(0.0);
    let res = dev.combine(
        &state.hat,
        &mut state.nonlinear,
        spare,
        e2,
        tension,
        sigma.is_some(),
    )?;
    dev.hermitian(&mut state.nonlinear)?;
    state.residual = match sigma {
        Some(_) => (res / (dev.points() as f64 * cell)).sqrt(),
        None => f64::NAN,
    };
    Ok(Ok(change))
}

impl<B: Backend> Engine for DeviceEngine<B>
where
    DeviceEngine<B>: Send,
{
    fn phi(&self) -> &Array3<f64> {
        self.host.phi.get_or_init(|| {
            let v = self
                .dev
                .download_field(&self.cur.phi)
                .expect("GPU: reading φ");
            Array3::from_shape_vec(self.grid.shape, v).expect("field shape")
        })
    }

    fn sigma(&self) -> f64 {
        self.sigma
    }

    fn measures(&self) -> Measures {
        self.cur.measures
    }

    fn residual(&self) -> f64 {
        self.cur.residual
    }

    fn set_area(&mut self, area: AreaConstraint) {
        if area.method == AreaMethod::None {
            self.sigma = 0.0;
        }
        self.area = area;
    }

    fn step(&mut self, _t: f64, dt: f64) -> Result<StepReport, Diverged> {
        let adaptive = self.adaptive.clone();
        let ((_, sigma_after), dt, rejected) =
            control::with_retries(adaptive.as_ref(), dt, |dt| self.attempt(dt))?;
        let f_old = self.cur.measures.energy;
        self.accept(sigma_after, dt).map_err(Diverged)?;
        let rate = self.max_change / dt;
        if let Some(a) = &self.adaptive {
            self.dt_next = Some(control::propose(a, dt, f_old, self.cur.measures.energy));
        }
        Ok(StepReport { dt, rate, rejected })
    }

    fn next_dt(&self, dt: f64) -> f64 {
        self.dt_next.unwrap_or(dt)
    }

    fn guard_energy(&mut self, on: bool) {
        self.energy_guard = on;
    }

    fn name(&self) -> &'static str {
        "spectral (GPU)"
    }

    fn save(&self) -> Saved<'_> {
        let download = |s: &B::Spectrum| {
            self.dev
                .download_spectrum(s)
                .expect("GPU: reading a spectrum")
        };
        let hat = self.host.hat.get_or_init(|| download(&self.cur.hat));
        let mut saved = Saved::default()
            .scalar("sigma", self.sigma)
            .scalar("volume0", self.volume0)
            .scalar("dt_prev", self.dt_prev)
            .scalar("dt_next", self.dt_next.unwrap_or(f64::NAN))
            .array("phi_hat", SavedArray::Complex(hat.view().into()));
        if let Some((h, n)) = &self.prev {
            let (hat, nonlinear) = self.host.prev.get_or_init(|| (download(h), download(n)));
            saved = saved
                .array("prev_phi_hat", SavedArray::Complex(hat.view().into()))
                .array(
                    "prev_nonlinear",
                    SavedArray::Complex(nonlinear.view().into()),
                );
        }
        saved
    }

    fn restore(&mut self, saved: &mut Saved<'_>, _t: f64) -> Result<(), String> {
        let shape = self.dev.spectral_shape();
        let spectrum = |saved: &Saved<'_>, name: &str| -> Result<Array3<Complex64>, String> {
            saved.complex(name, &shape).map(|v| v.to_owned())
        };
        self.cur.hat = self.dev.upload_spectrum(&spectrum(saved, "phi_hat")?)?;
        self.sigma = saved.get("sigma")?;
        self.volume0 = saved.get("volume0")?;
        self.dt_prev = saved.get("dt_prev")?;
        let dt_next = saved.get("dt_next")?;
        self.dt_next = (!dt_next.is_nan()).then_some(dt_next);
        self.prev = match (self.scheme, spectrum(saved, "prev_phi_hat")) {
            (Scheme::Sbdf2, Ok(hat)) => Some((
                self.dev.upload_spectrum(&hat)?,
                self.dev
                    .upload_spectrum(&spectrum(saved, "prev_nonlinear")?)?,
            )),
            _ => None,
        };
        self.host = HostCopies::default();
        self.evaluate_current(Some(self.sigma))
    }
}
