//! What a scene simulates: its solvers, stepped on one clock.

use super::coupling::Exchange;
use super::statistics::MediumStatistics;
use super::turbulence::Turbulence;
use crate::grid::{GridError, GridSolver};
use crate::io::IoError;
use crate::sph::{Instability, SphSolver};
use crate::vortex::VortexError;
use crate::{Real, Vec3};

/// Why a step could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    #[error(transparent)]
    Sph(#[from] Instability),
    #[error(transparent)]
    Grid(#[from] GridError),
    #[error(transparent)]
    Io(#[from] IoError),
    #[error(transparent)]
    Vortex(#[from] VortexError),
}

/// The solvers of a scene and the one clock they share. Each solver keeps its own copy of the
/// time (its moving bodies read it); every step advances all of them by the same `dt`.
pub struct Simulation {
    /// The SPH fluid, when the scene has a `[fluid]`.
    pub sph: Option<SphSolver>,
    /// The MAC-grid fluid, when the scene has a `[grid]`.
    pub grid: Option<GridSolver>,
    /// The grid's boundary-layer field and vortex particles, when an obstacle has a database.
    pub grid_turbulence: Option<Turbulence>,
    /// The SPH fluid's vortex particles (its boundary-layer field rides on the particles),
    /// when an obstacle has a database; a coupled scene has both sets, each in its medium.
    pub sph_turbulence: Option<Turbulence>,
    /// What the water received across its surface in the last step, in a coupled scene.
    pub exchange: Option<Exchange>,
    /// The running statistics of each medium, when the scene has `[statistics]`.
    pub statistics: Vec<MediumStatistics>,
    /// The SPH fluid's vorticity (`SphSolver::vorticity`) of the current state, taken by the
    /// first stage that needs it and shared with the stages after it that only measure (the
    /// statistics and the metrics read the same curl of the same state); the driver drops it
    /// before any stage that may change the state ([`super::stages::Stage::measures_only`]).
    pub particle_vorticity: Option<Vec<Vec3>>,
    pub(super) time: Real,
    pub(super) steps: u64,
}

impl Simulation {
    /// The solvers at t = 0.
    pub fn new(sph: Option<SphSolver>, grid: Option<GridSolver>) -> Self {
        Self {
            sph,
            grid,
            grid_turbulence: None,
            sph_turbulence: None,
            exchange: None,
            statistics: Vec::new(),
            particle_vorticity: None,
            time: 0.0,
            steps: 0,
        }
    }

    /// Whether it holds both a fluid and a grid: each medium's files then carry its name.
    pub fn both_media(&self) -> bool {
        self.sph.is_some() && self.grid.is_some()
    }

    /// Simulated time, s.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The step every solver can take now: the smallest of their stable steps.
    pub fn stable_dt(&mut self) -> Result<Real, StepError> {
        let mut dt = Real::INFINITY;
        if let Some(sph) = self.sph.as_mut() {
            dt = dt.min(sph.stable_dt()?);
        }
        if let Some(grid) = self.grid.as_ref() {
            dt = dt.min(grid.stable_dt()?);
        }
        Ok(dt)
    }

    /// The SPH fluid; only stages built for one call this.
    pub(super) fn sph(&mut self) -> &mut SphSolver {
        self.sph
            .as_mut()
            .expect("SPH stages are built only for a scene with a fluid")
    }

    /// The grid; only stages built for one call this.
    pub(super) fn grid(&mut self) -> &mut GridSolver {
        self.grid
            .as_mut()
            .expect("grid stages are built only for a scene with a grid")
    }
}
