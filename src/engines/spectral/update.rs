//! The semi-implicit SBDF update at one wavenumber, shared by every device that runs the spectral
//! step (the CPU sweeps, and the GPU kernels, which receive [`Update`] as it is laid out here).
//!
//! In Fourier space the conserved flow reads
//!
//! ```text
//! ∂φ̂/∂t = N̂ − 2ε⁴|k|⁶ φ̂ − c_σ σ |k|⁴ φ̂,   N̂ = −2|k|² FT[f'Φ] − 2ε²|k|⁴ FT[f],   c_σ = 3/√2 ε,
//! ```
//!
//! with the sixth-order term and a linear stabiliser S(k) = s2|k|² + s4 ε²|k|⁴ implicit and the
//! rest explicit. One variable-step SBDF formula covers every scheme (Wang & Ruuth 2008), with
//! the history j = 1 … L (j = 1 the current step):
//!
//! ```text
//! (a0 + Δt(2ε⁴k⁶ + S)) φ̂^{n+1} = −Σ_j a_j φ̂^{n+1−j}
//!         + Δt Σ_j b_j (N̂^{n+1−j} + S φ̂^{n+1−j}) − Δt c_σ σ k⁴ Σ_j b_j φ̂^{n+1−j}
//! ```
//!
//! The coefficients of each scheme are a row of [`SCHEMES`]. φ̂^{n+1} = P̂ + σ Q̂ is affine in σ,
//! so the area of the result is a quadratic in σ; see [`super::stepper`]. Under the Stokes flow
//! the advection per unit σ joins Q̂ ([`ValueFactors`]).

use crate::problem::config::{Scheme, Stabilizer};
use crate::problem::model::TENSION_FACTOR;

/// The longest history any scheme reads (SBDF2: φ̂ⁿ and φ̂ⁿ⁻¹). The GPU kernels' `Update`
/// has the same bound.
pub const MAX_LEVELS: usize = 2;

/// One scheme: its name and the coefficients (a0, a_1…a_L, b_1…b_L) of a step of Δt after
/// the steps `previous` (most recent first, as many as the scheme has taken so far).
pub struct SchemeRow {
    /// The scheme of the scene file.
    pub scheme: Scheme,
    /// Levels of history the scheme reads once it has them.
    pub levels: usize,
    /// The coefficients for a step of `dt` after the steps `previous`.
    pub coefficients: fn(dt: f64, previous: &[f64]) -> Coefficients,
}

/// The SBDF coefficients of one step: a0, then a_j and b_j for the history j = 1 … `levels`
/// (unused entries zero).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// a0, a1, …, a_L.
    pub a: [f64; MAX_LEVELS + 1],
    /// b1, …, b_L.
    pub b: [f64; MAX_LEVELS],
}

/// SBDF1 (semi-implicit Euler): a = (1, −1), b = (1).
fn sbdf1(_dt: f64, _previous: &[f64]) -> Coefficients {
    Coefficients {
        a: [1.0, -1.0, 0.0],
        b: [1.0, 0.0],
    }
}

/// Variable-step SBDF2 with ω = Δt_n/Δt_{n−1}: a = ((1+2ω)/(1+ω), −(1+ω), ω²/(1+ω)),
/// b = (1+ω, −ω); SBDF1 on its first step.
fn sbdf2(dt: f64, previous: &[f64]) -> Coefficients {
    let Some(&dt_prev) = previous.first() else {
        return sbdf1(dt, previous);
    };
    let w = dt / dt_prev;
    Coefficients {
        a: [(1.0 + 2.0 * w) / (1.0 + w), -(1.0 + w), w * w / (1.0 + w)],
        b: [1.0 + w, -w],
    }
}

/// The schemes, a row each.
pub const SCHEMES: [SchemeRow; 2] = [
    SchemeRow {
        scheme: Scheme::Sbdf1,
        levels: 1,
        coefficients: sbdf1,
    },
    SchemeRow {
        scheme: Scheme::Sbdf2,
        levels: 2,
        coefficients: sbdf2,
    },
];

/// The row of `scheme`.
pub fn row(scheme: Scheme) -> &'static SchemeRow {
    SCHEMES
        .iter()
        .find(|r| r.scheme == scheme)
        .expect("every scheme has a row")
}

/// The update of one step at every wavenumber: the coefficients, Δt and the implicit operator's
/// constants. `#[repr(C)]`: the GPU kernels take it as their `Update` struct.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Update {
    /// The SBDF coefficients of this step.
    pub c: Coefficients,
    /// Δt.
    pub dt: f64,
    /// s2 of the stabiliser S = s2 k² + s4 ε² k⁴.
    pub s2: f64,
    /// s4 ε².
    pub s4e2: f64,
    /// 2ε⁴.
    pub e4x2: f64,
    /// c_σ = 3/√2 ε.
    pub c_sigma: f64,
}

