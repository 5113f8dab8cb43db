//! A stability study (`eddy sweep --stress`): each point runs long, a run whose energy grows
//! without bound counts as unstable even before it reaches NaN, and each varied key gets the
//! bound between its stable and unstable values (stability.csv).

use std::path::Path;

use super::axes::Axis;
use super::measure::series;
use super::rows::{write_records, Row};
use super::status::Status;
use super::StudyError;

/// Marks a finished run unstable when its energy grew beyond `factor` times its running
/// minimum (a blow-up that has not reached NaN yet): the energy is the metrics' total_energy
/// (SPH: kinetic, potential and rotational), else kinetic_energy (grid). A running minimum of
/// zero (a run that starts at rest) is not a base for a factor and is skipped.
pub(super) fn flag_energy_growth(row: &mut Row, dir: &Path, factor: f64) {
    if row.status != Status::Finished {
        return;
    }
    let path = dir.join("metrics.csv");
    let Some(energy) =
        series(&path, "time", "total_energy").or_else(|| series(&path, "time", "kinetic_energy"))
    else {
        return;
    };
    let mut least = f64::INFINITY;
    for (t, e) in energy {
        least = least.min(e);
        if least > 0.0 && e > factor * least {
            row.status = Status::Unstable;
            row.cause = format!(
                "energy {e:.4e} at t = {t:.6} s is more than {factor} times its running minimum \
                 {least:.4e}"
            );
            return;
        }
    }
}

/// Where one varied key turns unstable.
#[derive(Debug, Clone, PartialEq)]
pub struct Bound {
    pub key: String,
    /// The largest value at which every point was stable (finished).
    pub largest_stable: Option<String>,
    /// The smallest value at which one was not.
    pub smallest_unstable: Option<String>,
}

/// The bound of each varied key, its values ordered numerically when they are numbers (else
/// in the order given).
pub(super) fn bounds(axes: &[Axis], rows: &[Row]) -> Vec<Bound> {
    axes.iter()
        .enumerate()
        .map(|(k, axis)| {
            let rank = |v: &str| -> f64 {
                v.parse::<f64>()
                    .unwrap_or_else(|_| axis.values.iter().position(|x| x == v).unwrap_or(0) as f64)
            };
            let stable_at = |v: &String| {
                let mine: Vec<&Row> = rows.iter().filter(|r| &r.values[k] == v).collect();
                !mine.is_empty() && mine.iter().all(|r| r.status == Status::Finished)
            };
            let tried = |v: &String| rows.iter().any(|r| &r.values[k] == v);
            let by_rank = |a: &&String, b: &&String| rank(a).total_cmp(&rank(b));
            Bound {
                key: axis.key.clone(),
                largest_stable: axis
                    .values
                    .iter()
                    .filter(|v| stable_at(v))
                    .max_by(by_rank)
                    .cloned(),
                smallest_unstable: axis
                    .values
                    .iter()
                    .filter(|v| tried(v) && !stable_at(v))
                    .min_by(by_rank)
                    .cloned(),
            }
        })
        .collect()
}

/// Writes `bounds` as stability.csv (key, largest_stable, smallest_unstable; empty where
/// there is none) to `path`.
pub(super) fn write_bounds(path: &Path, bounds: &[Bound]) -> Result<(), StudyError> {
    let mut records = vec![vec![
        "key".to_string(),
        "largest_stable".into(),
        "smallest_unstable".into(),
    ]];
    records.extend(bounds.iter().map(|b| {
        vec![
            b.key.clone(),
            b.largest_stable.clone().unwrap_or_default(),
            b.smallest_unstable.clone().unwrap_or_default(),
        ]
    }));
    write_records(path, &records)
}
