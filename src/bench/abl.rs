//! `eddy bench-abl`: run time against error for the artificial boundary layers, the protocol of
//! Pfaff et al. 2009, Figure 8. A scene at its coarse resolution with boundary-layer seeding
//! (`abl`), with the same particles seeded at random along the walls (`random`), and with no
//! turbulence (`none`), against the plain run at `scale` times the resolution (`reference`).
//! On a grid the scene is the backward-facing step (below); on SPH particles a stream past
//! obstacles in a channel, measured as [`super::abl_particles`] says, the reference at
//! `1/scale` the spacing.
//!
//! **Measure.** Each run keeps the running statistics of its flow (`[statistics]`, from the
//! scene's `grid.average_from`, or half the run on particles) with one station per position
//! behind the obstacles: a box one coarse cell thick along x, cut into coarse bins across the
//! flow (y on the grid, z on particles) and taking the whole span (z) or depth (y). A bin's
//! time-averaged velocity `U` and turbulent kinetic energy `k` are the averages of its lattice
//! cells' (`crate::metrics::stations`): each cell's own temporal fluctuation, so a fine run's
//! small-scale fluctuation counts as fluctuation, not the mean shear across a bin; on the grid
//! the cells along the periodic span are pooled first, as one ensemble. On
//! particles every run's lattice has the same cells (two coarse spacings), so the reference is
//! filtered as the coarse runs are. The errors are root-mean-square differences from the reference over the
//! stations' bins: `U` in units of |U_0|, `k` in units of |U_0|^2.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use super::abl_particles::{default_stations, Bins};
use crate::io::plot::{error_figure, CurvePanel, ErrorPoint};
use crate::io::{read_checkpoint, write_checkpoint, AttrValue, CsvSeries, IoError};
use crate::pipeline::outputs::write_statistics;
use crate::pipeline::{CheckpointError, Pipeline, RunError};
use crate::scene::{self, Axis, Scene, Station, Statistics};
use crate::Real;

/// What `eddy bench-abl` measures.
#[derive(Debug, Clone)]
pub struct AblBenchOptions {
    /// Resolution factor of the reference run (default 4 on a grid, 2 on particles: 8 times
    /// the particles).
    pub scale: Option<usize>,
    /// Stations behind the obstacles, m along x (default: the step's five on a grid, two and
    /// four obstacle lengths behind each obstacle with a database on particles).
    pub stations: Vec<Real>,
    /// Statistics from this time, s (default: the grid's `average_from`, half the run on
    /// particles).
    pub from: Option<Real>,
    /// Overrides applied to every run (`--set`).
    pub overrides: Vec<String>,
    /// Skip the reference (its profiles are then compared with nothing).
    pub skip_reference: bool,
    /// Read the reference's profiles from this CSV (written by an earlier run into
    /// `profiles`) instead of running it: calibration sweeps then cost only the coarse runs.
    pub reference: Option<PathBuf>,
    /// Write each run's profiles into this folder as `LABEL.csv` (station, y, U, k); a run
    /// keeps its progress there (`LABEL.checkpoint.h5`) and goes on from it.
    pub profiles: Option<PathBuf>,
    /// Draw the U and k errors against wall time and the U profiles at the middle station into
    /// this PNG.
    pub plot: Option<PathBuf>,
    /// Seeding is random: the `random` and `abl` runs (and `none` too when the scene's inflow
    /// fluctuates, `grid.inflow_turbulence`) are repeated with this many scene seeds (the
    /// scene's, then the next ones), one row each, and summarised by label.
    pub seeds: u64,
    /// Only these runs (labels none, random, abl, reference); every one when empty. A
    /// reference run alone is how one is stored for later `reference` comparisons.
    pub runs: Vec<String>,
    /// Wall time between a run's checkpoints in `profiles` (`LABEL.checkpoint.h5`).
    pub checkpoint_every: std::time::Duration,
}

/// One run of the table.
#[derive(Debug, Clone)]
pub struct AblBenchRow {
    pub label: &'static str,
    /// The scene seed of the run.
    pub seed: u64,
    /// Grid cells, or fluid particles at the start.
    pub cells: usize,
    pub steps: u64,
    pub seconds: f64,
    /// Vortex particles at the end.
    pub particles: usize,
    /// Vortex particles on average over the statistics' window.
    pub mean_particles: Real,
    /// Why the run stopped early, if it did (its statistics then cover what it ran).
    pub failed: Option<String>,
    /// Mean of k over the bins (the mean of U is fixed by the flux through the section).
    pub mean_k: Real,
    /// Errors against the reference (NaN for the reference itself or without one).
    pub u_error: Real,
    pub k_error: Real,
}

