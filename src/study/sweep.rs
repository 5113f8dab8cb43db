//! A study from its description to its rows: every point's scene is checked before any run
//! (a bad key or value stops the study there, naming the point), then the points run a few at
//! once, each worker taking the next point, the cores split between them. A point that cannot
//! be run or recorded stops its worker; the others finish theirs.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

use super::point::{run_point, Point};
use super::rows::{run_folder, write_rows, Row};
use super::stability::{bounds, flag_energy_growth, write_bounds, Bound};
use super::{Design, Measure, StudyError};

/// A parameter study of one scene.
#[derive(Debug, Clone)]
pub struct Study {
    /// The scene file every point runs.
    pub scene: PathBuf,
    /// The varied keys and the points.
    pub design: Design,
    /// Overrides (`KEY=VALUE`) held for every point, before its varied values.
    pub set: Vec<String>,
    /// The `error_*` columns.
    pub measures: Vec<Measure>,
    /// A stability study: long runs, energy growth counted as unstable, stability.csv.
    pub stress: Option<Stress>,
    /// Runs at once (at least one); the cores are split between them.
    pub jobs: usize,
    /// (k, N): run every N-th point starting at k, into sweep-k-of-N.csv.
    pub shard: Option<(usize, usize)>,
    /// Wall-clock seconds after which a run is stopped and recorded as timed out.
    pub timeout: Option<f64>,
    /// The study's folder; `out/sweep_<scene name>` when None.
    pub out: Option<PathBuf>,
}

/// The long runs of a stability study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stress {
    /// The step cap of each run (`eddy run --steps`), unless the scene's end comes first.
    pub steps: u64,
    /// A finished run whose energy exceeds this factor times its running minimum is unstable;
    /// 0 turns the check off.
    pub energy_growth: f64,
}

/// A study checked and laid out, ready to run.
#[derive(Debug)]
pub struct Plan<'a> {
    study: &'a Study,
    /// The study's folder, created.
    pub out: PathBuf,
    /// Its rows: sweep.csv, or sweep-k-of-N.csv of a shard.
    pub csv: PathBuf,
    /// The points this shard runs.
    pub here: Vec<usize>,
    /// Runs at once.
    pub jobs: usize,
    /// Threads of each run.
    pub threads: usize,
}

impl Study {
    /// Loads every point's scene (and checks it against the analytic solutions measured),
    /// creates the study's folder and picks this shard's points and the threads of each run.
    pub fn plan(&self) -> Result<Plan<'_>, StudyError> {
        let mut name = String::new();
        for index in 0..self.design.points().len() {
            let refused = |source: StudyError| StudyError::Point {
                index,
                point: self.design.describe(index),
                source: Box::new(source),
            };
            let scene = crate::scene::load(&self.scene, &self.design.overrides(&self.set, index))
                .map_err(|e| refused(e.into()))?;
            for m in &self.measures {
                if let Measure::Analytic(a) = m {
                    a.check(&scene).map_err(refused)?;
                }
            }
            name = scene.name;
        }
        let out = self
            .out
            .clone()
            .unwrap_or_else(|| Path::new("out").join(format!("sweep_{name}")));
        std::fs::create_dir_all(&out).map_err(|source| StudyError::Create {
            path: out.clone(),
            source,
        })?;
        let (k, n) = self.shard.unwrap_or((0, 1));
        let here: Vec<usize> = (0..self.design.points().len())
            .filter(|i| i % n == k)
            .collect();
        let csv = self.file(&out, "sweep");
        let jobs = self.jobs.min(here.len()).max(1);
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        Ok(Plan {
            study: self,
            out,
            csv,
            here,
            jobs,
            threads: (cores / jobs).max(1),
        })
    }

    /// `STEM.csv` in the study's folder `out`, or `STEM-k-of-N.csv` of a shard.
    fn file(&self, out: &Path, stem: &str) -> PathBuf {
        out.join(match self.shard {
            Some((k, n)) => format!("{stem}-{k}-of-{n}.csv"),
            None => format!("{stem}.csv"),
        })
    }
}

impl Plan<'_> {
    /// Runs this shard's points with the eddy executable `exe`, rewriting the rows file after
    /// each, and returns the rows. `progress` hears of each point as it ends: its row, or None
    /// when it could not be run or recorded (the study then fails with why, once the other
    /// workers are done).
    pub fn run(
        &self,
        exe: &Path,
        progress: impl Fn(Option<&Row>) + Sync,
    ) -> Result<Vec<Row>, StudyError> {
        let keys = self.study.design.keys();
        let errors: Vec<String> = self.study.measures.iter().map(Measure::name).collect();
        let rows: Mutex<Vec<Row>> = Mutex::new(Vec::new());
        let next = AtomicUsize::new(0);
        let failure: Mutex<Option<StudyError>> = Mutex::new(None);
        std::thread::scope(|scope| {
            for _ in 0..self.jobs {
                scope.spawn(|| {
                    while let Some(&index) = self.here.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let row = self.measured(exe, index);
                        progress(row.as_ref().ok());
                        let written = row.and_then(|row| {
                            let mut rows = lock(&rows);
                            rows.push(row);
                            write_rows(&self.csv, &keys, &errors, &rows)
                        });
                        if let Err(e) = written {
                            lock(&failure).get_or_insert(e);
                            return;
                        }
                    }
                });
            }
        });
        if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
            return Err(e);
        }
        let rows = rows.into_inner().unwrap_or_else(|p| p.into_inner());
        // Written once more for a shard that had no point to run: its header.
        write_rows(&self.csv, &keys, &errors, &rows)?;
        Ok(rows)
    }

    /// Point `index` run and measured.
    fn measured(&self, exe: &Path, index: usize) -> Result<Row, StudyError> {
        let study = self.study;
        let point = Point {
            index,
            values: &study.design.points()[index],
            overrides: study.design.overrides(&study.set, index),
            steps: study.stress.map(|s| s.steps),
        };
        let mut row = run_point(
            exe,
            &study.scene,
            &self.out,
            &point,
            self.threads,
            study.timeout,
        )?;
        let dir = self.out.join(run_folder(index));
        row.errors = study.measures.iter().map(|m| m.error(&dir)).collect();
        if let Some(s) = study.stress.filter(|s| s.energy_growth > 0.0) {
            flag_energy_growth(&mut row, &dir, s.energy_growth);
        }
        Ok(row)
    }

    /// Of a stability study, where each varied key turns unstable over `rows`.
    pub fn bounds(&self, rows: &[Row]) -> Option<Vec<Bound>> {
        self.study
            .stress
            .map(|_| bounds(&self.study.design.axes, rows))
    }

    /// Writes `bounds` to stability.csv (stability-k-of-N.csv of a shard).
    pub fn write_bounds(&self, bounds: &[Bound]) -> Result<(), StudyError> {
        write_bounds(&self.study.file(&self.out, "stability"), bounds)
    }
}

/// The lock of `m`, also when a worker panicked holding it (the rows stay whole: a push).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}
