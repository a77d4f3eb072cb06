//! The time series of a run: one [`Record`] per recorded step, written to `timeseries.csv`
//! with the contract's columns first.

use crate::engines::Engine;
use crate::error::{Error, Result};
use serde::Serialize;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// One row of `timeseries.csv` (and the `"final"` object of `summary.json`).
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Record {
    /// Accepted steps so far.
    pub step: usize,
    /// Simulated time.
    pub t: f64,
    /// The step that produced this state (0 for the initial state).
    pub dt: f64,
    /// F_sc.
    pub energy: f64,
    /// Diffuse area A.
    pub area: f64,
    /// Diffuse volume V.
    pub volume: f64,
    /// v (docs/src/theory/model.md).
    pub reduced_volume: f64,
    /// e (docs/src/theory/model.md).
    pub reduced_energy: f64,
    /// σ.
    pub sigma: f64,
    /// Stationarity residual: RMS over the full box of μ − μ̄ (docs/src/reference/outputs.md).
    pub residual: f64,
    /// max|φ^{n+1} − φ^n|/Δt of the step that produced this state (NaN for the initial state
    /// and for the relaxational engine, whose time is nominal).
    pub rate: f64,
    /// Rejected attempts so far (adaptive stepping).
    pub rejected: usize,
    /// Wall-clock seconds since the time loop started.
    pub wall_seconds: f64,
    /// With an area-difference term (ADE or the bilayer couple): its columns; then
    /// `reduced_energy` is w.
    #[serde(flatten)]
    pub couple: Option<CoupleColumns>,
    /// With the Stokes dynamics: its columns.
    #[serde(flatten)]
    pub flow: Option<FlowColumns>,
}

/// The columns of a run with the Stokes dynamics (docs/src/theory/flow.md), after the others.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct FlowColumns {
    /// max|u| over the grid.
    pub max_speed: f64,
    /// η∫|∇u|² (∫2η|D(u)|² with unequal viscosities), the energy the fluid dissipates per
    /// unit time.
    pub dissipation: f64,
    /// The most conjugate-gradient iterations one Stokes solve of the step's last evaluation
    /// took (0 at equal viscosities, whose solve is direct).
    pub stokes_iterations: f64,
}

/// The names of [`FlowColumns`], as the CSV header appends them.
pub const FLOW_COLUMNS: [&str; 3] = ["max_speed", "dissipation", "stokes_iterations"];

impl FlowColumns {
    /// The values in the order of [`FLOW_COLUMNS`].
    pub fn values(&self) -> [f64; 3] {
        [self.max_speed, self.dissipation, self.stokes_iterations]
    }
}

/// The columns of a run with an area-difference term (docs/src/theory/ade.md), after the
/// others.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct CoupleColumns {
    /// e, the reduced bending energy.
    pub bending_energy: f64,
    /// Δa = M/M₁.
    pub da: f64,
    /// w = e + πα(Δa − Δa0)² (e for the bilayer couple).
    pub w: f64,
    /// c̄0,eff = c̄0 + 2πα(Δa0 − Δa), or c̄0 − λM₁/E₁ for the bilayer couple.
    pub c0_eff: f64,
    /// λ, the term's multiplier.
    pub lambda: f64,
}

/// The names of [`CoupleColumns`], as the CSV header appends them.
pub const COUPLE_COLUMNS: [&str; 5] = ["bending_energy", "da", "w", "c0_eff", "lambda"];

impl CoupleColumns {
    /// The values in the order of [`COUPLE_COLUMNS`].
    pub fn values(&self) -> [f64; 5] {
        [
            self.bending_energy,
            self.da,
            self.w,
            self.c0_eff,
            self.lambda,
        ]
    }
}

impl Record {
    /// The values in the order of [`COLUMNS`] (the counts as floats).
    pub fn values(&self) -> [f64; 13] {
        [
            self.step as f64,
            self.t,
            self.dt,
            self.energy,
            self.area,
            self.volume,
            self.reduced_volume,
            self.reduced_energy,
            self.sigma,
            self.residual,
            self.rate,
            self.rejected as f64,
            self.wall_seconds,
        ]
    }

