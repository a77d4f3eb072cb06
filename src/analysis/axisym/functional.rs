//! The discrete Ritz functional: reduced energy, closure defect and reduced volume of a shape
//! `ψ(t) = πt + Σ_k a_k sin(kπt)`, and their exact gradients in the coefficients `a_k`.
//!
//! The arc length is `s = L t`, `t ∈ [0, 1]`. At `R0 = 1` the area fixes the length,
//! `L = √(2/I_A)`; with `ρ(t) = r/L = ∫_0^t cos ψ` and `h = ψ_t + sin ψ / ρ = L·2H`,
//!
//! ```text
//! e   = ∮(2H − c̄0)² dA / (16π) = e_0 − c̄0 J + c̄0²/4
//! e_0 = ∮(2H)² dA / (16π) = (1/8) ∫_0^1 h² ρ dt                      (scale free)
//! J   = ∮2H dA / (8π R0) = (L/4) M,   M = ∫_0^1 h ρ dt = ∫_0^1 (ψ_t ρ + sin ψ) dt
//! G   = ρ(1) = ∫_0^1 cos ψ dt                                           (closure: G = 0)
//! v   = V / ((4π/3) R0³) = (3/4) I_V / (I_A/2)^{3/2},
//!       I_A = ∫ ρ dt  (A = 2π L² I_A),   I_V = ∫ ρ² sin ψ dt  (V = π L³ I_V)
//! ```
//!
//! Only `e_0` is scale free: the spontaneous-curvature term couples to the integrated mean
//! curvature, which scales with `L`, so at fixed `A` (`R0 = 1`) it carries the factor
//! `L = √(2/I_A)`; the last term is `c̄0² A/(16π) = c̄0²/4`. A sphere has `e_0 = J = 1`,
//! `e = (1 − c̄0/2)²`.
//!
//! With a stretched parameter ([`super::map`]) the modes are sines in `τ`, `t = t(τ)`, and
//! every `dt` above becomes `(dt/dτ) dτ`, `ψ_t = ψ_τ/(dt/dτ)`, `ρ = ∫ cos ψ (dt/dτ) dτ`.
//!
//! The integrals use Clenshaw–Curtis quadrature on Chebyshev–Lobatto nodes and `ρ` the
//! spectral integration matrix `Q` ([`super::quadrature`]). In place of `ρ` the functional uses
//! `ρ̃(t) = ρ(t) − t G`, which equals `ρ` on closed shapes and vanishes at both poles for any
//! `a`, so `sin ψ / ρ̃` stays finite during Newton iterations off the closure constraint. The
//! energy integrand vanishes at the poles (`ρ̃ = 0` there, `sin ψ / ρ̃` finite), so only interior
//! nodes contribute.

use super::map::NeckMap;
use super::quadrature;
use super::Model;
use std::f64::consts::PI;

/// Nodes, weights and mode tables of one discretisation (`m + 1` nodes, the listed modes),
/// and the reduced spontaneous curvature `c̄0` of the energy.
#[derive(Clone, Debug)]
pub(crate) struct Basis {
    /// Reduced spontaneous curvature `c̄0 = c0 R0`.
    pub c0: f64,
    /// The energy model: spontaneous curvature, ADE (the energy is `w`), or the bilayer couple
    /// (the constraint `J = Δa` and its gradient).
    pub model: Model,
    /// Mode numbers `k` of the coefficients, in order.
    pub modes: Vec<usize>,
    /// Nodes `t_j` on `[0, 1]`.
    pub t: Vec<f64>,
    /// Clenshaw–Curtis weights.
    pub w: Vec<f64>,
    /// Integration matrix `Q` (row-major): `ρ = Q cos ψ`, `z/L = Q sin ψ`.
    pub q: Vec<f64>,
    /// `Q̃ = Q − t wᵀ` (row-major): `ρ̃ = Q̃ cos ψ`.
    qt: Vec<f64>,
    /// `Q̃ᵀ` (row-major), so that `Q̃ x` is a sum of rows (vectorises).
    qt_trans: Vec<f64>,
    /// The stretching `t(τ)` of the contour parameter (identity unless set by
    /// [`Basis::with_map`]); the nodes `t` above are nodes in `τ`.
    pub map: NeckMap,
    /// `dt/dτ` at the nodes (1 without a map).
    pub stretch: Vec<f64>,
    /// The arclength fraction `t(τ_j) = s_j/L` at the nodes.
    pub arc: Vec<f64>,
    /// `sin(kπ t_j)`, row `j`, column = mode index.
    sin_tab: Vec<f64>,
    /// `kπ cos(kπ t_j)`, row `j`, column = mode index.
    dsin_tab: Vec<f64>,
    /// `sin(kπ t_j)`, row = mode index, column `j`.
    sin_cols: Vec<f64>,
    /// `kπ cos(kπ t_j)`, row = mode index, column `j`.
    dsin_cols: Vec<f64>,
}

