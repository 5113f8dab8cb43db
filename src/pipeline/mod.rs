//! The one simulation pipeline: a resolved scene, handed over as a [`RunSpec`] (no part of the
//! pipeline but its front door, `entry.rs`, names a scene), becomes a [`Simulation`] (its
//! solvers on one clock) and a list of [`Stage`]s that run in order each step; one driver loop
//! steps every run to its end, writing metrics, probes and frames. `eddy run --plan` prints
//! the [`Plan`] read from the same stage objects, and a run can record the stages it ran (the
//! stage trace), so plan and execution cannot drift.
//!
//! Each step the driver asks every solver for its largest stable step, takes the smallest,
//! shortens it to land on the end time, and runs the stages with it.

mod build;
mod checkpoint;
mod coupling;
mod driver;
mod entry;
mod footprint;
mod order;
pub mod outputs;
mod plan;
mod simulation;
mod spec;
mod stages;
mod statistics;
mod turbulence;

use std::path::PathBuf;

pub use build::Pipeline;
pub use checkpoint::{CheckpointError, INTERRUPTED_EXIT};
pub use coupling::{Exchange, DRAG_HEIGHT};
pub use driver::{drive, Progress, Run};
pub use entry::{grid_solver, output_dir, resolve, run, run_scene, sph_solver};
pub use footprint::{available_memory, Footprint};
pub use order::{register_stage, stage_kinds, Built, SceneKind, Slot, StageKind};
pub use outputs::{Kind, Output, OutputSpec, Outputs};
pub use plan::{Plan, PlannedStage};
pub use simulation::{Simulation, StepError};
pub use spec::{GridSpec, RunEnd, RunSpec, SphSpec};
pub use stages::{AddedColumns, Stage, StepRecord};
pub use statistics::{MediumStatistics, StatisticsSpec};
pub use turbulence::{
    fit_to_liquid, GridTurbulence, SphTurbulence, Surface, Turbulence, TurbulenceStats, ABL_FIELD,
    SHELL_INNER, SHELL_OUTER,
};

use crate::abl::AblError;
use crate::geometry::GeometryError;
use crate::grid::GridError;
use crate::io::IoError;
use crate::scene::SceneError;
use crate::sph::Instability;
use crate::Real;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    #[error(transparent)]
    Io(#[from] IoError),
    #[error(transparent)]
    Setup(Box<GridError>),
    #[error(transparent)]
    Abl(#[from] AblError),
    #[error(transparent)]
    Vortex(#[from] crate::vortex::VortexError),
    #[error("{cause}; the {frames} frames written so far are kept in {}", out.display())]
    Unstable {
        cause: Instability,
        frames: usize,
        out: PathBuf,
    },
    #[error("{cause}; the {frames} frames written so far are kept in {}", out.display())]
    Grid {
        cause: Box<GridError>,
        frames: usize,
        out: PathBuf,
    },
    #[error("{0}")]
    Unsupported(String),
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error(
        "stopped by a signal at t = {time} s (step {steps}); the checkpoint and the {frames} \
         frames written so far are in {}: go on with `eddy resume {}`",
        out.display(),
        out.display()
    )]
    Interrupted {
        time: Real,
        steps: u64,
        frames: usize,
        out: PathBuf,
    },
    #[error(
        "scene '{scene}' needs {footprint}, more than the {} MiB this machine has available; \
         coarsen fluid.spacing or grid.resolution",
        (available / (1024.0 * 1024.0)).round()
    )]
    TooLarge {
        scene: String,
        footprint: Footprint,
        available: f64,
    },
    #[error("{option} = {value}: {allowed}")]
    InvalidOption {
        option: &'static str,
        value: String,
        allowed: &'static str,
    },
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
    /// Record the stage trace in the summary (see [`Plan::step_trace`]).
    pub trace: bool,
    /// Go on from the checkpoint in the output folder instead of starting at t = 0.
    pub resume: bool,
    /// Set from outside (a signal handler): the run writes a checkpoint after the step in
    /// progress and stops with [`RunError::Interrupted`].
    pub stop: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

/// What a finished run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub out: PathBuf,
    pub steps: u64,
    pub time: Real,
    pub frames: usize,
    pub fluid_particles: usize,
    /// Fluid particles lost through open sides of the domain (`fluid.lost_fraction`).
    pub lost_particles: u64,
    pub boundary_particles: usize,
    /// Cells of the grid (0 without one).
    pub grid_cells: usize,
    pub wall_seconds: f64,
    /// The plan the run was built with.
    pub plan: Plan,
    /// With [`RunOptions::trace`], every stage and part in the order they ran.
    pub trace: Vec<String>,
}

impl RunOptions {
    /// Checks the options that are not part of the scene: `until` a finite time > 0, `steps`
    /// at least 1.
    pub fn check(&self) -> Result<(), RunError> {
        if let Some(t) = self.until.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(RunError::InvalidOption {
                option: "--until",
                value: t.to_string(),
                allowed: "a finite time > 0 s",
            });
        }
        if self.steps == Some(0) {
            return Err(RunError::InvalidOption {
                option: "--steps",
                value: "0".into(),
                allowed: "at least 1 step",
            });
        }
        Ok(())
    }
}
