//! Least-squares fits the studies quote with every order.
//!
//! * [`linear`]: y = a + b x by ordinary least squares, with the standard error of the slope
//!   s_b = √(Σr² / ((n − 2) Σ(x − x̄)²)) and R² = 1 − Σr² / Σ(y − ȳ)².
//! * [`power`]: e = C x^p, the linear fit of ln e against ln x (p the observed order).
//! * [`exponential`]: e = C exp(b x), the linear fit of ln e against x (spectral convergence,
//!   the sphere's phase-field error in R0/ε).
//! * [`limit`]: e(x) = e0 + c x^p, the extrapolated limit e0: linear in (e0, c) at each p, the
//!   p with the least residual kept (the fit of [`crate::analysis::curves`], shared with the diagram).
//! * [`quadratic`]: y = a + b x + c x² by least squares, and its residuals (the lattice pinning
//!   study: what a smooth law in (ε/R0)² leaves unexplained).
//! * [`resolved`]: how many of a refinement's errors lie above its floor (round-off, or the
//!   reference's own error): the error laws are fitted to those only.

use std::fmt;

/// y = intercept + slope · x, fitted by least squares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// b.
    pub slope: f64,
    /// a.
    pub intercept: f64,
    /// Standard error of the slope (NaN with two points).
    pub slope_error: f64,
    /// Coefficient of determination.
    pub r2: f64,
    /// Points fitted.
    pub n: usize,
}

/// The least-squares line through `(x, y)` (pairs with a non-finite coordinate are left out);
/// `None` with fewer than two distinct x.
pub fn linear(x: &[f64], y: &[f64]) -> Option<Line> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .map(|(&a, &b)| (a, b))
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let nf = n as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / nf;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / nf;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ss_res: f64 = pts
        .iter()
        .map(|p| (p.1 - intercept - slope * p.0).powi(2))
        .sum();
    let slope_error = if n > 2 {
        (ss_res / ((nf - 2.0) * sxx)).sqrt()
    } else {
        f64::NAN
    };
    let r2 = if syy > 0.0 { 1.0 - ss_res / syy } else { 1.0 };
    Some(Line {
        slope,
        intercept,
        slope_error,
        r2,
        n,
    })
}

/// e = C x^p.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Power {
    /// The fit of ln e = ln C + p ln x.
    pub line: Line,
}

impl Power {
    /// The order p.
    pub fn order(&self) -> f64 {
        self.line.slope
    }

    /// C x^p.
    pub fn at(&self, x: f64) -> f64 {
        (self.line.intercept + self.line.slope * x.ln()).exp()
    }
}

impl fmt::Display for Power {
    /// `order 1.98 ± 0.02 (R² 0.99990, 5 points; e = 3.1e-2 x^1.98)`.
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let l = &self.line;
        write!(
            f,
            "order {:.3} ± {:.3} (least squares on ln e = ln C + p ln x: R² {:.5}, {} points, C = {:.3e})",
            l.slope,
            l.slope_error,
            l.r2,
            l.n,
            l.intercept.exp()
        )
    }
}

/// The power law through `(x, e)` with x, e > 0 (others left out).
pub fn power(x: &[f64], e: &[f64]) -> Option<Power> {
    let (lx, le): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(e)
        .filter(|(a, b)| **a > 0.0 && **b > 0.0)
        .map(|(a, b)| (a.ln(), b.ln()))
        .unzip();
    linear(&lx, &le).map(|line| Power { line })
}

/// e = C exp(b x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exponential {
    /// The fit of ln e = ln C + b x.
    pub line: Line,
}

impl Exponential {
    /// C exp(b x).
    pub fn at(&self, x: f64) -> f64 {
        (self.line.intercept + self.line.slope * x).exp()
    }
}

impl fmt::Display for Exponential {
    /// `rate −2.31 ± 0.05 per unit x (R² …)`.
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let l = &self.line;
        write!(
            f,
            "e ∝ exp({:.3} x), ± {:.3} (least squares on ln e = ln C + b x: R² {:.5}, {} points; a factor 10 per {:.3} in x)",
            l.slope,
            l.slope_error,
            l.r2,
            l.n,
            (10f64).ln() / l.slope.abs()
        )
    }
}

/// The exponential through `(x, e)` with e > 0 (others left out).
pub fn exponential(x: &[f64], e: &[f64]) -> Option<Exponential> {
    let (xs, le): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(e)
        .filter(|(_, b)| **b > 0.0)
        .map(|(a, b)| (*a, b.ln()))
        .unzip();
    linear(&xs, &le).map(|line| Exponential { line })
}

