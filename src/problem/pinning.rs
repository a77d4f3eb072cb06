//! Lattice pinning of stationary energies: how far the lattice moves a stationary shape's
//! reduced energy e at a given h/ε, as measured by `vesicle study pinning
//! runs/studies/pinning.json` (committed in `runs/results/pinning/bound.csv`; the manual's
//! "Stationary shapes" page). At a fixed h/ε, e is a smooth function of ε/R0 plus a corrugation
//! that depends on where the interface crosses the lattice: moving R0 by ε/4 or the centre by a
//! fraction of h moves e by up to the bound of this table (the largest, over a prolate, an oblate
//! and a stomatocyte, of the residual of a smooth fit over R0 = 16 … 17ε and of the spread over
//! sub-cell shifts). The table is written here once; `vesicle check` and `vesicle run` print
//! [`note`] for the scene's h/ε.

/// One measured row: the grid spacing and the pinning bound of e there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// h/ε.
    pub h_over_eps: f64,
    /// The largest pinning figure of e over the shapes (absolute; e ≈ 1.5–2 on these shapes).
    pub e: f64,
}

/// The measured table, in increasing h/ε (`runs/results/pinning/bound.csv`).
pub const TABLE: [Row; 4] = [
    Row {
        h_over_eps: 1.0 / 3.0,
        e: 2.5e-5,
    },
    Row {
        h_over_eps: 0.5,
        e: 5.5e-5,
    },
    Row {
        h_over_eps: 2.0 / 3.0,
        e: 8.9e-5,
    },
    Row {
        h_over_eps: 1.0,
        e: 3.7e-3,
    },
];

/// The study and the file the table comes from.
pub const SOURCE: &str =
    "vesicle study pinning runs/studies/pinning.json (runs/results/pinning/bound.csv)";

/// The h/ε the program recommends for stationary energies: the coarsest measured spacing whose
/// pinning (8.9e-5, 6e-5 of e) lies well below the phase-field error in ε/R0 that any affordable
/// R0 leaves (2.4e-4 at best in `vesicle study resolution`, extrapolated); the 40-fold step in
/// pinning lies between h = ε and 2ε/3, and h = ε/2 costs 2.4× the points for 8.9e-5 → 5.5e-5.
pub const RECOMMENDED_H_OVER_EPS: f64 = 2.0 / 3.0;

/// The pinning bound at some h/ε.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// Inside the measured range: a row, or interpolated log–log between the two rows around it.
    Within(f64),
    /// Finer than the finest row: at most that row's bound.
    AtMost(f64),
    /// Coarser than the coarsest row: at least that row's bound.
    AtLeast(f64),
}

impl Bound {
    /// The number of the bound, whichever side.
    pub fn value(self) -> f64 {
        match self {
            Bound::Within(x) | Bound::AtMost(x) | Bound::AtLeast(x) => x,
        }
    }
}

/// The pinning bound of e at `h_over_eps` from [`TABLE`].
pub fn bound(h_over_eps: f64) -> Bound {
    let (first, last) = (TABLE[0], TABLE[TABLE.len() - 1]);
    const TOL: f64 = 1e-9;
    if h_over_eps < first.h_over_eps - TOL {
        return Bound::AtMost(first.e);
    }
    if h_over_eps > last.h_over_eps + TOL {
        return Bound::AtLeast(last.e);
    }
    if let Some(row) = TABLE
        .iter()
        .find(|r| (r.h_over_eps - h_over_eps).abs() <= TOL)
    {
        return Bound::Within(row.e);
    }
    let h = h_over_eps.clamp(first.h_over_eps, last.h_over_eps);
    let i = TABLE
        .windows(2)
        .position(|w| h <= w[1].h_over_eps)
        .expect("h lies within the table");
    let (a, b) = (TABLE[i], TABLE[i + 1]);
    let t = (h.ln() - a.h_over_eps.ln()) / (b.h_over_eps.ln() - a.h_over_eps.ln());
    Bound::Within((a.e.ln() + t * (b.e.ln() - a.e.ln())).exp())
}

/// The one-line note `check` and `run` print for a phase-field scene at `h_over_eps`.
pub fn note(h_over_eps: f64) -> String {
    let b = bound(h_over_eps);
    let how = match b {
        Bound::Within(_) => "within",
        Bound::AtMost(_) => "within at most",
        Bound::AtLeast(_) => "by at least",
    };
    let advice = if h_over_eps > RECOMMENDED_H_OVER_EPS + 1e-9 {
        format!(
            "; h/ε = {:.3} or finer is recommended for stationary energies ({:.1e})",
            RECOMMENDED_H_OVER_EPS,
            bound(RECOMMENDED_H_OVER_EPS).value()
        )
    } else {
        String::new()
    };
    format!(
        "lattice pinning: at h/ε = {h_over_eps:.3} a stationary reduced energy e is pinned {how} \
         {:.1e} (absolute; {SOURCE}){advice}",
        b.value()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound falls as the grid is refined (a finer lattice pins less), its rows are read
    /// back exactly, a spacing between two rows lies between their bounds, and outside the
    /// table the bound is one-sided.
    #[test]
    fn the_bound_is_monotone_and_bracketed() {
        assert!(TABLE.windows(2).all(|w| w[0].h_over_eps < w[1].h_over_eps));
        assert!(TABLE.windows(2).all(|w| w[0].e < w[1].e), "{TABLE:?}");
        for r in TABLE {
            assert_eq!(bound(r.h_over_eps), Bound::Within(r.e));
        }
        for w in TABLE.windows(2) {
            let mid = (w[0].h_over_eps * w[1].h_over_eps).sqrt();
            let b = bound(mid).value();
            assert!(b > w[0].e && b < w[1].e, "{mid}: {b}");
        }
        assert_eq!(bound(0.1), Bound::AtMost(TABLE[0].e));
        assert_eq!(bound(2.0), Bound::AtLeast(TABLE[3].e));
        assert!(note(1.0).contains("recommended") && !note(0.5).contains("recommended"));
    }
}
