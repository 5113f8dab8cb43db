//! Whole-file replacement that a crash cannot leave half done.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::IoError;

/// The temporary sibling `.NAME.tmp` that [`write_atomic`] writes before renaming.
pub(crate) fn temp_sibling(path: &Path) -> Result<PathBuf, IoError> {
    let name = path
        .file_name()
        .ok_or_else(|| IoError::invalid(path, "path has no file name"))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(".tmp");
    Ok(path.with_file_name(tmp_name))
}

/// Writes via a temporary sibling name (`.NAME.tmp`), then renames, so a crash never leaves a
/// half-written file that looks whole.
///
/// The data is synced to disk before the rename, so after a power loss `path` holds either the
/// old or the new content. If `write` (or anything after it) fails, the temporary file is removed
/// and `path` is left as it was. Two writers must not target the same `path` at once: they would
/// share the temporary name.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let tmp = temp_sibling(path)?;
    let result = write_then_rename(path, &tmp, write);
    if result.is_err() {
        // Best effort: the error being returned matters more than a leftover temp file.
        let _ = fs::remove_file(&tmp);
    }
    result
}

fn write_then_rename(
    path: &Path,
    tmp: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let file = File::create(tmp).map_err(|e| IoError::io(tmp, "creating", e))?;
    let mut out = BufWriter::new(file);
    write(&mut out).map_err(|e| IoError::io(path, "writing", e))?;
    let file = out
        .into_inner()
        .map_err(|e| IoError::io(path, "writing", e.into_error()))?;
    file.sync_all()
        .map_err(|e| IoError::io(tmp, "syncing", e))?;
    drop(file);
    fs::rename(tmp, path).map_err(|e| IoError::io(path, "renaming temporary file onto", e))
}
