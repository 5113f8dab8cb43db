//! Drives a scene from its first step to its last frame: loads and resolves the scene, builds
//! the bodies and the solver, steps with a progress bar, and writes metrics, probes and frames.
//! An unstable run stops with a diagnostic and keeps every frame written so far.

use crate::geometry::{GeometryError, RigidBody};
use crate::io::{write_atomic, AttrValue, Field, Hdf5Frames, IoError, ParticleFrame, PvdSeries};
use crate::metrics::{MetricsRecorder, ProbeRecorder};
use crate::scene::{self, plan::Plan, Scene, SceneError};
use crate::sph::{Instability, SphSolver};
use crate::{Real, Vec3};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod grid;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    #[error(transparent)]
    Io(#[from] IoError),
    #[error("{cause}; the {frames} frames written so far are kept in {}", out.display())]
    Unstable {
        cause: Instability,
        frames: usize,
        out: PathBuf,
    },
    #[error("{cause}; the {frames} frames written so far are kept in {}", out.display())]
    Grid {
        cause: Box<crate::grid::GridError>,
        frames: usize,
        out: PathBuf,
    },
    #[error("{0}")]
    Unsupported(String),
}

/// Command-line choices that are not part of the scene.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output folder, overriding `output.dir`.
    pub out: Option<PathBuf>,
    /// `dotted.key=value` overrides, applied in order.
    pub overrides: Vec<String>,
    /// Stop at this simulated time if it comes before the scene's end.
    pub until: Option<Real>,
    /// Stop after this many steps if they come before the scene's end.
    pub steps: Option<u64>,
    /// Show a progress bar.
    pub progress: bool,
}

/// What a finished run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub out: PathBuf,
    pub steps: u64,
    pub time: Real,
    pub frames: usize,
    pub fluid_particles: usize,
    pub boundary_particles: usize,
    /// Cells of a grid scene (0 for SPH scenes).
    pub grid_cells: usize,
    pub wall_seconds: f64,
}

/// Loads `path` with the options' overrides, ready to run.
pub fn resolve(path: &Path, options: &RunOptions) -> Result<Scene, RunError> {
    Ok(scene::load(path, &options.overrides)?)
}

/// The output folder of a scene under these options.
pub fn output_dir(scene: &Scene, options: &RunOptions) -> PathBuf {
    options
        .out
        .clone()
        .or_else(|| scene.output.dir.clone())
        .unwrap_or_else(|| Path::new("out").join(&scene.name))
}

/// The bodies of a scene: the container first, then the obstacles.
pub fn bodies(scene: &Scene) -> Result<Vec<RigidBody>, GeometryError> {
    scene
        .container
        .iter()
        .chain(&scene.obstacles)
        .enumerate()
        .map(|(i, b)| RigidBody::from_scene(b, i))
        .collect()
}

/// Runs the scene at `path`.
pub fn run(path: &Path, options: &RunOptions) -> Result<RunSummary, RunError> {
    let scene = resolve(path, options)?;
    run_scene(&scene, options)
}

/// Runs an already resolved scene.
pub fn run_scene(scene: &Scene, options: &RunOptions) -> Result<RunSummary, RunError> {
    if scene.fluid.is_none() && scene.grid.is_none() {
        return Err(RunError::Unsupported(format!(
            "scene '{}' has neither [fluid] nor [grid]: nothing to simulate",
            scene.name
        )));
    }
    let out = output_dir(scene, options);
    std::fs::create_dir_all(&out).map_err(|e| IoError::Io {
        path: out.clone(),
        action: "creating the output folder",
        source: e,
    })?;
    let resolved = scene.to_toml();
    write_atomic(&out.join("scene.toml"), |w| {
        w.write_all(resolved.as_bytes())
    })?;
    if scene.grid.is_some() {
        return grid::run_grid(scene, options, &out);
    }

    let plan = Plan::of(scene);
    let started = Instant::now();
    let mut solver = SphSolver::new(scene, bodies(scene)?);
    let gravity = Vec3::from(scene.gravity);
    let end_time = [scene.time.end, options.until]
        .into_iter()
        .flatten()
        .reduce(Real::min);
    let end_steps = [scene.time.steps, options.steps]
        .into_iter()
        .flatten()
        .min();
    solver.stop_at(end_time);
    let mut metrics = (plan.has("metrics"))
        .then(|| MetricsRecorder::create(&out.join("metrics.csv"), &scene.output.metrics))
        .transpose()?;
    let mut probes = (plan.has("probes"))
        .then(|| ProbeRecorder::create(&out.join("probes.csv"), &scene.probes))
        .transpose()?;
    let mut frames = FrameWriter::new(&out, scene, &solver)?;
    let bar = progress_bar(options.progress, end_time, end_steps);

    let mut next_frame = 0.0;
    let done = |s: &SphSolver| {
        end_time.is_some_and(|t| s.time() >= t - 1e-12) || end_steps.is_some_and(|n| s.steps() >= n)
    };
    loop {
        if solver.time() >= next_frame - 1e-12 || done(&solver) {
            frames.write(&solver)?;
            while next_frame <= solver.time() + 1e-12 {
                next_frame += scene.output.interval;
            }
        }
        if done(&solver) {
            break;
        }
        if let Some(p) = probes.as_mut() {
            p.record(&solver)?;
        }
        let state = metrics.as_ref().map(|m| m.measure(&solver, &gravity));
        let (step, time) = (solver.steps(), solver.time());
        let stats = solver.advance().map_err(|cause| RunError::Unstable {
            cause,
            frames: frames.count,
            out: out.clone(),
        })?;
        if let (Some(m), Some(state)) = (metrics.as_mut(), state) {
            m.write(step, time, &state, &stats)?;
        }
        solver.update_neighborhoods();
        update_bar(&bar, &solver, end_time, &stats);
    }
    bar.finish_and_clear();
    Ok(RunSummary {
        out,
        steps: solver.steps(),
        time: solver.time(),
        frames: frames.count,
        fluid_particles: solver.fluid.len(),
        boundary_particles: solver.boundary.len(),
        grid_cells: 0,
        wall_seconds: started.elapsed().as_secs_f64(),
    })
}

