//! The studies' tables: a row type describes its columns once ([`Row::columns`]: the CSV name,
//! the printed label and unit, the printed format, the value), and the same rows are written as
//! a CSV file ([`csv()`]) and as an aligned text table ([`text`]).
//!
//! * **CSV**: a header of the column names, one record per row; every value through the csv
//!   crate's serde writer: a float in the shortest form that reads back to the same bits (`NaN`,
//!   `inf`), a count as an integer, a name quoted only where it holds a comma or a quote.
//!   Columns without a name (printed only) are left out.
//! * **Text**: the columns with a label, headed `label [unit]`, each as wide as its widest
//!   cell, two spaces apart, the table indented by two; numbers right-aligned, names
//!   left-aligned; a float in the column's [`Format`]; a missing value (a NaN, an empty name)
//!   shown as the column's placeholder (`-` unless set). Columns without a label (CSV only) are
//!   left out.

use crate::error::{Error, Result};
use serde::ser::{Serialize, Serializer};

/// One value of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell<'r> {
    /// A measured or derived number.
    Float(f64),
    /// A count (steps, evaluations, pieces).
    Int(usize),
    /// A name or a class.
    Text(&'r str),
}

impl From<f64> for Cell<'_> {
    fn from(x: f64) -> Self {
        Cell::Float(x)
    }
}

impl From<usize> for Cell<'_> {
    fn from(n: usize) -> Self {
        Cell::Int(n)
    }
}

impl<'r> From<&'r str> for Cell<'r> {
    fn from(s: &'r str) -> Self {
        Cell::Text(s)
    }
}

impl Serialize for Cell<'_> {
    /// As the value it holds (`f64`, `usize`, `str`): a CSV field as serde writes that type.
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match *self {
            Cell::Float(x) => s.serialize_f64(x),
            Cell::Int(n) => s.serialize_u64(n as u64),
            Cell::Text(t) => s.serialize_str(t),
        }
    }
}

/// One column of a study's table as typed values (what the library returns beside the CSV file).
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Counts.
    Int(Vec<i64>),
    /// Numbers (NaN where a value is missing).
    Float(Vec<f64>),
    /// Names and classes.
    Text(Vec<String>),
}

/// A study's table as typed columns: the CSV file `name.csv`'s columns, from the same rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The CSV file's stem (`stability` for `stability.csv`).
    pub name: String,
    /// `(CSV header, values)` in the file's order.
    pub columns: Vec<(String, Values)>,
}

/// How a float is printed in the text table (counts and names print as they are).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// The shortest form that reads back (`{}`): values given in the study file.
    Plain,
    /// `n` decimals (`{:.n}`).
    Fixed(usize),
    /// `n` decimals in scientific notation (`{:.ne}`).
    Sci(usize),
}

/// One column of a row type: where it appears (CSV, text or both), how it is printed, and its
/// value in a row.
pub struct Column<R> {
    /// The CSV header (`None`: printed only).
    name: Option<&'static str>,
    /// The text header (`None`: CSV only).
    label: Option<&'static str>,
    /// The unit, printed after the label in brackets.
    unit: Option<&'static str>,
    /// The printed form of a float.
    format: Format,
    /// What a missing value (NaN, empty name) prints as.
    missing: &'static str,
    /// The value in a row.
    value: for<'r> fn(&'r R) -> Cell<'r>,
}

impl<R> Column<R> {
    /// A column of the CSV file only, headed `name`.
    pub fn csv(name: &'static str, value: for<'r> fn(&'r R) -> Cell<'r>) -> Self {
        Column {
            name: Some(name),
            label: None,
            unit: None,
            format: Format::Plain,
            missing: "-",
            value,
        }
    }

    /// A column of the CSV file (headed `name`) that is also printed (headed `label`, floats
    /// in `format`).
    pub fn both(
        name: &'static str,
        label: &'static str,
        format: Format,
        value: for<'r> fn(&'r R) -> Cell<'r>,
    ) -> Self {
        Column {
            label: Some(label),
            format,
            ..Column::csv(name, value)
        }
    }

