//! A stretching of the contour parameter that clusters the Ritz modes at a narrow neck.
//!
//! The modes are sines in a computational parameter `τ ∈ [0, 1]`; the arclength fraction
//! `t = s/L` is a monotone function of it. [`NeckMap`] defines the node density `dτ/dt` as a
//! background plus a pair of Poisson kernels centred on the neck at `t_n` (and its mirror image
//! at `−t_n`, which keeps `dτ/dt` even about both poles):
//!
//! ```text
//! dτ/dt = α + (1 − α) [P_β(π(t − t_n)) + P_β(π(t + t_n))] / 2,
//! P_β(θ) = (1 − β²) / (1 − 2β cos θ + β²)          (mean 1 over a period, peak (1+β)/(1−β))
//! τ(t)  = α t + (1 − α)/(2π) [F(π(t − t_n)) − F(−π t_n) + F(π(t + t_n)) − F(π t_n)],
//! F(θ)  = 2 arctan(k tan(θ/2)),  k = (1 + β)/(1 − β)   (continued across θ = ±π; F' = P_β)
//! ```
//!
//! so `τ(0) = 0`, `τ(1) = 1`. Since `dτ/dt` is even and 2-periodic, `t(τ) − τ` is odd about
//! both poles, and a smooth surface of revolution keeps `ψ(τ) − πτ` odd about both poles: the
//! sine series still converges exponentially, now with a share `(1 − α)/2` of the modes on the
//! Lorentzian of half-width `(1 − β)/π` in `t` around the neck. `α = 1` is the identity.
//!
//! An up–down symmetric shape (`ψ(1 − t) = π − ψ(t)`) with a neck at `t_n` has its mirror
//! image at `1 − t_n`. The **mirrored** map puts the same kernels at both and halves each pair:
//!
//! ```text
//! dτ/dt = α + (1 − α) [P_β(π(t − t_n)) + P_β(π(t + t_n)) + P_β(π(t − 1 + t_n)) + P_β(π(t + 1 − t_n))] / 4
//! ```
//!
//! which is also even about the equator, `τ(1 − t) = 1 − τ(t)`: `ψ(τ) − πτ` stays odd about
//! `τ = 1/2`, so the symmetric branches keep their even modes (and their automatic closure) in
//! it. At `t_n = 1/2` (one neck on the equator) it is the map above.

use super::Solution;
use std::f64::consts::PI;

/// The map `t(τ)` of the module docs: neck position, kernel width and background weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeckMap {
    /// Arclength fraction `t_n = s_n/L` of the neck (0 < t_n < 1).
    pub centre: f64,
    /// Kernel parameter `β ∈ [0, 1)`: the kernel's half-width in `t` is `(1 − β)/π`.
    pub beta: f64,
    /// Background weight `α ∈ (0, 1]` (1: no clustering).
    pub alpha: f64,
    /// Whether the kernels are repeated at the mirror image `1 − t_n` of the neck (the map of
    /// an up–down symmetric shape, even about `t = 1/2`).
    pub mirrored: bool,
}

/// Default background weight of [`NeckMap::at_neck`]: half the modes stay uniform.
const ALPHA: f64 = 0.5;

/// The kernel half-width of [`NeckMap::at_neck`] in units of the neck radius.
const ZONE: f64 = 3.0;

impl NeckMap {
    /// The identity `t = τ`.
    pub const IDENTITY: NeckMap = NeckMap {
        centre: 0.5,
        beta: 0.0,
        alpha: 1.0,
        mirrored: false,
    };

    /// A map for a neck of radius `neck` at arclength `s_n` on a contour of length `length`:
    /// centre `t_n = s_n/L`, half-width `(1 − β)/π = ZONE·neck/L` (`ZONE` = 3 neck radii),
    /// `α = 1/2`. The half-width is capped at 0.1 (β ≥ 1 − 0.1π).
    pub fn at_neck(s_n: f64, neck: f64, length: f64) -> Self {
        let hw = (ZONE * neck / length).min(0.1);
        NeckMap {
            centre: (s_n / length).clamp(0.01, 0.99),
            beta: 1.0 - PI * hw,
            alpha: ALPHA,
            mirrored: false,
        }
    }

