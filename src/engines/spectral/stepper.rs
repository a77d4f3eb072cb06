//! The spectral step, written once for every device (docs/src/theory/spectral.md). A
//! [`Stepper`] holds the step's scalars and logic: the scheme's coefficients
//! ([`super::update::SCHEMES`]), the choice of σ (the exact area projection, the Lagrangian
//! update, or none), the volume target, the checks a step must pass, the retries of rejected
//! adaptive steps, the proposal of the next step and the checkpoint's keys. What touches the
//! arrays is a device's [`Passes`]: the CPU sweeps ([`super::engine::CpuPasses`]) or the GPU
//! kernels (`engines::gpu`).
//!
//! φ̂^{n+1} = P̂ + σQ̂ is affine in σ ([`super::update`]), so the area A(φ^{n+1}) = A_PP +
//! 2σ A_PQ + σ² A_QQ is a quadratic computed by Parseval with no extra transform; the exact
//! projection takes the root nearest the last σ and rejects a step with no real root.

use super::control;
use super::curvature::CoupleSums;
use super::flow::FlowStats;
use super::update::{self, Update};
use crate::engines::numerics::nearest_root;
use crate::engines::{
    AreaConstraint, Diverged, Engine, Rejection, Saved, SavedArray, StepError, StepReport,
};
use crate::problem::area_difference::{AreaDifference, Law};
use crate::problem::config::{AdaptiveSettings, AreaMethod, Scene, Scheme, Stabilizer, VolumeRamp};
use crate::problem::grid::Grid;
use crate::problem::model::Measures;
use ndarray::{Array3, CowArray, Ix3};
use num_complex::Complex64;

/// A failure of the device itself (a GPU out of memory, a kernel that failed to launch): no
/// smaller step mends it.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceFailure(pub String);

/// What evaluating a state gives: max|φ^{n+1} − φ^n| (0 without a previous state), or that
/// the state diverged; `Err` if the device failed.
pub type Evaluation = Result<Result<f64, Diverged>, DeviceFailure>;

/// A state on a device: φ̂, the explicit term N̂, φ, and its measures.
pub trait DeviceState {
    /// A spectrum on the device.
    type Spectrum;
    /// F_sc, A, V (full-box values).
    fn measures(&self) -> Measures;
    /// The stationarity residual at the σ it was evaluated with.
    fn residual(&self) -> f64;
    /// φ̂ and N̂.
    fn spectra(&self) -> [&Self::Spectrum; 2];
    /// φ̂ and N̂, writable.
    fn spectra_mut(&mut self) -> [&mut Self::Spectrum; 2];
}

/// The states a device holds for the step: the current one, the one a step writes (the next),
/// and the history the scheme reads (φ̂ⁿ⁻¹, N̂ⁿ⁻¹).
pub struct States<S: DeviceState> {
    /// The current state.
    pub cur: S,
    /// The state the last attempt wrote.
    pub next: S,
    /// φ̂ⁿ⁻¹ and N̂ⁿ⁻¹, after the first accepted step of a two-level scheme.
    pub prev: Option<[S::Spectrum; 2]>,
}

impl<S: DeviceState> States<S> {
    /// The current and next states, no history.
    pub fn new(cur: S, next: S) -> Self {
        States {
            cur,
            next,
            prev: None,
        }
    }

    /// Make the next state current; with `keep_history`, the old current state's φ̂ and N̂
    /// become the history: swapped in, or the first time copied by `copy`.
    ///
    /// # Errors
    /// If `copy` fails.
    pub fn accept(
        &mut self,
        keep_history: bool,
        copy: impl Fn(&S::Spectrum) -> Result<S::Spectrum, DeviceFailure>,
    ) -> Result<(), DeviceFailure> {
        std::mem::swap(&mut self.cur, &mut self.next);
        if keep_history {
            match &mut self.prev {
                Some([h, n]) => {
                    let [old_h, old_n] = self.next.spectra_mut();
                    std::mem::swap(h, old_h);
                    std::mem::swap(n, old_n);
                }
                None => {
                    let [h, n] = self.next.spectra();
                    self.prev = Some([copy(h)?, copy(n)?]);
                }
            }
        }
        Ok(())
    }
}

