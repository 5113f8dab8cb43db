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
    /// Rows in the file below the header.
    rows: u64,
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
            rows: 0,
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
        self.rows += 1;
        Ok(())
    }

    /// Rows written below the header.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Appends the rows of `kept` ([`kept_rows`] of the file this series replaced) to a series
    /// just created, after checking that its header is this series' own.
    pub fn go_on_from(&mut self, kept: &KeptRows) -> Result<(), IoError> {
        let header = self.columns.iter().map(|c| quote(c)).collect::<Vec<_>>();
        if kept.header != header.join(",") {
            return Err(IoError::invalid(
                &self.path,
                format!(
                    "the checkpoint's run wrote the columns {:?}, this run writes {:?}",
                    kept.header,
                    header.join(",")
                ),
            ));
        }
        self.file
            .write_all(kept.rows.as_bytes())
            .map_err(|e| IoError::io(&self.path, "appending the kept rows to", e))?;
        self.rows = kept.count;
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

/// The header and the first rows of a series' file, read before a resumed run replaces it.
#[derive(Debug, Clone)]
pub struct KeptRows {
    header: String,
    rows: String,
    count: u64,
}

/// Reads the header and the first `count` rows of the series `path` (a checkpoint's rows; any
/// after them were written past the checkpoint and are dropped); an error when it has fewer.
pub fn kept_rows(path: &Path, count: u64) -> Result<KeptRows, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, "reading", e))?;
    let mut lines = text.split_inclusive('\n');
    let header = lines.next().unwrap_or_default().trim_end().to_owned();
    let rows: Vec<&str> = lines
        .take(count as usize)
        .take_while(|l| l.ends_with('\n'))
        .collect();
    if (rows.len() as u64) < count {
        return Err(IoError::invalid(
            path,
            format!(
                "{} whole rows, the checkpoint counted {count}: the file was changed after it",
                rows.len()
            ),
        ));
    }
    Ok(KeptRows {
        header,
        rows: rows.concat(),
        count,
    })
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
