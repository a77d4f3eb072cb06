//! One run per output folder: `DIR/.lock` holds the process id of the run writing there.

use crate::error::{Error, Result};
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const LOCK_FILE: &str = ".lock";

/// Held while a run writes into its folder; released (the file removed) when dropped.
#[derive(Debug)]
pub struct RunLock {
    path: PathBuf,
}

impl RunLock {
    /// Take the lock of `dir`. A lock left by a process that no longer runs (a killed run) is
    /// taken over.
    ///
    /// # Errors
    /// `Error::Config` on field `--out` if a running process holds it; `Error::Io` if the file
    /// cannot be written.
    pub fn acquire(dir: &Path) -> Result<Self> {
        refuse_if_held(dir)?;
        let path = dir.join(LOCK_FILE);
        let mut file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .map_err(|source| Error::Io {
                path: path.clone(),
                source,
            })?;
        writeln!(file, "{}", std::process::id()).map_err(|source| Error::Io {
            path: path.clone(),
            source,
        })?;
        Ok(RunLock { path })
    }
}

impl Drop for RunLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Refuse when another running process holds the lock of `dir`.
///
/// # Errors
/// `Error::Config` on field `--out` naming the process.
pub fn refuse_if_held(dir: &Path) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(dir.join(LOCK_FILE)) else {
        return Ok(());
    };
    match text.trim().parse::<u32>() {
        Ok(pid) if pid != std::process::id() && process_runs(pid) => Err(Error::config(
            "--out",
            format!(
                "{} is being written by another vesicle run (process {pid}); wait for it or stop it",
                dir.display()
            ),
        )),
        _ => Ok(()),
    }
}

/// Whether process `pid` exists (Linux: `/proc/<pid>`; elsewhere assumed to run).
fn process_runs(pid: u32) -> bool {
    if Path::new("/proc/self").exists() {
        Path::new(&format!("/proc/{pid}")).exists()
    } else {
        true
    }
}
