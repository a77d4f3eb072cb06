//! Speed against accuracy, shared by `vesicle study precision` and `vesicle study stationary`:
//! the fastest spectral and FD configuration to each error level (`levels.csv`), and the Pareto
//! front of `(wall, error)` points.

use super::table::{Column, Format, Row};

/// The fastest spectral and FD configuration to an error level; a row of `levels.csv`.
pub struct Level<'a> {
    /// The study's part: `stationary` or `transient`.
    pub part: &'static str,
    /// The error level.
    pub level: f64,
    /// `(wall seconds, name)` of the fastest spectral configuration below `level` (`None`: none
    /// gets there).
    pub spectral: Option<(f64, &'a str)>,
    /// `(wall seconds, name)` of the fastest FD configuration below `level`.
    pub fd: Option<(f64, &'a str)>,
}

impl Level<'_> {
    /// Spectral wall time over FD's (NaN unless both reach the level).
    pub fn ratio(&self) -> f64 {
        match (self.spectral, self.fd) {
            (Some(a), Some(b)) => a.0 / b.0,
            _ => f64::NAN,
        }
    }
}

impl Row for Level<'_> {
    fn columns() -> Vec<Column<Self>> {
        vec![
            Column::csv("part", |r| r.part.into()),
            Column::both("level", "level", Format::Sci(0), |r| r.level.into()),
            Column::both(
                "fastest_spectral",
                "fastest spectral",
                Format::Plain,
                |r: &Self| r.spectral.map_or("", |x| x.1).into(),
            )
            .or("not reached"),
            Column::both(
                "spectral_wall_seconds",
                "wall",
                Format::Sci(3),
                |r: &Self| r.spectral.map_or(f64::NAN, |x| x.0).into(),
            )
            .unit("s"),
            Column::both("fastest_fd", "fastest FD", Format::Plain, |r: &Self| {
                r.fd.map_or("", |x| x.1).into()
            })
            .or("not reached"),
            Column::both("fd_wall_seconds", "wall", Format::Sci(3), |r: &Self| {
                r.fd.map_or(f64::NAN, |x| x.0).into()
            })
            .unit("s"),
            Column::both(
                "ratio_spectral_over_fd",
                "spectral/FD",
                Format::Sci(3),
                |r| r.ratio().into(),
            ),
        ]
    }
}

/// The Pareto front of `(wall, error)` points: those no other point beats in both, by wall.
pub fn pareto(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::INFINITY;
    pts.into_iter()
        .filter(|p| {
            let keep = p.1 < best;
            best = best.min(p.1);
            keep
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Pareto front keeps the points no other beats in both wall time and error.
    #[test]
    fn the_pareto_front_is_the_undominated_points() {
        let front = pareto(vec![
            (1.0, 1e-2),
            (2.0, 1e-3),
            (1.5, 1e-2),
            (3.0, 1e-4),
            (2.5, 1e-3),
        ]);
        assert_eq!(front, vec![(1.0, 1e-2), (2.0, 1e-3), (3.0, 1e-4)]);
    }

    /// A level neither family reaches is an empty name and NaN walls and ratio in the CSV.
    #[test]
    fn an_unreached_level_is_empty() {
        let rows = [
            Level {
                part: "transient",
                level: 1e-2,
                spectral: Some((0.5, "SBDF2 dt = 0.1")),
                fd: Some((2.0, "FD explicit Euler, 0.9 of bound")),
            },
            Level {
                part: "transient",
                level: 1e-5,
                spectral: None,
                fd: None,
            },
        ];
        let csv = String::from_utf8(super::super::table::csv(&rows).unwrap()).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines,
            [
                "part,level,fastest_spectral,spectral_wall_seconds,fastest_fd,fd_wall_seconds,ratio_spectral_over_fd",
                "transient,0.01,SBDF2 dt = 0.1,0.5,\"FD explicit Euler, 0.9 of bound\",2.0,0.25",
                "transient,0.00001,,NaN,,NaN,NaN",
            ]
        );
    }
}