/// Per station, per coarse bin (y on a grid, z on particles): the time-averaged streamwise
/// velocity U and k with their 95 % half-widths (batch means; NaN for a stored reference
/// without them).
pub type Profiles = Vec<Vec<ProfileBin>>;

/// One bin of a profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileBin {
    pub u: Real,
    pub k: Real,
    pub u_ci: Real,
    pub k_ci: Real,
}

/// The coarse bins of a comparison.
#[derive(Debug, Clone, Copy)]
enum Coarse {
    /// A grid's cell size and rows in y.
    Grid(Real, usize),
    /// Particle bins across the channel.
    Particles(Bins),
}

impl Coarse {
    fn bins(&self) -> usize {
        match self {
            Coarse::Grid(_, rows) => *rows,
            Coarse::Particles(b) => b.count,
        }
    }

    /// The centre of bin `b`, m.
    fn centre(&self, b: usize) -> Real {
        match self {
            Coarse::Grid(size, _) => (b as Real + 0.5) * size,
            Coarse::Particles(bins) => bins.origin + (b as Real + 0.5) * bins.size,
        }
    }

    /// The statistics every run keeps: from `from`, on particles on a lattice of the coarse
    /// spacing, with a station at each of `stations` (m along x): the coarse cell of the
    /// scene's lattice around it, cut into the coarse bins.
    fn statistics(&self, scene: &Scene, stations: &[Real], from: Real) -> Statistics {
        let (lo, hi) = (scene.domain.min, scene.domain.max);
        let (size, axis, bins, across) = match *self {
            Coarse::Grid(size, rows) => (size, Axis::Y, rows, (lo[1], lo[1] + rows as Real * size)),
            Coarse::Particles(b) => (
                b.size,
                Axis::Z,
                b.count,
                (b.origin, b.origin + b.count as Real * b.size),
            ),
        };
        let station = |(k, &x): (usize, &Real)| {
            let cell = ((x - lo[0]) / size).floor().max(0.0);
            let (x0, x1) = (lo[0] + cell * size, lo[0] + (cell + 1.0) * size);
            let (mut min, mut max) = (lo, hi);
            (min[0], max[0]) = (x0, x1.min(hi[0]));
            let a = axis.index();
            (min[a], max[a]) = across;
            Station {
                name: format!("x{k}"),
                min,
                max,
                axis,
                bins,
                // The step's periodic span is homogeneous: its cells are one ensemble.
                pool: matches!(self, Coarse::Grid(..)).then_some(Axis::Z),
            }
        };
        Statistics {
            from,
            every: 1,
            bin: matches!(self, Coarse::Particles(_)).then_some(size),
            batches: 10,
            stations: stations.iter().enumerate().map(station).collect(),
        }
    }
}

/// Runs one configuration to the scene's end (or until it fails: the row then says why),
/// timing the steps; returns the row (without errors) and its profiles.
/// A run's progress in a bench checkpoint: the pipeline's state, then the bench's own counts.
fn save_progress(
    path: &Path,
    key: &str,
    p: &Pipeline,
    (steps, counted, window, seconds): (u64, Real, Real, f64),
) -> Result<(), RunError> {
    let mut state = p.save_state();
    let mut b = state.section("bench");
    b.u64("steps", steps);
    b.reals("counted_window_seconds", &[counted, window, seconds]);
    write_checkpoint(path, &[("scene", AttrValue::Str(key.to_owned()))], &state)?;
    Ok(())
}

/// Takes a run's progress back from `path` into `p`, built from the same scene (`key`).
fn resume_progress(
    path: &Path,
    key: &str,
    p: &mut Pipeline,
) -> Result<(u64, Real, Real, f64), RunError> {
    let stored = read_checkpoint(path)?;
    if stored.text("scene") != Some(key) {
        return Err(RunError::Unsupported(format!(
            "{}: a bench-abl checkpoint of another scene or run; remove it to start the run again",
            path.display()
        )));
    }
    let invalid = |source| CheckpointError::State {
        path: path.to_path_buf(),
        source,
    };
    p.restore_state(&stored.state).map_err(invalid)?;
    let b = stored.state.read("bench");
    let steps = b.u64("steps").map_err(invalid)?;
    let v = b.reals_n("counted_window_seconds", 3).map_err(invalid)?;
    Ok((steps, v[0], v[1], v[2]))
}

