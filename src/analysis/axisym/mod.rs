//! Axisymmetric reference solver for the shape diagram of closed vesicles in the
//! spontaneous-curvature model (Seifert, Berndl & Lipowsky, Phys. Rev. A 44, 1182, 1991),
//! independent of the phase-field engines.
//!
//! The generating curve `(r(s), z(s))`, `s ∈ [0, L]`, is given by its tangent angle `ψ(s)`:
//!
//! ```text
//! r' = cos ψ,   z' = sin ψ,   2H = ψ' + sin ψ / r,   dA = 2π r ds,   V = π ∫ r² sin ψ ds
//! ψ(0) = 0,   ψ(L) = π,   r(0) = r(L) = 0 (closure)
//! e = ∮(2H − c̄0)² dA / (16π)  (a sphere has e = (1 − c̄0/2)²),   c̄0 = c0 R0
//! v = V / ((4π/3) R0³),   R0 = √(A/4π)
//! ```
//!
//! With this orientation (the contour runs from the lower pole to the upper, the normal points
//! out) a sphere of radius `R` has `2H = 2/R`: a positive `c0` prefers outward buds, and the
//! sphere's energy vanishes at `c0 = 2/R`.
//!
//! **Method (Ritz).** `ψ(t) = πt + Σ_{k ≤ K} a_k sin(kπt)`, `t = s/L`: the boundary values hold
//! for any `a`, and since `ψ − πt` is odd about both poles on a smooth surface of revolution,
//! the sine series converges exponentially for analytic shapes. Up–down symmetric shapes
//! (prolate, oblate: `ψ(1 − t) = π − ψ(t)`) use the even `k` only, which also makes the
//! closure automatic; the stomatocyte uses every `k` and holds the closure by a multiplier.
//! At `R0 = 1` the length follows from the area, `L = √(2/I_A)` (`functional.rs`); integrals are
//! Clenshaw–Curtis on Chebyshev–Lobatto nodes ([`quadrature`]). The constrained minimum of `e`
//! at fixed `v` is found by Newton on the Lagrangian (`solver.rs`), and each branch is followed
//! by continuation in `v` with a secant predictor and step halving ([`branches`]): prolate and
//! oblate from the sphere, the stomatocyte from a sphere-in-sphere start at small `v`, the
//! pear from its bifurcation off the prolate ([`pear`]). [`diagram`] computes the c0 = 0
//! diagram and [`phase`] the (v, c̄0) diagram, which the command `vesicle axisym` (with `--c0`)
//! writes.
//!
//! **ADE and the bilayer couple.** [`Options::model`] selects the energy ([`model`]): SC, ADE
//! (`w = e + πα(Δa − Δa0)²`, whose gradient is that of `e` at `c̄0,eff`) or BC (`Δa` held by a
//! further Newton constraint). [`bc`] follows the BC branches in `Δa` at fixed `v`, [`ade`]
//! maps them to ADE and solves ADE shapes ([`ade_solution`]), [`ade_phase`] builds the
//! `(v, Δa)` and `(v, Δa0)` diagrams and [`limits`] gives the limit lines `L_pear`, `L_sto`.
//! Both phase charts, [`phase`] and [`ade_phase`], find the lowest branch and its transitions
//! by [`lowest`].
//!
//! **Multipliers.** With `e*(v)` the branch energy at `R0 = 1`, the pressure difference and the
//! tension of the shape equation `δE_b − P δV + σ δA = 0` (`E_b = (κ/2)∮(2H − c0)² dA =
//! 8πκ e`) are, in units of `κ/R0³` and `κ/R0²`: `P = 6 de*/dv = −6 λ_v` (vary `V` at fixed
//! `A`) and `σ = P v / 2 + c̄0 J − c̄0²/2` (a dilation by `R0` changes `E_b` by
//! `8πκ (−c0 J + c0² R0/2) dR0`, `J = ∮2H dA/(8π R0)`; at `c0 = 0`, `2σA = 3PV`).

use std::f64::consts::PI;

pub mod ade;
pub mod ade_phase;
pub mod bc;
pub mod branches;
pub mod diagram;
pub(crate) mod eigen;
pub(crate) mod functional;
pub mod limits;
pub mod lowest;
pub mod map;
pub mod model;
pub mod pear;
pub mod phase;
pub mod quadrature;
pub(crate) mod solver;

pub use ade::{ade_image, ade_solution, AdePoint};
pub use bc::{bc_bifurcation, bc_curve, bc_solution, updown_changes, BcCurve, UpdownChange};
pub use branches::{branch_curve, branch_end, crossings, follow, solve, Followed};
pub use limits::{
    inner_spheres_da, l_pear_at, l_sto_at, limit_line, outer_buds_da, Limit, LimitShape,
};
pub use model::{ade_c0_eff, ade_da0, Model};
pub use pear::{
    follow_pear, l_pear, l_pear_radii, neck_limit, pear_at, pear_bifurcation, prolate_updown,
    prolate_updown_zero, symmetric_fold, Bifurcation, NeckLimit, PearBranch, PearEnd, NECK_FIT,
};