/// Values and gradients of the functional at one coefficient vector.
#[derive(Clone, Debug)]
pub(crate) struct Eval {
    /// The model's reduced energy: `e` (SC, BC) or `w = e + πα(J − Δa0)²` (ADE).
    pub e: f64,
    /// Reduced bending energy `e = e_0 − c̄0 J + c̄0²/4` (equal to `e` but for ADE).
    pub e_bend: f64,
    /// Reduced integrated mean curvature `J = ∮2H dA / (8π R0)` (1 on the sphere).
    pub j: f64,
    /// Closure defect `G = ρ(1)`.
    pub g: f64,
    /// Reduced volume `v`.
    pub v: f64,
    /// `I_A = ∫ρ̃ dt` (the contour length scale is `L = R0 √(2/I_A)`).
    pub ia: f64,
    /// `∂e/∂a`.
    pub grad_e: Vec<f64>,
    /// `∂G/∂a`.
    pub grad_g: Vec<f64>,
    /// `∂v/∂a`.
    pub grad_v: Vec<f64>,
    /// `∂J/∂a`, computed for the bilayer couple only (its constraint's gradient).
    pub grad_j: Option<Vec<f64>>,
}

/// The shape's samples at the nodes.
#[derive(Clone, Debug)]
pub(crate) struct Samples {
    /// `ψ(t_j)`.
    pub psi: Vec<f64>,
    /// `ψ_t(t_j)`.
    pub dpsi: Vec<f64>,
    /// `ρ̃(t_j)`.
    pub rho: Vec<f64>,
}