/// Runs `label`'s scene to its end and reads its profiles. With `checkpoint` (a path and how
/// often), a long run keeps its progress there and goes on from it when it is there (the
/// reference at half the particle spacing takes hours: it can run in pieces); the file is
/// removed when the run ends.
fn measure(
    label: &'static str,
    scene: &Scene,
    stations: &[Real],
    coarse: Coarse,
    from: Real,
    checkpoint: Option<(&Path, std::time::Duration)>,
) -> Result<(AblBenchRow, Profiles, Pipeline), RunError> {
    let (checkpoint, every) = checkpoint.unzip();
    let mut scene = scene.clone();
    scene.statistics = Some(coarse.statistics(&scene, stations, from));
    let mut p = Pipeline::build(&scene)?;
    let end = scene.time.end.ok_or_else(|| {
        RunError::Unsupported("bench-abl: the scene needs a time.end to average up to".into())
    })?;
    let cells = match (&scene.grid, &p.sim.sph) {
        (Some(grid), _) => grid.resolution.iter().product(),
        (None, Some(sph)) => sph.fluid.len(),
        (None, None) => 0,
    };
    let bar = ProgressBar::new(1000).with_message(label);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:>9} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let vortices = |p: &Pipeline| {
        let t = p
            .sim
            .grid_turbulence
            .as_ref()
            .or(p.sim.sph_turbulence.as_ref());
        t.map_or(0, |t| t.vortices.len())
    };
    let started = Instant::now();
    let (mut steps, mut failed) = (0, None);
    let (mut counted, mut window, mut earlier) = (0.0, 0.0, 0.0);
    let key = scene.to_toml();
    if let Some(path) = checkpoint.filter(|p| p.exists()) {
        (steps, counted, window, earlier) = resume_progress(path, &key, &mut p)?;
        tracing::warn!(
            "bench-abl: {label} goes on from {} at t = {} s",
            path.display(),
            p.sim.time()
        );
    }
    let mut saved = Instant::now();
    while p.sim.time() < end - 1e-12 {
        let rec = match p.step(Some(end), None) {
            Ok(rec) => rec,
            Err(e) => {
                failed = Some(e.to_string());
                break;
            }
        };
        steps += 1;
        bar.set_position((1000.0 * p.sim.time() / end) as u64);
        if rec.time + rec.dt > from {
            let dt = rec.dt.min(rec.time + rec.dt - from);
            counted += vortices(&p) as Real * dt;
            window += dt;
        }
        if let Some(path) = checkpoint.filter(|_| every.is_some_and(|e| saved.elapsed() >= e)) {
            let seconds = earlier + started.elapsed().as_secs_f64();
            save_progress(path, &key, &p, (steps, counted, window, seconds))?;
            saved = Instant::now();
        }
    }
    let seconds = earlier + started.elapsed().as_secs_f64();
    if let Some(path) = checkpoint.filter(|p| p.exists()) {
        std::fs::remove_file(path).map_err(|e| IoError::io(path, "removing", e))?;
    }
    bar.finish_and_clear();
    let stats = &p.sim.statistics[0].stats;
    let profiles: Profiles = stats
        .stations
        .iter()
        .map(|s| {
            let bins = s.profile(&stats.cells).into_iter();
            bins.map(|b| ProfileBin {
                u: b.mean[0],
                k: b.k,
                u_ci: b.mean_ci[0],
                k_ci: b.k_ci,
            })
            .collect()
        })
        .collect();
    let bins: Vec<Real> = profiles
        .iter()
        .flatten()
        .map(|b| b.k)
        .filter(|k| k.is_finite())
        .collect();
    let mean_k = bins.iter().sum::<Real>() / bins.len() as Real;
    Ok((
        AblBenchRow {
            label,
            seed: scene.seed,
            cells,
            steps,
            seconds,
            particles: vortices(&p),
            mean_particles: if window > 0.0 { counted / window } else { 0.0 },
            failed,
            mean_k,
            u_error: Real::NAN,
            k_error: Real::NAN,
        },
        profiles,
        p,
    ))
}

