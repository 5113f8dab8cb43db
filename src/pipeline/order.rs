//! The order of a step's stages, one function per kind of scene. [`stages`] builds the stages
//! a scene needs (each is `None` when nothing asks for it) and hands them to the ordering of
//! its kind; a stage that is not built does not run, and `--plan` prints the list as ordered
//! here. A new stage is its own file plus one line in the ordering functions that run it; the
//! metrics columns it adds reach its solver's metrics stage from here ([`Stage::adopt_columns`]).

use super::coupling::{SurfaceExchange, SurfacePressure};
use super::outputs::{Kind, METRICS_FILE, PROBES_FILE};
use super::simulation::Simulation;
use super::stages::{
    GridMetrics, GridProbes, GridStep, SphMetrics, SphNeighbours, SphProbes, SphStep, Stage,
    TaylorGreenDecay,
};
use super::statistics::StatisticsStage;
use super::turbulence::{GridTurbulence, SphTurbulence};
use super::RunError;
use crate::metrics::{Metric, Probe};
use crate::scene::{build, Coupling, InitialFlow, Scene};
use crate::Vec3;

type Built = Option<Box<dyn Stage>>;

/// The kinds of scene, each with its own order of stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneKind {
    /// A MAC grid alone.
    Grid,
    /// SPH particles alone.
    Sph,
    /// A grid and SPH particles on one clock, exchanging nothing.
    SideBySide,
    /// Air on the grid over water in SPH, exchanging momentum across the surface.
    Coupled,
}

/// The stages one scene needs, before they are ordered.
struct StageSet {
    sph_probes: Built,
    grid_probes: Built,
    /// Pfaff et al. Figure 9, lines 1–25, on the grid's cells.
    grid_turbulence: Built,
    /// The same lines on the particles.
    sph_turbulence: Built,
    /// The running statistics of every medium, after the solvers' step.
    statistics: Built,
    sph_metrics: Built,
    grid_metrics: Built,
}

/// The kind of `scene` and its stages, in the order a step runs them.
pub fn stages(
    scene: &Scene,
    sim: &mut Simulation,
) -> Result<(SceneKind, Vec<Box<dyn Stage>>), RunError> {
    let (has_sph, has_grid) = (sim.sph.is_some(), sim.grid.is_some());
    let coupling = scene.coupling.clone().filter(|_| has_sph && has_grid);
    let set = StageSet::build(scene, sim, coupling.is_some())?;
    let (kind, order) = match (coupling, has_sph, has_grid) {
        (Some(coupling), _, _) => (SceneKind::Coupled, coupled(set, coupling)),
        (None, true, true) => (SceneKind::SideBySide, side_by_side(set)),
        (None, true, false) => (SceneKind::Sph, sph(set)),
        (None, false, _) => (SceneKind::Grid, grid(set)),
    };
    let mut stages: Vec<Box<dyn Stage>> = order.into_iter().flatten().collect();
    let added: Vec<_> = stages.iter().filter_map(|s| s.added_columns(sim)).collect();
    for stage in &mut stages {
        stage.adopt_columns(&added);
    }
    Ok((kind, stages))
}

/// A grid scene: Figure 9's turbulence (lines 1–25), then the grid's own step (line 28).
fn grid(s: StageSet) -> Vec<Built> {
    vec![
        s.grid_probes,
        s.grid_turbulence,
        Some(Box::new(GridStep)),
        s.statistics,
        s.grid_metrics,
    ]
}

/// An SPH scene: the turbulence on the particles, the solver's step (its refinements run
/// inside, as step hooks), then the neighbourhood of the new positions.
fn sph(s: StageSet) -> Vec<Built> {
    vec![
        s.sph_probes,
        s.sph_turbulence,
        Some(Box::new(SphStep)),
        Some(Box::new(SphNeighbours)),
        s.statistics,
        s.sph_metrics,
    ]
}

/// A fluid and a grid that do not exchange anything: each steps as in its own scene (the
/// turbulence drives the grid).
fn side_by_side(s: StageSet) -> Vec<Built> {
    vec![
        s.sph_probes,
        s.grid_probes,
        s.sph_turbulence,
        Some(Box::new(SphStep)),
        Some(Box::new(SphNeighbours)),
        s.grid_turbulence,
        Some(Box::new(GridStep)),
        s.statistics,
        s.sph_metrics,
        s.grid_metrics,
    ]
}

