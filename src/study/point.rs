//! One point of a study, run as `eddy run` in its own folder as a child process: a point that
//! blows up, panics or runs out of time is recorded and the study goes on, and its peak memory
//! is its own.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use super::rows::{run_folder, Row};
use super::status::{read_status, Status};
use super::StudyError;

/// A point as its run needs it.
pub(super) struct Point<'a> {
    pub(super) index: usize,
    pub(super) values: &'a [String],
    pub(super) overrides: Vec<String>,
    /// `eddy run --steps`: the step cap of a stress run.
    pub(super) steps: Option<u64>,
}

/// Runs one point with the eddy executable `exe` as `eddy run` in its folder under `out` and
/// reads how it ended (the row's errors are left empty).
pub(super) fn run_point(
    exe: &Path,
    scene: &Path,
    out: &Path,
    point: &Point,
    threads: usize,
    timeout: Option<f64>,
) -> Result<Row, StudyError> {
    let dir = out.join(run_folder(point.index));
    std::fs::create_dir_all(&dir).map_err(|source| StudyError::Create {
        path: dir.clone(),
        source,
    })?;
    let status_file = dir.join("status.toml");
    let _ = std::fs::remove_file(&status_file);
    let log = std::fs::File::create(dir.join("log.txt")).map_err(|source| StudyError::Log {
        dir: dir.clone(),
        source,
    })?;
    let mut command = Command::new(exe);
    command
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(&dir)
        .arg("--status")
        .arg(&status_file)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .stdout(Stdio::null())
        .stderr(log);
    for o in &point.overrides {
        command.arg("--set").arg(o);
    }
    if let Some(steps) = point.steps {
        // A stress run goes on to its step cap unless the scene's end comes first.
        command.arg("--steps").arg(steps.to_string());
    }
    let started = Instant::now();
    let mut child = command.spawn().map_err(|source| StudyError::Start {
        exe: exe.to_path_buf(),
        source,
    })?;
    let waiting = |source: std::io::Error| StudyError::Wait {
        dir: dir.clone(),
        source,
    };
    let mut timed_out = false;
    loop {
        if child.try_wait().map_err(waiting)?.is_some() {
            break;
        }
        if timeout.is_some_and(|t| started.elapsed().as_secs_f64() > t) {
            child.kill().map_err(waiting)?;
            child.wait().map_err(waiting)?;
            timed_out = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let wall_seconds = started.elapsed().as_secs_f64();
    let report = read_status(&status_file);
    let (status, cause) = if timed_out {
        (
            Status::TimedOut,
            format!("stopped after {:.0} s", timeout.unwrap_or_default()),
        )
    } else {
        (report.status, report.cause)
    };
    let (steps, time) = last_metrics(&dir.join("metrics.csv"));
    Ok(Row {
        index: point.index,
        values: point.values.to_vec(),
        status,
        cause,
        steps,
        time,
        wall_seconds,
        peak_memory_mib: report.peak_memory_mib,
        errors: Vec::new(),
    })
}

/// The steps a run took and the time it ended at, from its metrics.csv.
fn last_metrics(path: &Path) -> (Option<u64>, Option<f64>) {
    let Ok(mut reader) = csv::Reader::from_path(path) else {
        return (None, None);
    };
    let Ok(header) = reader.headers().cloned() else {
        return (None, None);
    };
    let col = |name: &str| header.iter().position(|h| h == name);
    let (Some(step), Some(time), Some(dt)) = (col("step"), col("time"), col("dt")) else {
        return (None, None);
    };
    let Some(last) = reader.records().filter_map(Result::ok).last() else {
        return (None, None);
    };
    let value = |c: usize| last.get(c).and_then(|v| v.parse::<f64>().ok());
    // A row records the step that starts at `time` (step 0 at t = 0): the run has taken one
    // step more than the last row's index and ended at its time plus its dt.
    (
        last.get(step)
            .and_then(|s| s.parse::<u64>().ok())
            .map(|s| s + 1),
        value(time).zip(value(dt)).map(|(t, dt)| t + dt),
    )
}