/// The scene without any boundary layer (the plain grid: no ABL stages are built).
fn plain(mut scene: Scene) -> Scene {
    scene.obstacles.iter_mut().for_each(|b| b.abl = None);
    scene.turbulence = None;
    scene
}

/// The step's stations on a grid, m along x.
pub const GRID_STATIONS: [Real; 5] = [1.25, 1.5, 2.0, 2.5, 3.0];

/// Runs the four configurations of `path` (the backward-facing step on a grid, a stream past
/// obstacles on particles) and returns the table rows: none, random, abl, then the reference.
pub fn run(path: &Path, options: &AblBenchOptions) -> Result<Vec<AblBenchRow>, RunError> {
    let load = |extra: &[String]| -> Result<Scene, RunError> {
        let mut all = options.overrides.clone();
        all.extend_from_slice(extra);
        Ok(scene::load(path, &all)?)
    };
    let base = load(&[])?;
    if scene::build::abl_settings(&base).is_none() {
        return Err(RunError::Unsupported(format!(
            "bench-abl: {} has no obstacle with `abl = {{ database = ... }}`",
            path.display()
        )));
    }
    let on_particles = base.grid.is_none();
    let end = base.time.end.unwrap_or(0.0);
    let (coarse, reference_override, stations, from) = match (&base.grid, &base.fluid) {
        (Some(grid), _) => {
            let n = grid.resolution;
            let s = options.scale.unwrap_or(4);
            (
                Coarse::Grid(grid.spacing(&base), n[1]),
                format!("grid.resolution=[{},{},{}]", n[0] * s, n[1] * s, n[2] * s),
                GRID_STATIONS.to_vec(),
                grid.average_from.unwrap_or(0.0),
            )
        }
        (None, Some(fluid)) => {
            let s = options.scale.unwrap_or(2);
            let bins = Bins::across(&base).expect("a fluid");
            let bodies = scene::build::bodies(&base).map_err(RunError::from)?;
            let stations = default_stations(&base, &bodies);
            (
                Coarse::Particles(bins),
                format!("fluid.spacing={}", fluid.spacing / s as Real),
                stations,
                0.5 * end,
            )
        }
        (None, None) => {
            return Err(RunError::Unsupported(format!(
                "{} has neither [grid] nor [fluid]",
                path.display()
            )))
        }
    };
    let stations = if options.stations.is_empty() {
        stations
    } else {
        options.stations.clone()
    };
    // A station's coarse cell must lie in the domain: one beyond it measures nothing.
    let (x0, x1) = (base.domain.min[0], base.domain.max[0]);
    let size = match coarse {
        Coarse::Grid(size, _) => size,
        Coarse::Particles(b) => b.size,
    };
    let (inside, outside): (Vec<Real>, Vec<Real>) = stations
        .into_iter()
        .partition(|&x| x >= x0 && x0 + ((x - x0) / size).floor() * size + size <= x1 + 1e-9);
    if !outside.is_empty() {
        tracing::warn!("bench-abl: stations {outside:?} lie beyond the domain (x up to {x1} m) and are left out");
    }
    if inside.is_empty() {
        return Err(RunError::Unsupported(format!(
            "bench-abl: no station lies in the domain (x from {x0} to {x1} m)"
        )));
    }
    let stations = inside;
    let from = options.from.unwrap_or(from);
    let seeded =
        |label: &'static str, extra: Vec<String>| -> Vec<(&'static str, Result<Scene, RunError>)> {
            (0..options.seeds.max(1))
                .map(|k| {
                    let mut all = extra.clone();
                    all.push(format!("seed={}", base.seed + k));
                    (label, load(&all))
                })
                .collect()
        };
    // The plain run is random only through a fluctuating inflow: then it is repeated per seed
    // too, so every label sees the same inflows.
    let gusty = base
        .grid
        .as_ref()
        .is_some_and(|g| g.inflow_turbulence.is_some());
    let none: Vec<_> = if gusty {
        seeded("none", Vec::new())
    } else {
        vec![("none", load(&[]))]
    };
    let configs: Vec<(&'static str, Scene)> = none
        .into_iter()
        .map(|(l, r)| (l, r.map(plain)))
        .chain(seeded("random", vec!["turbulence.seeding=random".into()]))
        .chain(seeded("abl", Vec::new()))
        .collect::<Vec<_>>()
        .into_iter()
        .chain(
            (!options.skip_reference && options.reference.is_none()).then(|| {
                (
                    "reference",
                    load(std::slice::from_ref(&reference_override)).map(plain),
                )
            }),
        )
        .map(|(l, r)| r.map(|sc| (l, sc)))
        .collect::<Result<_, _>>()?;
    // A stored reference is read first: a bad file fails before the runs.
    let stored = options
        .reference
        .as_ref()
        .map(|path| read_profiles(path, stations.len(), coarse.bins()))
        .transpose()?;
    if let Some(dir) = &options.profiles {
        std::fs::create_dir_all(dir).map_err(|e| IoError::io(dir, "creating", e))?;
    }
    let mut rows = Vec::new();
    let mut profiles = Vec::new();
    let chosen = |label: &str| options.runs.is_empty() || options.runs.iter().any(|r| r == label);
    for (label, scene) in configs.iter().filter(|(l, _)| chosen(l)) {
        let repeated = match *label {
            "random" | "abl" => true,
            "none" => gusty,
            _ => false,
        };
        let name = if repeated && options.seeds > 1 {
            format!("{label}_seed{}", scene.seed)
        } else {
            (*label).to_owned()
        };
        let checkpoint = options
            .profiles
            .as_ref()
            .map(|dir| dir.join(format!("{name}.checkpoint.h5")));
        let checkpoint = checkpoint.as_deref().map(|c| (c, options.checkpoint_every));
        let (row, prof, p) = measure(label, scene, &stations, coarse, from, checkpoint)?;
        // Each run's profiles and statistics are written as it ends: a long comparison keeps
        // what it has measured.
        if let Some(dir) = &options.profiles {
            write_profiles(&dir.join(format!("{name}.csv")), &prof, &stations, coarse)?;
            let m = &p.sim.statistics[0];
            let attrs = [
                ("scene", AttrValue::from(scene.name.as_str())),
                ("seed", AttrValue::Int(scene.seed as i64)),
                ("run", AttrValue::from(row.label)),
            ];
            let at = (p.sim.steps(), p.sim.time());
            let h5 = dir.join(format!("{name}_statistics.h5"));
            write_statistics(&h5, None, &m.stats, m.kind, at, &attrs, 6)?;
        }
        rows.push(row);
        profiles.push(prof);
    }
    let reference = match stored {
        Some(r) => Some(r),
        None => rows
            .iter()
            .position(|r| r.label == "reference")
            .map(|i| profiles[i].clone()),
    };
    if let Some(reference) = &reference {
        let u0 = base.turbulence_u0().unwrap_or(1.0);
        for (row, prof) in rows.iter_mut().zip(&profiles) {
            // Bins no particle reached in one of the two runs are left out.
            let pairs: Vec<_> = prof
                .iter()
                .flatten()
                .zip(reference.iter().flatten())
                .filter(|(a, b)| a.u.is_finite() && b.u.is_finite())
                .collect();
            let rms = |f: &dyn Fn(&ProfileBin) -> Real| {
                (pairs
                    .iter()
                    .map(|(a, b)| (f(a) - f(b)).powi(2))
                    .sum::<Real>()
                    / pairs.len() as Real)
                    .sqrt()
            };
            row.u_error = rms(&|b| b.u) / u0;
            row.k_error = rms(&|b| b.k) / (u0 * u0);
        }
    }
    if let Some(png) = &options.plot {
        let points: Vec<ErrorPoint> = rows
            .iter()
            .map(|r| ErrorPoint {
                label: r.label.into(),
                seconds: r.seconds,
                errors: vec![r.u_error, r.k_error],
            })
            .collect();
        let middle = stations.len() / 2;
        let profile = |label: &str, prof: &Profiles| {
            let curve = prof[middle]
                .iter()
                .enumerate()
                .filter(|(_, bin)| bin.u.is_finite())
                .map(|(b, bin)| (coarse.centre(b), bin.u))
                .collect();
            (label.to_owned(), curve)
        };
        let mut curves: Vec<_> = rows
            .iter()
            .zip(&profiles)
            .map(|(r, p)| profile(r.label, p))
            .collect();
        if options.reference.is_some() {
            if let Some(r) = &reference {
                curves.push(profile("reference", r));
            }
        }
        let across = if on_particles { "z" } else { "y" };
        let title = format!(
            "time-averaged U at x = {} m against {across} (m)",
            stations[middle]
        );
        error_figure(
            png,
            &["U error against wall time", "k error against wall time"],
            &points,
            CurvePanel {
                title: &title,
                x_label: if on_particles { "z (m)" } else { "y (m)" },
                curves: &curves,
            },
        )?;
    }
    Ok(rows)
}

