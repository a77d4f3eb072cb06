//! The [`Scene`] struct, its small enums and settings types, and the defaults they resolve to.

use super::c0::C0Spec;
use super::schedule::Schedule;
use super::shapes::Initial;
use serde::{Deserialize, Serialize};

/// One run, as read from a scene file (see README's scene-file reference).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free text: what the scene shows.
    #[serde(default)]
    pub description: String,
    /// Spatial dimension, 2 or 3.
    pub dim: usize,
    /// Grid points of the full box along each axis (`dim` entries).
    pub n: Vec<usize>,
    /// Grid spacing h.
    #[serde(default = "one")]
    pub h: f64,
    /// Interface width parameter ε.
    #[serde(default = "one")]
    pub eps: f64,
    /// Engine: Fourier semi-implicit (`spectral`) or the paper's finite differences (`fd`).
    #[serde(default)]
    pub method: Method,
    /// Time scheme of the spectral engine.
    #[serde(default)]
    pub scheme: Scheme,
    /// Time step (the first one when adaptive).
    pub dt: f64,
    /// Adaptive time stepping: `false`, `true` (default controller) or controller settings.
    #[serde(default)]
    pub adaptive: AdaptiveSpec,
    /// Stop at this simulated time.
    #[serde(default)]
    pub t_end: Option<f64>,
    /// Stop after this many steps.
    #[serde(default)]
    pub max_steps: Option<usize>,
    /// Stop when the stationarity residual RMS over the full box of μ − μ̄ (the same for every
    /// engine and box, free of Δt) falls below this. 1e-6 puts F_sc within about 1e-7 of its
    /// stationary value (README).
    #[serde(default)]
    pub stop_residual: Option<f64>,
    /// Stop, with a checkpoint, before this run (this invocation of `run` or `resume`) would
    /// spend more than this many minutes of wall time stepping: after the step whose end plus
    /// the longest step so far passes it. The run ends with `"stopped": "wall_time"` and exit 0,
    /// and `vesicle resume` continues it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_wall_minutes: Option<f64>,
    /// Initial shape, or `{"file": "phi.npy"}`.
    pub initial: Initial,
    /// Unconstrained steps (σ = 0) that build the tanh profile before A0 is taken.
    #[serde(default)]
    pub prepare_steps: usize,
    /// Spontaneous curvature c0: a number (uniform) or a field object.
    #[serde(default)]
    pub c0: C0Spec,
    /// Area constraint.
    #[serde(default)]
    pub area: AreaSpec,
    /// Time-dependent volume target (osmotic deflation or inflation); absent: the dynamics
    /// conserves the volume of the prepared initial field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<VolumeRamp>,
    /// Area-difference elasticity: `{"alpha": α, "da0": Δa0}` adds πα(Δa − Δa0)² to the
    /// reduced energy (3D only; docs/src/theory/ade.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ade: Option<AdeSpec>,
    /// The bilayer couple: `{"da": Δa}` holds the reduced integrated mean curvature Δa fixed
    /// with a second multiplier (3D only; spectral engine, conserved or relaxational dynamics).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bilayer_couple: Option<BilayerCoupleSpec>,
    /// Mirror planes through the box centre: e.g. `["x","y","z"]`, `[]`, or `"auto"`.
    #[serde(default)]
    pub symmetry: Symmetry,
    /// Walls across the named axes (e.g. `["y"]`), half a cell outside the box's first and last
    /// points: Neumann for φ, free-slip for the fluid; the imposed shear between them is plane
    /// Couette flow (docs/src/theory/flow.md).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<String>,
    /// Allow a Δt beyond the method's stability bound (stability studies).
    #[serde(default)]
    pub allow_unstable: bool,
    /// Worker threads (default: [`Scene::threads`]).
    #[serde(default)]
    pub threads: Option<usize>,
    /// `conserved` (∂φ/∂t = ∇²μ, the paper's dynamics) or `relaxational` (fastest route to the
    /// same stationary states).
    #[serde(default)]
    pub dynamics: Dynamics,
    /// The fluid of `"dynamics": "stokes"`: `{"viscosity": η, "mobility": M}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flow: Option<FlowSpec>,
    /// Discrete Laplacian of the spectral engine: `spectral` (−|k|², the default) or `fd` (the
    /// symbol −Σ (4/h²) sin²(k_a h/2) of the FD reference's (2d+1)-point stencil: the engine
    /// then integrates exactly the FD reference's semi-discrete equations, semi-implicitly).
    #[serde(default)]
    pub laplacian: Laplacian,
    /// L-BFGS memory (pairs kept) of the relaxational dynamics.
    #[serde(default = "default_memory")]
    pub lbfgs_memory: usize,
    /// Linear stabiliser of the spectral engine, S(k) = s2 |k|² + s4 ε² |k|⁴ (default: see
    /// [`Stabilizer::default_for`]).
    #[serde(default)]
    pub stabilizer: StabilizerSpec,
    /// Output schedule.
    #[serde(default)]
    pub output: OutputSpec,
    /// Where the spectral engine runs: the CPU (default) or an NVIDIA GPU (a binary built
    /// with the `gpu` feature).
    #[serde(default, skip_serializing_if = "Device::is_cpu")]
    pub device: Device,
}

