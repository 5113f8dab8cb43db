//! What each run of a study is measured against, one `error_*` column of sweep.csv each: an
//! analytic solution, a column of a reference run (`--reference`, `--compare`) or a published
//! table (`--reference-csv`, `--column`). The references are read and checked when the measure
//! is made, before any run, so a study does not run for hours to find a column missing.

use std::path::{Path, PathBuf};

use super::{Analytic, StudyError};

/// A measure of each run: a column of sweep.csv.
#[derive(Debug, Clone)]
pub enum Measure {
    /// An analytic solution eddy knows.
    Analytic(Analytic),
    /// A series of the run against the same series of a reference.
    Series(Series),
}

/// A series of a run, (time or s, value), against a reference's.
#[derive(Debug, Clone)]
pub struct Series {
    /// The run's file (metrics, probes, profile_NAME); None: metrics or probes, whichever has
    /// the column.
    file: Option<String>,
    along: &'static str,
    column: String,
    /// The sweep.csv column is `error_<name>`.
    name: String,
    reference: Vec<(f64, f64)>,
}

impl Measure {
    /// A column of the reference run in `dir`, `spec` as `--compare` takes it: metrics:COLUMN
    /// or probes:COLUMN (against time), profile:PROBE:COLUMN (against s along the probe).
    pub fn compare(dir: &Path, spec: &str) -> Result<Measure, StudyError> {
        let parts: Vec<&str> = spec.split(':').collect();
        let (file, along, column, name) = match parts[..] {
            ["metrics", col] | ["probes", col] => {
                (parts[0].to_string(), "time", col, col.to_string())
            }
            ["profile", probe, col] => (
                format!("profile_{probe}"),
                "s",
                col,
                format!("{probe}_{col}"),
            ),
            _ => return Err(StudyError::CompareForm(spec.to_string())),
        };
        let path = dir.join(format!("{file}.csv"));
        let reference = series(&path, along, column).ok_or_else(|| StudyError::CompareColumn {
            spec: spec.to_string(),
            path: path.clone(),
        })?;
        Ok(Measure::Series(Series {
            file: Some(file),
            along,
            column: column.to_string(),
            name,
            reference,
        }))
    }

    /// `column` of a published table at `path` (CSV with a `time` column), against the run's
    /// metrics or probes column of that name.
    pub fn table(path: &Path, column: &str) -> Result<Measure, StudyError> {
        let reference = series(path, "time", column).ok_or_else(|| StudyError::TableColumns {
            path: PathBuf::from(path),
            column: column.to_string(),
        })?;
        // Named after the table too, so it cannot clash with --compare's error of the column.
        let table = path.file_stem().unwrap_or_default().to_string_lossy();
        Ok(Measure::Series(Series {
            file: None,
            along: "time",
            column: column.to_string(),
            name: format!("{column}_{table}"),
            reference,
        }))
    }

    /// Its column in sweep.csv.
    pub fn name(&self) -> String {
        match self {
            Measure::Analytic(a) => a.column().into(),
            Measure::Series(s) => format!("error_{}", s.name),
        }
    }

    /// The error of the run in `dir`; None when it has no such series.
    pub fn error(&self, dir: &Path) -> Option<f64> {
        match self {
            Measure::Analytic(a) => a.error(dir),
            Measure::Series(s) => {
                let files = match &s.file {
                    Some(f) => vec![f.as_str()],
                    None => vec!["metrics", "probes"],
                };
                let run = files
                    .iter()
                    .find_map(|f| series(&dir.join(format!("{f}.csv")), s.along, &s.column))?;
                relative_l2(&run, &s.reference)
            }
        }
    }
}

/// (`along`, value) of `column` of a CSV with an `along` column (time, or s of a profile);
/// None when either is missing. Lines starting with `#` are comments (a published table's
/// source, as in `scenes/reference/`).
pub(super) fn series(path: &Path, along: &str, column: &str) -> Option<Vec<(f64, f64)>> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .ok()?;
    let header = reader.headers().ok()?.clone();
    let t = header.iter().position(|h| h == along)?;
    let c = header.iter().position(|h| h == column)?;
    Some(
        reader
            .records()
            .filter_map(Result::ok)
            .filter_map(|r| Some((r.get(t)?.parse().ok()?, r.get(c)?.parse().ok()?)))
            .collect(),
    )
}

/// sqrt(sum (a(t_k) - r_k)^2 / sum r_k^2) over the reference rows (t_k, r_k) inside the run's
/// span of t (time, or s along a profile), with a(t) the run's series interpolated linearly;
/// None when none overlap.
fn relative_l2(run: &[(f64, f64)], reference: &[(f64, f64)]) -> Option<f64> {
    let (first, last) = (run.first()?.0, run.last()?.0);
    let (mut num, mut den, mut n) = (0.0, 0.0, 0);
    for &(t, r) in reference.iter().filter(|(t, _)| *t >= first && *t <= last) {
        let i = run.partition_point(|(s, _)| *s < t);
        let a = match (i.checked_sub(1).map(|j| run[j]), run.get(i)) {
            (_, Some(&(s, v))) if s == t => v,
            (Some((s0, v0)), Some(&(s1, v1))) => v0 + (v1 - v0) * (t - s0) / (s1 - s0),
            (Some((_, v)), None) | (None, Some(&(_, v))) => v,
            (None, None) => return None,
        };
        num += (a - r) * (a - r);
        den += r * r;
        n += 1;
    }
    (n > 0).then(|| {
        if den > 0.0 {
            (num / den).sqrt()
        } else {
            num.sqrt()
        }
    })
}