impl Update {
    /// The update of a step of `dt` with coefficients `c`, interface width `eps`, stabiliser
    /// `s` and mobility `m` of the diffusive channel m∇²μ (1 for the conserved flow): each of
    /// the operator's terms (2ε⁴k⁶, S, c_σσk⁴) is multiplied by m, and N̂ holds m times the
    /// conserved flow's explicit part (plus the advection of the Stokes dynamics,
    /// [`super::flow`]).
    pub fn new(c: Coefficients, dt: f64, eps: f64, s: &Stabilizer, m: f64) -> Self {
        let e2 = eps * eps;
        Update {
            c,
            dt,
            s2: m * s.s2,
            s4e2: m * s.s4 * e2,
            e4x2: m * 2.0 * e2 * e2,
            c_sigma: m * TENSION_FACTOR * eps,
        }
    }

    /// Levels of history this step reads: the last j with a_j ≠ 0 (SBDF2 after its first step
    /// reads 2, every first-order step 1).
    pub fn levels(&self) -> usize {
        (1..=MAX_LEVELS)
            .rev()
            .find(|&j| self.c.a[j] != 0.0)
            .unwrap_or(1)
    }

    /// S = s2 k + s4 ε² k² at |k|² = `k`.
    #[inline(always)]
    fn stabilizer(&self, k: f64) -> f64 {
        self.s2 * k + self.s4e2 * k * k
    }

    /// The real factors of the update at |k|² = `k` (see [`ValueFactors`]) for the first `L`
    /// levels of history.
    #[inline(always)]
    pub fn at<const L: usize>(&self, k: f64) -> ValueFactors<L> {
        let (dt, s) = (self.dt, self.stabilizer(k));
        let inv = 1.0 / (self.c.a[0] + dt * (self.e4x2 * k * k * k + s));
        let qc = -dt * self.c_sigma * k * k * inv;
        ValueFactors {
            h: std::array::from_fn(|j| (-self.c.a[j + 1] + dt * self.c.b[j] * s) * inv),
            n: std::array::from_fn(|j| dt * self.c.b[j] * inv),
            q: std::array::from_fn(|j| self.c.b[j] * qc),
        }
    }
}

/// The update at one wavenumber as real factors per level j of history (k standing for |k|²):
///
/// ```text
/// P̂ = Σ_j h_j φ̂^{n+1−j} + n_j N̂^{n+1−j},   Q̂ = Σ_j q_j φ̂^{n+1−j} − n_j T̂^{n+1−j},
/// h_j = (−a_j + Δt b_j S)/D,  n_j = Δt b_j/D,  q_j = −Δt c_σ k⁴ b_j/D,  D = a0 + Δt(2ε⁴k⁶ + S),
/// ```
///
/// where T̂ = FT[u_σ·∇φ] is the Stokes flow's advection per unit σ ([`super::flow`]): under a
/// flow split in σ the tension acts through the flow as well as through the diffusive channel,
/// and φ̂^{n+1} = P̂ + σQ̂ stays affine in σ. Without one the T̂ terms are absent.
pub struct ValueFactors<const L: usize> {
    /// h_j, the factor of φ̂ in P̂.
    pub h: [f64; L],
    /// n_j, the factor of N̂ in P̂ (and of −T̂ in Q̂).
    pub n: [f64; L],
    /// q_j, the factor of φ̂ in Q̂.
    pub q: [f64; L],
}

impl<const L: usize> ValueFactors<L> {
    /// (P̂, Q̂) at one mode of `W` reals from (φ̂, N̂, T̂) of each level, the current step first;
    /// T̂ is read only with `FLOW` (a Stokes flow split in σ).
    #[inline(always)]
    pub fn apply<const W: usize, const FLOW: bool>(
        &self,
        levels: [[&[f64; W]; 3]; L],
    ) -> ([f64; W], [f64; W]) {
        let mut p = [0.0; W];
        let mut q = [0.0; W];
        for (j, [x, n, t]) in levels.iter().enumerate() {
            for c in 0..W {
                p[c] += x[c] * self.h[j] + n[c] * self.n[j];
                q[c] += x[c] * self.q[j];
                if FLOW {
                    q[c] -= t[c] * self.n[j];
                }
            }
        }
        (p, q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every scheme's coefficients are consistent (Σ a_j = 0: a constant is stationary;
    /// Σ b_j = 1: the explicit part is first-order consistent) at several step ratios, and
    /// SBDF2's first step is SBDF1. A slipped coefficient breaks one of the sums by O(1).
    #[test]
    fn every_row_is_consistent() {
        for r in &SCHEMES {
            for previous in [&[][..], &[0.5], &[1.0], &[2.0, 1.0]] {
                let c = (r.coefficients)(1.0, previous);
                assert!(c.a.iter().sum::<f64>().abs() <= 1e-15, "{:?}", r.scheme);
                assert!((c.b.iter().sum::<f64>() - 1.0).abs() <= 1e-15);
            }
            assert_eq!((r.coefficients)(1.0, &[]), sbdf1(1.0, &[]));
            assert!(r.levels <= MAX_LEVELS);
        }
    }
}