/// `ade`: the area-difference elasticity's modulus ratio α = κ̄/κ and preferred Δa0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdeSpec {
    /// α = κ̄/κ ≥ 0.
    pub alpha: f64,
    /// Δa0, the preferred reduced area difference (1 on a sphere).
    pub da0: f64,
    /// How the spectral engine's conserved step treats the multiplier λ: `implicit` (default,
    /// solved with σ in the step) or `lagged` (λ of the current state; for stability studies).
    /// The FD reference always lags λ; L-BFGS minimises the energy itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multiplier: Option<AdeMultiplier>,
}

/// The treatment of the ADE multiplier λ in the conserved spectral step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AdeMultiplier {
    /// λ^{n+1} = λ(M^{n+1}), M linearised about φⁿ, solved with σ.
    #[default]
    Implicit,
    /// λⁿ from the current state.
    Lagged,
}

/// `bilayer_couple`: the reduced area difference Δa the run holds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BilayerCoupleSpec {
    /// Δa (1 on a sphere).
    pub da: f64,
}

/// Where the spectral engine runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Device {
    /// The CPU, on `threads` threads.
    #[default]
    Cpu,
    /// The first NVIDIA GPU (CUDA driver, cuFFT and NVRTC loaded at run time).
    Gpu,
}

impl Device {
    /// Whether this is the default, the CPU (not written into a scene's record).
    pub fn is_cpu(&self) -> bool {
        *self == Device::Cpu
    }
}

/// Rows of `timeseries.csv` the automatic `output.record_every` aims at.
pub const RECORD_ROWS: usize = 2000;

/// Computed points below which one thread is faster than two on this machine kind (the
/// 24³ eighth box of the 48³ prolate: 5.6 s on one thread, 9.1 s on two).
pub const SERIAL_BELOW: usize = 1 << 17;

pub(super) fn one() -> f64 {
    1.0
}

/// L-BFGS memory: 5 pairs. Iterations to the energy 1e-6 above F* on the full / eighth 48³
/// prolate vary erratically with the memory (3: 136 / 155, 5: 178 / 121, 8: 131 / 131,
/// 10: 130 / 130, 20: 136 / 107), and each pair costs two arrays read twice per iteration; no
/// memory was best in wall time on both.
fn default_memory() -> usize {
    5
}

/// Largest `lbfgs_memory` (the relaxational engine's coefficient recursion keeps its sums in
/// fixed arrays of this length).
pub const MAX_LBFGS_MEMORY: usize = 32;

/// Engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Fourier pseudo-spectral, semi-implicit.
    #[default]
    Spectral,
    /// Second-order finite differences, explicit Euler (the paper's method).
    Fd,
}

/// Time scheme of the spectral engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// First-order semi-implicit backward differentiation.
    #[default]
    Sbdf1,
    /// Second-order semi-implicit backward differentiation (variable step).
    Sbdf2,
}

/// Discrete Laplacian used by the spectral engine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Laplacian {
    /// Exact Fourier symbol −|k|².
    #[default]
    Spectral,
    /// Symbol of the second-order stencil, −Σ_a (4/h²) sin²(k_a h/2).
    Fd,
}

