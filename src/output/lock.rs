//! One run per output folder: `DIR/.lock` holds the process id of the run writing there, and
//! that run holds an exclusive lock of the operating system on it (`flock` on Linux).
//!
//! Taking the lock is one atomic step of the operating system, so of two runs starting on the
//! same folder at once (two processes, or two threads of one) exactly one gets it. The system
//! releases a lock when its process ends, also when it is killed: the file a killed run leaves
//! behind is not locked, and the next run takes it over.

use crate::error::{Error, Result};
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const LOCK_FILE: &str = ".lock";

/// Held while a run writes into its folder; released (the file removed) when dropped.
#[derive(Debug)]
pub struct RunLock {
    path: PathBuf,
    /// The locked file: the lock lasts as long as this handle is open.
    _file: File,
}

impl RunLock {
    /// Take the lock of `dir`. A lock left by a process that no longer runs (a killed run) is
    /// taken over.
    ///
    /// # Errors
    /// `Error::Config` on field `--out` if a running process (or another lock of this one)
    /// holds it; `Error::Io` if the file cannot be written.
    pub fn acquire(dir: &Path) -> Result<Self> {
        let path = dir.join(LOCK_FILE);
        let io = |source| Error::Io {
            path: path.clone(),
            source,
        };
        loop {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(io)?;
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => return Err(held(dir, &mut file)),
                Err(TryLockError::Error(e)) => return Err(io(e)),
            }
            // The run that held the lock removes the file before it lets go: a file locked after
            // that is no longer the folder's lock; open the one there now.
            if !names(&path, &file) {
                continue;
            }
            file.set_len(0).map_err(io)?;
            writeln!(file, "{}", std::process::id()).map_err(io)?;
            return Ok(RunLock { path, _file: file });
        }
    }
}

impl Drop for RunLock {
    /// Remove the file while it is still locked; closing it then releases the lock.
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Refuse when another running process (or another lock of this one) holds the lock of `dir`.
/// Takes nothing: a check before a run, which takes the lock with [`RunLock::acquire`].
///
/// # Errors
/// `Error::Config` on field `--out` naming the process.
pub fn refuse_if_held(dir: &Path) -> Result<()> {
    let Ok(mut file) = File::open(dir.join(LOCK_FILE)) else {
        return Ok(());
    };
    // A shared lock is refused while a run holds the exclusive one; it ends with `file`.
    match file.try_lock_shared() {
        Err(TryLockError::WouldBlock) => Err(held(dir, &mut file)),
        Ok(()) | Err(TryLockError::Error(_)) => Ok(()),
    }
}

/// The refusal of a lock `file` of `dir` held by another run, naming its process when the
/// file holds one (a run that has just taken the lock may not have written it yet).
fn held(dir: &Path, file: &mut File) -> Error {
    let mut text = String::new();
    let pid = file
        .rewind()
        .and_then(|()| file.read_to_string(&mut text))
        .ok()
        .and_then(|_| text.trim().parse::<u32>().ok());
    let who = pid.map_or_else(String::new, |pid| format!(" (process {pid})"));
    Error::config(
        "--out",
        format!(
            "{} is being written by another vesicle run{who}; wait for it or stop it",
            dir.display()
        ),
    )
}

/// Whether `path` still names the open `file` (the same device and inode).
#[cfg(unix)]
fn names(path: &Path, file: &File) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(path), file.metadata()) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Whether `path` still names the open `file`: always, where an open file cannot be removed.
#[cfg(not(unix))]
fn names(_path: &Path, _file: &File) -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Barrier;

    /// Threads racing for one folder's lock, round after round: never two holders at once, and
    /// a holder in every round (the refused ones were refused because of it).
    #[test]
    fn racing_takers_never_both_hold_the_lock() {
        const THREADS: usize = 6;
        const ROUNDS: usize = 200;
        let tmp = tempfile::TempDir::new().unwrap();
        let dir = tmp.path();
        let holders = AtomicUsize::new(0);
        let most = AtomicUsize::new(0);
        for _ in 0..ROUNDS {
            let start = Barrier::new(THREADS);
            let won = AtomicUsize::new(0);
            std::thread::scope(|s| {
                for _ in 0..THREADS {
                    s.spawn(|| {
                        start.wait();
                        match RunLock::acquire(dir) {
                            Ok(lock) => {
                                let now = holders.fetch_add(1, Ordering::SeqCst) + 1;
                                most.fetch_max(now, Ordering::SeqCst);
                                won.fetch_add(1, Ordering::SeqCst);
                                std::thread::yield_now();
                                holders.fetch_sub(1, Ordering::SeqCst);
                                drop(lock);
                            }
                            Err(e) => {
                                let text = e.to_string();
                                assert!(text.contains("is being written by another vesicle run"));
                            }
                        }
                    });
                }
            });
            assert!(won.load(Ordering::SeqCst) >= 1, "a round without a holder");
            assert!(!dir.join(LOCK_FILE).exists(), "the last holder removed it");
        }
        assert_eq!(most.load(Ordering::SeqCst), 1, "two holders at once");
    }

    /// A held lock is refused, by `acquire` and by `refuse_if_held`, naming the holder's
    /// process; once dropped the file is gone and the folder is free.
    #[test]
    fn a_held_lock_is_refused_with_the_holder_named() {
        let tmp = tempfile::TempDir::new().unwrap();
        let lock = RunLock::acquire(tmp.path()).unwrap();
        let pid = std::process::id();
        let text = std::fs::read_to_string(tmp.path().join(LOCK_FILE)).unwrap();
        assert_eq!(text.trim(), pid.to_string());
        let named = format!("is being written by another vesicle run (process {pid})");
        let e = RunLock::acquire(tmp.path()).unwrap_err().to_string();
        assert!(e.contains(&named), "{e}");
        let e = refuse_if_held(tmp.path()).unwrap_err().to_string();
        assert!(e.contains(&named), "{e}");
        drop(lock);
        assert!(!tmp.path().join(LOCK_FILE).exists());
        refuse_if_held(tmp.path()).unwrap();
        drop(RunLock::acquire(tmp.path()).unwrap());
    }

    /// A lock file that no process holds (left by a killed run, whose process id is gone or
    /// has been given to another process, this one included) is taken over: it then holds
    /// this process's id, and is removed at the end.
    #[test]
    fn a_stale_lock_is_taken_over() {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        child.wait().unwrap();
        for left in [child.id(), std::process::id()] {
            let tmp = tempfile::TempDir::new().unwrap();
            let path = tmp.path().join(LOCK_FILE);
            std::fs::write(&path, format!("{left}\n")).unwrap();
            refuse_if_held(tmp.path()).unwrap();
            let lock = RunLock::acquire(tmp.path()).unwrap();
            let text = std::fs::read_to_string(&path).unwrap();
            assert_eq!(text.trim(), std::process::id().to_string());
            drop(lock);
            assert!(!path.exists());
        }
    }
}