/// Air on the grid over water in SPH (`super::coupling`): the water is the air's boundary for
/// the step, the air's pressure on it is known after the grid's projection, and both reach the
/// particles before they move.
fn coupled(s: StageSet, coupling: Coupling) -> Vec<Built> {
    vec![
        s.sph_probes,
        s.grid_probes,
        Some(Box::new(SurfaceExchange { coupling })),
        s.grid_turbulence,
        Some(Box::new(GridStep)),
        Some(Box::new(SurfacePressure)),
        s.sph_turbulence,
        Some(Box::new(SphStep)),
        Some(Box::new(SphNeighbours)),
        s.statistics,
        s.sph_metrics,
        s.grid_metrics,
    ]
}

impl StageSet {
    /// Builds what `scene` asks for. The grid's turbulence in a scene with a grid, the fluid's
    /// in a scene with a fluid; a coupled scene has both, each seeded and synthesised in its
    /// own medium (an uncoupled scene with both drives the grid).
    fn build(scene: &Scene, sim: &mut Simulation, coupled: bool) -> Result<Self, RunError> {
        let (has_sph, has_grid) = (sim.sph.is_some(), sim.grid.is_some());
        let both = has_sph && has_grid;
        let (mut grid_turbulence, mut sph_turbulence): (Built, Built) = (None, None);
        if let Some(settings) = build::abl_settings(scene) {
            let shapes: Vec<_> = scene
                .container
                .iter()
                .chain(&scene.obstacles)
                .map(|b| b.shape.clone())
                .collect();
            if let Some(grid) = scene.grid.as_ref() {
                grid_turbulence = Some(Box::new(GridTurbulence::build(
                    settings.clone(),
                    sim,
                    &shapes,
                    grid.advection,
                )?));
            }
            if has_sph && (coupled || !has_grid) {
                sph_turbulence = Some(Box::new(SphTurbulence::build(settings, sim, &shapes)?));
            }
        }
        let probes = &scene.probes;
        let per_step = |p: &&Probe| !matches!(p, Probe::Line { .. });
        let sph_probes: Built = (has_sph && !probes.is_empty()).then(|| {
            Box::new(SphProbes {
                probes: probes.clone(),
                file: Kind::Particles.file(PROBES_FILE, both),
                recorder: None,
            }) as Box<dyn Stage>
        });
        let grid_probes: Built = (has_grid && probes.iter().any(|p| per_step(&p))).then(|| {
            let offset = usize::from(scene.container.is_some());
            let bodies = scene
                .obstacles
                .iter()
                .enumerate()
                .filter_map(|(i, b)| b.name.clone().map(|n| (n, i + offset)))
                .collect();
            Box::new(GridProbes {
                probes: probes.iter().filter(per_step).cloned().collect(),
                bodies,
                file: Kind::Grid.file(PROBES_FILE, both),
                recorder: None,
            }) as Box<dyn Stage>
        });
        let asked = scene.output.metrics.as_deref();
        let sph_chosen = Metric::chosen(asked, &Metric::SPH);
        let sph_metrics: Built = (has_sph && !sph_chosen.is_empty()).then(|| {
            Box::new(SphMetrics {
                metrics: sph_chosen,
                gravity: Vec3::from(scene.gravity),
                file: Kind::Particles.file(METRICS_FILE, both),
                recorder: None,
                added: Vec::new(),
            }) as Box<dyn Stage>
        });
        let grid_chosen = Metric::chosen(asked, &Metric::GRID);
        let grid_metrics: Built = (has_grid && !grid_chosen.is_empty()).then(|| {
            let taylor_green = scene
                .grid
                .as_ref()
                .is_some_and(|g| g.initial_flow == Some(InitialFlow::TaylorGreen))
                .then_some(TaylorGreenDecay {
                    nu: scene.viscosity.kinematic,
                    initial_energy: 0.0,
                });
            Box::new(GridMetrics {
                metrics: grid_chosen,
                file: Kind::Grid.file(METRICS_FILE, both),
                csv: None,
                taylor_green,
                added: Vec::new(),
            }) as Box<dyn Stage>
        });
        let statistics: Built = build::statistics_spec(scene)
            .map(|spec| {
                Ok::<_, RunError>(Box::new(StatisticsStage::build(spec, sim)?) as Box<dyn Stage>)
            })
            .transpose()?;
        Ok(Self {
            statistics,
            sph_probes,
            grid_probes,
            grid_turbulence,
            sph_turbulence,
            sph_metrics,
            grid_metrics,
        })
    }
}