    /// The mirrored map (module docs) for an up–down symmetric shape with a neck of radius
    /// `neck` at arclength `s_n` (and its image at `L − s_n`): as [`NeckMap::at_neck`], with the
    /// centre taken on the lower half, `t_n = min(s_n, L − s_n)/L`.
    pub fn at_symmetric_necks(s_n: f64, neck: f64, length: f64) -> Self {
        NeckMap {
            mirrored: true,
            ..NeckMap::at_neck(s_n.min(length - s_n), neck, length)
        }
    }

    /// The map for a neck of radius `neck` at `s_n` on a contour of length `length`:
    /// [`NeckMap::at_symmetric_necks`] if `symmetric`, else [`NeckMap::at_neck`].
    pub fn for_neck(s_n: f64, neck: f64, length: f64, symmetric: bool) -> Self {
        if symmetric {
            NeckMap::at_symmetric_necks(s_n, neck, length)
        } else {
            NeckMap::at_neck(s_n, neck, length)
        }
    }

    /// Distance in `t` from `t` to the nearest neck the map is centred on (`t_n`, and
    /// `1 − t_n` when mirrored).
    pub fn offset(&self, t: f64) -> f64 {
        self.centres()
            .map(|c| (t - c).abs())
            .fold(f64::INFINITY, f64::min)
    }

    /// The necks the kernel pairs are centred on: `t_n`, and `1 − t_n` when mirrored.
    fn centres(&self) -> impl Iterator<Item = f64> {
        let c = self.centre;
        std::iter::once(c).chain(self.mirrored.then_some(1.0 - c))
    }

    /// Whether this is the identity.
    pub fn is_identity(&self) -> bool {
        self.alpha >= 1.0
    }

    /// The kernel half-width `(1 − β)/π` in `t`.
    pub fn half_width(&self) -> f64 {
        (1.0 - self.beta) / PI
    }

    /// Poisson kernel `P_β(θ) = (1 − β²)/(1 − 2β cos θ + β²)`.
    fn kernel(&self, theta: f64) -> f64 {
        let b = self.beta;
        (1.0 - b * b) / (1.0 - 2.0 * b * theta.cos() + b * b)
    }

    /// Antiderivative `F(θ) = 2 arctan(k tan(θ/2))` of the kernel, continued across `θ = ±π`.
    fn kernel_integral(&self, theta: f64) -> f64 {
        let k = (1.0 + self.beta) / (1.0 - self.beta);
        let n = (theta / (2.0 * PI)).round();
        let th = theta - 2.0 * PI * n;
        2.0 * (k * (0.5 * th).tan()).atan() + 2.0 * PI * n
    }

    /// Node density `dτ/dt = α + (1 − α)[P_β(π(t − t_n)) + P_β(π(t + t_n))]/2`, the bracket
    /// averaged over `t_n` and `1 − t_n` when mirrored.
    pub fn density(&self, t: f64) -> f64 {
        if self.is_identity() {
            return 1.0;
        }
        let bump: f64 = self
            .centres()
            .map(|c| 0.5 * (self.kernel(PI * (t - c)) + self.kernel(PI * (t + c))))
            .sum();
        self.alpha + (1.0 - self.alpha) * bump / self.centres().count() as f64
    }

    /// `τ(t) = α t + (1 − α)/(2π)[F(π(t − t_n)) − F(−π t_n) + F(π(t + t_n)) − F(π t_n)]`, the
    /// bracket averaged over `t_n` and `1 − t_n` when mirrored.
    pub fn tau(&self, t: f64) -> f64 {
        if self.is_identity() {
            return t;
        }
        let f = |x: f64| self.kernel_integral(x);
        let bump: f64 = self
            .centres()
            .map(|c| f(PI * (t - c)) - f(-PI * c) + f(PI * (t + c)) - f(PI * c))
            .sum();
        self.alpha * t + (1.0 - self.alpha) / (2.0 * PI) * bump / self.centres().count() as f64
    }

