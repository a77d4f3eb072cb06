//! The phase-field model of DESIGN.md §1 (with the paper's two sign slips corrected):
//!
//! ```text
//! f(φ)  = (φ + εC0)(φ² − 1),          f'(φ) = 3φ² − 1 + 2εC0 φ
//! Φ     = f(φ) − ε²∇²φ,               F_sc = ∫ Φ² dx
//! A     = (3/(2√2)) ε ∫ |∇φ|² dx,     V = ∫ (1 + φ)/2 dx
//! μ     = 2[f'(φ)Φ − ε²∇²Φ] − (3/√2) ε σ ∇²φ,    ∂φ/∂t = ∇²μ
//! ```
//!
//! C0 = c0/√2 with c0 the membrane's spontaneous curvature; a sphere of radius R then has the
//! reduced bending energy e = (1 − c0 R/2)².

use crate::config::{C0Field, C0Spec};
use crate::grid::Grid;
use ndarray::Array3;

/// 3/(2√2): the area density prefactor, a = (3/(2√2)) ε |∇φ|².
pub const AREA_PREFACTOR: f64 = 1.060_660_171_779_821_2;

/// The spontaneous-curvature field, stored as εC0 (the combination the model uses).
#[derive(Clone, Debug)]
pub enum SpontaneousCurvature {
    /// c0 = 0 everywhere: the C0 terms are skipped.
    Zero,
    /// Uniform εC0, scaled by the ramp.
    Uniform(f64),
    /// εC0(x) on the computed box, scaled by the ramp.
    Field(Array3<f64>),
}

/// εC0(x, t) = ramp(t) · εC0(x).
#[derive(Clone, Debug)]
pub struct C0 {
    /// Spatial part.
    pub shape: SpontaneousCurvature,
    /// Ramp time: full strength from t = ramp_time on (None: always full).
    pub ramp_time: Option<f64>,
}

impl C0 {
    /// Build εC0 = ε c0/√2 on the grid from the scene's `c0`.
    pub fn new(spec: &C0Spec, grid: &Grid, eps: f64) -> Self {
        let k = eps / std::f64::consts::SQRT_2;
        match spec {
            C0Spec::Uniform(c) if *c == 0.0 => C0 {
                shape: SpontaneousCurvature::Zero,
                ramp_time: None,
            },
            C0Spec::Uniform(c) => C0 {
                shape: SpontaneousCurvature::Uniform(k * c),
                ramp_time: None,
            },
            C0Spec::Field(f) => C0 {
                shape: patch(f, grid, k),
                ramp_time: f.ramp_time,
            },
        }
    }

    /// Ramp factor r(t) = min(t/ramp_time, 1).
    pub fn ramp(&self, t: f64) -> f64 {
        self.ramp_time.map_or(1.0, |tr| (t / tr).clamp(0.0, 1.0))
    }

    /// True when the C0 terms vanish identically.
    pub fn is_zero(&self) -> bool {
        matches!(self.shape, SpontaneousCurvature::Zero)
    }

    /// True when εC0 changes with time (the energy is then not a Lyapunov function).
    pub fn is_ramped(&self) -> bool {
        self.ramp_time.is_some() && !self.is_zero()
    }

    /// The two forms of εC0 at ramp factor `r`: the uniform value (0 when c0 = 0 or a field
    /// is given) and the unramped field (multiply by `r`).
    pub fn parts(&self, r: f64) -> (f64, Option<&[f64]>) {
        match &self.shape {
            SpontaneousCurvature::Zero => (0.0, None),
            SpontaneousCurvature::Uniform(v) => (r * v, None),
            SpontaneousCurvature::Field(a) => (0.0, Some(a.as_slice().expect("standard layout"))),
        }
    }
}

/// εC0(x) = k [outside + (inside − outside)(1 − tanh((|x − c| − R)/w))/2], k = ε/√2.
fn patch(f: &C0Field, grid: &Grid, k: f64) -> SpontaneousCurvature {
    let Some(radius) = f.radius else {
        return SpontaneousCurvature::Uniform(k * f.inside);
    };
    let center = f.center.clone().unwrap_or_else(|| vec![0.0; grid.dim]);
    let field = grid.field_from(|p| {
        let r2: f64 = center.iter().zip(p).map(|(c, x)| (x - c).powi(2)).sum();
        let s = 0.5 * (1.0 - ((r2.sqrt() - radius) / f.width).tanh());
        k * (f.outside + (f.inside - f.outside) * s)
    });
    SpontaneousCurvature::Field(field)
}

/// f(φ) = (φ + εC0)(φ² − 1).
#[inline(always)]
pub fn bulk(phi: f64, ec0: f64) -> f64 {
    (phi + ec0) * (phi * phi - 1.0)
}

/// f'(φ) = 3φ² − 1 + 2εC0 φ.
#[inline(always)]
pub fn bulk_derivative(phi: f64, ec0: f64) -> f64 {
    3.0 * phi * phi - 1.0 + 2.0 * ec0 * phi
}

/// The integrals that define a state: F_sc, A, V (full-box values).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Measures {
    /// F_sc = ∫ Φ².
    pub energy: f64,
    /// A = (3/(2√2)) ε ∫ |∇φ|².
    pub area: f64,
    /// V = ∫ (1 + φ)/2.
    pub volume: f64,
}

/// Reduced volume and reduced energy (DESIGN.md §1, sharp-interface normalisation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reduced {
    /// 3D: v = V / ((4π/3) R0³), R0 = √(A/4π). 2D: v = 4πV/L².
    pub volume: f64,
    /// 3D: e = 3F/(32√2 π ε³). 2D: e = F R0 / ((2√2/3) ε³ 2π), R0 = L/2π.
    pub energy: f64,
}

impl Measures {
    /// Reduced quantities for a scene of dimension `dim` and width `eps`.
    pub fn reduced(&self, dim: usize, eps: f64) -> Reduced {
        use std::f64::consts::{PI, SQRT_2};
        if dim == 3 {
            let r0 = (self.area / (4.0 * PI)).sqrt();
            Reduced {
                volume: self.volume / (4.0 / 3.0 * PI * r0.powi(3)),
                energy: 3.0 * self.energy / (32.0 * SQRT_2 * PI * eps.powi(3)),
            }
        } else {
            let r0 = self.area / (2.0 * PI);
            Reduced {
                volume: 4.0 * PI * self.volume / (self.area * self.area),
                energy: self.energy * r0 / (2.0 * SQRT_2 / 3.0 * eps.powi(3) * 2.0 * PI),
            }
        }
    }
}

/// max|a − b| over two fields of the same shape (views allowed).
pub fn max_abs_diff<'a>(
    a: impl IntoIterator<Item = &'a f64>,
    b: impl IntoIterator<Item = &'a f64>,
) -> f64 {
    a.into_iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// Largest |φ| a state may reach before the run counts as blown up.
pub const PHI_BLOWUP: f64 = 5.0;

/// A state has diverged when max|φ| exceeds [`PHI_BLOWUP`] (or is NaN) or F is not finite.
pub fn diverged(max_abs_phi: f64, energy: f64) -> bool {
    max_abs_phi.is_nan() || max_abs_phi > PHI_BLOWUP || !energy.is_finite()
}
