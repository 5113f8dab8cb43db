//! A precomputation run: the directions of this shard that are not finished yet, computed in
//! parallel, each kept as a part when done, and the database written at the end.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use anyhow::{bail, Context};
use eddy::abl::{AblData, AblHeader, DirectionTable, MotionKind};
use eddy::Vec3;

use crate::parts;
use crate::solve::{solve, Surface};
use crate::spec::ObstacleSpec;

/// One direction to compute: polar and azimuth sample of one motion kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Job {
    pub kind: MotionKind,
    pub polar: usize,
    pub azimuth: usize,
}

/// Every direction of `spec` that needs its own solve, in the canonical order shards count in:
/// translation then rotation, polar-major, each pole once.
pub fn all_jobs(spec: &ObstacleSpec) -> Vec<Job> {
    MotionKind::ALL
        .iter()
        .zip(spec.samplings())
        .flat_map(|(&kind, s)| {
            s.distinct().into_iter().map(move |(polar, azimuth)| Job {
                kind,
                polar,
                azimuth,
            })
        })
        .collect()
}

/// How to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The database (or shard) to write.
    pub out: PathBuf,
    /// `(k, n)`: compute every n-th direction starting at k.
    pub shard: Option<(usize, usize)>,
    /// Keep the directions finished in `out` or its parts folder.
    pub resume: bool,
    /// Directions computed at once, each on one thread (so the result does not depend on
    /// thread scheduling, sharding or resuming: every direction is computed the same way).
    pub workers: usize,
    /// Show a progress bar.
    pub progress: bool,
}

/// What a run did.
#[derive(Debug, Clone, Copy)]
pub struct Summary {
    pub computed: usize,
    pub reused: usize,
    pub points: usize,
    /// Mean wall time of one direction on one thread, s.
    pub seconds_per_direction: f64,
}

/// An empty database of `spec` (no direction computed) over `surface`.
pub fn empty_database(spec: &ObstacleSpec, surface: &Surface) -> anyhow::Result<AblData> {
    let (fingerprint, geometry_fingerprint) = spec.fingerprints()?;
    let spacing = spec.spacing()?;
    let [ts, rs] = spec.samplings();
    let p = surface.points.len();
    Ok(AblData {
        header: AblHeader {
            obstacle: spec.name.clone(),
            fingerprint,
            geometry_fingerprint,
            beta: spec.layer.beta,
            layer_thickness: spec.layer.thickness * spacing,
            spacing,
            settings: spec.settings_toml(),
        },
        points: surface.points.clone(),
        normals: surface.normals.clone(),
        translation: DirectionTable::empty(ts, p),
        rotation: DirectionTable::empty(rs, p),
    })
}

/// A finished direction as it reaches the run: its values (or why it failed) and its wall
/// time on one thread, s.
pub type Finished = (Job, anyhow::Result<Vec<Vec3>>, f64);

/// What computes the directions of a run: threads of this process ([`Threads`]), or MPI ranks
/// (`crate::mpi`, feature `mpi`). `compute` hands out the jobs of `todo` and passes each
/// finished one to `deliver` as it arrives; once `deliver` returns false it hands out no more
/// and returns when those in flight are done.
pub trait Engine {
    fn compute(
        &mut self,
        spec: &ObstacleSpec,
        surface: &Surface,
        todo: &[Job],
        deliver: &mut dyn FnMut(Finished) -> bool,
    );
}

/// One direction, on one thread (so its values do not depend on how many run at once).
pub fn compute_job(spec: &ObstacleSpec, surface: &Surface, job: &Job) -> anyhow::Result<Vec<Vec3>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let s = spec.samplings()[usize::from(job.kind == MotionKind::Rotation)];
    let d = s.direction(job.polar, job.azimuth);
    pool.install(|| solve(spec, surface, job.kind, &d))
}

/// The jobs of a run, handed out one at a time (to threads or ranks) until they run out or the
/// run is stopped.
pub struct JobQueue<'a> {
    todo: &'a [Job],
    next: AtomicUsize,
    stopped: AtomicBool,
}