/// The spectra a checkpoint holds, read in a device's layout ([`Passes::read_spectrum`]).
pub struct SavedSpectra<'s, 'c> {
    /// φ̂ of the current state.
    pub hat: CowArray<'s, Complex64, Ix3>,
    /// φ̂ⁿ⁻¹ and N̂ⁿ⁻¹, when the scheme reads them and the checkpoint holds them.
    pub history: Option<[CowArray<'s, Complex64, Ix3>; 2]>,
    /// The whole checkpoint, for what a device's flow keeps beside the spectra
    /// ([`Passes::flow_arrays`]).
    pub checkpoint: &'s Saved<'c>,
}

/// The passes of the spectral step on one device. The device holds its [`States`]; each pass
/// states the formula it implements.
pub trait Passes {
    /// The device's state.
    type State: DeviceState;
    /// The grid the device computes on.
    fn grid(&self) -> &Grid;
    /// The device's states.
    fn states(&self) -> &States<Self::State>;
    /// φ of the current state on the grid.
    fn phi(&self) -> &Array3<f64>;
    /// (A_PP, A_PQ, A_QQ) = Σ_k a (|P̂|², Re P̂Q̂*, |Q̂|²), a = (3/(2√2)) ε |k|² w, of the update
    /// `u` from the current state and `u.levels()` levels of history; nothing is stored. Under
    /// a Stokes flow split in σ, Q̂ holds the flow's advection per unit σ too
    /// ([`super::update::ValueFactors`]): σ then acts through the flow as well as through the
    /// diffusive channel.
    fn area_quadratic(&self, u: &Update) -> Result<[f64; 3], DeviceFailure>;
    /// φ̂^{n+1} = P̂ + σQ̂ of the update `u` (Q̂ as in [`Passes::area_quadratic`]) into the next
    /// state, with the inputs of its evaluation's inverse transforms (a copy of φ̂^{n+1} and
    /// −|k|²φ̂^{n+1}) written in the same pass; returns A(φ̂^{n+1}).
    fn write_update(&mut self, u: &Update, sigma: f64) -> Result<f64, DeviceFailure>;
    /// Set the k = 0 coefficient of the written φ̂^{n+1} (and of its copy) to `value`: with the
    /// unnormalised forward transforms X̂₀ = Σφ over the stored points.
    fn set_mean_mode(&mut self, value: f64) -> Result<(), DeviceFailure>;
    /// Evaluate the written next state at time `t`: φ, its measures, N̂ and the residual at
    /// multiplier `sigma`, given its area `area`. Returns max|φ^{n+1} − φ^n|, or that the state
    /// diverged (not finite, or |φ| too large).
    fn finish_next(&mut self, area: f64, t: f64, sigma: f64) -> Evaluation;
    /// Make the next state current ([`States::accept`]); with `keep_history`, the old current
    /// state becomes the history (φ̂ⁿ⁻¹, N̂ⁿ⁻¹).
    fn accept(&mut self, keep_history: bool) -> Result<(), DeviceFailure>;
    /// The current φ̂ and, when kept, the history (φ̂ⁿ⁻¹, N̂ⁿ⁻¹), as they are held (a device
    /// copies them to the host).
    fn spectra(&self) -> (SavedArray<'_>, Option<[SavedArray<'_>; 2]>);
    /// What the current state's flow keeps beside the spectra for a checkpoint: the
    /// inextensible membrane's tensions ([`super::tensions`]); none by default.
    fn flow_arrays(&self) -> Vec<(String, SavedArray<'_>)> {
        Vec::new()
    }
    /// The saved spectrum `name` in this device's layout.
    ///
    /// # Errors
    /// If it is missing, real or of another shape.
    fn read_spectrum<'s>(
        &self,
        saved: &'s Saved<'_>,
        name: &str,
    ) -> Result<CowArray<'s, Complex64, Ix3>, String>;
    /// Hold the `saved` spectra, and evaluate the current state at time `t` with multiplier
    /// `sigma`.
    ///
    /// # Errors
    /// A sentence if the device fails or the state is not finite.
    fn restore(&mut self, saved: SavedSpectra<'_, '_>, t: f64, sigma: f64) -> Result<(), String>;
    /// Short name for logs and tables.
    fn name(&self) -> &'static str;
    /// What the current state's Stokes flow measured, if the step has one.
    fn flow(&self) -> Option<FlowStats> {
        None
    }
    /// Hold the area-difference term `term` (ADE or the bilayer couple). A device without it
    /// fails (its scenes are refused before: [`crate::engines::supports`]).
    fn set_area_difference(&mut self, term: AreaDifference) -> Result<(), DeviceFailure> {
        let _ = term;
        Err(no_area_difference(self.name()))
    }
    /// The sums of the update `u` with the area-difference term ([`CoupleSums`]).
    fn couple_sums(&self, u: &Update) -> Result<CoupleSums, DeviceFailure> {
        let _ = u;
        Err(no_area_difference(self.name()))
    }
    /// Add λR̂ of the update `u` to the written next state (and its inverse inputs); returns
    /// its area.
    fn add_couple(&mut self, u: &Update, lambda: f64) -> Result<f64, DeviceFailure> {
        let _ = (u, lambda);
        Err(no_area_difference(self.name()))
    }
    /// Set the residual of the next state (`next`) or the current one at multipliers `sigma`
    /// and `lambda` (μ with λ δM/δφ).
    fn set_residual(&mut self, next: bool, sigma: f64, lambda: f64) -> Result<(), DeviceFailure> {
        let _ = (next, sigma, lambda);
        Err(no_area_difference(self.name()))
    }
}