    /// The names of this record's columns: [`COLUMNS`], then [`COUPLE_COLUMNS`] and
    /// [`FLOW_COLUMNS`] when it has them (the header its `timeseries.csv` is written with).
    pub fn names(&self) -> Vec<&'static str> {
        let mut names = COLUMNS.to_vec();
        if self.couple.is_some() {
            names.extend(COUPLE_COLUMNS);
        }
        if self.flow.is_some() {
            names.extend(FLOW_COLUMNS);
        }
        names
    }

    /// The values after [`COLUMNS`]: the couple's, then the flow's, when the record has them.
    fn extra_values(&self) -> Vec<f64> {
        let couple = self.couple.iter().flat_map(|c| c.values());
        couple
            .chain(self.flow.iter().flat_map(|f| f.values()))
            .collect()
    }

    /// The value of the column `name` of [`Record::names`], if the record has it.
    pub fn get(&self, name: &str) -> Option<f64> {
        if let Some(i) = COLUMNS.iter().position(|c| *c == name) {
            return Some(self.values()[i]);
        }
        if let Some(i) = COUPLE_COLUMNS.iter().position(|c| *c == name) {
            return self.couple.map(|c| c.values()[i]);
        }
        let i = FLOW_COLUMNS.iter().position(|c| *c == name)?;
        self.flow.map(|f| f.values()[i])
    }

    /// A record of the state `engine` holds at `step`, time `t`, reached by a step `dt`, in a
    /// scene of dimension `dim`, width `eps` (`rate` NaN, counters 0).
    pub fn of(step: usize, t: f64, dt: f64, engine: &dyn Engine, dim: usize, eps: f64) -> Self {
        let m = engine.measures();
        let r = m.reduced(dim, eps);
        let couple = engine.area_difference().map(|term| {
            let lambda = engine.lambda();
            let w = r.energy + term.reduced_energy(m.curvature);
            CoupleColumns {
                bending_energy: r.energy,
                da: term.da(m.curvature),
                w,
                c0_eff: term.c0_eff(m.curvature, lambda),
                lambda,
            }
        });
        Record {
            step,
            t,
            dt,
            energy: m.energy,
            area: m.area,
            volume: m.volume,
            reduced_volume: r.volume,
            reduced_energy: couple.map_or(r.energy, |c| c.w),
            sigma: engine.sigma(),
            residual: engine.residual(),
            rate: f64::NAN,
            rejected: 0,
            wall_seconds: 0.0,
            couple,
            flow: engine.flow().map(|f| FlowColumns {
                max_speed: f.max_speed,
                dissipation: f.dissipation,
                stokes_iterations: f.solve_iterations as f64,
            }),
        }
    }
}

/// The columns of `timeseries.csv` ([`HEADER`]), in order.
pub const COLUMNS: [&str; 13] = [
    "step",
    "t",
    "dt",
    "energy",
    "area",
    "volume",
    "reduced_volume",
    "reduced_energy",
    "sigma",
    "residual",
    "rate",
    "rejected",
    "wall_seconds",
];

/// The CSV header: the contract's ten columns, then `rate,rejected,wall_seconds`.
pub const HEADER: &str =
    "step,t,dt,energy,area,volume,reduced_volume,reduced_energy,sigma,residual,\
rate,rejected,wall_seconds";

/// Writes `timeseries.csv` row by row (values in shortest round-trip form). The header comes
/// with the first row (with [`COUPLE_COLUMNS`] or [`FLOW_COLUMNS`] appended when its record has
/// them), or at the first flush of a file with no rows.
pub struct TimeSeries {
    path: PathBuf,
    out: BufWriter<File>,
    header_written: bool,
}

impl TimeSeries {
    /// Create the file (the header follows with the first row).
    ///
    /// # Errors
    /// `Error::Io` if the file cannot be created.
    pub fn create(path: &Path) -> Result<Self> {
        let file = File::create(path).map_err(|source| io(path, source))?;
        Ok(TimeSeries {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            header_written: false,
        })
    }

    /// Write the header if it is not yet written: the names of `first`, the first row's record
    /// (without a row, [`HEADER`]).
    fn header(&mut self, first: Option<&Record>) -> Result<()> {
        if self.header_written {
            return Ok(());
        }
        self.header_written = true;
        let header = first.map_or(HEADER.to_string(), |r| r.names().join(","));
        writeln!(self.out, "{header}").map_err(|e| io(&self.path, e))
    }

