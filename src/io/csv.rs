//! Append-only CSV time series (metrics.csv, probes.csv).

use std::fmt::Write as _;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::IoError;
use crate::Real;

/// A CSV time series: a header of column names, then one row per call, each row handed to the
/// OS in one write so a crashed run keeps every finished row.
///
/// Numbers are written in Rust's shortest round-trip form, so parsing them back (Rust, Python,
/// pandas) gives the identical f64; very large or small magnitudes use exponent form (`1e-300`).
/// Non-finite values appear as `NaN`, `inf`, `-inf`, which those parsers also accept.
#[derive(Debug)]
pub struct CsvSeries {
    path: PathBuf,
    file: File,
    columns: Vec<String>,
    line: String,
    /// The last row written, for readers that step a run themselves (the Python bindings).
    last: Vec<Real>,
}

impl CsvSeries {
    /// Creates (or truncates) `path` and writes the header. Column names holding `,`, `"` or
    /// line breaks are quoted as RFC 4180 says.
    pub fn create(path: &Path, columns: &[String]) -> Result<Self, IoError> {
        if columns.is_empty() {
            return Err(IoError::invalid(
                path,
                "a CSV series needs at least one column",
            ));
        }
        let mut file = File::create(path).map_err(|e| IoError::io(path, "creating", e))?;
        let header = columns
            .iter()
            .map(|c| quote(c))
            .collect::<Vec<_>>()
            .join(",");
        file.write_all(format!("{header}\n").as_bytes())
            .map_err(|e| IoError::io(path, "writing header to", e))?;
        Ok(CsvSeries {
            path: path.to_path_buf(),
            file,
            columns: columns.to_vec(),
            line: String::new(),
            last: Vec::new(),
        })
    }

    /// Appends one row; a row whose length differs from the header's is an error and writes
    /// nothing.
    pub fn row(&mut self, values: &[Real]) -> Result<(), IoError> {
        if values.len() != self.columns.len() {
            return Err(IoError::invalid(
                &self.path,
                format!(
                    "CSV row has {} values for {} columns",
                    values.len(),
                    self.columns.len()
                ),
            ));
        }
        self.line.clear();
        for (i, &v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            write_number(&mut self.line, v);
        }
        self.line.push('\n');
        self.file
            .write_all(self.line.as_bytes())
            .map_err(|e| IoError::io(&self.path, "appending a row to", e))?;
        self.last = values.to_vec();
        Ok(())
    }

    /// The last row written, column by column; empty before the first.
    pub fn last_row(&self) -> impl Iterator<Item = (&str, Real)> {
        let names = self.columns.iter().map(String::as_str);
        names.zip(self.last.iter().copied())
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Plain decimals where they stay short, exponent form elsewhere; both round-trip exactly.
fn write_number(out: &mut String, v: Real) {
    let a = v.abs();
    let _ = if a == 0.0 || !a.is_finite() || (1e-5..1e15).contains(&a) {
        write!(out, "{v}")
    } else {
        write!(out, "{v:e}")
    };
}

fn quote(name: &str) -> String {
    if name.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", name.replace('"', "\"\""))
    } else {
        name.to_string()
    }
}