/// The failure of a device asked for the area-difference term it does not have.
fn no_area_difference(device: &str) -> DeviceFailure {
    DeviceFailure(format!("the {device} engine has no area-difference term"))
}

/// Secant iterations of the area-difference multiplier before a step is rejected.
pub(crate) const COUPLE_ITERATIONS: usize = 12;

/// The area-difference multiplier's equation is held each step to this fraction of M0
/// (round-off of M's sum over the box): |M − M0| for the bilayer couple.
pub(crate) const COUPLE_TOL: f64 = 1e-12;

/// The spectral conserved flow on the device `P` (module documentation).
pub struct Stepper<P> {
    passes: P,
    eps: f64,
    /// M of the diffusive channel M∇²μ (1 but for the Stokes dynamics).
    mobility: f64,
    stabilizer: Stabilizer,
    scheme: Scheme,
    /// Controller settings with dt_min and dt_max resolved.
    adaptive: Option<AdaptiveSettings>,
    /// The step before the current one (the SBDF2 step ratio).
    dt_prev: f64,
    /// max|φ^{n+1} − φ^n| of the last attempt.
    max_change: f64,
    sigma: f64,
    area: AreaConstraint,
    /// V of the prepared initial field: the volume held, or V_init of the ramp.
    volume0: f64,
    /// The scene's time-dependent volume target, if any.
    volume_ramp: Option<VolumeRamp>,
    /// Whether C0 is ramped in time (F may then rise legitimately).
    c0_ramped: bool,
    /// Whether an imposed flow does work on the membrane (F may then rise legitimately).
    driven: bool,
    dt_next: Option<f64>,
    /// Reject steps that raise F_eff (see [`Stepper::check_constraints`]).
    energy_guard: bool,
    /// The area-difference term, if the scene has one.
    couple: Option<AreaDifference>,
    /// Its multiplier λ of the current state.
    lambda: f64,
}

