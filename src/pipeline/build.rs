//! A run's specification compiled into a [`Pipeline`]: its solvers, the stages a step runs and
//! the outputs it writes. A stage that nothing in the run needs is not built, so it cannot run.

use std::path::Path;

use super::footprint::{available_memory, Footprint};
use super::order::{self, SceneKind};
use super::outputs::Outputs;
use super::simulation::Simulation;
use super::spec::RunSpec;
use super::stages::Stage;
use super::RunError;
use crate::geometry::RigidBody;
use crate::grid::{GridError, GridSolver};
use crate::io::{read_velocity, IoError};
use crate::metrics::Probe;
use crate::sph::SphSolver;

/// A scene ready to step: the simulation, its stages in order and its outputs.
pub struct Pipeline {
    /// The memory estimate the scene was admitted with.
    pub footprint: Footprint,
    pub sim: Simulation,
    /// Which solvers the scene runs and whether they exchange anything.
    pub kind: SceneKind,
    pub stages: Vec<Box<dyn Stage>>,
    /// What is written at frame times and at the end (VTK, HDF5, ...).
    pub outputs: Outputs,
    /// Wall time each stage has run for so far, s, in the order of `stages`.
    pub stage_seconds: Vec<f64>,
}

/// The SPH fluid of `spec` with its bodies and its refinement attached as a step hook.
pub(super) fn sph_among(spec: &RunSpec, bodies: Vec<RigidBody>) -> Result<SphSolver, RunError> {
    let sph = spec
        .sph
        .as_ref()
        .ok_or_else(|| RunError::Unsupported(format!("scene '{}' has no [fluid]", spec.name)))?;
    let refinement = |n| sph.refinement.build(n, sph.seed).into_iter().collect();
    Ok(SphSolver::with_hooks(&sph.params, bodies, refinement))
}

/// The MAC grid of `spec` with its bodies, its initial or stored flow set.
pub(super) fn grid_among(spec: &RunSpec, bodies: Vec<RigidBody>) -> Result<GridSolver, RunError> {
    let grid = spec
        .grid
        .as_ref()
        .ok_or_else(|| RunError::Unsupported(format!("scene '{}' has no [grid]", spec.name)))?;
    let params = &grid.params;
    let setup = |e| RunError::Setup(Box::new(e));
    let mut solver = GridSolver::new(params, bodies).map_err(setup)?;
    if let Some(flow) = grid.initial_flow {
        solver.set_velocity(|x| flow.velocity(x)).map_err(setup)?;
    }
    if let Some((path, frame)) = &grid.static_flow {
        let stored = read_velocity(path, *frame)?;
        let mismatch = stored.dims != params.resolution
            || (stored.spacing - params.dx).abs() > 1e-9 * params.dx
            || (stored.origin - params.origin).norm() > 1e-9 * params.dx;
        if mismatch {
            return Err(setup(GridError::StaticFlow(format!(
                "{} holds a grid of {:?} cells of {} m at {:?}; this scene's is {:?} cells of {} \
                 m at {:?}",
                path.display(),
                stored.dims,
                stored.spacing,
                stored.origin.as_slice(),
                params.resolution,
                params.dx,
                params.origin.as_slice()
            ))));
        }
        solver.freeze_velocity(&stored.velocity).map_err(setup)?;
    }
    Ok(solver)
}

/// Refuses a point probe inside an obstacle at the start: it would read no fluid. One on the
/// surface reads the fluid beside it (`metrics::grid_probes::fluid_sample`).
fn probes_in_the_fluid(spec: &RunSpec) -> Result<(), RunError> {
    for (k, probe) in spec.probes.iter().enumerate() {
        let Probe::Point { name, position } = probe else {
            continue;
        };
        let x = crate::Point3::from(*position);
        for body in spec.obstacles() {
            let depth = -body.signed_distance(0.0, &x);
            // Rounding puts a point on the surface a few ulps either side of it.
            if depth > 1e-9 * (1.0 + x.coords.norm()) {
                return Err(RunError::Unsupported(format!(
                    "probe {name:?} (`probes.{k}.position` = {position:?}) lies {depth:.3e} m \
                     inside obstacle {:?}: a point probe reads the fluid, so put it on or \
                     outside the surface",
                    body.name()
                )));
            }
        }
    }
    Ok(())
}

/// Admission: a run with something to simulate, its probes in the fluid, and a memory
/// estimate under what the machine has.
fn admit(spec: &RunSpec) -> Result<Footprint, RunError> {
    if spec.sph.is_none() && spec.grid.is_none() {
        return Err(RunError::Unsupported(format!(
            "scene '{}' has neither [fluid] nor [grid]: nothing to simulate",
            spec.name
        )));
    }
    probes_in_the_fluid(spec)?;
    let footprint = Footprint::of(spec);
    if let Some(available) = available_memory().filter(|&a| footprint.bytes > a) {
        return Err(RunError::TooLarge {
            scene: spec.name.clone(),
            footprint,
            available,
        });
    }
    Ok(footprint)
}

impl Pipeline {
    /// Builds the solvers, stages and outputs of `spec`. Nothing is written.
    pub fn from_spec(spec: &RunSpec) -> Result<Self, RunError> {
        let footprint = admit(spec)?;
        let sph = spec
            .sph
            .is_some()
            .then(|| sph_among(spec, spec.bodies.clone()))
            .transpose()?;
        let grid = spec
            .grid
            .is_some()
            .then(|| grid_among(spec, spec.bodies.clone()))
            .transpose()?;
        let mut sim = Simulation::new(sph, grid);
        let (kind, stages) = order::stages(spec, &mut sim)?;
        let outputs = Outputs::build(&spec.outputs, &sim)?;
        Ok(Self {
            footprint,
            sim,
            kind,
            stages,
            outputs,
            stage_seconds: Vec::new(),
        })
    }

    /// Creates the output files of every stage and output in `out`.
    pub fn open(&mut self, out: &Path) -> Result<(), IoError> {
        for stage in &mut self.stages {
            stage.open(&self.sim, out)?;
        }
        self.outputs.open(&self.sim, out)
    }
}