impl Basis {
    /// A basis with `m + 1` nodes, the given mode numbers and `c̄0 = 0`.
    pub fn new(m: usize, modes: Vec<usize>) -> Self {
        let t = quadrature::nodes(m);
        let q = quadrature::integration_matrix(m);
        let n = m + 1;
        let w = q[m * n..].to_vec();
        let mut qt = q.clone();
        for i in 0..n {
            for j in 0..n {
                qt[i * n + j] -= t[i] * w[j];
            }
        }
        let mut qt_trans = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                qt_trans[j * n + i] = qt[i * n + j];
            }
        }
        let nm = modes.len();
        let mut sin_tab = vec![0.0; n * nm];
        let mut dsin_tab = vec![0.0; n * nm];
        for (j, tj) in t.iter().enumerate() {
            for (c, &k) in modes.iter().enumerate() {
                let kp = k as f64 * PI;
                sin_tab[j * nm + c] = (kp * tj).sin();
                dsin_tab[j * nm + c] = kp * (kp * tj).cos();
            }
        }
        Basis {
            c0: 0.0,
            model: Model::Sc,
            modes,
            map: NeckMap::IDENTITY,
            stretch: vec![1.0; n],
            arc: t.clone(),
            t,
            w,
            q,
            qt,
            qt_trans,
            sin_cols: transpose(&sin_tab, n, nm),
            dsin_cols: transpose(&dsin_tab, n, nm),
            sin_tab,
            dsin_tab,
        }
    }

    /// The same basis with reduced spontaneous curvature `c0`.
    pub fn with_c0(mut self, c0: f64) -> Self {
        self.c0 = c0;
        self
    }

    /// The same basis with the energy model `model`.
    pub fn with_model(mut self, model: Model) -> Self {
        self.model = model;
        self
    }

    /// The same basis with the contour parameter stretched by `map`: the modes are sines in
    /// `τ`, and `ds = L (dt/dτ) dτ` ([`super::map`]).
    pub fn with_map(mut self, map: NeckMap) -> Self {
        self.map = map;
        self.arc = self.t.iter().map(|tau| map.t(*tau)).collect();
        self.stretch = self.t.iter().map(|tau| map.stretch(*tau)).collect();
        self
    }

    /// Number of nodes `m + 1`.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// `ψ`, `ψ_t` and `ρ̃` at the nodes for coefficients `a`.
    pub fn samples(&self, a: &[f64]) -> Samples {
        let n = self.len();
        let nm = self.modes.len();
        let mut psi: Vec<f64> = self.t.iter().map(|t| PI * t).collect();
        let mut dpsi = vec![PI; n];
        for (c, ac) in a.iter().enumerate().take(nm) {
            axpy(&mut psi, *ac, &self.sin_cols[c * n..(c + 1) * n]);
            axpy(&mut dpsi, *ac, &self.dsin_cols[c * n..(c + 1) * n]);
        }
        let cos: Vec<f64> = psi
            .iter()
            .zip(&self.stretch)
            .map(|(p, m)| p.cos() * m)
            .collect();
        let rho = mat_t_vec(&self.qt_trans, &cos);
        Samples { psi, dpsi, rho }
    }

    /// `e`, `G`, `v` and their gradients at `a`; `None` if `ρ̃ ≤ 0` at an interior node (the
    /// curve crosses the axis: not a shape).
    pub fn eval(&self, a: &[f64]) -> Option<Eval> {
        let n = self.len();
        let Samples { psi, dpsi, rho } = self.samples(a);
        if rho[1..n - 1].iter().any(|r| *r <= 0.0 || !r.is_finite()) {
            return None;
        }
        let w = &self.w;
        let st = &self.stretch;
        // Weights of the integrals in t: dt = (dt/dτ) dτ.
        let ww: Vec<f64> = w.iter().zip(st).map(|(w, m)| w * m).collect();
        let (s, c): (Vec<f64>, Vec<f64>) = psi.iter().map(|p| p.sin_cos()).unzip();
        // Energy and its partial derivatives in ψ_j (explicit), ψ_τ,j and ρ̃_j; with
        // h = ψ_τ/(dt/dτ) + sin ψ/ρ̃, e_0 = (1/8) ∫ h² ρ̃ dt.
        let mut e = 0.0;
        let mut e_psi = vec![0.0; n];
        let mut e_dpsi = vec![0.0; n];
        let mut e_rho = vec![0.0; n];
        for j in 1..n - 1 {
            let h = dpsi[j] / st[j] + s[j] / rho[j];
            e += 0.125 * ww[j] * h * h * rho[j];
            e_psi[j] = 0.25 * ww[j] * h * c[j];
            e_dpsi[j] = 0.25 * w[j] * h * rho[j];
            e_rho[j] = 0.125 * ww[j] * (h * h - 2.0 * h * s[j] / rho[j]);
        }
        // Closure defect.
        let g: f64 = (0..n).map(|j| ww[j] * c[j]).sum();
        let g_psi: Vec<f64> = (0..n).map(|j| -ww[j] * s[j]).collect();
        // Reduced volume.
        let ia: f64 = (0..n).map(|j| ww[j] * rho[j]).sum();
        let iv: f64 = (0..n).map(|j| ww[j] * rho[j] * rho[j] * s[j]).sum();
        let v = 0.75 * iv / (0.5 * ia).powf(1.5);
        let v_psi: Vec<f64> = (0..n)
            .map(|j| v * ww[j] * rho[j] * rho[j] * c[j] / iv)
            .collect();
        let v_rho: Vec<f64> = (0..n)
            .map(|j| v * (2.0 * ww[j] * rho[j] * s[j] / iv - 1.5 * ww[j] / ia))
            .collect();
        // Spontaneous curvature: e += −c̄0 J + c̄0²/4, J = (L/4) M, L = √(2/I_A),
        // M = ∫ (ψ_τ ρ̃ dτ + sin ψ dt), so ∂J/∂ψ_j = (L/4) ŵ_j cos ψ_j, ∂J/∂ψ_τ,j = (L/4) w_j ρ̃_j,
        // ∂J/∂ρ̃_j = (L/4)(w_j ψ_τ,j − ŵ_j M/(2 I_A)) (ŵ = w dt/dτ).
        let length = (2.0 / ia).sqrt();
        let m: f64 = (1..n - 1)
            .map(|j| w[j] * dpsi[j] * rho[j] + ww[j] * s[j])
            .sum();
        let j_mean = 0.25 * length * m;
        let c0 = self.c0;
        // The energy depends on J through −c̄0 J (+ πα(J − Δa0)² for ADE): its derivative in J
        // is −c̄0,eff, so the ADE term enters the gradient as c̄0 → c̄0,eff = c̄0 + 2πα(Δa0 − J).
        let e_bend = e - c0 * j_mean + 0.25 * c0 * c0;
        let (e_model, c_eff) = match self.model {
            Model::Ade { alpha, da0 } => (
                e_bend + PI * alpha * (j_mean - da0).powi(2),
                c0 + 2.0 * PI * alpha * (da0 - j_mean),
            ),
            Model::Sc | Model::Bc { .. } => (e_bend, c0),
        };
        e = e_model;
        if c_eff != 0.0 {
            let f = -c_eff * 0.25 * length;
            for j in 1..n - 1 {
                e_psi[j] += f * ww[j] * c[j];
                e_dpsi[j] += f * w[j] * rho[j];
                e_rho[j] += f * (w[j] * dpsi[j] - 0.5 * ww[j] * m / ia);
            }
        }
        // ∂ρ̃_i/∂ψ_j = −Q̃_ij sin ψ_j (dt/dτ)_j.
        let s_st: Vec<f64> = s.iter().zip(st).map(|(s, m)| s * m).collect();
        // ∂J/∂a of the bilayer couple's constraint, with the partials of J above.
        let grad_j = matches!(self.model, Model::Bc { .. }).then(|| {
            let f = 0.25 * length;
            let mut j_psi = vec![0.0; n];
            let mut j_dpsi = vec![0.0; n];
            let mut j_rho = vec![0.0; n];
            for j in 1..n - 1 {
                j_psi[j] = f * ww[j] * c[j];
                j_dpsi[j] = f * w[j] * rho[j];
                j_rho[j] = f * (w[j] * dpsi[j] - 0.5 * ww[j] * m / ia);
            }
            let back = mat_t_vec(&self.qt, &j_rho);
            self.chain(&j_psi, Some(&j_dpsi), Some(&back), &s_st)
        });
        let (back_e, back_v) = mat_t_vec2(&self.qt, &e_rho, &v_rho);
        let grad_e = self.chain(&e_psi, Some(&e_dpsi), Some(&back_e), &s_st);
        let grad_g = self.chain(&g_psi, None, None, &s_st);
        let grad_v = self.chain(&v_psi, None, Some(&back_v), &s_st);
        Some(Eval {
            e,
            e_bend,
            j: j_mean,
            g,
            v,
            ia,
            grad_e,
            grad_g,
            grad_v,
            grad_j,
        })
    }

    /// Chain rule to the coefficients: `∂F/∂a_k = Σ_j (F_ψj − σ_j (Q̃ᵀ F_ρ)_j) sin(kπτ_j)
    /// + Σ_j F_ψ'j kπ cos(kπτ_j)`, since `∂ρ̃_i/∂ψ_j = −Q̃_ij σ_j` with
    /// `σ_j = sin ψ_j (dt/dτ)_j` (the argument `sin`); `back = Q̃ᵀ F_ρ`.
    fn chain(
        &self,
        f_psi: &[f64],
        f_dpsi: Option<&[f64]>,
        back: Option<&[f64]>,
        sin: &[f64],
    ) -> Vec<f64> {
        let n = self.len();
        let nm = self.modes.len();
        let mut g_psi = f_psi.to_vec();
        if let Some(back) = back {
            for j in 0..n {
                g_psi[j] -= sin[j] * back[j];
            }
        }
        let mut grad = vec![0.0; nm];
        for j in 0..n {
            let srow = &self.sin_tab[j * nm..(j + 1) * nm];
            for (g, s) in grad.iter_mut().zip(srow) {
                *g += g_psi[j] * s;
            }
            if let Some(fd) = f_dpsi {
                let drow = &self.dsin_tab[j * nm..(j + 1) * nm];
                for (g, d) in grad.iter_mut().zip(drow) {
                    *g += fd[j] * d;
                }
            }
        }
        grad
    }
}