/// The branches of the diagram: the three of c0 = 0 ([`Branch::ALL`]) and the pear.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Branch {
    /// Up–down symmetric, elongated along the axis (from the sphere, `a_2 > 0`).
    Prolate,
    /// Up–down symmetric, flattened (from the sphere, `a_2 < 0`); discocytes at smaller `v`.
    Oblate,
    /// Not up–down symmetric: an invaginated cup; tends to a sphere inside a sphere (`e → 2`) as
    /// `v → 0`, and ends at a limit point near `v ≈ 0.66` (at c0 = 0).
    Stomatocyte,
    /// Not up–down symmetric: bifurcates from the prolate where the prolate loses stability to
    /// up–down asymmetric deformations, and narrows to a bud on a closing neck (the limit
    /// shape `L_pear`).
    Pear,
}

impl Branch {
    /// The branches of the c0 = 0 diagram, in its order.
    pub const ALL: [Branch; 3] = [Branch::Prolate, Branch::Oblate, Branch::Stomatocyte];

    /// The branches of the diagram at c0 ≠ 0: [`Branch::ALL`] and the pear.
    pub const WITH_PEAR: [Branch; 4] = [
        Branch::Prolate,
        Branch::Oblate,
        Branch::Stomatocyte,
        Branch::Pear,
    ];

    /// Lower-case name used in files (`prolate`, `oblate`, `stomatocyte`, `pear`).
    pub fn name(self) -> &'static str {
        match self {
            Branch::Prolate => "prolate",
            Branch::Oblate => "oblate",
            Branch::Stomatocyte => "stomatocyte",
            Branch::Pear => "pear",
        }
    }

    /// Whether the branch's shapes are up–down symmetric (even modes only, closure automatic).
    pub fn up_down_symmetric(self) -> bool {
        matches!(self, Branch::Prolate | Branch::Oblate)
    }
}

/// Discretisation and continuation settings.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Quadrature nodes (Chebyshev–Lobatto, including both poles); also the contour samples.
    pub nodes: usize,
    /// Highest mode number `K` of `ψ` (the symmetric branches use the even `k ≤ K`).
    pub modes: usize,
    /// Newton stops when the largest KKT residual falls below this.
    pub tol: f64,
    /// Newton iterations before a solve counts as failed.
    pub max_iter: usize,
    /// Largest continuation step in `v`.
    pub dv_max: f64,
    /// Continuation step below which the branch counts as ended (a limit point).
    pub dv_min: f64,
    /// Reduced spontaneous curvature `c̄0 = c0 R0` of the energy.
    pub c0: f64,
    /// The pear branch is followed until its narrowest neck (in units of `R0`) falls below
    /// this (the modes cluster at the neck below 0.1 R0, [`map::NeckMap`]; at c̄0 = 3 the
    /// path to 0.005 R0 agrees between K = 80 and 160 to 1e-9 in `e`).
    pub neck_min: f64,
    /// The energy model ([`Model::Sc`] by default; ADE and BC solves set it themselves).
    pub model: Model,
}

impl Default for Options {
    /// 241 nodes and `K = 80`: energies within 1e-12 of a 513-node run on the prolate and
    /// oblate branches, and within 4e-5 on the stomatocyte (whose narrow neck converges
    /// slowest; worst at the smallest v, 0.5). Newton to 1e-11, continuation steps of at most
    /// 0.02 in `v`, branch ends located to about 1e-4.
    fn default() -> Self {
        Options::with_nodes(241)
    }
}

impl Options {
    /// Defaults with `nodes` quadrature nodes and `K = (nodes − 1)/3` modes (three nodes per
    /// mode keep the quadrature of the nonlinear integrand below the truncation error: on the
    /// stomatocyte at v = 0.5 with K = 80, 241 and 321 nodes agree to 5e-9, 161 nodes are off
    /// by 3e-6).
    pub fn with_nodes(nodes: usize) -> Self {
        Options {
            nodes,
            modes: ((nodes - 1) / 3).max(2),
            tol: 1e-11,
            max_iter: 15,
            dv_max: 0.02,
            dv_min: 1e-4,
            c0: 0.0,
            neck_min: NECK_MIN,
            model: Model::Sc,
        }
    }

    /// The same options at reduced spontaneous curvature `c0`.
    pub fn with_c0(mut self, c0: f64) -> Self {
        self.c0 = c0;
        self
    }