impl<P: Passes> Stepper<P> {
    /// The step of `scene` on `passes`, which hold the evaluated initial state at t = 0, no
    /// area constraint yet; `c0_ramped` when the scene ramps C0 in time.
    pub fn with_passes(passes: P, scene: &Scene, c0_ramped: bool) -> Self {
        Stepper {
            volume0: passes.states().cur.measures().volume,
            passes,
            eps: scene.eps,
            mobility: scene.mobility(),
            stabilizer: scene.stabilizer(),
            scheme: scene.scheme,
            adaptive: control::adaptive_settings(scene),
            dt_prev: scene.dt,
            max_change: 0.0,
            sigma: 0.0,
            area: AreaConstraint::none(),
            volume_ramp: scene.volume,
            c0_ramped,
            driven: scene.stokes_flow().is_some_and(|f| f.shear_rate.is_some()),
            dt_next: None,
            energy_guard: true,
            couple: None,
            lambda: 0.0,
        }
    }

    /// The device's passes, writable (tests drive single passes).
    #[cfg(test)]
    pub(crate) fn passes_mut(&mut self) -> &mut P {
        &mut self.passes
    }

    /// F_sc, A, V of the current state.
    fn current(&self) -> Measures {
        self.passes.states().cur.measures()
    }

    /// `m` with the area-difference term added to its energy: F_ade (ADE), or λ(M − M0)
    /// with the step's multiplier `lambda` (the bilayer couple's Lagrangian, whose term
    /// vanishes once M is held): the functional the flow decreases.
    fn with_ade(&self, mut m: Measures, lambda: f64) -> Measures {
        if let Some(term) = &self.couple {
            m.energy += match term.law {
                Law::Elastic { .. } => term.energy(m.curvature),
                Law::Couple { .. } => lambda * (m.curvature - term.target()),
            };
        }
        m
    }

    /// The update of a step of `dt` from the current state: the scheme's coefficients after the
    /// steps the history holds.
    pub fn update(&self, dt: f64) -> Update {
        let history: &[f64] = if self.passes.states().prev.is_some() {
            &[self.dt_prev]
        } else {
            &[]
        };
        let c = (update::row(self.scheme).coefficients)(dt, history);
        Update::new(c, dt, self.eps, &self.stabilizer, self.mobility)
    }

    /// σ used in this step's update, or `None` if the projection has no real root (only the
    /// projection needs the area quadratic's pass).
    fn choose_sigma(&self, u: &Update) -> Result<Option<f64>, DeviceFailure> {
        Ok(match self.area.method {
            AreaMethod::None => Some(0.0),
            AreaMethod::Lagrangian | AreaMethod::Fixed => Some(self.sigma),
            AreaMethod::Projection => {
                let [app, apq, aqq] = self.passes.area_quadratic(u)?;
                nearest_root(aqq, apq, app - self.area.target, self.sigma)
            }
        })
    }

    /// σ and λ of this step's update with the area-difference term `term`, from its sums `s`
    /// ([`CoupleSums`]), with `miss` what the linearised M is taken to miss of M^{n+1} (0 at
    /// the first try): λ = l0 + l1 σ from
    ///
    /// ```text
    /// ADE, implicit:  λ = κ_λ (M_lin(σ, λ) + miss − M0)     lagged:  λ = κ_λ (Mⁿ − M0)
    /// bilayer couple: M_lin(σ, λ) + miss = M0,              M_lin = Mⁿ + c_P + σ c_Q + λ c_R
    /// ```
    ///
    /// then σ as [`Stepper::choose_sigma`] does, on the area of P̂ + l0R̂ + σ(Q̂ + l1R̂). `None` if
    /// the projection has no real root.
    fn choose_multipliers(
        &self,
        term: &AreaDifference,
        s: &CoupleSums,
        miss: f64,
    ) -> Option<(f64, f64)> {
        let [app, apq, aqq, apr, aqr, arr] = s.area;
        let [cp, cq, cr] = s.curvature;
        let (mn, m0) = (self.current().curvature, term.target());
        let (l0, l1) = match term.law {
            Law::Elastic { lagged: true, .. } => (term.multiplier(mn), 0.0),
            Law::Elastic { .. } => {
                let k = term.stiffness();
                let d = 1.0 - k * cr;
                (k * (mn + cp + miss - m0) / d, k * cq / d)
            }
            Law::Couple { .. } => ((m0 - miss - mn - cp) / cr, -cq / cr),
        };
        let sigma = match self.area.method {
            AreaMethod::None => 0.0,
            AreaMethod::Lagrangian | AreaMethod::Fixed => self.sigma,
            AreaMethod::Projection => {
                let pp = app + 2.0 * l0 * apr + l0 * l0 * arr;
                let pq = apq + l1 * apr + l0 * aqr + l0 * l1 * arr;
                let qq = aqq + 2.0 * l1 * aqr + l1 * l1 * arr;
                nearest_root(qq, pq, pp - self.area.target, self.sigma)?
            }
        };
        Some((sigma, l0 + l1 * sigma))
    }