/// `y += α x`.
fn axpy(y: &mut [f64], alpha: f64, x: &[f64]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += alpha * x;
    }
}

/// The transpose of a row-major `rows × cols` matrix.
fn transpose(a: &[f64], rows: usize, cols: usize) -> Vec<f64> {
    let mut t = vec![0.0; rows * cols];
    for i in 0..rows {
        for j in 0..cols {
            t[j * rows + i] = a[i * cols + j];
        }
    }
    t
}

/// `(Aᵀ x1, Aᵀ x2)` for a square row-major `A`, in one pass over `A`.
fn mat_t_vec2(a: &[f64], x1: &[f64], x2: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = x1.len();
    let mut y1 = vec![0.0; n];
    let mut y2 = vec![0.0; n];
    for i in 0..n {
        let (u, w) = (x1[i], x2[i]);
        for ((y1, y2), a) in y1.iter_mut().zip(y2.iter_mut()).zip(&a[i * n..(i + 1) * n]) {
            *y1 += a * u;
            *y2 += a * w;
        }
    }
    (y1, y2)
}

/// `A x` for a square row-major `A`.
pub(crate) fn mat_vec(a: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            a[i * n..(i + 1) * n]
                .iter()
                .zip(x)
                .map(|(a, x)| a * x)
                .sum()
        })
        .collect()
}