/// e(x) = e0 + c x^p.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limit {
    /// The extrapolated limit e(0).
    pub e0: f64,
    /// c.
    pub c: f64,
    /// The exponent p.
    pub p: f64,
    /// RMS residual of the fit.
    pub rms: f64,
    /// Points fitted.
    pub n: usize,
}

impl Limit {
    /// e0 + c x^p.
    pub fn at(&self, x: f64) -> f64 {
        self.e0 + self.c * x.powf(self.p)
    }
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let (lo, hi) = crate::analysis::curves::ORDERS;
        write!(
            f,
            "limit {:.6} (least squares e = e0 + c x^p over p in [{lo}, {hi}]: p = {:.2}, c = {:.4e}, RMS residual {:.2e}, {} points)",
            self.e0, self.p, self.c, self.rms, self.n
        )
    }
}

/// The fit e = e0 + c x^p through `(x, e)` (x > 0): p by [`crate::analysis::curves::common_order`] on
/// this one series, then e0 and c by [`crate::analysis::curves::power_fit`]; `None` with fewer than
/// three points or no spread in e. With exactly three points the fit interpolates them.
pub fn limit(x: &[f64], e: &[f64]) -> Option<Limit> {
    let (xs, es): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(e)
        .filter(|(a, b)| **a > 0.0 && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip();
    let p = crate::analysis::curves::common_order(&[(xs.clone(), es.clone())])?;
    let (e0, c, rss) = crate::analysis::curves::power_fit(p, &xs, &es);
    Some(Limit {
        e0,
        c,
        p,
        rms: (rss / xs.len() as f64).sqrt(),
        n: xs.len(),
    })
}

/// Factor by which an error must fall from one refinement to the next to count as resolved.
pub const FALL: f64 = 0.9;

/// The residuals y_i − q(x_i) of the least-squares quadratic q(x) = a + b x + c x² through
/// `(x, y)` (x centred and scaled to [−1, 1] before the normal equations are solved); `None`
/// with fewer than three distinct x or a non-finite value.
pub fn quadratic(x: &[f64], y: &[f64]) -> Option<Vec<f64>> {
    if x.len() != y.len() || x.len() < 3 || x.iter().chain(y).any(|v| !v.is_finite()) {
        return None;
    }
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if hi <= lo {
        return None;
    }
    let t: Vec<f64> = x.iter().map(|v| (2.0 * v - lo - hi) / (hi - lo)).collect();
    // Normal equations M k = r for k = (a, b, c) in powers of t.
    let mut m = [[0.0f64; 4]; 3];
    for (ti, yi) in t.iter().zip(y) {
        let p = [1.0, *ti, ti * ti];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += p[i] * p[j];
            }
            m[i][3] += p[i] * yi;
        }
    }
    for col in 0..3 {
        let pivot = (col..3).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        m.swap(col, pivot);
        if m[col][col].abs() < 1e-12 {
            return None;
        }
        let pivot_row = m[col];
        for (row, r) in m.iter_mut().enumerate() {
            if row != col {
                let f = r[col] / pivot_row[col];
                for (x, p) in r.iter_mut().zip(pivot_row).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    let k: Vec<f64> = (0..3).map(|i| m[i][3] / m[i][i]).collect();
    Some(
        t.iter()
            .zip(y)
            .map(|(ti, yi)| yi - (k[0] + k[1] * ti + k[2] * ti * ti))
            .collect(),
    )
}

/// The number of leading errors of `e` (ordered coarse to fine) that are above the floor: the
/// run over which each error is finite, positive and at most [`FALL`] × the previous one. From
/// the first that is not (the error has stopped falling: round-off, a stop tolerance, or the
/// reference's own error), the points are on the floor, and a law fitted through them would
/// measure the floor, not the scheme.
pub fn resolved(e: &[f64]) -> usize {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    match e.first() {
        Some(&v) if ok(v) => {}
        _ => return 0,
    }
    1 + e
        .windows(2)
        .take_while(|w| ok(w[1]) && w[1] <= FALL * w[0])
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact power laws give their order back with zero standard error and R² = 1: errors
    /// 0.3 dt² over dt = 0.1 … 0.0125 fit to order 2 (to 1e-12).
    #[test]
    fn power_recovers_an_exact_order() {
        let x = [0.1, 0.05, 0.025, 0.0125];
        let e: Vec<f64> = x.iter().map(|v| 0.3 * v * v).collect();
        let f = power(&x, &e).unwrap();
        assert!((f.order() - 2.0).abs() < 1e-12, "{f}");
        assert!(f.line.slope_error < 1e-10 && (f.line.r2 - 1.0).abs() < 1e-12);
        assert!((f.at(0.2) - 0.012).abs() < 1e-14);
    }

    /// Noise of ±5% on a first-order law: the fitted order is 1 within 0.05 and the standard
    /// error is not zero (the noise pattern +, −, +, −, + changes ln e by at most 0.05 over
    /// ln x spanning 2.77, so the slope moves by at most 0.1/2.77 ≈ 0.036).
    #[test]
    fn power_with_noise_reports_an_error_bar() {
        let x = [0.16, 0.08, 0.04, 0.02, 0.01];
        let noise = [1.05, 0.95, 1.05, 0.95, 1.05];
        let e: Vec<f64> = x.iter().zip(noise).map(|(v, s)| 2.0 * v * s).collect();
        let f = power(&x, &e).unwrap();
        assert!((f.order() - 1.0).abs() < 0.05, "{f}");
        assert!(f.line.slope_error > 1e-3 && f.line.r2 < 1.0);
    }

    /// e = 1e-2 exp(−3 x) is recovered by the semi-log fit (rate −3 to 1e-12).
    #[test]
    fn exponential_recovers_the_rate() {
        let x = [1.0, 1.5, 2.0, 3.0];
        let e: Vec<f64> = x.iter().map(|v: &f64| 1e-2 * (-3.0 * v).exp()).collect();
        let f = exponential(&x, &e).unwrap();
        assert!((f.line.slope + 3.0).abs() < 1e-12 && (f.at(0.0) - 1e-2).abs() < 1e-14);
    }

    /// e = 1.2 + 0.8 x² sampled at four x: the extrapolated limit 1.2 and the exponent 2 are
    /// recovered (both to 1e-9: the order search is refined by golden section).
    #[test]
    fn limit_recovers_e0_and_the_exponent() {
        let x = [0.1, 0.075, 0.05, 0.025];
        let e: Vec<f64> = x.iter().map(|v| 1.2 + 0.8 * v * v).collect();
        let f = limit(&x, &e).unwrap();
        assert!((f.p - 2.0).abs() < 1e-9 && (f.e0 - 1.2).abs() < 1e-9, "{f}");
        assert!(limit(&x[..2], &e[..2]).is_none());
    }

    /// A law that falls then flattens (round-off at 1e-12) is resolved up to its last falling
    /// point; a series that never falls (the sphere's |e − 1| at the stop tolerance) has one
    /// resolved point, so nothing to fit.
    #[test]
    fn the_floor_is_left_out() {
        assert_eq!(resolved(&[1e-2, 1e-4, 1e-8, 1e-12, 1.1e-12, 0.9e-12]), 4);
        assert_eq!(resolved(&[3.2e-6, 1.7e-6, 3.2e-6, 3.3e-8]), 2);
        assert_eq!(resolved(&[1e-3, f64::NAN, 1e-5]), 1);
        assert_eq!(resolved(&[]), 0);
    }

    /// A quadratic law is fitted exactly (residuals below 1e-12 at x ~ 4e-3, where a fit in
    /// raw powers would lose six digits), a zig-zag of ±1e-4 on it leaves residuals of that
    /// size, and two distinct x give no fit.
    #[test]
    fn quadratic_residuals_measure_what_is_not_smooth() {
        let x: Vec<f64> = [16.0, 16.25, 16.5, 16.75, 17.0]
            .iter()
            .map(|r: &f64| (1.0 / r).powi(2))
            .collect();
        let smooth: Vec<f64> = x.iter().map(|v| 1.5 - 3.0 * v + 40.0 * v * v).collect();
        let r = quadratic(&x, &smooth).unwrap();
        assert!(r.iter().all(|v| v.abs() < 1e-12), "{r:?}");
        let zigzag: Vec<f64> = smooth
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 2 == 0 { 1e-4 } else { -1e-4 })
            .collect();
        let worst = quadratic(&x, &zigzag)
            .unwrap()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(worst > 3e-5 && worst < 2e-4, "{worst}");
        assert!(quadratic(&[1.0, 1.0, 2.0], &[1.0, 2.0, 3.0]).is_none());
    }

    /// Fewer than two usable points give no fit; non-positive errors are left out.
    #[test]
    fn degenerate_input_gives_none() {
        assert!(power(&[1.0], &[1.0]).is_none());
        assert!(power(&[1.0, 2.0], &[0.0, 1.0]).is_none());
        assert!(linear(&[1.0, 1.0], &[1.0, 2.0]).is_none());
    }
}
