//! The output folder of a command: checked before any computation ([`check_out_dir`]), then
//! made ([`make_out_dir`]); an existing folder is replaced only when forced.

use super::lock;
use crate::error::{Error, Result};
use std::path::Path;

/// Make the output folder: refuse an existing one unless `force`, which replaces it by an empty
/// one. Sub-folders are made by their writers (`snapshots/` by the first snapshot).
///
/// # Errors
/// `Error::Config` on field `--out` if it exists without `force`; `Error::Io` on failure.
pub fn make_out_dir(out: &Path, force: bool) -> Result<()> {
    if out.exists() {
        if !force {
            return Err(Error::config(
                "--out",
                format!(
                    "{} already exists; results are never overwritten silently (pass --force to replace it)",
                    out.display()
                ),
            ));
        }
        std::fs::remove_dir_all(out).map_err(|source| Error::Io {
            path: out.to_path_buf(),
            source,
        })?;
    }
    std::fs::create_dir_all(out).map_err(|source| Error::Io {
        path: out.to_path_buf(),
        source,
    })
}

/// Check, before any computation, that the output folder can be made: refuse an existing one
/// without `force` (as [`make_out_dir`]), an existing path that is not a folder, and a folder
/// whose nearest existing ancestor is not a folder or cannot be written (probed by creating
/// and removing an empty folder in it). Writes nothing that stays.
///
/// # Errors
/// `Error::Config` on field `--out` with the reason.
pub fn check_out_dir(out: &Path, force: bool) -> Result<()> {
    let bad =
        |why: String| Error::config("--out", format!("cannot write {}: {why}", out.display()));
    if out.exists() {
        lock::refuse_if_held(out)?;
        if !force {
            return make_out_dir(out, false);
        }
        if !out.is_dir() {
            return Err(bad("it exists and is not a folder".into()));
        }
    }
    // The nearest existing ancestor: where the folder (or its replacement) will be created.
    let mut ancestor = out;
    loop {
        ancestor = match ancestor.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if ancestor.exists() || ancestor == Path::new(".") || ancestor.parent().is_none() {
            break;
        }
    }
    let meta = std::fs::metadata(ancestor)
        .map_err(|e| bad(format!("{} cannot be read: {e}", ancestor.display())))?;
    if !meta.is_dir() {
        return Err(bad(format!("{} is not a folder", ancestor.display())));
    }
    let probe = ancestor.join(format!(".vesicle-write-probe-{}", std::process::id()));
    std::fs::create_dir(&probe)
        .map_err(|e| bad(format!("{} is not writable: {e}", ancestor.display())))?;
    // An empty folder of ours: removing it cannot fail short of a race; ignore that.
    let _ = std::fs::remove_dir(&probe);
    Ok(())
}
