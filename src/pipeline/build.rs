//! A resolved scene compiled into a [`Pipeline`]: its solvers, the stages a step runs and the
//! outputs it writes. A stage that nothing in the scene needs is not built, so it cannot run.

use std::path::Path;

use super::footprint::{available_memory, Footprint};
use super::order::{self, SceneKind};
use super::outputs::Outputs;
use super::simulation::Simulation;
use super::stages::Stage;
use super::RunError;
use crate::geometry::RigidBody;
use crate::grid::{GridError, GridSolver};
use crate::io::{read_velocity, IoError};
use crate::metrics::Probe;
use crate::scene::{build, Scene};
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

/// The SPH fluid of `scene` with its bodies and its refinement attached as a step hook.
pub fn sph_solver(scene: &Scene) -> Result<SphSolver, RunError> {
    sph_among(scene, build::bodies(scene)?)
}

/// The MAC grid of `scene` with its obstacles.
pub fn grid_solver(scene: &Scene) -> Result<GridSolver, RunError> {
    grid_among(scene, build::bodies(scene)?)
}

/// [`sph_solver`] with the scene's bodies already built.
fn sph_among(scene: &Scene, bodies: Vec<RigidBody>) -> Result<SphSolver, RunError> {
    let params = build::sph_params(scene)
        .ok_or_else(|| RunError::Unsupported(format!("scene '{}' has no [fluid]", scene.name)))?;
    let refinement = |n| scene.refinement.build(n, scene.seed).into_iter().collect();
    Ok(SphSolver::with_hooks(&params, bodies, refinement))
}

/// [`grid_solver`] with the scene's bodies already built.
fn grid_among(scene: &Scene, bodies: Vec<RigidBody>) -> Result<GridSolver, RunError> {
    let params = build::grid_params(scene)
        .ok_or_else(|| RunError::Unsupported(format!("scene '{}' has no [grid]", scene.name)))?;
    let mut solver = GridSolver::new(&params, bodies).map_err(|e| RunError::Setup(Box::new(e)))?;
    build::set_initial_flow(scene, &mut solver).map_err(|e| RunError::Setup(Box::new(e)))?;
    if let Some(path) = scene.grid.as_ref().and_then(|g| g.static_flow.as_ref()) {
        let frame = scene.grid.as_ref().and_then(|g| g.static_flow_frame);
        let stored = read_velocity(path, frame)?;
        let mismatch = stored.dims != params.resolution
            || (stored.spacing - params.dx).abs() > 1e-9 * params.dx
            || (stored.origin - params.origin).norm() > 1e-9 * params.dx;
        if mismatch {
            return Err(RunError::Setup(Box::new(GridError::StaticFlow(format!(
                "{} holds a grid of {:?} cells of {} m at {:?}; this scene's is {:?} cells of {} \
                 m at {:?}",
                path.display(),
                stored.dims,
                stored.spacing,
                stored.origin.as_slice(),
                params.resolution,
                params.dx,
                params.origin.as_slice()
            )))));
        }
        solver
            .freeze_velocity(&stored.velocity)
            .map_err(|e| RunError::Setup(Box::new(e)))?;
    }
    Ok(solver)
}

/// Refuses a point probe inside an obstacle at the start: it would read no fluid. One on the
/// surface reads the fluid beside it (`metrics::grid_probes::fluid_sample`).
fn probes_in_the_fluid(scene: &Scene, bodies: &[RigidBody]) -> Result<(), RunError> {
    let obstacles = &bodies[usize::from(scene.container.is_some())..];
    for (k, probe) in scene.probes.iter().enumerate() {
        let Probe::Point { name, position } = probe else {
            continue;
        };
        let x = crate::Point3::from(*position);
        for body in obstacles {
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

/// Admission: a scene with something to simulate, its probes in the fluid, and a memory
/// estimate under what the machine has. Returns the scene's bodies (meshes are read here, once,
/// for the estimate and both solvers) and the estimate.
fn admit(scene: &Scene) -> Result<(Vec<RigidBody>, Footprint), RunError> {
    if scene.fluid.is_none() && scene.grid.is_none() {
        return Err(RunError::Unsupported(format!(
            "scene '{}' has neither [fluid] nor [grid]: nothing to simulate",
            scene.name
        )));
    }
    let bodies = build::bodies(scene)?;
    probes_in_the_fluid(scene, &bodies)?;
    let footprint = Footprint::of(scene, &bodies);
    if let Some(available) = available_memory().filter(|&a| footprint.bytes > a) {
        return Err(RunError::TooLarge {
            scene: scene.name.clone(),
            footprint,
            available,
        });
    }
    Ok((bodies, footprint))
}

impl Pipeline {
    /// Builds the solvers and stages of `scene`. Nothing is written.
    pub fn build(scene: &Scene) -> Result<Self, RunError> {
        let (bodies, footprint) = admit(scene)?;
        let (has_sph, has_grid) = (scene.fluid.is_some(), scene.grid.is_some());
        let sph = has_sph
            .then(|| sph_among(scene, bodies.clone()))
            .transpose()?;
        let grid = has_grid.then(|| grid_among(scene, bodies)).transpose()?;
        let mut sim = Simulation::new(sph, grid);
        let (kind, stages) = order::stages(scene, &mut sim)?;
        let outputs = Outputs::build(&build::output_spec(scene), &sim)?;
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
