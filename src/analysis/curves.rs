//! Curves given by scattered points `(x, y)`: local cubic interpolation, crossings of two
//! curves, and the power-law fit `y = y∞ + c x^p` behind the extrapolations in ε/R0.

/// The cubic (fewer points at short lists) through the four points of `pts` (sorted by `x`)
/// nearest to `x` in index, evaluated at `x` (Lagrange form).
pub fn cubic_at(pts: &[(f64, f64)], x: f64) -> f64 {
    let n = pts.len();
    let i = pts.partition_point(|p| p.0 < x).clamp(1, n.max(2) - 1);
    let lo = i.saturating_sub(2).min(n.saturating_sub(4));
    let stencil = &pts[lo..(lo + 4).min(n)];
    stencil
        .iter()
        .enumerate()
        .map(|(j, &(xj, yj))| {
            stencil
                .iter()
                .enumerate()
                .filter(|(m, _)| *m != j)
                .fold(yj, |acc, (_, &(xm, _))| acc * (x - xm) / (xj - xm))
        })
        .sum()
}

/// Where the curves through `a` and `b` (each sorted by `x`, two or more points) cross: the
/// sign changes of `cubic_at(a) − cubic_at(b)` at the points of both curves, each refined by
/// bisection to round-off. The range searched is the one both curves cover, widened at each
/// end by half the spacing of the nearer end points of the curve that ends there (a crossing
/// just beyond the last point of one curve is found from its end cubic). Curves whose widened
/// ranges do not overlap (one ends before the other starts) have no crossing: the roots of
/// the two end cubics extrapolated across the gap would be no point of either curve.
pub fn crossings(a: &[(f64, f64)], b: &[(f64, f64)]) -> Vec<f64> {
    if a.len() < 2 || b.len() < 2 {
        return Vec::new();
    }
    let start = |c: &[(f64, f64)]| c[0].0 - 0.5 * (c[1].0 - c[0].0);
    let end = |c: &[(f64, f64)]| {
        let n = c.len();
        c[n - 1].0 + 0.5 * (c[n - 1].0 - c[n - 2].0)
    };
    let lo = start(a).max(start(b)).max(a[0].0.min(b[0].0));
    let hi = end(a)
        .min(end(b))
        .min(a[a.len() - 1].0.max(b[b.len() - 1].0));
    if lo >= hi {
        return Vec::new();
    }
    let mut xs: Vec<f64> = a
        .iter()
        .chain(b)
        .map(|p| p.0)
        .filter(|x| *x >= lo && *x <= hi)
        .chain([lo, hi])
        .collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let gap = |x: f64| cubic_at(a, x) - cubic_at(b, x);
    let mut roots = Vec::new();
    for w in xs.windows(2) {
        let (mut x0, mut x1) = (w[0], w[1]);
        let (g0, g1) = (gap(x0), gap(x1));
        if g0 == 0.0 {
            roots.push(x0);
            continue;
        }
        if g0 * g1 >= 0.0 {
            continue;
        }
        for _ in 0..80 {
            let mid = 0.5 * (x0 + x1);
            if gap(mid).signum() == g0.signum() {
                x0 = mid;
            } else {
                x1 = mid;
            }
        }
        roots.push(0.5 * (x0 + x1));
    }
    if let Some(&x) = xs.last().filter(|x| gap(**x) == 0.0) {
        roots.push(x);
    }
    roots.dedup_by(|p, q| (*p - *q).abs() < 1e-12);
    roots
}

/// Least-squares fit of `y_k = y∞ + c x_k^p` at a given order `p`: `(y∞, c, Σ residual²)`.
/// Needs two or more distinct `x`.
pub fn power_fit(p: f64, xs: &[f64], ys: &[f64]) -> (f64, f64, f64) {
    let n = xs.len() as f64;
    let t: Vec<f64> = xs.iter().map(|x| x.powf(p)).collect();
    let (mt, my) = (t.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let stt: f64 = t.iter().map(|t| (t - mt).powi(2)).sum();
    let sty: f64 = t.iter().zip(ys).map(|(t, y)| (t - mt) * (y - my)).sum();
    let c = sty / stt;
    let y0 = my - c * mt;
    let rss = t
        .iter()
        .zip(ys)
        .map(|(t, y)| (y - y0 - c * t).powi(2))
        .sum();
    (y0, c, rss)
}

/// Orders searched by [`common_order`].
pub const ORDERS: (f64, f64) = (0.5, 6.0);

/// The order `p` shared by all `series` (each `(x_k, y_k)` with three or more points) that
/// minimises `Σ_series rss(p) / Σ_k (y_k − ȳ)²` of [`power_fit`] (the unexplained fraction of
/// each series' variation, so series of every size count alike), by a grid search over
/// [`ORDERS`] in steps of 0.01 refined by golden section. `None` without such a series.
pub fn common_order(series: &[(Vec<f64>, Vec<f64>)]) -> Option<f64> {
    let usable: Vec<_> = series
        .iter()
        .filter(|(xs, ys)| xs.len() >= 3 && spread(ys) > 0.0)
        .collect();
    if usable.is_empty() {
        return None;
    }
    let cost = |p: f64| -> f64 {
        usable
            .iter()
            .map(|(xs, ys)| power_fit(p, xs, ys).2 / spread(ys))
            .sum()
    };
    let step = 0.01;
    let steps = ((ORDERS.1 - ORDERS.0) / step).round() as usize;
    let best = (0..=steps)
        .map(|i| ORDERS.0 + step * i as f64)
        .min_by(|a, b| cost(*a).total_cmp(&cost(*b)))?;
    let (mut a, mut b) = ((best - step).max(ORDERS.0), (best + step).min(ORDERS.1));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if cost(c) < cost(d) {
            b = d;
        } else {
            a = c;
        }
    }
    Some(0.5 * (a + b))
}

