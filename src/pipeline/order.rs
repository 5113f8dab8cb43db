//! The stages of a step and their order. Every kind of stage is one entry of [`BUILT_IN`] (or a
//! [`register_stage`] call from outside the crate): it builds its stage from the run's
//! [`RunSpec`] when the run needs it, and names the [`Slot`] of the step it runs in. Each kind
//! of scene places the slots around its solvers' own stages (one function per kind); within a
//! slot, stages run in the order of [`stage_kinds`]. A stage that is not built does not run,
//! and `--plan` prints the list as ordered here. The metrics columns a stage adds reach its
//! solver's metrics stage from here ([`Stage::adopt_columns`]).

use std::sync::RwLock;

use super::coupling::{SurfaceExchange, SurfacePressure};
use super::simulation::Simulation;
use super::spec::RunSpec;
use super::stages::{
    GridMetrics, GridProbes, GridStep, SphMetrics, SphNeighbours, SphProbes, SphStep, Stage,
};
use super::statistics::StatisticsStage;
use super::turbulence::{GridTurbulence, SphTurbulence};
use super::RunError;

/// What building a stage gives: the stage, or `None` when the run does not need it.
pub type Built = Result<Option<Box<dyn Stage>>, RunError>;

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

/// Where in a step a stage runs, around the solvers' own stages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// First, reading the state the step starts from (the probes).
    Start,
    /// Just before the grid's step (its boundary-layer turbulence, Pfaff et al. Figure 9,
    /// lines 1–25).
    BeforeGrid,
    /// Just before the particles' step (the same lines on the particles).
    BeforeSph,
    /// After every solver has stepped and the particles' neighbourhood is rebuilt (the
    /// running statistics).
    AfterStep,
    /// Last: each solver's metrics row, with the columns the stages before it added.
    Metrics,
}

const SLOTS: usize = 5;

/// A kind of stage: how a run builds it and where in the step it runs.
pub struct StageKind {
    /// Its name, as the scene's `stages` asks for a registered one.
    pub name: &'static str,
    /// One line on what it does.
    pub summary: &'static str,
    pub slot: Slot,
    /// The stage, when the run needs it (a registered stage reads [`RunSpec::stages`]).
    pub build: fn(&RunSpec, &mut Simulation) -> Built,
}

/// The stages eddy ships, in their order within a slot.
pub static BUILT_IN: [StageKind; 7] = [
    StageKind {
        name: "sph_probes",
        summary: "the probes of the fluid, at the start of each step",
        slot: Slot::Start,
        build: SphProbes::stage,
    },
    StageKind {
        name: "grid_probes",
        summary: "the point and body probes of the grid, at the start of each step",
        slot: Slot::Start,
        build: GridProbes::stage,
    },
    StageKind {
        name: "grid_turbulence",
        summary: "Pfaff et al. Figure 9, lines 1-25, on the grid's cells",
        slot: Slot::BeforeGrid,
        build: GridTurbulence::stage,
    },
    StageKind {
        name: "sph_turbulence",
        summary: "Pfaff et al. Figure 9, lines 1-25, on the particles",
        slot: Slot::BeforeSph,
        build: SphTurbulence::stage,
    },
    StageKind {
        name: "statistics",
        summary: "the running statistics of every medium",
        slot: Slot::AfterStep,
        build: StatisticsStage::stage,
    },
    StageKind {
        name: "sph_metrics",
        summary: "the fluid's metrics.csv row",
        slot: Slot::Metrics,
        build: SphMetrics::stage,
    },
    StageKind {
        name: "grid_metrics",
        summary: "the grid's metrics.csv row",
        slot: Slot::Metrics,
        build: GridMetrics::stage,
    },
];

/// Kinds added by [`register_stage`].
static REGISTERED: RwLock<Vec<&'static StageKind>> = RwLock::new(Vec::new());

/// Adds a kind of stage from outside the crate: a run builds it when its `build` says so
/// (typically when the scene's `stages` names it). Refuses a name that is taken.
pub fn register_stage(kind: StageKind) -> Result<(), String> {
    let mut registered = REGISTERED.write().unwrap_or_else(|e| e.into_inner());
    let mut all = BUILT_IN.iter().chain(registered.iter().copied());
    if all.any(|k| k.name == kind.name) {
        return Err(format!("a stage named `{}` exists", kind.name));
    }
    registered.push(Box::leak(Box::new(kind)));
    Ok(())
}

