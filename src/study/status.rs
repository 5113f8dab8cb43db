//! The status file between a study and its runs: `eddy run --status FILE` writes how it ended,
//! why and its peak memory as it exits, and the study reads it back. A child process's exit
//! code cannot tell an instability from a bad scene, and only the child knows its own peak
//! memory.

use std::path::Path;

use super::StudyError;

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Finished,
    /// The solver stopped on an instability (its cause is in the row).
    Unstable,
    /// Any other error (the scene could not be built, a file could not be written).
    Failed,
    TimedOut,
}

impl Status {
    /// Its word in sweep.csv and in the status file.
    pub fn name(self) -> &'static str {
        match self {
            Status::Finished => "finished",
            Status::Unstable => "unstable",
            Status::Failed => "failed",
            Status::TimedOut => "timed out",
        }
    }
}

/// What `eddy run --status FILE` writes when the run ends: how, why, and the process's peak
/// resident memory.
pub fn write_status(path: &Path, status: Status, cause: &str) -> Result<(), StudyError> {
    let mut t = toml::Table::new();
    t.insert("status".into(), status.name().into());
    t.insert("cause".into(), cause.into());
    if let Some(bytes) = peak_memory() {
        t.insert("peak_memory_bytes".into(), (bytes as i64).into());
    }
    let text = toml::to_string(&t).map_err(|source| StudyError::StatusText {
        path: path.to_path_buf(),
        source,
    })?;
    crate::io::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    Ok(())
}

/// Peak resident memory of this process (Linux: VmHWM), bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// What a run's status file says.
pub(super) struct Report {
    pub(super) status: Status,
    pub(super) cause: String,
    pub(super) peak_memory_mib: Option<f64>,
}

/// The status file at `path`; a run that wrote none, or one that does not parse, failed.
pub(super) fn read_status(path: &Path) -> Report {
    let report: Option<toml::Table> = std::fs::read_to_string(path)
        .ok()
        .and_then(|t| t.parse().ok());
    let field = |k: &str| report.as_ref().and_then(|r| r.get(k));
    Report {
        status: match field("status").and_then(|s| s.as_str()) {
            Some("finished") => Status::Finished,
            Some("unstable") => Status::Unstable,
            _ => Status::Failed,
        },
        cause: field("cause")
            .and_then(|c| c.as_str())
            .map(String::from)
            .unwrap_or_else(|| "the run ended without a status (see log.txt)".into()),
        peak_memory_mib: field("peak_memory_bytes")
            .and_then(|b| b.as_integer())
            .map(|b| b as f64 / (1024.0 * 1024.0)),
    }
}
