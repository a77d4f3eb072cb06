//! The limit shapes of the bilayer-couple and ADE diagrams, as lines in `(v, Δa)` and
//! `(v, Δa0)`: `L_pear`, two spheres joined by an infinitesimal neck (a bud outside), and
//! `L_sto`, a sphere inside a sphere joined by an infinitesimal neck (Seifert, Berndl &
//! Lipowsky, Phys. Rev. A 44, 1182, 1991).
//!
//! With radii `R1 ≥ R2` in units of `R0` (total area `4πR0²`: `R1² + R2² = 1`):
//!
//! ```text
//! L_pear: v = R1³ + R2³,  Δa = R1 + R2,  neck: 1/R1 + 1/R2 = c̄0,eff,  e(c̄0 = 0) = 2
//! L_sto:  v = R1³ − R2³,  Δa = R1 − R2,  neck: 1/R1 − 1/R2 = c̄0,eff,  e(c̄0 = 0) = 2
//! ```
//!
//! (a sphere of radius `R` has `Δa = R`, and the inner sphere of `L_sto`, whose outward normal
//! points into it, `Δa = −R2`). Each limit shape is stationary in the SC model only at the
//! `c̄0,eff` of its neck condition (this program's convention: a sphere has `2H = 2/R`); in
//! the ADE model of `α` and `c̄0` that places it at `Δa0 = Δa + (c̄0,eff − c̄0)/(2πα)`
//! ([`super::ade_da0`]). End points: `L_pear` runs from two equal spheres
//! (`R1 = R2 = 1/√2`: `v = 1/√2`, `Δa = √2`) to one sphere (`v = Δa = 1`); `L_sto` from two
//! coinciding spheres (`v = Δa = 0`) to one sphere (`v = Δa = 1`).

use super::model::ade_da0;
use std::f64::consts::FRAC_1_SQRT_2;

/// Which limit shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// Two spheres touching from outside (`L_pear`).
    Pear,
    /// A sphere inside a sphere (`L_sto`).
    Stomatocyte,
}

/// One limit shape, in units of `R0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitShape {
    /// Which limit.
    pub kind: Limit,
    /// Radius of the larger (outer) sphere.
    pub r1: f64,
    /// Radius of the smaller (bud or inner) sphere.
    pub r2: f64,
    /// Reduced volume.
    pub v: f64,
    /// Reduced area difference `Δa`.
    pub da: f64,
    /// The spontaneous curvature `c̄0,eff` at which the neck is stationary (the neck condition).
    pub c0_neck: f64,
}

impl LimitShape {
    /// The limit shape `kind` with smaller radius `r2 ∈ [0, 1/√2]` (`R1 = √(1 − R2²)`); `None`
    /// outside that range. The neck condition is infinite at `r2 = 0`.
    pub fn new(kind: Limit, r2: f64) -> Option<Self> {
        if !(0.0..=FRAC_1_SQRT_2 + 1e-15).contains(&r2) {
            return None;
        }
        let r2 = r2.min(FRAC_1_SQRT_2);
        let r1 = (1.0 - r2 * r2).sqrt();
        let s = match kind {
            Limit::Pear => 1.0,
            Limit::Stomatocyte => -1.0,
        };
        Some(LimitShape {
            kind,
            r1,
            r2,
            v: r1.powi(3) + s * r2.powi(3),
            da: r1 + s * r2,
            c0_neck: 1.0 / r1 + s / r2,
        })
    }

    /// Reduced bending energy at `c̄0`: `(2 − c̄0 R1)²/4 + (2 ∓ c̄0 R2)²/4` (each sphere's
    /// `∮(2H − c̄0)² dA/16π`, `2H = ±2/R`); 2 at `c̄0 = 0`.
    pub fn e(&self, c0: f64) -> f64 {
        let s = match self.kind {
            Limit::Pear => 1.0,
            Limit::Stomatocyte => -1.0,
        };
        0.25 * (2.0 - c0 * self.r1).powi(2) + 0.25 * (2.0 - s * c0 * self.r2).powi(2)
    }