    /// Write the update with multipliers σ, λ into the next state and evaluate it at `t_new`
    /// (σ_after its σ for the residual); max|φ^{n+1} − φ^n| into `max_change`.
    fn write_and_finish(
        &mut self,
        u: &Update,
        (sigma, lambda): (f64, f64),
        t_new: f64,
        sigma_after: f64,
    ) -> Result<Result<(), Rejection>, DeviceFailure> {
        let mut area = self.passes.write_update(u, sigma)?;
        if self.couple.is_some() {
            area = self.passes.add_couple(u, lambda)?;
        }
        self.set_volume(t_new)?;
        Ok(match self.passes.finish_next(area, t_new, sigma_after)? {
            Ok(change) => {
                self.max_change = change;
                Ok(())
            }
            Err(d) => Err(Rejection::Diverged(d)),
        })
    }

    /// The volume the state must have at time `t`: V0(t) of the ramp, else V of the prepared
    /// field.
    fn volume_target(&self, t: f64) -> f64 {
        match &self.volume_ramp {
            Some(ramp) => ramp.target(self.volume0, t),
            None => self.volume0,
        }
    }

    /// Under a volume ramp, set the k = 0 coefficient of the written update so that
    /// V(φ^{n+1}) = V0(`t`): with V = (N + Σφ) dv/2 over the N stored points (dv the cell
    /// volume times the mirror factor) and X̂₀ = Σφ, X̂₀ = 2 V0/dv − N. This adds one constant
    /// to φ^{n+1}; the area (weight |k|² = 0 there) and every other mode are untouched, so the
    /// area projection's σ stands. Without a ramp the conserved update keeps X̂₀ itself.
    fn set_volume(&mut self, t: f64) -> Result<(), DeviceFailure> {
        if self.volume_ramp.is_none() {
            return Ok(());
        }
        let grid = self.passes.grid();
        let dv = grid.cell_volume() * grid.mirror_factor();
        let mean_mode = 2.0 * self.volume_target(t) / dv - grid.len() as f64;
        self.passes.set_mean_mode(mean_mode)
    }