    /// The inverse `t(τ)` of [`NeckMap::tau`] (Newton's method safeguarded by bisection, to
    /// 1e-15).
    pub fn t(&self, tau: f64) -> f64 {
        if self.is_identity() || tau <= 0.0 || tau >= 1.0 {
            return tau.clamp(0.0, 1.0);
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let mut t = tau;
        for _ in 0..200 {
            let r = self.tau(t) - tau;
            if r.abs() < 1e-15 {
                break;
            }
            if r > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let next = t - r / self.density(t);
            t = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo < 1e-16 {
                break;
            }
        }
        t
    }

    /// `dt/dτ` at `τ`: `1/(dτ/dt)` at `t(τ)`.
    pub fn stretch(&self, tau: f64) -> f64 {
        1.0 / self.density(self.t(tau))
    }
}

/// Neck radius (units of `R0`) below which the pear continuations stretch the contour parameter at
/// the neck ([`NeckMap::at_neck`]).
const MAP_NECK: f64 = 0.1;

/// The continuations map again when the neck has narrowed below this fraction of the neck the
/// current map was made for.
const REMAP_SHRINK: f64 = 0.7;

/// The map for `s` if its neck calls for a new one: a neck below [`MAP_NECK`] and no map yet,
/// or narrowed below [`REMAP_SHRINK`] of `mapped` (the neck the current map `map` was made
/// for), or moved by more than half the kernel's half-width; mirrored
/// ([`NeckMap::at_symmetric_necks`]) on the up–down symmetric branches. Returns the new map and
/// its neck.
pub(super) fn new_map(s: &Solution, map: &NeckMap, mapped: Option<f64>) -> Option<(NeckMap, f64)> {
    let (s_n, b) = s.neck_at()?;
    if b > MAP_NECK {
        return None;
    }
    let l = s.length();
    let moved = map.offset(s_n / l) > 0.5 * map.half_width();
    let narrowed = mapped.is_none_or(|m| b < REMAP_SHRINK * m);
    let symmetric = s.branch.up_down_symmetric();
    (narrowed || moved).then(|| (NeckMap::for_neck(s_n, b, l, symmetric), b))
}

/// On a stretched map `map`, the map `s` calls for whatever the width of its neck: the map at
/// its neck if the neck has moved from `map`'s centre by more than half the kernel's
/// half-width, or the identity if `s` has no neck (a path that has passed through wider necks,
/// or none, and narrows again elsewhere: the stomatocyte's mirror image beyond its fold in
/// `Δa`, whose invagination lies at the other pole). `None` on the identity or where `map`
/// still fits. Returns the new map and its neck (infinite for the identity).
pub(super) fn moved_map(s: &Solution, map: &NeckMap) -> Option<(NeckMap, f64)> {
    if map.is_identity() {
        return None;
    }
    let Some((s_n, b)) = s.neck_at() else {
        return Some((NeckMap::IDENTITY, f64::INFINITY));
    };
    let l = s.length();
    let symmetric = s.branch.up_down_symmetric();
    (map.offset(s_n / l) > 0.5 * map.half_width())
        .then(|| (NeckMap::for_neck(s_n, b, l, symmetric), b))
}

/// Points of the midpoint rule of [`mirror_asymmetry`] in a neck map: it integrates the
/// products of sines exactly up to mode 1023, above the most modes the solver takes (160 at
/// 481 nodes).
const ASYMMETRY_SAMPLES: usize = 512;

/// Size of the up–down asymmetric part of the contour whose tangent angle is
/// `ψ = πτ + Σ a_k sin(kπτ)` in the parameter `τ` of `map` (modes `modes`, coefficients `a`):
/// with `g(t) = ψ − πt` at the arclength fraction `t`, √2 times the root mean square over `t`
/// of its part even under the mirror `t → 1 − t`, `(g(t) + g(1 − t))/2`. In the identity map
/// `g = Σ a_k sin kπt`, whose odd `k` are exactly that part, so this is `√Σ_{k odd} a_k²`; in a
/// neck map centred off the equator the odd sines in `τ` do not measure the mirror asymmetry,
/// and the part is sampled in `t` instead (midpoint rule on [`ASYMMETRY_SAMPLES`] points).
pub fn mirror_asymmetry(map: &NeckMap, modes: &[usize], a: &[f64]) -> f64 {
    if map.is_identity() {
        return modes
            .iter()
            .zip(a)
            .filter(|(k, _)| *k % 2 == 1)
            .fold(0.0, |acc, (_, a)| acc + a * a)
            .sqrt();
    }
    let g = |t: f64| {
        let tau = map.tau(t);
        let series: f64 = modes
            .iter()
            .zip(a)
            .map(|(&k, a)| a * (k as f64 * PI * tau).sin())
            .sum();
        PI * (tau - t) + series
    };
    let n = ASYMMETRY_SAMPLES;
    let mean_square = (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) / n as f64;
            (0.5 * (g(t) + g(1.0 - t))).powi(2)
        })
        .sum::<f64>()
        / n as f64;
    (2.0 * mean_square).sqrt()
}

