//! The curves `eddy plot-sweep` draws from a sweep.csv: y against x of its rows, a curve per
//! value of the grouping columns. Grouped by status, the curves come in a fixed order, so a
//! stability map reads red for unstable (the palette's first colour) and green for finished
//! (its second) whatever order the rows are in.

use std::path::Path;

use super::StudyError;

/// A curve: its label and its points (x, y).
pub type Curve = (String, Vec<(f64, f64)>);

/// Column `y` against column `x` of the sweep.csv at `path`, a curve per value of the `by`
/// columns (one curve, labelled `y`, when `by` is empty), the points of a curve in order of x;
/// rows without a number in either column are left out.
pub fn curves(path: &Path, x: &str, y: &str, by: &[String]) -> Result<Vec<Curve>, StudyError> {
    let reading = |source: csv::Error| StudyError::Csv {
        path: path.to_path_buf(),
        source,
    };
    let mut reader = csv::Reader::from_path(path).map_err(reading)?;
    let header = reader.headers().map_err(reading)?.clone();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| StudyError::NoColumn {
                path: path.to_path_buf(),
                column: name.to_string(),
                columns: header.iter().collect::<Vec<_>>().join(", "),
            })
    };
    let (cx, cy) = (col(x)?, col(y)?);
    let by: Vec<(usize, &String)> = by
        .iter()
        .map(|name| Ok((col(name)?, name)))
        .collect::<Result<_, StudyError>>()?;
    let mut curves: Vec<Curve> = Vec::new();
    for record in reader.records() {
        let r = record.map_err(reading)?;
        let (Some(px), Some(py)) = (
            r.get(cx).and_then(|v| v.parse::<f64>().ok()),
            r.get(cy).and_then(|v| v.parse::<f64>().ok()),
        ) else {
            continue;
        };
        let label = if by.is_empty() {
            y.to_string()
        } else {
            by.iter()
                .map(|&(c, name)| format!("{name} = {}", r.get(c).unwrap_or_default()))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match curves.iter_mut().find(|(l, _)| *l == label) {
            Some((_, c)) => c.push((px, py)),
            None => curves.push((label, vec![(px, py)])),
        }
    }
    for (_, c) in &mut curves {
        c.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let rank = |label: &str| {
        ["unstable", "finished", "failed", "timed out"]
            .iter()
            .position(|s| label.contains(&format!("status = {s}")))
    };
    curves.sort_by_key(|(label, _)| rank(label));
    Ok(curves)
}
