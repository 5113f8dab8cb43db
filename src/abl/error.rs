//! Errors of opening, validating, writing and querying an ABL database; each names the file.

use std::path::PathBuf;

/// Why a database could not be read, written or used.
#[derive(Debug, thiserror::Error)]
pub enum AblError {
    /// There is no file at the path (or it cannot be read at all).
    #[error("cannot open {} as an ABL database: {cause}", .path.display())]
    Missing {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// HDF5 could not open the file at all.
    #[error(
        "cannot open {} as an ABL database: not an HDF5 file, or truncated ({message})",
        .path.display()
    )]
    Unreadable { path: PathBuf, message: String },
    /// An HDF5 file, but not one eddy wrote as an ABL database.
    #[error(
        "{} is not an eddy ABL database: root attribute `format` is {found}, expected \"{}\"",
        .path.display(), super::ABL_FORMAT
    )]
    Foreign { path: PathBuf, found: String },
    /// A database of a layout this eddy does not read.
    #[error(
        "{} has ABL format version {found}; this eddy reads version {}",
        .path.display(), super::ABL_FORMAT_VERSION
    )]
    Version { path: PathBuf, found: i64 },
    /// A dataset or attribute is missing, of the wrong type or shape, or inconsistent.
    #[error("{} is damaged: {what}", .path.display())]
    Corrupt { path: PathBuf, what: String },
    /// Some sampled directions were never computed (an unfinished or unmerged shard).
    #[error(
        "{} is incomplete: {count} {kind} direction(s) missing (first: polar {polar}, azimuth \
         {azimuth}); finish it with `eddy-precompute --resume` or merge every shard",
        .path.display()
    )]
    Incomplete {
        path: PathBuf,
        kind: &'static str,
        count: usize,
        polar: usize,
        azimuth: usize,
    },
    /// The database was precomputed for another obstacle geometry.
    #[error(
        "{} was precomputed for obstacle '{stored_name}' with geometry fingerprint {stored}, \
         but this obstacle's geometry has fingerprint {expected}: precompute it for this obstacle",
        .path.display()
    )]
    WrongObstacle {
        path: PathBuf,
        stored_name: String,
        stored: String,
        expected: String,
    },
    /// The obstacle's mesh could not be read to fingerprint it.
    #[error("cannot read mesh {} to fingerprint the obstacle: {source}", .path.display())]
    Mesh {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Writing failed.
    #[error("writing ABL database {}: {message}", .path.display())]
    Write { path: PathBuf, message: String },
    /// The caller's data do not form a database (lengths disagree, bad sampling).
    #[error("invalid ABL data: {0}")]
    Invalid(String),
}