/// Writes `profiles` as CSV rows `station, y, U, k, U_ci, k_ci` (bin centres, m: in y on a
/// grid, in z on particles, the column keeping its name; the 95 % half-widths of U and k).
fn write_profiles(
    path: &Path,
    profiles: &Profiles,
    stations: &[Real],
    coarse: Coarse,
) -> Result<(), IoError> {
    let columns = ["station", "y", "U", "k", "U_ci", "k_ci"].map(String::from);
    let mut csv = CsvSeries::create(path, &columns)?;
    for (x, prof) in stations.iter().zip(profiles) {
        for (b, bin) in prof.iter().enumerate() {
            csv.row(&[*x, coarse.centre(b), bin.u, bin.k, bin.u_ci, bin.k_ci])?;
        }
    }
    Ok(())
}

/// Reads profiles written by [`write_profiles`], checking they have `stations` x `bins` rows.
fn read_profiles(path: &Path, stations: usize, bins: usize) -> Result<Profiles, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, "reading", e))?;
    let rows: Vec<Vec<Real>> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|c| c.trim().parse::<Real>())
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()
        .map_err(|e| IoError::invalid(path, format!("not a profile table: {e}")))?;
    if rows.len() != stations * bins || rows.iter().any(|r| r.len() != 4 && r.len() != 6) {
        return Err(IoError::invalid(
            path,
            format!(
                "{} rows; this comparison has {stations} stations x {bins} bins of 4 columns \
                 (station, y, U, k) or 6 (and U_ci, k_ci)",
                rows.len()
            ),
        ));
    }
    let bin = |r: &Vec<Real>| ProfileBin {
        u: r[2],
        k: r[3],
        u_ci: r.get(4).copied().unwrap_or(Real::NAN),
        k_ci: r.get(5).copied().unwrap_or(Real::NAN),
    };
    Ok(rows
        .chunks(bins)
        .map(|c| c.iter().map(bin).collect())
        .collect())
}

