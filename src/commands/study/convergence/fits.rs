//! The convergence study's fits: the laws fitted to each series above its floor
//! ([`crate::commands::study::fit`]), as quoted in the table and `fits.csv`.

use super::measure::Row;
use crate::commands::study::fit;

/// A fit quoted by the study; a row of `fits.csv`.
#[derive(Clone, Debug)]
pub struct Quoted {
    /// Part and series it belongs to.
    pub part: &'static str,
    /// Series name.
    pub series: String,
    /// The law: `power`, `exponential`, `limit e`, `limit v`.
    pub law: &'static str,
    /// The order, rate or limit.
    pub value: f64,
    /// Its standard error (NaN for limits), or the fitted exponent of a limit.
    pub spread: f64,
    /// Printed form.
    pub text: String,
}

/// The series of `part`, in order of appearance.
pub fn series_of<'a>(rows: &'a [Row], part: &str) -> Vec<(&'a str, Vec<&'a Row>)> {
    let mut out: Vec<(&str, Vec<&Row>)> = Vec::new();
    for r in rows.iter().filter(|r| r.part == part) {
        match out.iter_mut().find(|(n, _)| *n == r.series) {
            Some((_, v)) => v.push(r),
            None => out.push((r.series.as_str(), vec![r])),
        }
    }
    out
}

/// The values `f` takes on the rows `rs`.
fn column(rs: &[&Row], f: impl Fn(&Row) -> f64) -> Vec<f64> {
    rs.iter().map(|r| f(r)).collect()
}

/// The points of a series above its floor ([`fit::resolved`]), coarse to fine (x falling):
/// `(x, error)` with the error taken by `err`; the laws are fitted to these only.
pub fn resolved(rs: &[&Row], err: impl Fn(&Row) -> f64) -> (Vec<f64>, Vec<f64>) {
    let mut pts: Vec<(f64, f64)> = rs.iter().map(|r| (r.x, err(r))).collect();
    pts.sort_by(|a, b| b.0.total_cmp(&a.0));
    let keep = fit::resolved(&pts.iter().map(|p| p.1).collect::<Vec<_>>());
    pts.truncate(keep);
    pts.into_iter().unzip()
}

/// Points fitted, for the quoted text: `, 4 of 6 points above the floor` when some were left.
fn floor_note(kept: usize, all: usize) -> String {
    if kept < all {
        format!("; {kept} of {all} points above the floor fitted")
    } else {
        String::new()
    }
}

/// The laws quoted for every series of `rows`: time and FD space a power law, spectral space
/// an exponential in ε/h, ε/R0 a power law of |e − e_ref(v)| and the extrapolated limits of e
/// and v (the sphere: an exponential in R0/ε); each through the points above the floor.
pub fn fits(rows: &[Row]) -> Vec<Quoted> {
    let mut q = Vec::new();
    let mut push = |part, series: &str, law, value, spread, text: String| {
        q.push(Quoted {
            part,
            series: series.to_string(),
            law,
            value,
            spread,
            text,
        })
    };
    for (name, rs) in series_of(rows, "time") {
        let (x, e) = resolved(&rs, |r| r.error);
        if let Some(f) = fit::power(&x, &e) {
            let note = floor_note(x.len(), rs.len());
            push(
                "time",
                name,
                "power",
                f.order(),
                f.line.slope_error,
                format!("{f}{note}"),
            );
        }
    }
    for (name, rs) in series_of(rows, "space") {
        let (x, e) = resolved(&rs, |r| r.error);
        let note = floor_note(x.len(), rs.len());
        if name.starts_with("FD") {
            if let Some(f) = fit::power(&x, &e) {
                push(
                    "space",
                    name,
                    "power",
                    f.order(),
                    f.line.slope_error,
                    format!("{f}{note}"),
                );
            }
        } else {
            let inv: Vec<f64> = x.iter().map(|h| 1.0 / h).collect();
            if let Some(f) = fit::exponential(&inv, &e) {
                push(
                    "space",
                    name,
                    "exponential",
                    f.line.slope,
                    f.line.slope_error,
                    format!("{f} with x = eps/h{note}"),
                );
            }
        }
    }
    for (name, rs) in series_of(rows, "eps") {
        let (x, err) = resolved(&rs, |r| r.error.abs());
        let note = floor_note(x.len(), rs.len());
        if name == "sphere" {
            let inv: Vec<f64> = x.iter().map(|v| 1.0 / v).collect();
            // Three points above the floor at least: with two, a line fits any pair.
            if let Some(f) = fit::exponential(&inv, &err).filter(|_| x.len() >= 3) {
                push(
                    "eps",
                    name,
                    "exponential",
                    f.line.slope,
                    f.line.slope_error,
                    format!("|e - 1|: {f} with x = R0/eps{note}"),
                );
            }
            continue;
        }
        if let Some(f) = fit::power(&x, &err).filter(|_| x.len() >= 3) {
            push(
                "eps",
                name,
                "power",
                f.order(),
                f.line.slope_error,
                format!("|e - e_ref(v)|: {f}{note}"),
            );
        }
        let all_x = column(&rs, |r| r.x);
        if let Some(f) = fit::limit(&all_x, &column(&rs, |r| r.e)) {
            push("eps", name, "limit e", f.e0, f.p, format!("e: {f}"));
        }
        if let Some(f) = fit::limit(&all_x, &column(&rs, |r| r.v)) {
            push(
                "eps",
                name,
                "limit v",
                f.e0,
                f.p,
                format!("v (phi = 0): {f}"),
            );
        }
    }
    q
}

/// A series' floor, for the table: where the error stopped falling, if it did.
pub fn floor_line(rs: &[&Row], err: impl Fn(&Row) -> f64) -> Option<String> {
    let (x, _) = resolved(rs, &err);
    (x.len() < rs.len()).then(|| {
        let lo = rs.iter().map(|r| err(r)).fold(f64::INFINITY, f64::min);
        format!(
            "  floor: the error stops falling after {} of {} points (smallest {lo:.2e}); no law is fitted through the rest",
            x.len(),
            rs.len()
        )
    })
}