/// `Aᵀ x` for a square row-major `A`.
fn mat_t_vec(a: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut y = vec![0.0; n];
    for (i, xi) in x.iter().enumerate() {
        if *xi != 0.0 {
            axpy(&mut y, *xi, &a[i * n..(i + 1) * n]);
        }
    }
    y
}

#[cfg(test)]
mod grad_j_tests {
    use super::*;

    /// `∂J/∂a` of the bilayer couple matches central differences of `J`.
    #[test]
    fn grad_j_matches_differences() {
        let basis = Basis::new(60, (1..=12).collect()).with_model(Model::Bc { da: 1.0 });
        let a: Vec<f64> = (0..12).map(|k| 0.05 / (1.0 + k as f64)).collect();
        let ev = basis.eval(&a).expect("admissible");
        let gj = ev.grad_j.clone().expect("computed for BC");
        for k in 0..12 {
            let mut ap = a.clone();
            ap[k] += 1e-6;
            let jp = basis.eval(&ap).unwrap().j;
            ap[k] -= 2e-6;
            let jm = basis.eval(&ap).unwrap().j;
            let fd = (jp - jm) / 2e-6;
            assert!((fd - gj[k]).abs() < 1e-7, "k = {k}: {fd} vs {}", gj[k]);
        }
    }
}
