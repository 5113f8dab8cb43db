//! `eddy sweep --collect`: the rows of a study run in shards (`--shard k/N`, each into its own
//! `sweep-k-of-N.csv`, perhaps on other machines) joined into one sweep.csv. A shard missing
//! or there twice is refused rather than joined into a study with holes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::rows::write_records;
use super::StudyError;

/// Joins the rows of the `sweep-k-of-N.csv` files in `dirs` into `out`: every shard 0..N
/// present once, one header for all, no point twice. Returns the number of rows.
pub fn collect(dirs: &[PathBuf], out: &Path) -> Result<usize, StudyError> {
    let shards = find_shards(dirs)?;
    let mut header: Option<csv::StringRecord> = None;
    let mut rows: BTreeMap<usize, Vec<String>> = BTreeMap::new();
    for path in shards.values() {
        let reading = |source: csv::Error| StudyError::Csv {
            path: path.clone(),
            source,
        };
        let mut reader = csv::Reader::from_path(path).map_err(reading)?;
        let h = reader.headers().map_err(reading)?.clone();
        if header.get_or_insert_with(|| h.clone()) != &h {
            return Err(StudyError::ShardColumns(path.clone()));
        }
        for record in reader.records() {
            let record = record.map_err(reading)?;
            let index: usize = record
                .get(0)
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| StudyError::NoPointNumber(path.clone()))?;
            if rows
                .insert(index, record.iter().map(String::from).collect())
                .is_some()
            {
                return Err(StudyError::PointTwice(index));
            }
        }
    }
    let mut records = vec![header
        .map(|h| h.iter().map(String::from).collect())
        .unwrap_or_default()];
    let n_rows = rows.len();
    records.extend(rows.into_values());
    write_records(out, &records)?;
    Ok(n_rows)
}

/// The shard files in `dirs` by k: all of one study in N shards, each there once.
fn find_shards(dirs: &[PathBuf]) -> Result<BTreeMap<usize, PathBuf>, StudyError> {
    let mut shards: BTreeMap<usize, PathBuf> = BTreeMap::new();
    let mut count = None;
    for dir in dirs {
        let listing = |source: std::io::Error| StudyError::Listing {
            dir: dir.clone(),
            source,
        };
        for entry in std::fs::read_dir(dir).map_err(listing)? {
            let path = entry.map_err(listing)?.path();
            let Some((k, n)) = path
                .file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.strip_prefix("sweep-")?.strip_suffix(".csv"))
                .and_then(|kn| {
                    let (k, n) = kn.split_once("-of-")?;
                    Some((k.parse::<usize>().ok()?, n.parse::<usize>().ok()?))
                })
            else {
                continue;
            };
            let first = *count.get_or_insert(n);
            if first != n {
                return Err(StudyError::ShardCount { path, n, first });
            }
            if let Some(other) = shards.insert(k, path.clone()) {
                return Err(StudyError::ShardTwice {
                    k,
                    first: other,
                    second: path,
                });
            }
        }
    }
    let n = count.ok_or(StudyError::NoShards)?;
    if let Some(k) = (0..n).find(|k| !shards.contains_key(k)) {
        return Err(StudyError::ShardMissing { k, n });
    }
    Ok(shards)
}