/// Every kind of stage: the built-in ones, then the registered ones.
pub fn stage_kinds() -> Vec<&'static StageKind> {
    let registered = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    BUILT_IN.iter().chain(registered.iter().copied()).collect()
}

/// One place in a kind of scene's order: a slot's stages, or one of the solvers' own.
enum At {
    Slot(Slot),
    Own(Box<dyn Stage>),
}

fn own(stage: impl Stage + 'static) -> At {
    At::Own(Box::new(stage))
}

/// The kind of run `spec` is and its stages, in the order a step runs them.
pub fn stages(
    spec: &RunSpec,
    sim: &mut Simulation,
) -> Result<(SceneKind, Vec<Box<dyn Stage>>), RunError> {
    let kinds = stage_kinds();
    if let Some(unknown) = spec
        .stages
        .iter()
        .find(|n| !kinds.iter().any(|k| k.name == n.as_str()))
    {
        let names: Vec<_> = kinds.iter().map(|k| k.name).collect();
        return Err(RunError::Unsupported(format!(
            "`stages`: unknown stage `{unknown}`, expected one of {}",
            names.join(", ")
        )));
    }
    let mut slots: [Vec<Box<dyn Stage>>; SLOTS] = Default::default();
    for kind in kinds {
        if let Some(stage) = (kind.build)(spec, sim)? {
            slots[kind.slot as usize].push(stage);
        }
    }
    let (has_sph, has_grid) = (sim.sph.is_some(), sim.grid.is_some());
    let coupling = spec.coupling.clone().filter(|_| sim.both_media());
    let (kind, order) = match (coupling, has_sph, has_grid) {
        (Some(coupling), _, _) => (SceneKind::Coupled, coupled(SurfaceExchange { coupling })),
        (None, true, true) => (SceneKind::SideBySide, side_by_side()),
        (None, true, false) => (SceneKind::Sph, sph()),
        (None, false, _) => (SceneKind::Grid, grid()),
    };
    let mut stages = Vec::new();
    for at in order {
        match at {
            At::Slot(slot) => stages.append(&mut slots[slot as usize]),
            At::Own(stage) => stages.push(stage),
        }
    }
    let added: Vec<_> = stages.iter().filter_map(|s| s.added_columns(sim)).collect();
    for stage in &mut stages {
        stage.adopt_columns(&added);
    }
    Ok((kind, stages))
}

/// A grid scene: Figure 9's turbulence (lines 1–25), then the grid's own step (line 28).
fn grid() -> Vec<At> {
    vec![
        At::Slot(Slot::Start),
        At::Slot(Slot::BeforeGrid),
        own(GridStep),
        At::Slot(Slot::AfterStep),
        At::Slot(Slot::Metrics),
    ]
}

/// An SPH scene: the turbulence on the particles, the solver's step (its refinements run
/// inside, as step hooks), then the neighbourhood of the new positions.
fn sph() -> Vec<At> {
    vec![
        At::Slot(Slot::Start),
        At::Slot(Slot::BeforeSph),
        own(SphStep),
        own(SphNeighbours),
        At::Slot(Slot::AfterStep),
        At::Slot(Slot::Metrics),
    ]
}

/// A fluid and a grid that do not exchange anything: each steps as in its own scene (the
/// turbulence drives the grid).
fn side_by_side() -> Vec<At> {
    vec![
        At::Slot(Slot::Start),
        At::Slot(Slot::BeforeSph),
        own(SphStep),
        own(SphNeighbours),
        At::Slot(Slot::BeforeGrid),
        own(GridStep),
        At::Slot(Slot::AfterStep),
        At::Slot(Slot::Metrics),
    ]
}

/// Air on the grid over water in SPH (`super::coupling`): the water is the air's boundary for
/// the step, the air's pressure on it is known after the grid's projection, and both reach the
/// particles before they move.
fn coupled(exchange: SurfaceExchange) -> Vec<At> {
    vec![
        At::Slot(Slot::Start),
        own(exchange),
        At::Slot(Slot::BeforeGrid),
        own(GridStep),
        own(SurfacePressure),
        At::Slot(Slot::BeforeSph),
        own(SphStep),
        own(SphNeighbours),
        At::Slot(Slot::AfterStep),
        At::Slot(Slot::Metrics),
    ]
}
