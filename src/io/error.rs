//! The one error type of the writers.

use std::path::PathBuf;

/// A failed write; every variant names the file it was about and what was being done.
///
/// HDF5 errors are kept as text: the library's error values hold handles into its global state,
/// which should not outlive the call that produced them.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// An operating-system I/O call failed.
    #[error("{action} {}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// An HDF5 library call failed.
    #[error("HDF5 file {}: {action}: {message}", path.display())]
    Hdf5 {
        path: PathBuf,
        action: String,
        message: String,
    },
    /// The caller's data cannot be written as asked (wrong lengths, bad names, wrong arity).
    #[error("{}: {reason}", path.display())]
    Invalid { path: PathBuf, reason: String },
}

impl IoError {
    pub(crate) fn io(path: &std::path::Path, action: &'static str, source: std::io::Error) -> Self {
        IoError::Io {
            path: path.to_path_buf(),
            action,
            source,
        }
    }

    pub(crate) fn invalid(path: &std::path::Path, reason: impl Into<String>) -> Self {
        IoError::Invalid {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }
}