/// Dynamics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dynamics {
    /// ∂φ/∂t = ∇²μ.
    #[default]
    Conserved,
    /// Preconditioned L-BFGS on the constrained energy (same stationary states; `t` counts
    /// iterations × dt, not physical time).
    Relaxational,
    /// The membrane in a Stokes fluid (`flow`): ∂φ/∂t + u·∇φ = M∇²μ, η∇²u − ∇p + μ∇φ = 0,
    /// ∇·u = 0 on the periodic box (docs/src/theory/flow.md).
    Stokes,
}

/// `flow`: the Stokes dynamics' viscosity η and mobility M.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlowSpec {
    /// η > 0, the same inside and out.
    pub viscosity: f64,
    /// M > 0, the mobility of the diffusive channel M∇²μ.
    pub mobility: f64,
    /// γ̇: an imposed Kolmogorov shear flow u = (γ̇/k₀) sin(k₀y) x̂, k₀ = 2π/L_y (y from the box
    /// centre), the Stokes flow of the body force ηγ̇k₀ sin(k₀y) x̂: shear rate γ̇ at y = 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_rate: Option<f64>,
    /// η_in > 0, the viscosity inside the membrane (χ = (1 + φ)/2 > 1/2), when it differs from
    /// the outside's `viscosity`: η(x) = η_out + (η_in − η_out)χ (periodic boxes only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity_inside: Option<f64>,
    /// A locally inextensible membrane: a tension field, a Lagrange multiplier, holds the
    /// velocity surface incompressible across the interface (∇_s·u = 0) in place of one
    /// global tension (periodic boxes, equal viscosities; docs/src/theory/flow.md).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub inextensible: bool,
}

impl FlowSpec {
    /// η_in where it differs from η_out (`viscosity`): the flow then has unequal viscosities.
    pub fn contrast(&self) -> Option<f64> {
        self.viscosity_inside
            .filter(|&inside| inside != self.viscosity)
    }
}

/// `adaptive`: a flag or the controller's settings.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub enum AdaptiveSpec {
    /// `false` or `true` (the default controller).
    Flag(bool),
    /// Explicit settings.
    Settings(AdaptiveSettings),
}

impl Default for AdaptiveSpec {
    fn default() -> Self {
        AdaptiveSpec::Flag(false)
    }
}

impl AdaptiveSpec {
    /// The controller settings, or `None` for fixed steps.
    pub fn settings(&self) -> Option<AdaptiveSettings> {
        match self {
            AdaptiveSpec::Flag(false) => None,
            AdaptiveSpec::Flag(true) => Some(AdaptiveSettings::default()),
            AdaptiveSpec::Settings(s) => Some(s.clone()),
        }
    }
}

/// Energy-based step controller (Qiao, Zhang & Tang 2011):
/// `Δt = clamp(dt_max / √(1 + energy_alpha · (Ḟ/F)²), dt_min, growth · Δt_prev)`;
/// a step that raises F_eff beyond round-off or breaks a constraint is retried with
/// `shrink · Δt`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdaptiveSettings {
    /// Smallest step; a rejection below it stops the run (exit 3).
    pub dt_min: Option<f64>,
    /// Largest step.
    pub dt_max: Option<f64>,
    /// Largest ratio of consecutive steps (SBDF2 needs < 1 + √2).
    pub growth: f64,
    /// Factor applied to Δt after a rejected step.
    pub shrink: f64,
    /// Sensitivity α of the energy-based rule to the relative energy rate.
    pub energy_alpha: f64,
}

impl Default for AdaptiveSettings {
    fn default() -> Self {
        AdaptiveSettings {
            dt_min: None,
            dt_max: None,
            growth: 1.5,
            shrink: 0.5,
            energy_alpha: 1e6,
        }
    }
}

/// Area constraint method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AreaMethod {
    /// σ^{n+1} from the quadratic A(φ^{n+1}(σ)) = A0: the area is held to round-off.
    Projection,
    /// The paper's update σ^{n+1} = σ^n + α (A^n − A0).
    Lagrangian,
    /// No area constraint (σ = 0).
    None,
    /// No area constraint, σ held at `area.sigma` (a membrane at fixed tension).
    Fixed,
}

