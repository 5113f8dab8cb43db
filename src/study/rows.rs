//! The rows of sweep.csv: a point's values, how its run ended and its errors. The file is
//! rewritten whole (atomically) after each run, so a killed study keeps what finished.

use std::path::Path;

use super::status::Status;
use super::StudyError;

/// One row of sweep.csv.
#[derive(Debug, Clone)]
pub struct Row {
    /// The point's number, its place in the study.
    pub index: usize,
    /// Its value of each varied key.
    pub values: Vec<String>,
    pub status: Status,
    pub cause: String,
    pub steps: Option<u64>,
    /// The simulated time it ended at, s.
    pub time: Option<f64>,
    pub wall_seconds: f64,
    pub peak_memory_mib: Option<f64>,
    /// One per measure, in the order of the study's measures.
    pub errors: Vec<Option<f64>>,
}

/// The fixed columns after the varied keys (the error columns come before `folder`).
const COLUMNS: [&str; 7] = [
    "status",
    "cause",
    "steps",
    "end_time",
    "wall_seconds",
    "peak_memory_mib",
    "folder",
];

/// The folder of point `index`, under the study's.
pub(super) fn run_folder(index: usize) -> String {
    format!("run_{index:04}")
}

impl Row {
    fn record(&self) -> Vec<String> {
        let mut r = vec![self.index.to_string()];
        r.extend(self.values.iter().cloned());
        r.extend([
            self.status.name().to_string(),
            self.cause.clone(),
            self.steps.map_or(String::new(), |s| s.to_string()),
            self.time.map_or(String::new(), |t| format!("{t}")),
            format!("{:.3}", self.wall_seconds),
            self.peak_memory_mib
                .map_or(String::new(), |m| format!("{m:.1}")),
        ]);
        r.extend(
            self.errors
                .iter()
                .map(|e| e.map_or(String::new(), |e| format!("{e:e}"))),
        );
        r.push(run_folder(self.index));
        r
    }
}

/// Writes the header (point, the varied `keys`, the fixed columns with the `errors` columns
/// before `folder`) and `rows` (in point order) to `path`, atomically.
pub(super) fn write_rows(
    path: &Path,
    keys: &[String],
    errors: &[String],
    rows: &[Row],
) -> Result<(), StudyError> {
    let mut header = vec!["point".to_string()];
    header.extend(keys.iter().cloned());
    let (fixed, folder) = COLUMNS.split_at(COLUMNS.len() - 1);
    header.extend(fixed.iter().map(|c| c.to_string()));
    header.extend(errors.iter().cloned());
    header.extend(folder.iter().map(|c| c.to_string()));
    let mut sorted: Vec<&Row> = rows.iter().collect();
    sorted.sort_by_key(|r| r.index);
    let mut records = vec![header];
    records.extend(sorted.iter().map(|r| r.record()));
    write_records(path, &records)
}

/// Writes `records` as CSV to `path`, atomically.
pub(super) fn write_records(path: &Path, records: &[Vec<String>]) -> Result<(), StudyError> {
    crate::io::write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        for r in records {
            w.write_record(r)?;
        }
        w.flush()
    })?;
    Ok(())
}