    /// The same options with the energy model `model`.
    pub fn with_model(mut self, model: Model) -> Self {
        self.model = model;
        self
    }
}

/// Default [`Options::neck_min`].
pub const NECK_MIN: f64 = 0.005;

/// One stationary shape, scaled to `R0 = 1`.
#[derive(Clone, Debug)]
pub struct Solution {
    /// The branch it belongs to.
    pub branch: Branch,
    /// Reduced volume `v`.
    pub v: f64,
    /// Reduced spontaneous curvature `c̄0` of the energy.
    pub c0: f64,
    /// Reduced bending energy `e = ∮(2H − c̄0)² dA / (16π)`.
    pub e: f64,
    /// Reduced integrated mean curvature `J = ∮2H dA / (8π R0)` (1 on the sphere): the reduced
    /// area difference `Δa` of the ADE and BC models.
    pub mean_curvature: f64,
    /// The energy model the shape is stationary for.
    pub model: Model,
    /// The model's energy: `w = e + πα(Δa − Δa0)²` for ADE, `e` for SC and BC. Branches are
    /// compared by it.
    pub w: f64,
    /// The effective spontaneous curvature: the shape is a stationary SC shape at this `c̄0`
    /// (`c̄0` for SC, `c̄0 + 2πα(Δa0 − Δa)` for ADE, `c̄0 − λ_Δa` for BC; [`model`]).
    pub c0_eff: f64,
    /// Multiplier `λ_Δa` of the bilayer-couple constraint `Δa − Δa_target` (0 otherwise).
    pub lambda_da: f64,
    /// Tension `σ R0²/κ` of the shape equation of the equivalent SC problem,
    /// `σ = P v/2 + c̄0,eff J − c̄0,eff²/2` (see the module docs).
    pub sigma: f64,
    /// Pressure difference `P R0³/κ = 6 de/dv` (inside minus outside).
    pub pressure: f64,
    /// Multiplier of the reduced-volume constraint in `e + λ_v (v − v0) + λ_G G`.
    pub lambda_v: f64,
    /// Multiplier of the closure `G = r(L)/L` (0 on the up–down symmetric branches).
    pub lambda_closure: f64,
    /// Mode numbers `k` of [`Solution::coefficients`].
    pub modes: Vec<usize>,
    /// `a_k` of `ψ(t) = πt + Σ a_k sin(kπt)`.
    pub coefficients: Vec<f64>,
    /// Arc length of the contour samples (Chebyshev–Lobatto in `s`, from 0 to `L`).
    pub s: Vec<f64>,
    /// Distance from the axis at the samples (`r = 0` at both poles).
    pub r: Vec<f64>,
    /// Height at the samples (`z = 0` at the pole `s = 0`).
    pub z: Vec<f64>,
    /// Tangent angle `ψ` at the samples.
    pub psi: Vec<f64>,
    /// The stretching of the contour parameter the modes are sines in ([`map::NeckMap`];
    /// the identity except on a pear with a narrow neck).
    pub map: map::NeckMap,
    /// Newton iterations of the last solve.
    pub iterations: usize,
    /// Final largest KKT residual.
    pub residual: f64,
}

impl Solution {
    /// The reduced area difference `Δa = ∮2H dA / (8π R0)` ([`Solution::mean_curvature`]).
    pub fn da(&self) -> f64 {
        self.mean_curvature
    }

    /// Contour length `L` (at `R0 = 1`).
    pub fn length(&self) -> f64 {
        *self.s.last().expect("contour has samples")
    }

    /// The narrowest waist or neck: the smallest interior local minimum of `r` along the
    /// contour (refined by the parabola through the three samples around it), in units of
    /// `R0`; `None` if `r` rises monotonically to its maximum and falls to the other pole.
    pub fn neck(&self) -> Option<f64> {
        let r = &self.r;
        let s = &self.s;
        (1..r.len() - 1)
            .filter(|&i| r[i] <= r[i - 1] && r[i] < r[i + 1] && i > 1 && i < r.len() - 2)
            .map(|i| parabola_min(s[i - 1], s[i], s[i + 1], r[i - 1], r[i], r[i + 1]))
            .min_by(f64::total_cmp)
    }

