//! A finished run's folder as the after-the-run commands (`render`, `measure`) read it: the
//! geometry from `DIR/summary.json`, and the saved states `DIR/snapshots/phi_<step>.npy` plus
//! `DIR/phi_final.npy` (all full-box fields, also when a reduced box was computed).

use crate::error::{Error, Result};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The run's geometry as saved in `summary.json`.
pub struct RunInfo {
    /// 2 or 3.
    pub dim: usize,
    /// Full-box grid points per axis (`dim` entries).
    pub n: Vec<usize>,
    /// Grid spacing.
    pub h: f64,
    /// The last step (`"steps"`), if recorded.
    pub final_step: Option<usize>,
    /// The last time (`"final"."t"`), if recorded.
    pub final_t: Option<f64>,
}

/// One saved state: its step and `.npy` file.
pub struct State {
    /// Step number.
    pub step: usize,
    /// The `.npy` file holding φ.
    pub path: PathBuf,
}

/// The folder itself must exist.
///
/// # Errors
/// `Error::Config` naming `DIR` when it does not.
pub fn check_dir(dir: &Path) -> Result<()> {
    if dir.is_dir() {
        Ok(())
    } else {
        Err(Error::config(
            "DIR",
            format!("{} is not a run folder (it does not exist)", dir.display()),
        ))
    }
}

/// `DIR/name` and its text.
///
/// # Errors
/// `Error::Config` naming `DIR` if the file cannot be read.
pub fn read_file(dir: &Path, name: &str) -> Result<(PathBuf, String)> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::config(
            "DIR",
            format!(
                "cannot read {}: {e} (is this a run folder?)",
                path.display()
            ),
        )
    })?;
    Ok((path, text))
}

/// `dim`, `n`, `h`, the final step and time from `DIR/summary.json` (`"spec"`,
/// `"steps"` and `"final"`).
///
/// # Errors
/// `Error::Config` naming `DIR` when the file is missing, not JSON, or lacks a valid
/// `spec.dim`, `spec.n` or `spec.h`.
pub fn run_info(dir: &Path) -> Result<RunInfo> {
    let (path, text) = read_file(dir, "summary.json")?;
    let bad = |what: &str| Error::config("DIR", format!("{}: no valid {what}", path.display()));
    let v: Value = serde_json::from_str(&text).map_err(|_| bad("JSON"))?;
    let spec = &v["spec"];
    let dim = spec["dim"]
        .as_u64()
        .filter(|d| *d == 2 || *d == 3)
        .ok_or_else(|| bad("spec.dim (2 or 3)"))? as usize;
    let n: Vec<usize> = spec["n"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_u64().map(|x| x as usize))
                .collect()
        })
        .filter(|n: &Vec<usize>| n.len() == dim && n.iter().all(|&m| m > 0))
        .ok_or_else(|| bad("spec.n"))?;
    let h = spec["h"]
        .as_f64()
        .filter(|h| *h > 0.0)
        .ok_or_else(|| bad("spec.h"))?;
    let final_step = v["steps"].as_u64().map(|s| s as usize);
    let final_t = v["final"]["t"].as_f64();
    Ok(RunInfo {
        dim,
        n,
        h,
        final_step,
        final_t,
    })
}

/// The saved states in step order: every `every`-th snapshot from the first, then the final
/// state unless a snapshot already has its step.
///
/// # Errors
/// `Error::Config` naming `DIR` when there are no snapshots.
pub fn states(dir: &Path, info: &RunInfo, every: usize) -> Result<Vec<State>> {
    let snap_dir = dir.join("snapshots");
    let none = || {
        Error::config(
            "DIR",
            format!(
                "no snapshots {}/phi_<step>.npy: run with --set output.snapshot_every=K",
                snap_dir.display()
            ),
        )
    };
    let entries = std::fs::read_dir(&snap_dir).map_err(|_| none())?;
    let mut snaps: Vec<State> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let step = name
                .strip_prefix("phi_")?
                .strip_suffix(".npy")?
                .parse()
                .ok()?;
            Some(State {
                step,
                path: e.path(),
            })
        })
        .collect();
    if snaps.is_empty() {
        return Err(none());
    }
    snaps.sort_by_key(|s| s.step);
    let mut chosen: Vec<State> = snaps.into_iter().step_by(every).collect();
    let final_path = dir.join("phi_final.npy");
    if let Some(step) = info.final_step.filter(|_| final_path.is_file()) {
        if chosen.iter().all(|s| s.step != step) {
            chosen.push(State {
                step,
                path: final_path,
            });
            chosen.sort_by_key(|s| s.step);
        }
    }
    Ok(chosen)
}