/// `area`: `{"method": ..., "alpha": α, "target": A0}`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaSpec {
    /// Default: `projection` for the spectral engine, `lagrangian` for FD.
    #[serde(default)]
    pub method: Option<AreaMethod>,
    /// Step size α of the Lagrangian update (default 1e-3).
    #[serde(default)]
    pub alpha: Option<f64>,
    /// Target area A0 (default: area of the prepared initial field).
    #[serde(default)]
    pub target: Option<f64>,
    /// The tension σ of the `fixed` method.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
}

/// `volume`: `{"final_fraction": f, "ramp_time": T}`, the target
/// V0(t) = V_init (1 + (f − 1) min(t/T, 1)), V_init the volume V = ∫(1 + φ)/2 of the prepared
/// initial field.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeRamp {
    /// V0 at and after `ramp_time`, as a fraction of V_init.
    pub final_fraction: f64,
    /// Simulated time over which V0 moves linearly from V_init to `final_fraction` · V_init.
    pub ramp_time: f64,
}

impl VolumeRamp {
    /// V0(t) = `initial` · (1 + (f − 1) min(t/T, 1)).
    pub fn target(&self, initial: f64, t: f64) -> f64 {
        initial * (1.0 + (self.final_fraction - 1.0) * (t / self.ramp_time).min(1.0))
    }
}

/// `symmetry`: declared mirror axes or automatic detection.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Symmetry {
    /// Mirror axes among "x", "y", "z".
    Axes(Vec<String>),
    /// `"auto"`: every axis about which the initial field and c0 are even.
    Auto(AutoTag),
}

/// The literal `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoTag {
    /// Detect mirror planes.
    Auto,
}

impl Default for Symmetry {
    fn default() -> Self {
        Symmetry::Axes(Vec::new())
    }
}

/// Spectral stabiliser S(k) = s2 |k|² + s4 ε² |k|⁴, treated implicitly and added explicitly.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stabilizer {
    /// Coefficient of |k|².
    pub s2: f64,
    /// Coefficient of ε²|k|⁴.
    pub s4: f64,
}

/// `stabilizer` as written: either coefficient may be left to the scheme's default.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StabilizerSpec {
    /// Coefficient of |k|².
    #[serde(default)]
    pub s2: Option<f64>,
    /// Coefficient of ε²|k|⁴.
    #[serde(default)]
    pub s4: Option<f64>,
}

impl Stabilizer {
    /// The default of each scheme, measured with `vesicle study stability` (base scene
    /// runs/stability2d.json, 200 steps): SBDF1 with S = 4k² + 4ε²k⁴ (half the bulk
    /// linearisation's lower-order part, the least S that makes it unconditionally stable) never
    /// raised F up to Δt = 5.6; SBDF2 with that S raised F from Δt = 0.1 on, with
    /// S = 8k² + 8ε²k⁴ not up to Δt = 10.
    pub fn default_for(scheme: Scheme) -> Self {
        match scheme {
            Scheme::Sbdf1 => Stabilizer { s2: 4.0, s4: 4.0 },
            Scheme::Sbdf2 => Stabilizer { s2: 8.0, s4: 8.0 },
        }
    }
}

/// `output`: what is written and how often. Each output has a [`Schedule`] key (`records`,
/// `snapshots`, `checkpoints`) and the older step-count keys, which stay valid; a scene gives one
/// form or the other for each output.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// A `timeseries.csv` row every this many steps (the first and last are always written).
    /// Absent: automatic, about 2 000 rows per run ([`Scene::record_every`]): with N the
    /// smaller of `max_steps` and, for fixed steps, ⌈t_end/dt⌉, every max(1, ⌈N/2000⌉) steps;
    /// every step when nothing bounds the number of steps (no `max_steps`, and no `t_end` or
    /// adaptive steps: a relaxation stopped by `stop_residual` alone).
    pub record_every: Option<usize>,
    /// When a `timeseries.csv` row is written (instead of `record_every`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub records: Option<Schedule>,
    /// Snapshots (`.npy`, `.vti`, `.png`) of the initial state (step 0) and every this many steps
    /// after it; 0 writes only the final state.
    pub snapshot_every: usize,
    /// When snapshots are written (instead of `snapshot_every`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub snapshots: Option<Schedule>,
    /// Write VTK ImageData `.vti` snapshots.
    pub vti: bool,
    /// Write PNG images of the mid-plane slices and charts of the time series.
    pub png: bool,
    /// A checkpoint (`checkpoint.bin`, for `vesicle resume`) every this many steps; 0: only by
    /// wall time and at the end.
    pub checkpoint_every: usize,
    /// A checkpoint every this many minutes of wall time (and always at the end); default
    /// [`CHECKPOINT_MINUTES`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checkpoint_minutes: Option<f64>,
    /// When checkpoints are written (instead of `checkpoint_every` and `checkpoint_minutes`);
    /// always also at the end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checkpoints: Option<Schedule>,
}