    /// Continue the file at `path` after its row of `step`: rows of later steps (written after
    /// the checkpoint a run resumes from) are dropped, the rest kept and returned, and rows are
    /// appended from there.
    ///
    /// # Errors
    /// `Error::Io` if the file cannot be read or written; `Error::Config` on field
    /// `timeseries.csv` if it is not this program's time series.
    pub fn resume(path: &Path, step: usize) -> Result<(Self, Vec<Record>)> {
        let text = std::fs::read_to_string(path).map_err(|source| io(path, source))?;
        let mut lines = text.lines();
        let couple_header = format!("{HEADER},{}", COUPLE_COLUMNS.join(","));
        let flow_header = format!("{HEADER},{}", FLOW_COLUMNS.join(","));
        if !matches!(lines.next(), Some(h) if h == HEADER || h == couple_header || h == flow_header)
        {
            return Err(Error::config(
                "timeseries.csv",
                format!("{} does not start with the header {HEADER}", path.display()),
            ));
        }
        let mut kept = Vec::new();
        for (i, line) in lines.enumerate() {
            let r = parse_row(line).ok_or_else(|| {
                Error::config(
                    "timeseries.csv",
                    format!("{}: row {} is not a time-series row", path.display(), i + 2),
                )
            })?;
            if r.step > step {
                break;
            }
            kept.push(r);
        }
        // Rewrite beside the file and rename over it: a crash leaves the old file or the new.
        let tmp = path.with_extension("csv.tmp");
        let mut ts = TimeSeries::create(&tmp)?;
        for r in &kept {
            ts.write_row(r)?;
        }
        ts.flush()?;
        std::fs::rename(&tmp, path).map_err(|source| io(path, source))?;
        ts.path = path.to_path_buf();
        Ok((ts, kept))
    }

    /// Append one row and flush it, so that a crash keeps every row written.
    ///
    /// # Errors
    /// `Error::Io` on a write failure.
    pub fn push(&mut self, r: &Record) -> Result<()> {
        self.write_row(r)?;
        self.flush()
    }

    fn write_row(&mut self, r: &Record) -> Result<()> {
        self.header(Some(r))?;
        write!(
            self.out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.step,
            r.t,
            r.dt,
            r.energy,
            r.area,
            r.volume,
            r.reduced_volume,
            r.reduced_energy,
            r.sigma,
            r.residual,
            r.rate,
            r.rejected,
            r.wall_seconds
        )
        .map_err(|e| io(&self.path, e))?;
        for v in r.extra_values() {
            write!(self.out, ",{v}").map_err(|e| io(&self.path, e))?;
        }
        writeln!(self.out).map_err(|e| io(&self.path, e))
    }

    /// Flush buffered rows to disk.
    ///
    /// # Errors
    /// `Error::Io` on a write failure.
    pub fn flush(&mut self) -> Result<()> {
        self.header(None)?;
        self.out.flush().map_err(|e| io(&self.path, e))
    }
}

/// A row of the file back into a record (the inverse of [`TimeSeries::push`]).
fn parse_row(line: &str) -> Option<Record> {
    let mut f = line.split(',');
    let mut x = || f.next()?.parse::<f64>().ok();
    let count = |v: f64| (v >= 0.0 && v.fract() == 0.0).then_some(v as usize);
    let r = Record {
        step: count(x()?)?,
        t: x()?,
        dt: x()?,
        energy: x()?,
        area: x()?,
        volume: x()?,
        reduced_volume: x()?,
        reduced_energy: x()?,
        sigma: x()?,
        residual: x()?,
        rate: x()?,
        rejected: count(x()?)?,
        wall_seconds: x()?,
        couple: None,
        flow: None,
    };
    let rest: Vec<f64> = f.map(|v| v.parse::<f64>().ok()).collect::<Option<_>>()?;
    let couple = match rest[..] {
        [bending_energy, da, w, c0_eff, lambda] => Some(CoupleColumns {
            bending_energy,
            da,
            w,
            c0_eff,
            lambda,
        }),
        _ => None,
    };
    let flow = match rest[..] {
        [max_speed, dissipation, stokes_iterations] => Some(FlowColumns {
            max_speed,
            dissipation,
            stokes_iterations,
        }),
        _ => None,
    };
    let known = [0, COUPLE_COLUMNS.len(), FLOW_COLUMNS.len()];
    known
        .contains(&rest.len())
        .then_some(Record { couple, flow, ..r })
}

fn io(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header the file is written with names the columns of [`COLUMNS`], in order.
    #[test]
    fn header_lists_the_columns() {
        assert_eq!(HEADER, COLUMNS.join(","));
    }
}
