//! What the run tests share: an obstacle file written to a folder, run options, the lock that
//! keeps tests that start processes apart, and waiting for finished directions.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use eddy_precompute::{ObstacleSpec, RunOptions};

/// Writes `text` as `dir/sphere.toml` and loads it.
pub fn obstacle(dir: &Path, text: &str) -> (ObstacleSpec, PathBuf) {
    let path = dir.join("sphere.toml");
    std::fs::write(&path, text).expect("writes the obstacle file");
    (ObstacleSpec::load(&path, &[]).expect("valid"), path)
}

/// A run into `out` on `workers` threads, without a progress bar.
pub fn options(
    out: PathBuf,
    shard: Option<(usize, usize)>,
    resume: bool,
    workers: usize,
) -> RunOptions {
    RunOptions {
        out,
        shard,
        resume,
        workers,
        progress: false,
    }
}

/// HDF5 opens files without close-on-exec: a child started while another test of the file has
/// a database open inherits the descriptor and its lock, and the next open fails. Tests that
/// start processes therefore hold this while they run.
pub fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Finished directions (part files) in the parts folder `dir`.
pub fn finished_parts(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |r| {
        r.filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "bin"))
        })
        .count()
    })
}

/// Waits (at most a minute) until `n` directions are finished in `dir`.
pub fn wait_for_parts(dir: &Path, n: usize) {
    let started = Instant::now();
    while finished_parts(dir) < n {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "no direction finished"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}