    /// Try one step of size `dt` from time `t`: on success the next state holds the result (its
    /// residual at the new multipliers) and the σ and λ of the state after it are returned; a
    /// rejection says why; `Err` if the device failed. With the area-difference term, λ is
    /// corrected until it holds with M^{n+1} itself, to [`COUPLE_TOL`] of M0: ADE's implicit
    /// λ = κ_λ(M^{n+1} − M0) and the bilayer couple's M^{n+1} = M0, each by secant iterations
    /// on M's linearisation error.
    fn attempt(&mut self, t: f64, dt: f64) -> Result<Result<(f64, f64), Rejection>, DeviceFailure> {
        let u = self.update(dt);
        let t_new = t + dt;
        let Some(term) = self.couple else {
            let Some(sigma) = self.choose_sigma(&u)? else {
                return Ok(Err(Rejection::NoRealRoot));
            };
            let sigma_after =
                control::sigma_after(&self.area, self.sigma, self.current().area, sigma);
            if let Err(r) = self.write_and_finish(&u, (sigma, 0.0), t_new, sigma_after)? {
                return Ok(Err(r));
            }
            return Ok(self
                .check_constraints((sigma, 0.0), t, t_new)
                .map(|()| (sigma_after, 0.0)));
        };
        let sums = self.passes.couple_sums(&u)?;
        let [cp, cq, cr] = sums.curvature;
        let (mn, m0) = (self.current().curvature, term.target());
        let m_lin = |(s, l): (f64, f64)| mn + cp + s * cq + l * cr;
        // What M_lin misses of M^{n+1}, found by the secant method on the equation λ must
        // satisfy (its first correction the chord's, slope −1).
        let (mut miss, mut last): (f64, Option<(f64, f64)>) = (0.0, None);
        let mut iterations = 0;
        let (multipliers, sigma_after) = loop {
            let Some(multipliers) = self.choose_multipliers(&term, &sums, miss) else {
                return Ok(Err(Rejection::NoRealRoot));
            };
            let sigma_after =
                control::sigma_after(&self.area, self.sigma, self.current().area, multipliers.0);
            if let Err(r) = self.write_and_finish(&u, multipliers, t_new, sigma_after)? {
                return Ok(Err(r));
            }
            let m_new = self.passes.states().next.measures().curvature;
            iterations += 1;
            // The equation λ must satisfy with M^{n+1}, as a residual in M's units: ADE's
            // M^{n+1} − M_lin − miss (λ = κ_λ(M^{n+1} − M0) once it vanishes), the couple's
            // M^{n+1} − M0; each falls by about the change of `miss`.
            let off = match term.law {
                Law::Elastic { lagged: true, .. } => 0.0,
                Law::Elastic { .. } => m_new - m_lin(multipliers) - miss,
                Law::Couple { .. } => m_new - m0,
            };
            if off.abs() <= COUPLE_TOL * m0.abs() {
                break (multipliers, sigma_after);
            }
            let slope = match last {
                Some((x0, r0)) if off != r0 => (off - r0) / (miss - x0),
                _ => -1.0,
            };
            last = Some((miss, off));
            miss -= off / slope;
            if iterations == COUPLE_ITERATIONS {
                return Ok(Err(Rejection::AreaDifferenceDrift(off.abs() / m0.abs())));
            }
        };
        let lambda_after = match term.law {
            Law::Elastic { .. } => term.multiplier(self.passes.states().next.measures().curvature),
            Law::Couple { .. } => multipliers.1,
        };
        self.passes.set_residual(true, sigma_after, lambda_after)?;
        Ok(self
            .check_constraints(multipliers, t, t_new)
            .map(|()| (sigma_after, lambda_after)))
    }

    /// Volume (and area under projection) held; F_eff (at the σ of the update) must not rise
    /// where the scheme guarantees that it falls: adaptive steps, and fixed SBDF1 steps (the
    /// stabilised first-order step is dissipative; SBDF2 is not guaranteed to be, and a ramped
    /// C0 or an imposed shear flow may raise F legitimately). Off when the energy guard is off
    /// (stability studies), and
    /// for a step that starts (time `t`) while a volume ramp runs: deflating does work on the
    /// vesicle, so F may rise; once V0 is constant the guard holds again. The volume is checked
    /// against its target at the step's end, `t_new`.
    fn check_constraints(
        &self,
        (sigma, lambda): (f64, f64),
        t: f64,
        t_new: f64,
    ) -> Result<(), Rejection> {
        let ramping = self.volume_ramp.is_some_and(|r| t < r.ramp_time);
        let guard = self.energy_guard
            && control::dissipative(self.adaptive.as_ref(), self.scheme)
            && !ramping
            && !self.c0_ramped
            && !self.driven;
        let states = self.passes.states();
        control::check_step(
            &self.with_ade(states.cur.measures(), lambda),
            &self.with_ade(states.next.measures(), lambda),
            sigma,
            self.volume_target(t_new),
            &self.area,
            guard,
        )
    }

    /// Make the next state current with multiplier `sigma`, keeping the old one as history
    /// when the scheme reads it.
    fn accept(&mut self, sigma: f64, dt: f64) -> Result<(), DeviceFailure> {
        self.passes.accept(update::row(self.scheme).levels > 1)?;
        self.dt_prev = dt;
        self.sigma = sigma;
        Ok(())
    }
}