/// The coefficients, in the basis of `to` (modes `modes`), of the shape with coefficients
/// `a` in the basis of `from`: `ψ` is a function of the arclength fraction `t`, so at
/// `τ_j = j/N` of the new parameter, `ψ = π τ_old + Σ a_k sin(kπ τ_old)` with
/// `τ_old = τ_from(t_to(τ_j))`, and `a'_k = (2/N) Σ_j (ψ_j − π τ_j) sin(kπ j/N)` (the discrete
/// sine transform, exact for sine series below `N = 4 max k`); `a` itself when the maps are equal.
pub(super) fn reproject(a: &[f64], from: &NeckMap, to: &NeckMap, modes: &[usize]) -> Vec<f64> {
    if from == to {
        return a.to_vec();
    }
    let kmax = modes.iter().copied().max().unwrap_or(1);
    let n = 4 * kmax;
    let f: Vec<f64> = (1..n)
        .map(|j| {
            let tau = j as f64 / n as f64;
            let old = from.tau(to.t(tau));
            let psi: f64 = PI * old
                + modes
                    .iter()
                    .zip(a)
                    .map(|(k, ak)| ak * (*k as f64 * PI * old).sin())
                    .sum::<f64>();
            psi - PI * tau
        })
        .collect();
    modes
        .iter()
        .map(|&k| {
            2.0 / n as f64
                * f.iter()
                    .enumerate()
                    .map(|(i, fj)| fj * (k as f64 * PI * (i + 1) as f64 / n as f64).sin())
                    .sum::<f64>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_ends() {
        let m = NeckMap::at_neck(2.9, 0.01, 4.5);
        assert!((m.tau(0.0)).abs() < 1e-14 && (m.tau(1.0) - 1.0).abs() < 1e-14);
        for i in 0..=20 {
            let tau = i as f64 / 20.0;
            assert!((m.tau(m.t(tau)) - tau).abs() < 1e-13);
        }
        // Derivative of τ(t) against the density (central difference).
        let t = 0.6;
        let d = (m.tau(t + 1e-7) - m.tau(t - 1e-7)) / 2e-7;
        assert!((d - m.density(t)).abs() < 1e-5 * d);
    }

    /// The mirrored map of a symmetric shape is even about the equator, `τ(1 − t) = 1 − τ(t)`,
    /// so an up–down symmetric contour (even modes only) moved into it keeps every odd
    /// coefficient at round-off (1e-12 against a_2 = 0.3): the symmetric branches keep their
    /// even-mode basis. The unmirrored map at the same neck is not even (its odd coefficients
    /// exceed 1e-3). At `t_n = 1/2` the two maps coincide.
    #[test]
    fn the_mirrored_map_keeps_up_down_symmetry() {
        let m = NeckMap::at_symmetric_necks(0.7, 0.02, 4.5);
        assert!((m.centre - 0.7 / 4.5).abs() < 1e-15 && m.mirrored);
        for i in 0..=20 {
            let t = i as f64 / 20.0;
            assert!((m.tau(1.0 - t) - (1.0 - m.tau(t))).abs() < 1e-13, "t = {t}");
            assert!((m.tau(m.t(t)) - t).abs() < 1e-13);
        }
        let d = (m.tau(0.3 + 1e-7) - m.tau(0.3 - 1e-7)) / 2e-7;
        assert!((d - m.density(0.3)).abs() < 1e-5 * d);
        // The other neck, at L − s_n, gives the same map.
        let other = NeckMap::at_symmetric_necks(4.5 - 0.7, 0.02, 4.5);
        assert!((other.centre - m.centre).abs() < 1e-15 && other.beta == m.beta);
        let modes: Vec<usize> = (1..=80).collect();
        let mut symmetric = vec![0.0; 80];
        (symmetric[1], symmetric[3]) = (0.3, -0.05);
        let odd = |a: &[f64]| a.iter().step_by(2).fold(0.0f64, |m, x| m.max(x.abs()));
        let moved = reproject(&symmetric, &NeckMap::IDENTITY, &m, &modes);
        assert!(odd(&moved) < 1e-12, "mirrored: {}", odd(&moved));
        let one_sided = NeckMap::at_neck(0.7, 0.02, 4.5);
        let moved = reproject(&symmetric, &NeckMap::IDENTITY, &one_sided, &modes);
        assert!(odd(&moved) > 1e-3, "one-sided: {}", odd(&moved));
        let equator = NeckMap::at_symmetric_necks(2.25, 0.02, 4.5);
        for i in 0..=20 {
            let t = i as f64 / 20.0;
            let plain = NeckMap::at_neck(2.25, 0.02, 4.5).tau(t);
            assert!((equator.tau(t) - plain).abs() < 1e-14);
        }
    }

    /// The mirror asymmetry does not depend on the parameter: an up–down symmetric contour
    /// (even modes only, a_2 = 0.3, a_4 = −0.05) moved into a neck map centred at t = 0.64 has
    /// odd coefficients above 0.01 in the new `τ` (what the asymmetry read before it was
    /// sampled in `t`) but an asymmetry below 1e-9; an asymmetric one (a_1 = 0.1, a_3 = 0.02
    /// added) keeps its √(0.1² + 0.02²) to 1e-9 in both maps.
    #[test]
    fn mirror_asymmetry_is_the_same_in_any_map() {
        let modes: Vec<usize> = (1..=80).collect();
        let neck = NeckMap::at_neck(2.9, 0.05, 4.5);
        let mut symmetric = vec![0.0; 80];
        (symmetric[1], symmetric[3]) = (0.3, -0.05);
        let moved = reproject(&symmetric, &NeckMap::IDENTITY, &neck, &modes);
        let odd = mirror_asymmetry(&NeckMap::IDENTITY, &modes, &moved);
        assert!(odd > 0.01, "the odd sines in τ: {odd}");
        let asymmetry = mirror_asymmetry(&neck, &modes, &moved);
        assert!(asymmetry < 1e-9, "{asymmetry}");
        let mut pear = symmetric.clone();
        (pear[0], pear[2]) = (0.1, 0.02);
        let want = (0.1f64.powi(2) + 0.02f64.powi(2)).sqrt();
        assert!((mirror_asymmetry(&NeckMap::IDENTITY, &modes, &pear) - want).abs() < 1e-12);
        let moved = reproject(&pear, &NeckMap::IDENTITY, &neck, &modes);
        let asymmetry = mirror_asymmetry(&neck, &modes, &moved);
        assert!(
            (asymmetry - want).abs() < 1e-9,
            "{asymmetry} against {want}"
        );
    }
}