    /// Where the limit shape lies in the ADE diagram of `α` and `c̄0`:
    /// `Δa0 = Δa + (c̄0,neck − c̄0)/(2πα)`.
    pub fn da0(&self, alpha: f64, c0: f64) -> f64 {
        ade_da0(c0, alpha, self.da, self.c0_neck)
    }
}

/// The limit line `kind` sampled at `n + 1` radii `R2 = (i/n)/√2`, from one sphere (`i = 0`,
/// skipped: its neck condition is infinite) to two equal spheres (`i = n`); `n` points.
pub fn limit_line(kind: Limit, n: usize) -> Vec<LimitShape> {
    (1..=n)
        .filter_map(|i| LimitShape::new(kind, FRAC_1_SQRT_2 * i as f64 / n as f64))
        .collect()
}

/// The `L_pear` point at reduced volume `v ∈ [1/√2, 1)` (bisection in `R2`); `None` outside.
pub fn l_pear_at(v: f64) -> Option<LimitShape> {
    at_v(Limit::Pear, v)
}

/// The `L_sto` point at reduced volume `v ∈ (0, 1)` (bisection in `R2`); `None` outside.
pub fn l_sto_at(v: f64) -> Option<LimitShape> {
    at_v(Limit::Stomatocyte, v)
}

/// `Δa` of a sphere holding `n ≥ 1` equal spheres inside it, each joined to it by an
/// infinitesimal neck, at reduced volume `v ∈ (0, 1)` (radii `R1`, `R2`: `R1² + n R2² = 1`,
/// `v = R1³ − n R2³`, `Δa = R1 − n R2`): for `n = 1` `L_sto`, for `n = 2` the up–down
/// symmetric shape invaginated at both poles. `None` for `v` outside `(0, 1)`.
pub fn inner_spheres_da(v: f64, n: u32) -> Option<f64> {
    satellites_da(v, n, -1.0)
}

/// `Δa` of a sphere carrying `n ≥ 1` equal buds outside it, each joined to it by an
/// infinitesimal neck, at reduced volume `v` (`R1² + n R2² = 1`, `v = R1³ + n R2³`,
/// `Δa = R1 + n R2`, `e = n + 1` at `c̄0 = 0`): for `n = 1` `L_pear`, for `n = 2` the up–down
/// symmetric shape budded at both poles, where the BC prolate's path ends at `v ≳ 0.86`. `None`
/// for `v` outside `((n + 1)^(−1/2), 1)` (the buds as large as the sphere at its lower end).
pub fn outer_buds_da(v: f64, n: u32) -> Option<f64> {
    satellites_da(v, n, 1.0)
}

/// `Δa = R1 + s n R2` of a sphere with `n` equal spheres joined to it, outside (`s = 1`) or
/// inside (`s = −1`), at reduced volume `v = R1³ + s n R2³` (`R1² + n R2² = 1`; bisection in
/// `R2 ∈ [0, (n + 1)^(−1/2)]`, along which `v` falls); `None` where no `R2` gives `v`.
fn satellites_da(v: f64, n: u32, s: f64) -> Option<f64> {
    let n = f64::from(n.max(1));
    let of = |r2: f64| {
        let r1 = (1.0 - n * r2 * r2).sqrt();
        (r1.powi(3) + s * n * r2.powi(3), r1 + s * n * r2)
    };
    let (mut lo, mut hi) = (0.0, (1.0 / (n + 1.0)).sqrt());
    if !(v > of(hi).0.max(0.0) && v < 1.0) {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if of(mid).0 > v {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(of(0.5 * (lo + hi)).1)
}

/// Bisection for the limit shape of reduced volume `v` (`v` falls monotonically with `R2`).
fn at_v(kind: Limit, v: f64) -> Option<LimitShape> {
    let v_of = |r2: f64| LimitShape::new(kind, r2).map_or(f64::NAN, |s| s.v);
    if !(v < 1.0 && v >= v_of(FRAC_1_SQRT_2)) {
        return None;
    }
    let (mut lo, mut hi) = (0.0, FRAC_1_SQRT_2);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if v_of(mid) > v {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    LimitShape::new(kind, 0.5 * (lo + hi))
}
