//! Errors of a parameter study, written for the person at the command line: each names the
//! argument (`--vary`, `--zip`, `--compare`, ...) or the file that is wrong, and a refused point
//! of the study is named with its values.

use std::path::PathBuf;

use crate::io::IoError;
use crate::scene::SceneError;

/// Why a study could not be set up, run, joined or plotted.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A `--vary` argument without `=`.
    #[error("--vary `{0}`: expected KEY=V1,V2,...")]
    VaryForm(String),
    #[error("--vary `{0}`: the key is empty")]
    VaryEmptyKey(String),
    /// Value `number` (from 1) of a `--vary` list is empty (`0.1,,0.2`).
    #[error("--vary `{arg}`: value {number} is empty")]
    VaryEmptyValue { arg: String, number: usize },
    #[error("--vary {0} is given twice")]
    VaryTwice(String),
    #[error("--zip {0}: not a --vary key")]
    ZipKey(String),
    /// Zipped lists differ in length: `first` has `count` values, `other` has `other_count`.
    #[error(
        "--zip pairs lists of one length: {first} has {count} values, {other} has {other_count}"
    )]
    ZipLengths {
        first: String,
        count: usize,
        other: String,
        other_count: usize,
    },
    #[error("--compare `{0}`: expected metrics:COLUMN, probes:COLUMN or profile:PROBE:COLUMN")]
    CompareForm(String),
    /// The reference run's file at `path` lacks the column `--compare spec` names.
    #[error("--compare {spec}: the reference {} has no such column", path.display())]
    CompareColumn { spec: String, path: PathBuf },
    /// The published table lacks a `time` column or `column`.
    #[error("--reference-csv {}: no `time` and `{column}` columns", path.display())]
    TableColumns { path: PathBuf, column: String },
    /// The scene is not the flow the analytic solution (by its command-line name) describes.
    #[error("--analytic {analytic}: {reason}")]
    NotDescribed {
        analytic: &'static str,
        reason: String,
    },
    /// Point `index` (`point`: its values) is refused before any run; the source says why.
    #[error("point {index} ({point})")]
    Point {
        index: usize,
        point: String,
        #[source]
        source: Box<StudyError>,
    },
    /// A point's scene does not load.
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("creating {}", path.display())]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The log file of the run in `dir` cannot be created.
    #[error("creating the log in {}", dir.display())]
    Log {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The eddy executable `exe` does not start.
    #[error("starting {}", exe.display())]
    Start {
        exe: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The child process of the run in `dir` cannot be waited for or stopped.
    #[error("waiting for the run in {}", dir.display())]
    Wait {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The status file at `path` cannot be put in TOML.
    #[error("writing {}", path.display())]
    StatusText {
        path: PathBuf,
        #[source]
        source: toml::ser::Error,
    },
    /// A folder given to `--collect` cannot be listed.
    #[error("listing {}", dir.display())]
    Listing {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The shard at `path` is one of `n`, the first one found of `first`.
    #[error(
        "{} belongs to a study in {n} shards, the others to one in {first}",
        path.display()
    )]
    ShardCount {
        path: PathBuf,
        n: usize,
        first: usize,
    },
    #[error("shard {k} is there twice: {} and {}", first.display(), second.display())]
    ShardTwice {
        k: usize,
        first: PathBuf,
        second: PathBuf,
    },
    #[error("no sweep-k-of-N.csv in the folders given")]
    NoShards,
    #[error("shard {k} of {n} is missing: run it with --shard {k}/{n}")]
    ShardMissing { k: usize, n: usize },
    /// A CSV file (a shard, a sweep.csv) cannot be read.
    #[error("reading {}", path.display())]
    Csv {
        path: PathBuf,
        #[source]
        source: csv::Error,
    },
    /// A shard whose header differs from the first shard's.
    #[error("{} has other columns than the first shard", .0.display())]
    ShardColumns(PathBuf),
    #[error("{}: a row without a point number", .0.display())]
    NoPointNumber(PathBuf),
    #[error("point {0} is in two shards")]
    PointTwice(usize),
    /// The sweep.csv at `path` has no `column`; `columns` lists those it has.
    #[error("{} has no column `{column}` (it has: {columns})", path.display())]
    NoColumn {
        path: PathBuf,
        column: String,
        columns: String,
    },
    /// Writing sweep.csv, stability.csv or a status file failed.
    #[error(transparent)]
    Io(#[from] IoError),
}