impl<'a> JobQueue<'a> {
    pub fn new(todo: &'a [Job]) -> Self {
        Self {
            todo,
            next: AtomicUsize::new(0),
            stopped: AtomicBool::new(false),
        }
    }

    /// The next job, or `None` once all are handed out or the run is stopped.
    pub fn take(&self) -> Option<Job> {
        if self.stopped.load(Ordering::Relaxed) {
            return None;
        }
        self.todo
            .get(self.next.fetch_add(1, Ordering::Relaxed))
            .copied()
    }

    /// Hands out no more jobs.
    pub fn stop(&self) {
        self.stopped.store(true, Ordering::Relaxed);
    }

    /// Computes jobs on this thread, sending each to `tx` as it finishes, until the queue is
    /// done or nobody receives.
    pub fn work(&self, spec: &ObstacleSpec, surface: &Surface, tx: &mpsc::Sender<Finished>) {
        while let Some(job) = self.take() {
            let started = Instant::now();
            let result = compute_job(spec, surface, &job);
            if tx
                .send((job, result, started.elapsed().as_secs_f64()))
                .is_err()
            {
                break;
            }
        }
    }
}

/// `workers` directions at once, one thread each, pulling the next job when done.
pub struct Threads {
    pub workers: usize,
}

impl Engine for Threads {
    fn compute(
        &mut self,
        spec: &ObstacleSpec,
        surface: &Surface,
        todo: &[Job],
        deliver: &mut dyn FnMut(Finished) -> bool,
    ) {
        let queue = &JobQueue::new(todo);
        let (tx, rx) = mpsc::channel::<Finished>();
        std::thread::scope(|scope| {
            for _ in 0..self.workers.max(1).min(todo.len().max(1)) {
                let tx = tx.clone();
                scope.spawn(move || queue.work(spec, surface, &tx));
            }
            drop(tx);
            for finished in rx {
                if !deliver(finished) {
                    queue.stop();
                }
            }
        });
    }
}

/// Runs the precomputation of `spec` as `options` say, on `options.workers` threads.
pub fn precompute(spec: &ObstacleSpec, options: &RunOptions) -> anyhow::Result<Summary> {
    let mut threads = Threads {
        workers: options.workers,
    };
    precompute_with(spec, options, &mut threads)
}

/// [`precompute`] with the directions computed by `engine`. Only this process reads and
/// writes the output and its parts: each finished direction becomes a part as it arrives, so
/// a run killed at any moment loses only the directions in flight.
pub fn precompute_with(
    spec: &ObstacleSpec,
    options: &RunOptions,
    engine: &mut dyn Engine,
) -> anyhow::Result<Summary> {
    let surface = Surface::of(spec)?;
    let mut data = empty_database(spec, &surface)?;
    let fingerprint = data.header.fingerprint.clone();
    let dir = parts::folder(&options.out);
    let mut reused = 0;
    if options.resume {
        if options.out.exists() {
            let old = AblData::read(&options.out)?;
            if old.header.fingerprint != fingerprint || old.points != data.points {
                bail!(
                    "{} was computed with other settings or geometry; --resume needs the same \
                     obstacle file and overrides",
                    options.out.display()
                );
            }
            data.translation = old.translation;
            data.rotation = old.rotation;
        }
        for (job, values) in parts::read_all(&dir, &fingerprint, surface.points.len())? {
            data.table_mut(job.kind)
                .set(job.polar, job.azimuth, &values);
        }
    } else if dir.exists() {
        bail!(
            "{} holds directions finished by an interrupted run: pass --resume to keep them, or \
             delete the folder",
            dir.display()
        );
    }
    let (k, n) = options.shard.unwrap_or((0, 1));
    let mine: Vec<Job> = all_jobs(spec)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % n == k)
        .map(|(_, j)| j)
        .collect();
    let todo: Vec<Job> = mine
        .iter()
        .copied()
        .filter(|j| {
            let t = data.table(j.kind);
            !t.complete[t.sampling.row(j.polar, j.azimuth)]
        })
        .collect();
    reused += mine.len() - todo.len();
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let bar = progress_bar(options.progress, mine.len() as u64, reused as u64);
    let mut seconds = 0.0;
    let mut failure = None;
    engine.compute(spec, &surface, &todo, &mut |(job, result, secs)| {
        let kept = result.and_then(|values| {
            parts::write(&dir, &fingerprint, &job, &values)?;
            Ok(values)
        });
        match kept {
            Ok(values) => {
                data.table_mut(job.kind)
                    .set(job.polar, job.azimuth, &values);
                seconds += secs;
                bar.inc(1);
                bar.set_message(format!("{secs:.1} s/direction"));
            }
            Err(e) => {
                failure.get_or_insert(e.context(format!(
                    "{} direction (polar {}, azimuth {})",
                    job.kind.name(),
                    job.polar,
                    job.azimuth
                )));
            }
        }
        failure.is_none()
    });
    bar.finish_and_clear();
    if let Some(e) = failure {
        return Err(e);
    }
    if let Some(job) = todo.iter().find(|j| {
        let t = data.table(j.kind);
        !t.complete[t.sampling.row(j.polar, j.azimuth)]
    }) {
        bail!(
            "the run ended with {} direction (polar {}, azimuth {}) not computed",
            job.kind.name(),
            job.polar,
            job.azimuth
        );
    }
    data.write(&options.out)?;
    std::fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
    Ok(Summary {
        computed: todo.len(),
        reused,
        points: surface.points.len(),
        seconds_per_direction: if todo.is_empty() {
            0.0
        } else {
            seconds / todo.len() as f64
        },
    })
}