/// The frame writers a scene asked for.
struct FrameWriter {
    out: PathBuf,
    pvd: Option<PvdSeries>,
    hdf5: Option<Hdf5Frames>,
    count: usize,
}

impl FrameWriter {
    fn new(out: &Path, scene: &Scene, solver: &SphSolver) -> Result<Self, IoError> {
        let pvd = scene
            .output
            .vtk
            .then(|| PvdSeries::new(&out.join("particles.pvd")));
        let hdf5 = if scene.output.hdf5 {
            Some(Hdf5Frames::create(
                &out.join("frames.h5"),
                &[
                    ("scene", AttrValue::Str(scene.name.clone())),
                    ("particle_spacing", AttrValue::Real(solver.spacing)),
                    ("particle_mass", AttrValue::Real(solver.fluid.mass)),
                    ("rest_density", AttrValue::Real(solver.fluid.rest_density)),
                    ("seed", AttrValue::Int(scene.seed as i64)),
                ],
            )?)
        } else {
            None
        };
        Ok(Self {
            out: out.to_path_buf(),
            pvd,
            hdf5,
            count: 0,
        })
    }

    fn write(&mut self, solver: &SphSolver) -> Result<(), IoError> {
        if self.pvd.is_none() && self.hdf5.is_none() {
            return Ok(());
        }
        let f = &solver.fluid;
        let mut frame = ParticleFrame {
            step: solver.steps(),
            time: solver.time(),
            positions: &f.x,
            fields: vec![
                Field::vector("velocity", &f.v),
                Field::scalar("density", &f.density),
                Field::scalar("pressure", &f.pressure),
            ],
        };
        let extra = solver.refinement_fields();
        frame
            .fields
            .extend(extra.iter().map(|(name, data)| Field::vector(name, data)));
        if let Some(pvd) = self.pvd.as_mut() {
            let name = format!("particles_{:06}.vtp", self.count);
            crate::io::write_particles_vtk(&self.out.join(&name), &frame)?;
            pvd.push(frame.time, &name)?;
        }
        if let Some(h5) = self.hdf5.as_mut() {
            h5.append(&frame)?;
        }
        self.count += 1;
        Ok(())
    }
}

fn progress_bar(show: bool, end_time: Option<Real>, end_steps: Option<u64>) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = match (end_time, end_steps) {
        (Some(_), _) => ProgressBar::new(1000),
        (None, Some(n)) => ProgressBar::new(n),
        (None, None) => ProgressBar::no_length(),
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

fn update_bar(
    bar: &ProgressBar,
    solver: &SphSolver,
    end_time: Option<Real>,
    stats: &crate::sph::StepStats,
) {
    match end_time {
        Some(t) => bar.set_position((solver.time() / t * 1000.0).min(1000.0) as u64),
        None => bar.set_position(solver.steps()),
    }
    let elapsed = bar.elapsed().as_secs_f64().max(1e-9);
    bar.set_message(format!(
        "t = {:.4} s, step {}, dt = {:.2e} s, {:.1} steps/s",
        solver.time(),
        solver.steps(),
        stats.dt,
        solver.steps() as f64 / elapsed
    ));
}