    /// The curvatures `ψ'` at the two poles, `(s = 0, s = L)`, in units of `1/R0`: at a pole
    /// both principal curvatures equal `ψ'`, so `2H = 2ψ'` there (1 on the unit sphere). From
    /// the modes, `ψ'(0) = (π + Σ k π a_k)/(L t'(0))` and
    /// `ψ'(L) = (π + Σ (−1)^k k π a_k)/(L t'(1))` (`t' = dt/dτ` of [`Solution::map`], 1
    /// without one). Near the
    /// budding limit `L_pear` the poles are those of its two spheres, and `ψ'(0) + ψ'(L)`
    /// approaches the neck condition `1/R1 + 1/R2 = c̄0`.
    pub fn pole_curvatures(&self) -> (f64, f64) {
        let l = self.length();
        let (mut d0, mut d1) = (PI, PI);
        for (k, a) in self.modes.iter().zip(&self.coefficients) {
            let ka = *k as f64 * PI * a;
            d0 += ka;
            d1 += if k % 2 == 0 { ka } else { -ka };
        }
        let (m0, m1) = (self.map.stretch(0.0), self.map.stretch(1.0));
        (d0 / (l * m0), d1 / (l * m1))
    }

    /// The narrowest neck as `(s, r)`: its arclength and radius (see [`Solution::neck`]).
    pub fn neck_at(&self) -> Option<(f64, f64)> {
        let r = &self.r;
        let s = &self.s;
        (2..r.len().saturating_sub(2))
            .filter(|&i| r[i] <= r[i - 1] && r[i] < r[i + 1])
            .map(|i| {
                (
                    s[i],
                    parabola_min(s[i - 1], s[i], s[i + 1], r[i - 1], r[i], r[i + 1]),
                )
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// Size of the up–down asymmetric part of the contour ([`map::mirror_asymmetry`]): 0 on
    /// symmetric branches, `√Σ_{k odd} a_k²` in the identity map.
    pub fn asymmetry(&self) -> f64 {
        map::mirror_asymmetry(&self.map, &self.modes, &self.coefficients)
    }

    /// Whether the surface intersects itself: the polygon through the contour samples crosses
    /// itself (two non-adjacent segments meet), or leaves `r ≥ 0`.
    pub fn self_intersecting(&self) -> bool {
        let n = self.r.len();
        let inner = &self.r[1..n - 1];
        if inner.iter().any(|r| *r < 0.0) {
            return true;
        }
        let p: Vec<(f64, f64)> = self.r.iter().copied().zip(self.z.iter().copied()).collect();
        for i in 0..n - 1 {
            for j in i + 2..n - 1 {
                if segments_cross(p[i], p[i + 1], p[j], p[j + 1]) {
                    return true;
                }
            }
        }
        false
    }
}

/// The minimum of the parabola through `(x0, y0)`, `(x1, y1)`, `(x2, y2)` (`y1` the smallest
/// of the three, so the vertex lies in `[x0, x2]`).
fn parabola_min(x0: f64, x1: f64, x2: f64, y0: f64, y1: f64, y2: f64) -> f64 {
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let curv = (d12 - d01) / (x2 - x0);
    if curv <= 0.0 {
        return y1;
    }
    // p(x) = y1 + b (x − x1) + curv (x − x1)², b = slope at x1.
    let b = d01 + curv * (x1 - x0);
    (y1 - b * b / (4.0 * curv)).min(y1)
}

/// Whether the segments `ab` and `cd` cross (proper intersection, or touching).
fn segments_cross(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
    };
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Build the [`Solution`] of a converged Ritz state.
pub(crate) fn solution(
    branch: Branch,
    basis: &functional::Basis,
    c: &solver::Converged,
) -> Solution {
    let smp = basis.samples(&c.a);
    let length = (2.0 / c.eval.ia).sqrt();
    let sin: Vec<f64> = smp
        .psi
        .iter()
        .zip(&basis.stretch)
        .map(|(p, m)| p.sin() * m)
        .collect();
    let z = functional::mat_vec(&basis.q, &sin);
    let pressure = -6.0 * c.lambda_v;
    let c0 = basis.c0;
    let j = c.eval.j;
    let c0_eff = match basis.model {
        Model::Sc => c0,
        Model::Ade { alpha, da0 } => ade_c0_eff(c0, alpha, j, da0),
        Model::Bc { .. } => c0 - c.lambda_j,
    };
    Solution {
        branch,
        v: c.eval.v,
        c0,
        e: c.eval.e_bend,
        mean_curvature: j,
        model: basis.model,
        w: c.eval.e,
        c0_eff,
        lambda_da: c.lambda_j,
        sigma: 0.5 * pressure * c.eval.v + c0_eff * j - 0.5 * c0_eff * c0_eff,
        pressure,
        lambda_v: c.lambda_v,
        lambda_closure: c.lambda_g,
        modes: basis.modes.clone(),
        coefficients: c.a.clone(),
        s: basis.arc.iter().map(|t| t * length).collect(),
        r: smp.rho.iter().map(|r| r * length).collect(),
        z: z.iter().map(|z| z * length).collect(),
        psi: smp.psi,
        map: basis.map,
        iterations: c.iterations,
        residual: c.residual,
    }
}