/// Minutes of wall time between two checkpoints when the scene says nothing.
pub const CHECKPOINT_MINUTES: f64 = 10.0;

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            record_every: None,
            records: None,
            snapshot_every: 0,
            snapshots: None,
            vti: true,
            png: true,
            checkpoint_every: 0,
            checkpoint_minutes: None,
            checkpoints: None,
        }
    }
}

impl Scene {
    /// The area method after defaults: projection for spectral, Lagrangian for FD.
    pub fn area_method(&self) -> AreaMethod {
        self.area.method.unwrap_or(match self.method {
            Method::Spectral => AreaMethod::Projection,
            Method::Fd => AreaMethod::Lagrangian,
        })
    }

    /// The stabiliser after defaults ([`Stabilizer::default_for`] the scheme).
    pub fn stabilizer(&self) -> Stabilizer {
        let d = Stabilizer::default_for(self.scheme);
        Stabilizer {
            s2: self.stabilizer.s2.unwrap_or(d.s2),
            s4: self.stabilizer.s4.unwrap_or(d.s4),
        }
    }

    /// α of the Lagrangian area update (default 1e-3).
    pub fn alpha(&self) -> f64 {
        self.area.alpha.unwrap_or(1e-3)
    }

    /// Whether each scene axis is bounded by walls.
    pub fn wall_flags(&self) -> Vec<bool> {
        (0..self.dim)
            .map(|a| {
                self.walls
                    .iter()
                    .any(|n| axis_index(n, self.dim) == Some(a))
            })
            .collect()
    }

    /// The flow of the Stokes dynamics, if the scene runs it.
    pub fn stokes_flow(&self) -> Option<FlowSpec> {
        self.flow.filter(|_| self.dynamics == Dynamics::Stokes)
    }

    /// The mobility M of the step's diffusive channel: the flow's, else 1 (∂φ/∂t = ∇²μ).
    pub fn mobility(&self) -> f64 {
        self.stokes_flow().map_or(1.0, |f| f.mobility)
    }

    /// Steps between two `timeseries.csv` rows: `output.record_every` if given, else
    /// ⌈N / [`RECORD_ROWS`]⌉ (at least 1) with N the bound on the number of steps: the smaller
    /// of `max_steps` and, for fixed steps, ⌈t_end/dt⌉ (within the stop rule's 1e-6 of a step).
    /// Nothing bounds N (adaptive steps without `max_steps`, or `stop_residual` alone): 1.
    pub fn record_every(&self) -> usize {
        if let Some(k) = self.output.record_every {
            return k;
        }
        let by_time = match (self.t_end, self.adaptive.settings()) {
            (Some(t_end), None) => Some((t_end / self.dt - 1e-6).ceil().max(1.0) as usize),
            _ => None,
        };
        match (self.max_steps, by_time) {
            (None, None) => 1,
            (m, t) => {
                let n = m.unwrap_or(usize::MAX).min(t.unwrap_or(usize::MAX));
                n.div_ceil(RECORD_ROWS).max(1)
            }
        }
    }

    /// Worker threads: `threads` if given, else one for a grid of fewer than [`SERIAL_BELOW`]
    /// computed points (the box's points halved for each declared mirror plane) and all cores
    /// otherwise.
    pub fn threads(&self) -> usize {
        if let Some(k) = self.threads {
            return k;
        }
        let mirrored = match &self.symmetry {
            Symmetry::Axes(a) => a.len() as u32,
            Symmetry::Auto(_) => 0,
        };
        let points = self.n.iter().fold(1usize, |p, &m| p.saturating_mul(m)) >> mirrored;
        if points < SERIAL_BELOW {
            1
        } else {
            crate::cpu::cores()
        }
    }