/// `Σ (y − ȳ)²`.
fn spread(ys: &[f64]) -> f64 {
    let m = ys.iter().sum::<f64>() / ys.len() as f64;
    ys.iter().map(|y| (y - m).powi(2)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two lines that would cross at x = 4 if extrapolated, one given on [0, 3] and the other
    /// on [5, 8]: no crossing (before the guard, the search ran from the later start down to
    /// the earlier end and returned 4).
    #[test]
    fn curves_that_do_not_overlap_do_not_cross() {
        let a: Vec<(f64, f64)> = (0..4).map(|i| (i as f64, 1.0 + 0.3 * i as f64)).collect();
        let b: Vec<(f64, f64)> = (5..9).map(|i| (i as f64, 3.0 - 0.2 * i as f64)).collect();
        assert_eq!(crossings(&a, &b), Vec::<f64>::new());
        // Overlapping on [2, 3], lines that meet at 2.5 cross there.
        let b: Vec<(f64, f64)> = (2..9).map(|i| (i as f64, 2.25 - 0.2 * i as f64)).collect();
        let x = crossings(&a, &b);
        assert!(x.len() == 1 && (x[0] - 2.5).abs() < 1e-9, "{x:?}");
    }

    #[test]
    fn cubic_interpolation_is_exact_for_cubics() {
        let f = |x: f64| 1.0 - 2.0 * x + 0.5 * x * x - x * x * x;
        let pts: Vec<(f64, f64)> = (0..9).map(|i| 0.1 * i as f64).map(|x| (x, f(x))).collect();
        for x in [0.0, 0.05, 0.33, 0.71, 0.8] {
            assert!((cubic_at(&pts, x) - f(x)).abs() < 1e-12);
        }
    }

    /// Two cubics on different point sets cross where their difference vanishes.
    #[test]
    fn crossings_of_scattered_curves() {
        let a: Vec<(f64, f64)> = (0..7)
            .map(|i| 0.5 + 0.05 * i as f64)
            .map(|x| (x, 3.0 - 2.0 * x))
            .collect();
        let b: Vec<(f64, f64)> = (0..6)
            .map(|i| 0.52 + 0.06 * i as f64)
            .map(|x| (x, 1.7 - (x - 0.6) * 0.5 + (x - 0.6).powi(2)))
            .collect();
        // With u = x − 0.6: 1.8 − 2u = 1.7 − 0.5u + u²  ⇔  u² + 1.5u − 0.1 = 0.
        let root = 0.6 + (-1.5 + 2.65f64.sqrt()) / 2.0;
        let found = crossings(&a, &b);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!((found[0] - root).abs() < 1e-12, "{} vs {root}", found[0]);
    }

    /// Data following a power law exactly give back its order and limit.
    #[test]
    fn power_law_order_and_limit_are_recovered() {
        let xs: Vec<f64> = vec![1.0 / 12.0, 1.0 / 18.0, 1.0 / 24.0, 1.0 / 36.0];
        let series: Vec<(Vec<f64>, Vec<f64>)> = [(1.3, 2.0), (2.1, -5.0), (0.9, 40.0)]
            .iter()
            .map(|&(y0, c)| {
                (
                    xs.clone(),
                    xs.iter().map(|x| y0 + c * x.powf(2.7)).collect(),
                )
            })
            .collect();
        let p = common_order(&series).expect("fit");
        assert!((p - 2.7).abs() < 1e-6, "p = {p}");
        let (y0, c, rss) = power_fit(p, &series[1].0, &series[1].1);
        assert!((y0 - 2.1).abs() < 1e-9 && (c + 5.0).abs() < 1e-6 && rss < 1e-20);
    }
}
