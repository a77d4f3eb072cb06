//! `vesicle diagram --merge` (and the end of a sweep): the case folders of `OUT/cases/` into
//! the merged files. Each c̄0 of the diagram is one slice, extrapolated and compared with the
//! reference at its own c̄0 ([`merge_slice`]); a diagram of one c̄0 writes its slice in `OUT`
//! (the files of the c0 = 0 diagram), a diagram of several writes each in `OUT/c0_<c̄0>/`
//! and the files that span them in `OUT` ([`super::summary`]).

use super::case::{read_result, CaseResult};
use super::chart;
use super::extrapolate::{self, Orders, Point};
use super::reference::{self, Reference};
use super::report::{self, Kind};
use super::spec::{Case, DiagramSpec, SliceAt, BRANCHES};
use super::summary;
use crate::analysis::axisym::Branch;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// What one slice (one c̄0) of a merged diagram found.
#[derive(Clone, Debug)]
pub struct Slice {
    /// Where the slice sits (c̄0, and α, Δa0 with ADE).
    pub at: SliceAt,
    /// Where its files went.
    pub dir: PathBuf,
    /// Its points, extrapolated.
    pub points: Vec<Point>,
    /// Its cases.
    pub results: Vec<CaseResult>,
    /// The reference at this c̄0.
    pub reference: Reference,
    /// Per pair of [`reference::TRANSITIONS`]: name, `[reference, extrapolated, finest]`
    /// crossing volumes (NaN where the curves do not cross once), and what the reference
    /// crossing is.
    pub transitions: Vec<(String, [f64; 3], Kind)>,
    /// The printed table.
    pub table: String,
}

/// Collect the case results of `out/cases/` into the merged files.
///
/// # Errors
/// `Error::Config` (field `--merge`) if merged files exist without `force` or cases have no
/// result; field `r0` if the orders in ε/R0 cannot be fitted; I/O and drawing errors.
pub fn merge(spec: &DiagramSpec, cases: &[Case], out: &Path, force: bool) -> Result<()> {
    let marker = out.join("transitions.csv");
    if marker.exists() && !force {
        return Err(Error::config(
            "--merge",
            format!(
                "{} exists; --force replaces the merged files",
                marker.display()
            ),
        ));
    }
    let found: Vec<Option<CaseResult>> = cases
        .iter()
        .map(|c| read_result(&out.join("cases").join(c.folder())))
        .collect::<Result<_>>()?;
    report::check_complete(cases.len(), &found)?;
    let results: Vec<CaseResult> = found.into_iter().flatten().collect();
    let Some(orders) = extrapolate::orders(&results) else {
        return Err(Error::config(
            "r0",
            "the orders in ε/R0 need three or more resolutions with distinct values",
        ));
    };
    let thumbnails = |at: SliceAt| -> Vec<PathBuf> {
        cases
            .iter()
            .filter(|c| c.slice() == at)
            .map(|c| out.join("cases").join(c.folder()).join("thumbnail.png"))
            .filter(|p| p.exists())
            .collect()
    };
    let ats = spec.slices();
    if let [at] = ats.as_slice() {
        let slice = merge_slice(*at, &results, orders, &thumbnails(*at), out)?;
        print!("{}", slice.table);
        println!("-> {}", out.display());
        return Ok(());
    }
    let mut slices = Vec::new();
    for at in ats {
        let dir = out.join(at.folder());
        std::fs::create_dir_all(&dir).map_err(|source| Error::Io {
            path: dir.clone(),
            source,
        })?;
        let mine: Vec<CaseResult> = results
            .iter()
            .filter(|r| r.slice() == at)
            .cloned()
            .collect();
        slices.push(merge_slice(at, &mine, orders, &thumbnails(at), &dir)?);
    }
    let all_thumbnails: Vec<PathBuf> = slices.iter().flat_map(|s| thumbnails(s.at)).collect();
    chart::write_montage(&out.join("thumbnails.png"), &all_thumbnails, 4)?;
    let table = summary::write(out, &slices)?;
    print!("{table}");
    println!("-> {}", out.display());
    Ok(())
}

/// Merge the cases `results` of one slice `at`, extrapolated at the diagram's `orders`, into `dir`: `diagram.csv`, `cases.csv`,
/// `transitions.csv`, `reference.csv`, `table.txt`, `diagram.png`, `errors.png` and
/// `thumbnails.png` (of the pictures `thumbnails`).
///
/// # Errors
/// I/O and drawing errors.
pub fn merge_slice(
    at: SliceAt,
    results: &[CaseResult],
    orders: Orders,
    thumbnails: &[PathBuf],
    dir: &Path,
) -> Result<Slice> {
    let points = extrapolate::extrapolate(results, orders);
    let (v_lo, v_hi) = results.iter().fold((1.0f64, 0.0f64), |(a, b), r| {
        (a.min(r.v).min(r.v_target), b.max(r.v).max(r.v_target))
    });
    let listed: Vec<Branch> = BRANCHES
        .into_iter()
        .filter(|b| results.iter().any(|r| r.branch == b.name()))
        .collect();
    let reference = Reference::at(at, v_lo - 0.03, v_hi + 0.03, &listed);
    report::write_csv(dir, &points, results, &reference)?;
    let extrapolated = report::branch_points(&points, |p| (p.v, p.e));
    let found: Vec<(String, [f64; 3], Kind)> = report::transitions(&points, &reference)
        .into_iter()
        .zip(report::kinds(&reference))
        .map(|((name, t), kind)| (name, t, kind))
        .collect();
    // Each transition: its name, the reference volume, and the extrapolated crossing as a
    // point of the diagram (e on the first of the two branches).
    let drawn: Vec<chart::Transition> = found
        .iter()
        .zip(reference::TRANSITIONS)
        .map(|((name, t, kind), (a, _))| {
            let branch = &extrapolated[BRANCHES.iter().position(|b| *b == a).expect("listed")];
            let crossing = (t[1].is_finite() && !branch.is_empty())
                .then(|| (t[1], crate::analysis::curves::cubic_at(branch, t[1])));
            chart::Transition {
                name: name.clone(),
                reference: t[0],
                crossing,
                ground: *kind == Kind::Transition,
            }
        })
        .collect();
    chart::write_chart(
        &dir.join("diagram.png"),
        at,
        &reference,
        &extrapolated,
        &report::branch_points(&points, |p| (p.finest().v, p.finest().e)),
        &drawn,
    )?;
    report::write_error_chart(dir, at, &points, &reference)?;
    chart::write_montage(&dir.join("thumbnails.png"), thumbnails, 4)?;
    let mut table = report::table(&points, results, orders, &reference);
    if at.couple.is_some() {
        table.push_str(&report::da_table(
            "Δa of the phase field's functional (M/M₁)",
            &points,
            &reference,
            |c| c.da.unwrap_or(f64::NAN),
            |p| p.da,
        ));
    }
    if results.iter().all(|r| r.da_surface.is_some()) {
        table.push_str(&report::da_table(
            "Δa of the φ = 0 surface",
            &points,
            &reference,
            |c| c.da_surface.unwrap_or(f64::NAN),
            |p| p.da_surface,
        ));
    }
    crate::commands::study::write_text(dir, "table.txt", &table)?;
    Ok(Slice {
        at,
        dir: dir.to_path_buf(),
        points,
        results: results.to_vec(),
        reference,
        transitions: found,
        table,
    })
}
