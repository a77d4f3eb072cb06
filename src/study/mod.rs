//! `vesicle study …`: measurements that compare methods in one run and print ratios.

pub mod fit;
pub mod precision;
pub mod stability;
pub mod stationary;

use crate::error::{Error, Result};
use std::path::Path;

/// Write `text` to `dir/name`.
///
/// # Errors
/// `Error::Io` on failure.
pub fn write_text(dir: &Path, name: &str, text: &str) -> Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, text).map_err(|source| Error::Io { path, source })
}