impl<P: Passes> Engine for Stepper<P>
where
    Stepper<P>: Send,
{
    fn phi(&self) -> &Array3<f64> {
        self.passes.phi()
    }

    fn sigma(&self) -> f64 {
        self.sigma
    }

    fn measures(&self) -> Measures {
        self.current()
    }

    fn residual(&self) -> f64 {
        self.passes.states().cur.residual()
    }

    fn set_area(&mut self, area: AreaConstraint) {
        match area.method {
            AreaMethod::None => self.sigma = 0.0,
            AreaMethod::Fixed => self.sigma = area.sigma,
            _ => {}
        }
        self.area = area;
    }

    fn step(&mut self, t: f64, dt: f64) -> Result<StepReport, StepError> {
        let adaptive = self.adaptive.clone();
        let device = |f: DeviceFailure| StepError::Device(f.0);
        let ((sigma_after, lambda_after), dt, rejected) =
            control::with_retries(adaptive.as_ref(), dt, |dt| {
                self.attempt(t, dt).map_err(device)
            })?;
        let f_old = self.with_ade(self.current(), self.lambda).energy;
        self.accept(sigma_after, dt).map_err(device)?;
        self.lambda = lambda_after;
        let rate = self.max_change / dt;
        if let Some(a) = &self.adaptive {
            let f_new = self.with_ade(self.current(), self.lambda).energy;
            self.dt_next = Some(control::propose(a, dt, f_old, f_new));
        }
        Ok(StepReport { dt, rate, rejected })
    }

    fn next_dt(&self, dt: f64) -> f64 {
        self.dt_next.unwrap_or(dt)
    }

    fn lambda(&self) -> f64 {
        self.lambda
    }

    fn flow(&self) -> Option<FlowStats> {
        self.passes.flow()
    }

    fn area_difference(&self) -> Option<AreaDifference> {
        self.couple
    }

    fn set_area_difference(&mut self, term: AreaDifference) -> Result<(), String> {
        self.passes.set_area_difference(term).map_err(|f| f.0)?;
        self.couple = Some(term);
        self.lambda = term.multiplier(self.current().curvature);
        self.passes
            .set_residual(false, self.sigma, self.lambda)
            .map_err(|f| f.0)
    }

    fn guard_energy(&mut self, on: bool) {
        self.energy_guard = on;
    }

    fn name(&self) -> &'static str {
        self.passes.name()
    }

    fn save(&self) -> Saved<'_> {
        let (hat, history) = self.passes.spectra();
        let mut saved = Saved::default()
            .scalar("sigma", self.sigma)
            .scalar("volume0", self.volume0)
            .scalar("dt_prev", self.dt_prev)
            .scalar("dt_next", self.dt_next.unwrap_or(f64::NAN))
            .array("phi_hat", hat);
        if self.couple.is_some() {
            saved = saved.scalar("lambda", self.lambda);
        }
        if let Some([hat, nonlinear]) = history {
            saved = saved
                .array("prev_phi_hat", hat)
                .array("prev_nonlinear", nonlinear);
        }
        for (name, array) in self.passes.flow_arrays() {
            saved = saved.array(&name, array);
        }
        saved
    }

    fn restore(&mut self, saved: &mut Saved<'_>, t: f64) -> Result<(), String> {
        let hat = self.passes.read_spectrum(saved, "phi_hat")?;
        self.sigma = saved.get("sigma")?;
        self.volume0 = saved.get("volume0")?;
        self.dt_prev = saved.get("dt_prev")?;
        let dt_next = saved.get("dt_next")?;
        self.dt_next = (!dt_next.is_nan()).then_some(dt_next);
        let history = match self.passes.read_spectrum(saved, "prev_phi_hat") {
            Ok(h) if update::row(self.scheme).levels > 1 => {
                Some([h, self.passes.read_spectrum(saved, "prev_nonlinear")?])
            }
            _ => None,
        };
        self.passes.restore(
            SavedSpectra {
                hat,
                history,
                checkpoint: saved,
            },
            t,
            self.sigma,
        )?;
        if self.couple.is_some() {
            self.lambda = saved.get("lambda")?;
            self.passes
                .set_residual(false, self.sigma, self.lambda)
                .map_err(|f| f.0)?;
        }
        Ok(())
    }
}
