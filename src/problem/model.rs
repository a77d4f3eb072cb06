//! The phase-field model of docs/src/theory/model.md (with the paper's two sign slips corrected):
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

use crate::analysis::levelset::reduced_volume;
use crate::error::{Error, Result};
use crate::problem::config::{axis_index, C0Ball, C0Band, C0Cap, C0Field, C0File, C0Spec};
use crate::problem::grid::Grid;
use ndarray::Array3;

/// 3/(2√2): the area density prefactor, a = (3/(2√2)) ε |∇φ|².
pub const AREA_PREFACTOR: f64 = 1.060_660_171_779_821_2;

/// 3/√2: the tension term's prefactor in μ, (3/√2) ε σ ∇²φ (twice [`AREA_PREFACTOR`], the
/// derivative of A's density).
pub const TENSION_FACTOR: f64 = 3.0 / std::f64::consts::SQRT_2;

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
    /// Build εC0 = ε c0/√2 on the grid from the scene's `c0` (the formulas of each kind are in
    /// [`crate::problem::config::C0Field`]'s module). A `file` field holds the full box and is restricted
    /// to a reduced grid.
    ///
    /// # Errors
    /// `Error::Config` on field `c0.file` if the file cannot be read, is not float64 C order of
    /// shape `n`, or holds a non-finite value.
    pub fn new(spec: &C0Spec, grid: &Grid, eps: f64) -> Result<Self> {
        let k = eps / std::f64::consts::SQRT_2;
        Ok(match spec {
            C0Spec::Uniform(c) if *c == 0.0 => C0 {
                shape: SpontaneousCurvature::Zero,
                ramp_time: None,
            },
            C0Spec::Uniform(c) => C0 {
                shape: SpontaneousCurvature::Uniform(k * c),
                ramp_time: None,
            },
            C0Spec::Field(f) => C0 {
                shape: match f {
                    C0Field::Ball(b) => ball(b, grid, k),
                    C0Field::Cap(c) => SpontaneousCurvature::Field(cap(c, grid, k)),
                    C0Field::Band(b) => SpontaneousCurvature::Field(band(b, grid, k)),
                    C0Field::File(f) => SpontaneousCurvature::Field(from_file(f, grid, k)?),
                },
                ramp_time: f.ramp_time(),
            },
        })
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

/// The tanh blend of the patches: outside + (inside − outside)(1 − tanh(d/w))/2, with d the
/// signed distance to the patch edge (negative inside).
#[inline]
fn blend(inside: f64, outside: f64, d: f64, width: f64) -> f64 {
    outside + (inside - outside) * 0.5 * (1.0 - (d / width).tanh())
}

/// `p − c` (c absent: the box centre, 0).
fn offset(p: [f64; 3], center: Option<&[f64]>) -> [f64; 3] {
    let mut q = p;
    for (qi, ci) in q.iter_mut().zip(center.unwrap_or(&[])) {
        *qi -= ci;
    }
    q
}

/// The scene axis named `axis` (default: the last one).
fn axis_or_last(axis: &Option<String>, dim: usize) -> usize {
    axis.as_deref()
        .and_then(|a| axis_index(a, dim))
        .unwrap_or(dim - 1)
}

/// Ball: εC0(x) = k · blend(d = |x − c| − R); no radius: uniform k · inside.
fn ball(f: &C0Ball, grid: &Grid, k: f64) -> SpontaneousCurvature {
    let Some(radius) = f.radius else {
        return SpontaneousCurvature::Uniform(k * f.inside);
    };
    let field = grid.field_from(|p| {
        let q = offset(p, f.center.as_deref());
        let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        k * blend(f.inside, f.outside, r - radius, f.width)
    });
    SpontaneousCurvature::Field(field)
}

/// Cap: q = x − c, ζ = s q_a, ρ = |q|, ϑ = atan2(√(ρ² − ζ²), ζ); d = ρ (ϑ − θ_rim).
fn cap(f: &C0Cap, grid: &Grid, k: f64) -> Array3<f64> {
    let a = axis_or_last(&f.axis, grid.dim);
    let s = f.pole.sign();
    let rim = f.angle.to_radians();
    grid.field_from(|p| {
        let q = offset(p, f.center.as_deref());
        let zeta = s * q[a];
        let across: f64 = (0..3).filter(|&i| i != a).map(|i| q[i] * q[i]).sum();
        let rho = (across + zeta * zeta).sqrt();
        let theta = across.sqrt().atan2(zeta);
        k * blend(f.inside, f.outside, rho * (theta - rim), f.width)
    })
}

/// Band: ζ = (x − c)_a; d = |ζ| − b.
fn band(f: &C0Band, grid: &Grid, k: f64) -> Array3<f64> {
    let a = axis_or_last(&f.axis, grid.dim);
    grid.field_from(|p| {
        let zeta = offset(p, f.center.as_deref())[a];
        k * blend(f.inside, f.outside, zeta.abs() - f.half_width, f.width)
    })
}

/// File: k · c0 read on the full box, restricted to the computed grid.
fn from_file(f: &C0File, grid: &Grid, k: f64) -> Result<Array3<f64>> {
    let full = grid.full_shape();
    let n = &full[3 - grid.dim..];
    let c0 =
        crate::npy::read_npy(&f.file, n).map_err(|e| Error::config("c0.file", e.to_string()))?;
    if let Some(bad) = c0.iter().find(|x| !x.is_finite()) {
        return Err(Error::config(
            "c0.file",
            format!("{} holds a non-finite value ({bad})", f.file.display()),
        ));
    }
    Ok(grid.restrict(&c0).mapv(|c| k * c))
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

/// f(φ) at C0 = 0 without the C0 term: φ(φ² − 1), the value of [`bulk`]`(φ, 0)`.
#[inline(always)]
pub fn bulk_at_zero_c0(phi: f64) -> f64 {
    phi * (phi * phi - 1.0)
}

/// f'(φ) at C0 = 0 without the C0 term: 3φ² − 1, the value of [`bulk_derivative`]`(φ, 0)`.
#[inline(always)]
pub fn bulk_derivative_at_zero_c0(phi: f64) -> f64 {
    3.0 * phi * phi - 1.0
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
    /// M = ∫ Φ₀(1 − φ²), the integrated mean curvature's functional
    /// ([`crate::problem::area_difference`]); 0 unless the scene has an area-difference term.
    pub curvature: f64,
}

/// Reduced volume and reduced energy (docs/src/theory/model.md, sharp-interface normalisation).
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
        let volume = reduced_volume(self.area, self.volume, dim);
        if dim == 3 {
            Reduced {
                volume,
                energy: 3.0 * self.energy / (32.0 * SQRT_2 * PI * eps.powi(3)),
            }
        } else {
            let r0 = self.area / (2.0 * PI);
            Reduced {
                volume,
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

#[cfg(test)]
mod tests {
    use super::{
        bulk, bulk_at_zero_c0, bulk_derivative, bulk_derivative_at_zero_c0, SpontaneousCurvature,
        C0,
    };
    use crate::problem::config::C0Spec;
    use crate::problem::grid::Grid;
    use serde_json::json;

    fn field(spec: serde_json::Value, n: &[usize]) -> (Grid, ndarray::Array3<f64>) {
        let spec: C0Spec = serde_json::from_value(spec).unwrap();
        // The resolved JSON reads back as the same field (a resumed run rebuilds c0 from it).
        let again: C0Spec = serde_json::from_value(serde_json::to_value(&spec).unwrap()).unwrap();
        let grid = Grid::new(n, 1.0, &vec![false; n.len()]);
        let eps = std::f64::consts::SQRT_2; // εC0 = c0
        let get = |s: &C0Spec| match C0::new(s, &grid, eps).unwrap().shape {
            SpontaneousCurvature::Field(f) => f,
            other => panic!("{other:?}"),
        };
        let f = get(&spec);
        assert_eq!(f, get(&again));
        (grid, f)
    }

    /// Dropping the C0 terms at C0 = 0 changes no value: f and f' equal those of the full
    /// formulas at εC0 = 0 exactly, across the profile and beyond it.
    #[test]
    fn bulk_without_c0_terms_is_bulk_at_zero_c0() {
        for i in -400..=400 {
            let phi = i as f64 / 137.0;
            assert_eq!(bulk_at_zero_c0(phi), bulk(phi, 0.0), "f at φ = {phi}");
            assert_eq!(
                bulk_derivative_at_zero_c0(phi),
                bulk_derivative(phi, 0.0),
                "f' at φ = {phi}"
            );
        }
    }

    /// The cap: inside at its pole, outside at the opposite pole, the mean on the rim at the
    /// arc length given by the formula.
    #[test]
    fn cap_follows_its_formula() {
        let spec = json!({"kind": "cap", "inside": 1.0, "outside": -1.0, "angle": 90.0,
                          "axis": "z", "pole": "-", "width": 0.5});
        let (grid, f) = field(spec, &[8, 8, 40]);
        let z = grid.coords(2);
        // points on the z axis: x = y = ±0.5 (cell centres), polar angle ≈ 0 or π from −z
        let (lo, hi) = (f[[4, 4, 0]], f[[4, 4, 39]]);
        assert!(
            (lo - 1.0).abs() < 1e-6 && (hi + 1.0).abs() < 1e-6,
            "{lo} {hi}"
        );
        // a point on the rim plane z = 0 is not a grid point; check the formula at z = z[20]
        let (x, y) = (0.5, 0.5);
        let q: [f64; 3] = [x, y, z[20]];
        let rho = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        let theta = (q[0] * q[0] + q[1] * q[1]).sqrt().atan2(-q[2]);
        let d = rho * (theta - std::f64::consts::FRAC_PI_2);
        let expected = -1.0 + 2.0 * 0.5 * (1.0 - (d / 0.5).tanh());
        assert!((f[[4, 4, 20]] - expected).abs() < 1e-12);
    }

    /// The band: inside across |ζ| < b, outside beyond, the mean on its edges.
    #[test]
    fn band_follows_its_formula() {
        let spec = json!({"kind": "band", "inside": 0.3, "outside": 0.1, "axis": "x",
                          "center": [2.0, 0.0], "half_width": 4.5, "width": 1.0});
        let (grid, f) = field(spec, &[32, 8]);
        for (i, x) in grid.coords(1).iter().enumerate() {
            let d = (x - 2.0).abs() - 4.5;
            let expected = 0.1 + 0.2 * 0.5 * (1.0 - d.tanh());
            assert!((f[[0, i, 3]] - expected).abs() < 1e-12, "x = {x}");
        }
    }
}