/// The table as docs/src/abl-grid.md prints it.
pub fn table(rows: &[AblBenchRow]) -> String {
    let reference = rows
        .iter()
        .find(|r| r.label == "reference")
        .map(|r| r.seconds);
    let mut out = String::from(
        "| run | seed | cells or particles | steps | wall s | / reference | vortex particles (mean) | mean k | U error | k error |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let share = reference.map_or("-".into(), |t| format!("1/{:.0}", t / r.seconds));
        out.push_str(&format!(
            "| {} | {} | {} | {} | {:.1} | {} | {} ({:.1}) | {:.5} | {:.4} | {:.5} |\n",
            r.label,
            r.seed,
            r.cells,
            r.steps,
            r.seconds,
            share,
            r.particles,
            r.mean_particles,
            r.mean_k,
            r.u_error,
            r.k_error
        ));
    }
    for r in rows.iter().filter(|r| r.failed.is_some()) {
        let why = r.failed.as_deref().unwrap_or_default();
        out.push_str(&format!(
            "\n{} (seed {}) stopped early: {why}",
            r.label, r.seed
        ));
    }
    for label in ["none", "random", "abl"] {
        let runs: Vec<&AblBenchRow> = rows
            .iter()
            .filter(|r| r.label == label && r.u_error.is_finite())
            .collect();
        if runs.len() > 1 {
            let spread = |e: &dyn Fn(&AblBenchRow) -> Real| {
                let mean = runs.iter().map(|r| e(r)).sum::<Real>() / runs.len() as Real;
                let (lo, hi) = runs.iter().fold((Real::MAX, Real::MIN), |(a, b), r| {
                    (a.min(e(r)), b.max(e(r)))
                });
                format!("{mean:.4} (mean), {lo:.4} to {hi:.4}")
            };
            out.push_str(&format!(
                "\n{label} over {} seeds: U error {}; k error {}",
                runs.len(),
                spread(&|r| r.u_error),
                spread(&|r| r.k_error)
            ));
        }
    }
    out
}