    /// A printed column that the CSV file does not have (derived for reading only).
    pub fn text(label: &'static str, format: Format, value: for<'r> fn(&'r R) -> Cell<'r>) -> Self {
        Column {
            name: None,
            ..Column::both("", label, format, value)
        }
    }

    /// The unit of the printed header: `wall [s]`.
    pub fn unit(self, unit: &'static str) -> Self {
        Column {
            unit: Some(unit),
            ..self
        }
    }

    /// What a missing value prints as (`-` unless set).
    pub fn or(self, missing: &'static str) -> Self {
        Column { missing, ..self }
    }

    /// The printed header: the label, and the unit in brackets.
    fn header(&self) -> String {
        let label = self.label.unwrap_or_default();
        match self.unit {
            Some(u) => format!("{label} [{u}]"),
            None => label.to_string(),
        }
    }

    /// The printed form of `cell`.
    fn show(&self, cell: Cell) -> String {
        match cell {
            Cell::Float(x) if x.is_nan() => self.missing.to_string(),
            Cell::Float(x) => match self.format {
                Format::Plain => format!("{x}"),
                Format::Fixed(n) => format!("{x:.n$}"),
                Format::Sci(n) => format!("{x:.n$e}"),
            },
            Cell::Int(n) => n.to_string(),
            Cell::Text("") => self.missing.to_string(),
            Cell::Text(t) => t.to_string(),
        }
    }
}

/// A row type of a study table.
pub trait Row: Sized {
    /// The columns, in the order of the CSV file and of the text table.
    fn columns() -> Vec<Column<Self>>;
}

/// The CSV columns of `rows` as typed values, the table named `name`: a column of counts is
/// [`Values::Int`], of numbers [`Values::Float`], of names [`Values::Text`] (by its cells' kind;
/// a column whose cells are of mixed kinds, none in this program, is given as text).
pub fn typed<'r, R: Row + 'r>(name: &str, rows: impl IntoIterator<Item = &'r R>) -> Table {
    let rows: Vec<&R> = rows.into_iter().collect();
    let values = |c: &Column<R>| -> Values {
        let cells: Vec<Cell> = rows.iter().map(|r| (c.value)(r)).collect();
        let ints: Option<Vec<i64>> = cells
            .iter()
            .map(|v| match v {
                Cell::Int(n) => Some(*n as i64),
                _ => None,
            })
            .collect();
        let floats: Option<Vec<f64>> = cells
            .iter()
            .map(|v| match v {
                Cell::Float(x) => Some(*x),
                _ => None,
            })
            .collect();
        match (ints, floats) {
            (Some(i), _) if !cells.is_empty() => Values::Int(i),
            (_, Some(f)) => Values::Float(f),
            _ => Values::Text(
                cells
                    .iter()
                    .map(|v| match v {
                        Cell::Text(t) => t.to_string(),
                        Cell::Int(n) => n.to_string(),
                        Cell::Float(x) => x.to_string(),
                    })
                    .collect(),
            ),
        }
    };
    let columns = R::columns()
        .into_iter()
        .filter_map(|c| c.name.map(|n| (n.to_string(), values(&c))))
        .collect();
    Table {
        name: name.strip_suffix(".csv").unwrap_or(name).to_string(),
        columns,
    }
}

/// `rows` as CSV: the named columns ([`Column::csv`], [`Column::both`]).
///
/// # Errors
/// `Error::Config` if a record cannot be written (a bug).
pub fn csv<'r, R: Row + 'r>(rows: impl IntoIterator<Item = &'r R>) -> Result<Vec<u8>> {
    let bug = |e: csv::Error| Error::config("(csv)", e.to_string());
    let columns: Vec<Column<R>> = R::columns()
        .into_iter()
        .filter(|c| c.name.is_some())
        .collect();
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.write_record(columns.iter().filter_map(|c| c.name))
        .map_err(bug)?;
    for r in rows {
        let record: Vec<Cell> = columns.iter().map(|c| (c.value)(r)).collect();
        w.serialize(record).map_err(bug)?;
    }
    w.into_inner()
        .map_err(|e| Error::config("(csv)", e.to_string()))
}

/// `rows` as an aligned text table of the labelled columns ([`Column::both`],
/// [`Column::text`]): a header line and a line per row, each ending in a newline.
pub fn text<'r, R: Row + 'r>(rows: impl IntoIterator<Item = &'r R>) -> String {
    let columns: Vec<Column<R>> = R::columns()
        .into_iter()
        .filter(|c| c.label.is_some())
        .collect();
    let mut lines = vec![columns.iter().map(Column::header).collect::<Vec<_>>()];
    // A column is right-aligned unless it holds names.
    let mut left = vec![false; columns.len()];
    for r in rows {
        let cells = columns.iter().enumerate().map(|(i, c)| {
            let cell = (c.value)(r);
            left[i] = matches!(cell, Cell::Text(_));
            c.show(cell)
        });
        let line = cells.collect();
        lines.push(line);
    }
    let width = |i: usize| {
        lines
            .iter()
            .map(|l| l[i].chars().count())
            .max()
            .unwrap_or(0)
    };
    let widths: Vec<usize> = (0..columns.len()).map(width).collect();
    let mut out = String::new();
    for line in &lines {
        let padded: Vec<String> = line
            .iter()
            .zip(&widths)
            .zip(&left)
            .map(|((cell, &w), &l)| {
                if l {
                    format!("{cell:<w$}")
                } else {
                    format!("{cell:>w$}")
                }
            })
            .collect();
        out.push_str("  ");
        out.push_str(padded.join("  ").trim_end());
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sample {
        series: String,
        x: f64,
        steps: usize,
    }

    impl Row for Sample {
        fn columns() -> Vec<Column<Self>> {
            vec![
                Column::both("series", "series", Format::Plain, |r: &Self| {
                    r.series.as_str().into()
                })
                .or("none"),
                Column::both("x", "x", Format::Sci(2), |r: &Self| r.x.into()).unit("s"),
                Column::csv("steps", |r| r.steps.into()),
                Column::text("2x", Format::Fixed(1), |r| (2.0 * r.x).into()),
            ]
        }
    }

    fn samples() -> [Sample; 3] {
        [
            Sample {
                series: "FD, h = 1".into(),
                x: 0.1 + 0.2,
                steps: 3,
            },
            Sample {
                series: "spectral".into(),
                x: f64::NAN,
                steps: 0,
            },
            Sample {
                series: String::new(),
                x: 1e-6,
                steps: 12,
            },
        ]
    }

    /// The typed table has the CSV's columns, in its order and under its headers, each of its
    /// cells' kind: names as text (an empty name kept empty), floats bit for bit (NaN kept),
    /// counts as integers; the printed-only column is left out.
    #[test]
    fn rows_become_typed_columns() {
        let t = typed("runs.csv", &samples());
        assert_eq!(t.name, "runs");
        let names: Vec<&str> = t.columns.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["series", "x", "steps"]);
        assert_eq!(
            t.columns[0].1,
            Values::Text(vec!["FD, h = 1".into(), "spectral".into(), String::new()])
        );
        match &t.columns[1].1 {
            Values::Float(x) => {
                assert_eq!(x[0].to_bits(), (0.1f64 + 0.2).to_bits());
                assert!(x[1].is_nan());
                assert_eq!(x[2], 1e-6);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(t.columns[2].1, Values::Int(vec![3, 0, 12]));
    }

    /// The CSV has the named columns only; a comma inside a field is quoted; NaN reads `NaN`;
    /// a float reads back to the same bits; an empty name is an empty field.
    #[test]
    fn rows_become_csv() {
        let text = String::from_utf8(csv(&samples()).unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "series,x,steps");
        assert_eq!(lines[1], "\"FD, h = 1\",0.30000000000000004,3");
        assert_eq!(lines[2], "spectral,NaN,0");
        assert_eq!(lines[3], ",1e-6,12");
        let back: f64 = lines[1].split(',').nth(2).unwrap().parse().unwrap();
        assert_eq!(back, 0.1 + 0.2);
    }

    /// The CSV values are those serde writes for the same fields of a struct.
    #[test]
    fn csv_values_are_those_of_serde() {
        #[derive(serde::Serialize)]
        struct Plain<'a> {
            series: &'a str,
            x: f64,
            steps: usize,
        }
        let rows = samples();
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in &rows {
            w.serialize(Plain {
                series: &r.series,
                x: r.x,
                steps: r.steps,
            })
            .unwrap();
        }
        assert_eq!(w.into_inner().unwrap(), csv(&rows).unwrap());
    }

    /// The text has the labelled columns only, the unit in the header, names left-aligned and
    /// numbers right-aligned under their header, each column as wide as its widest cell; a
    /// missing value shows the placeholder.
    #[test]
    fn rows_become_an_aligned_table() {
        let t = text(&samples());
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(
            lines,
            [
                "  series       x [s]   2x",
                "  FD, h = 1  3.00e-1  0.6",
                "  spectral         -    -",
                "  none       1.00e-6  0.0",
            ]
        );
    }
}