fn progress_bar(show: bool, len: u64, done: u64) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {pos}/{len} directions, {elapsed} elapsed, ~{eta} left, {msg}",
    ) {
        bar.set_style(style);
    }
    bar.set_position(done);
    bar
}

/// Combines shard files into one database: all must share the fingerprint, and every direction
/// must be finished in exactly one of them (no overlap, no gap).
pub fn merge(shards: &[PathBuf], out: &Path) -> anyhow::Result<()> {
    let (first, rest) = shards
        .split_first()
        .context("merge needs at least one shard")?;
    let mut merged = AblData::read(first)?;
    let mut owner: Vec<Vec<Option<&Path>>> = MotionKind::ALL
        .iter()
        .map(|&k| {
            merged
                .table(k)
                .complete
                .iter()
                .map(|&c| c.then_some(first.as_path()))
                .collect()
        })
        .collect();
    for path in rest {
        let shard = AblData::read(path)?;
        if shard.header != merged.header
            || shard.points != merged.points
            || shard.normals != merged.normals
        {
            bail!(
                "{} and {} come from different precomputations (fingerprint or points differ)",
                first.display(),
                path.display()
            );
        }
        for (ki, kind) in MotionKind::ALL.into_iter().enumerate() {
            let src = shard.table(kind);
            let points = merged.points.len();
            let p = points * 3;
            let dst = merged.table_mut(kind);
            if src.sampling != dst.sampling {
                bail!("{} samples {} differently", path.display(), kind.name());
            }
            for row in (0..src.complete.len()).filter(|&r| src.complete[r]) {
                if let Some(other) = owner[ki][row] {
                    let a = src.sampling.azimuth;
                    bail!(
                        "shards overlap: {} direction (polar {}, azimuth {}) is in both {} and {}",
                        kind.name(),
                        row / a,
                        row % a,
                        other.display(),
                        path.display()
                    );
                }
                owner[ki][row] = Some(path.as_path());
                dst.omega[row * p..(row + 1) * p].copy_from_slice(src.row(row, points));
                dst.complete[row] = true;
            }
        }
    }
    for kind in MotionKind::ALL {
        let missing = merged.table(kind).missing();
        if let Some((i, j)) = missing.first() {
            bail!(
                "shards leave a gap: {} {} direction(s) in none of them (first: polar {i}, \
                 azimuth {j}); run the missing shard",
                missing.len(),
                kind.name()
            );
        }
    }
    merged.write(out)?;
    Ok(())
}