    /// When a `timeseries.csv` row is written: `output.records`, else every
    /// [`Scene::record_every`] steps.
    pub fn records(&self) -> Schedule {
        self.output
            .records
            .unwrap_or_else(|| Schedule::steps(self.record_every()))
    }

    /// When a snapshot is written: `output.snapshots`, else every `output.snapshot_every` steps
    /// (0: never).
    pub fn snapshots(&self) -> Schedule {
        match (self.output.snapshots, self.output.snapshot_every) {
            (Some(s), _) => s,
            (None, 0) => Schedule::NEVER,
            (None, k) => Schedule::steps(k),
        }
    }

    /// When a checkpoint is written (besides at the end): `output.checkpoints`, else every
    /// `output.checkpoint_every` steps (0: not by count) and every `output.checkpoint_minutes`
    /// (default [`CHECKPOINT_MINUTES`]).
    pub fn checkpoints(&self) -> Schedule {
        let o = &self.output;
        o.checkpoints.unwrap_or(Schedule {
            every_steps: (o.checkpoint_every > 0).then_some(o.checkpoint_every),
            every_time: None,
            every_minutes: Some(o.checkpoint_minutes.unwrap_or(CHECKPOINT_MINUTES)),
        })
    }

    /// The scene as JSON without the keys its method or dynamics ignores (which a scene file
    /// may not set), so that it reads back through [`super::from_value`]; what `summary.json`
    /// stores under `"spec"`.
    pub fn resolved_value(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(self).expect("a scene serialises");
        super::ignored::drop_ignored(&mut v, self);
        v
    }
}

/// Index of the scene axis named `name` ("x", "y", "z").
pub fn axis_index(name: &str, dim: usize) -> Option<usize> {
    let i = match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => return None,
    };
    (i < dim).then_some(i)
}

#[cfg(test)]
mod tests {
    use crate::problem::config::from_value;
    use serde_json::{json, Value};

    /// `record_every()` of a 2D scene with `extra` merged in.
    fn record_every(extra: Value) -> usize {
        let mut v = json!({
            "dim": 2, "n": [32, 32], "dt": 0.001,
            "initial": {"shape": "sphere", "radius": 6.0}
        });
        v.as_object_mut()
            .unwrap()
            .extend(extra.as_object().unwrap().clone());
        from_value(v).unwrap().record_every()
    }

    #[test]
    fn record_every_aims_at_2000_rows() {
        for (extra, expect) in [
            // explicit wins
            (
                json!({"max_steps": 1_000_000, "output": {"record_every": 7}}),
                7,
            ),
            // max_steps alone
            (json!({"max_steps": 2000}), 1),
            (json!({"max_steps": 2001}), 2),
            (json!({"max_steps": 4000}), 2),
            (json!({"max_steps": 4001}), 3),
            (
                json!({"max_steps": 40_000, "adaptive": {"dt_max": 50.0}}),
                20,
            ),
            // fixed steps to t_end: ceil(t_end/dt), without round-off adding a step
            (json!({"t_end": 4.0}), 2),
            (json!({"t_end": 4.000_001}), 3),
            (json!({"t_end": 120.0, "dt": 4e-4, "method": "fd"}), 150),
            (json!({"t_end": 0.0012, "dt": 4e-4, "method": "fd"}), 1),
            // the smaller bound
            (
                json!({"t_end": 120.0, "dt": 4e-4, "method": "fd", "max_steps": 10_000}),
                5,
            ),
            (json!({"t_end": 10.0, "max_steps": 1_000_000}), 5),
            // nothing bounds the steps: every step
            (json!({"stop_residual": 1e-9}), 1),
            (json!({"t_end": 1e6, "adaptive": true}), 1),
            (
                json!({"t_end": 1e6, "adaptive": true, "max_steps": 6000}),
                3,
            ),
        ] {
            assert_eq!(record_every(extra.clone()), expect, "{extra}");
        }
    }
}
