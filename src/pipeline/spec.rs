//! What a run is, resolved from its scene by `scene::build::run_spec`: the solvers' parameters,
//! the bodies (meshes read once), each stage's settings, the outputs and when the run ends.
//! The pipeline builds from this alone, so no part of it reads a scene; the scene's own
//! conventions (the container is body 0, a probe names a body) are resolved here once.

use std::path::{Path, PathBuf};

use super::outputs::OutputSpec;
use super::statistics::StatisticsSpec;
use super::RunOptions;
use crate::abl::AblSettings;
use crate::geometry::{RigidBody, Shape};
use crate::grid::GridParams;
use crate::metrics::{Metric, Probe};
use crate::refine::Refinement;
use crate::scene::{Coupling, InitialFlow};
use crate::sph::SphParams;
use crate::{Real, Vec3};

/// A resolved run.
#[derive(Debug, Clone)]
pub struct RunSpec {
    /// The scene's name: messages, and the default output folder `out/<name>`.
    pub name: String,
    /// The scene's `output.dir`, when it sets one.
    pub dir: Option<PathBuf>,
    /// The bodies, the container first when there is one (see [`RunSpec::obstacles`]).
    pub bodies: Vec<RigidBody>,
    /// Whether `bodies[0]` is the container.
    pub container: bool,
    /// Each body's shape, in the order of `bodies`, for the boundary layers' wall model.
    pub shapes: Vec<Shape>,
    /// The SPH fluid, when the scene has one.
    pub sph: Option<SphSpec>,
    /// The MAC grid, when the scene has one.
    pub grid: Option<GridSpec>,
    /// The run-time boundary layers, when an obstacle names a database.
    pub abl: Option<AblSettings>,
    /// The exchange across the water surface (`[coupling]`).
    pub coupling: Option<Coupling>,
    /// Every probe, in the scene's order.
    pub probes: Vec<Probe>,
    /// Each named obstacle's index among `bodies`, for the probes that read a body by name.
    pub body_names: Vec<(String, usize)>,
    /// The metrics asked for by name (`output.metrics`); every one of a medium when `None`.
    pub metrics: Option<Vec<Metric>>,
    /// Gravitational acceleration, m/s^2 (the metrics' potential energy).
    pub gravity: Vec3,
    /// The running statistics (`[statistics]`).
    pub statistics: Option<StatisticsSpec>,
    /// Registered stages asked for by name (`stages`).
    pub stages: Vec<String>,
    /// What is written.
    pub outputs: OutputSpec,
    /// When the run ends.
    pub end: RunEnd,
    /// The resolved scene as written beside the outputs (`scene.toml`).
    pub resolved: String,
    /// The scene as a checkpoint records it: without what a resumed run may change.
    pub checkpoint_key: String,
}

/// The SPH fluid of a run.
#[derive(Debug, Clone)]
pub struct SphSpec {
    pub params: SphParams,
    /// The turbulence refinement attached as a step hook.
    pub refinement: Refinement,
    /// The seed of the refinement's random generators.
    pub seed: u64,
}

/// The MAC grid of a run.
#[derive(Debug, Clone)]
pub struct GridSpec {
    pub params: GridParams,
    /// An analytic velocity set at the start (`grid.initial_flow`).
    pub initial_flow: Option<InitialFlow>,
    /// A stored velocity the grid holds frozen, and which of its frames (the last when `None`).
    pub static_flow: Option<(PathBuf, Option<usize>)>,
}

/// When a run ends: the first of its end time, its step count and a steady grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunEnd {
    pub time: Option<Real>,
    pub steps: Option<u64>,
    /// Relative change per unit time of the grid velocity below which it is steady.
    pub steady: Option<Real>,
}

impl RunSpec {
    /// The obstacles: every body but the container.
    pub fn obstacles(&self) -> &[RigidBody] {
        &self.bodies[usize::from(self.container)..]
    }

    /// The output folder under `options`: `--out`, else `output.dir`, else `out/<name>`.
    pub fn output_dir(&self, options: &RunOptions) -> PathBuf {
        output_dir(options, self.dir.as_deref(), &self.name)
    }
}

/// The output folder of a scene named `name` with `output.dir` = `dir` under `options`.
pub(super) fn output_dir(options: &RunOptions, dir: Option<&Path>, name: &str) -> PathBuf {
    options
        .out
        .clone()
        .or_else(|| dir.map(Path::to_path_buf))
        .unwrap_or_else(|| Path::new("out").join(name))
}
