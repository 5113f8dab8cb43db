//! The pipeline's front door from a scene: each call resolves the scene into a [`RunSpec`]
//! (`scene::build::run_spec`) and goes on from that. This is the one file of the pipeline that
//! names a [`Scene`]; it reads none of its sections.

use std::path::{Path, PathBuf};

use super::build::{grid_among, sph_among, Pipeline};
use super::driver::{drive, Run};
use super::spec::{output_dir as dir_of, RunSpec};
use super::{RunError, RunOptions, RunSummary};
use crate::grid::GridSolver;
use crate::scene::{self, build, Scene};
use crate::sph::SphSolver;
use crate::Real;

impl RunOptions {
    /// `scene` with `until` and `steps` folded into its `[time]` (each the earlier of the two
    /// ends), so the resolved scene written beside a run's outputs reproduces the run.
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut scene = scene.clone();
        let t = &mut scene.time;
        t.end = [t.end, self.until].into_iter().flatten().reduce(Real::min);
        t.steps = [t.steps, self.steps].into_iter().flatten().min();
        scene
    }

    /// The run of `scene` under these options (checked, and folded in by
    /// [`RunOptions::apply`]).
    pub fn spec(&self, scene: &Scene) -> Result<RunSpec, RunError> {
        self.check()?;
        Ok(build::run_spec(&self.apply(scene))?)
    }
}

/// Loads `path` with the options' overrides, ready to run; checks the options too.
pub fn resolve(path: &Path, options: &RunOptions) -> Result<Scene, RunError> {
    options.check()?;
    Ok(scene::load(path, &options.overrides)?)
}

/// The output folder of a scene under these options.
pub fn output_dir(scene: &Scene, options: &RunOptions) -> PathBuf {
    dir_of(options, scene.output.dir.as_deref(), &scene.name)
}

/// Runs the scene at `path`.
pub fn run(path: &Path, options: &RunOptions) -> Result<RunSummary, RunError> {
    let scene = resolve(path, options)?;
    run_scene(&scene, options)
}

/// Runs an already resolved scene into its output folder (see [`drive`]).
pub fn run_scene(scene: &Scene, options: &RunOptions) -> Result<RunSummary, RunError> {
    drive(&options.spec(scene)?, options)
}

/// The SPH fluid of `scene` with its bodies and its refinement attached as a step hook.
pub fn sph_solver(scene: &Scene) -> Result<SphSolver, RunError> {
    let spec = build::run_spec(scene)?;
    sph_among(&spec, spec.bodies.clone())
}

/// The MAC grid of `scene` with its obstacles.
pub fn grid_solver(scene: &Scene) -> Result<GridSolver, RunError> {
    let spec = build::run_spec(scene)?;
    grid_among(&spec, spec.bodies.clone())
}

impl Pipeline {
    /// Builds the solvers and stages of `scene`. Nothing is written.
    pub fn build(scene: &Scene) -> Result<Self, RunError> {
        Self::from_spec(&build::run_spec(scene)?)
    }
}

impl Run {
    /// [`Run::start_from`] the run of `scene` under `options`.
    pub fn start(scene: &Scene, options: &RunOptions) -> Result<Self, RunError> {
        Self::start_from(&options.spec(scene)?, options)
    }

    /// [`Run::begin_from`] the run of `scene` under `options`.
    pub fn begin(scene: &Scene, options: &RunOptions) -> Result<Self, RunError> {
        Self::begin_from(&options.spec(scene)?, options)
    }

    /// [`Run::resume_from`] the run of `scene` under `options`.
    pub fn resume(scene: &Scene, options: &RunOptions) -> Result<Self, RunError> {
        Self::resume_from(&options.spec(scene)?, options)
    }
}
