//! The one place that turns a resolved [`Scene`] into the parts' own parameters: the solvers,
//! the bodies and the refinement never read a scene, and the pipeline builds a run from the
//! [`RunSpec`] made here.

use super::{Body, Scene};
use crate::abl::AblSettings;
use crate::geometry::{GeometryError, RigidBody};
use crate::grid::poisson::SolverSettings;
use crate::grid::{GridParams, InflowModes};
use crate::io::{AttrValue, VtkOptions};
use crate::metrics::stations::StationSpec;
use crate::metrics::Probe;
use crate::pipeline::outputs::{LineProbe, OutputSpec};
use crate::pipeline::{GridSpec, RunEnd, RunSpec, SphSpec, StatisticsSpec};
use crate::sph::SphParams;
use crate::stepping::StepLimits;
use crate::{Real, Vec3};

impl Scene {
    /// The bodies in the order every part numbers them: the container first (body 0, when
    /// there is one), then the obstacles.
    pub fn all_bodies(&self) -> impl Iterator<Item = &Body> {
        self.container.iter().chain(&self.obstacles)
    }

    /// The obstacles with their index among [`Scene::all_bodies`].
    pub fn indexed_obstacles(&self) -> impl Iterator<Item = (usize, &Body)> {
        let first = usize::from(self.container.is_some());
        self.obstacles
            .iter()
            .enumerate()
            .map(move |(i, b)| (first + i, b))
    }
}

/// The run `scene` describes: each part's parameters, the bodies (meshes read here, once),
/// the stages' settings and the outputs.
pub fn run_spec(scene: &Scene) -> Result<RunSpec, GeometryError> {
    let sph = sph_params(scene).map(|params| SphSpec {
        params,
        refinement: scene.refinement.clone(),
        seed: scene.seed,
    });
    let grid = scene.grid.as_ref().zip(grid_params(scene));
    let grid = grid.map(|(g, params)| GridSpec {
        params,
        initial_flow: g.initial_flow,
        static_flow: g.static_flow.clone().map(|p| (p, g.static_flow_frame)),
    });
    Ok(RunSpec {
        name: scene.name.clone(),
        dir: scene.output.dir.clone(),
        bodies: bodies(scene)?,
        container: scene.container.is_some(),
        shapes: scene.all_bodies().map(|b| b.shape.clone()).collect(),
        sph,
        grid,
        abl: abl_settings(scene),
        coupling: scene.coupling.clone(),
        probes: scene.probes.clone(),
        body_names: scene
            .indexed_obstacles()
            .filter_map(|(i, b)| Some((b.name.clone()?, i)))
            .collect(),
        metrics: scene.output.metrics.clone(),
        gravity: Vec3::from(scene.gravity),
        statistics: statistics_spec(scene),
        stages: scene.stages.clone(),
        outputs: output_spec(scene),
        end: RunEnd {
            time: scene.time.end,
            steps: scene.time.steps,
            steady: scene.grid.as_ref().and_then(|g| g.steady_tolerance),
        },
        resolved: scene.to_toml(),
        checkpoint_key: checkpoint_key(scene),
    })
}

/// The scene as a checkpoint compares it: without what a resumed run may change (when it
/// ends, what it writes).
pub fn checkpoint_key(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.time.end = None;
    s.time.steps = None;
    s.output = Default::default();
    s.to_toml()
}

/// The bodies of a scene, in the order of [`Scene::all_bodies`].
pub fn bodies(scene: &Scene) -> Result<Vec<RigidBody>, GeometryError> {
    scene
        .all_bodies()
        .enumerate()
        .map(|(i, b)| RigidBody::from_scene(b, i))
        .collect()
}

/// The step limits of `[time]`, shared by every solver of the scene.
pub fn step_limits(scene: &Scene) -> StepLimits {
    let t = &scene.time;
    StepLimits {
        cfl: t.cfl,
        dt_min: t.dt_min,
        dt_max: t.dt_max,
        fixed_dt: t.dt,
    }
}

/// The SPH fluid's parameters, when the scene has a `[fluid]`.
pub fn sph_params(scene: &Scene) -> Option<SphParams> {
    let fluid = scene.fluid.as_ref()?;
    Some(SphParams {
        spacing: fluid.spacing,
        rest_density: fluid.density,
        blocks: fluid.blocks.clone(),
        gravity: Vec3::from(scene.gravity),
        pressure: scene.pressure.clone(),
        viscosity: scene.viscosity.clone(),
        wall_viscosity: wall_viscosities(scene),
        limits: step_limits(scene),
        domain: (Vec3::from(scene.domain.min), Vec3::from(scene.domain.max)),
        lost_fraction: fluid.lost_fraction,
        ramp: fluid.ramp,
        container: scene.container.is_some(),
        inflows: fluid.inflow.clone(),
        outflows: fluid.outflow.clone(),
    })
}

/// Per body of [`bodies`]: its `wall_viscosity`, else the scene's `viscosity.boundary`.
pub fn wall_viscosities(scene: &Scene) -> Vec<Real> {
    scene
        .all_bodies()
        .map(|b| b.wall_viscosity.unwrap_or(scene.viscosity.boundary))
        .collect()
}

/// The MAC grid's parameters, when the scene has a `[grid]`: it covers the scene's domain.
pub fn grid_params(scene: &Scene) -> Option<GridParams> {
    let grid = scene.grid.as_ref()?;
    Some(GridParams {
        resolution: grid.resolution,
        dx: grid.spacing(scene),
        origin: Vec3::from(scene.domain.min),
        initial_velocity: Vec3::from(grid.initial_velocity),
        sides: grid.boundary.sides(),
        inflow_turbulence: grid
            .inflow_turbulence
            .as_ref()
            .map(|t| InflowModes::new(t, scene.seed)),
        advection: grid.advection,
        reflection: grid.reflection,
        obstacle_surface: grid.surface(scene.coupling.is_some()),
        incremental_pressure: grid.incremental_pressure,
        viscosity_scheme: grid.viscosity_scheme,
        viscosity: scene.viscosity.kinematic,
        density: scene
            .coupling
            .as_ref()
            .map_or(grid.density, |c| c.air_density),
        confinement: grid.vorticity_confinement,
        gravity: Vec3::from(scene.gravity),
        gravity_force: grid.gravity,
        limits: step_limits(scene),
        pressure: SolverSettings {
            tolerance: grid.pressure_tolerance,
            max_iterations: grid.pressure_max_iterations as usize,
        },
        smoke: grid.smoke.clone(),
        smoke_refinement: abl_settings(scene).map_or(1, |s| s.params.upsample),
        average_from: grid.average_from,
        container: scene.fluid.is_some() && scene.container.is_some(),
    })
}

/// The run-time boundary layer's settings, when an obstacle names a database: the
/// `[turbulence]` table (or its defaults), |U_0| resolved, the seed, and each database with its
/// body. `None` also when |U_0| cannot be resolved, which validation refuses.
pub fn abl_settings(scene: &Scene) -> Option<AblSettings> {
    let databases: Vec<_> = scene
        .abl_obstacles()
        .filter_map(|(i, b)| Some((i, b.abl.as_ref()?.database.clone())))
        .collect();
    if databases.is_empty() {
        return None;
    }
    Some(AblSettings {
        params: scene.turbulence.clone().unwrap_or_default(),
        u0: scene.turbulence_u0()?,
        seed: scene.seed,
        databases,
    })
}

/// What the run writes: the `[output]` section, the HDF5 files' root attributes (scene name,
/// seed) and the line probes, whose profiles are written at the end of a grid run.
pub fn output_spec(scene: &Scene) -> OutputSpec {
    let out = &scene.output;
    let profiles = scene
        .probes
        .iter()
        .filter_map(|p| match p {
            Probe::Line {
                name,
                from,
                to,
                points,
            } => Some(LineProbe {
                name: name.clone(),
                from: *from,
                to: *to,
                points: *points,
            }),
            _ => None,
        })
        .collect();
    OutputSpec {
        interval: out.interval,
        vtk: out.vtk,
        vtk_options: VtkOptions {
            precision: out.precision,
            compression: out.compression,
        },
        hdf5: out.hdf5,
        compression: out.compression,
        attrs: vec![
            ("scene", AttrValue::Str(scene.name.clone())),
            ("seed", AttrValue::Int(scene.seed as i64)),
        ],
        profiles,
        formats: out.formats.clone(),
        checkpoint_interval: out.checkpoint_interval,
        checkpoint_every: out.checkpoint_every,
    }
}

/// The `[statistics]` section, its particle bins resolved (two particle spacings when left
/// out) over the scene's domain.
pub fn statistics_spec(scene: &Scene) -> Option<StatisticsSpec> {
    let stats = scene.statistics.as_ref()?;
    let spacing = scene.fluid.as_ref().map_or(1.0, |f| f.spacing);
    Some(StatisticsSpec {
        from: stats.from,
        every: stats.every,
        bin: stats.bin.unwrap_or(2.0 * spacing),
        domain: (Vec3::from(scene.domain.min), Vec3::from(scene.domain.max)),
        stations: stats
            .stations
            .iter()
            .map(|s| StationSpec {
                name: s.name.clone(),
                min: Vec3::from(s.min),
                max: Vec3::from(s.max),
                axis: s.axis.index(),
                bins: s.bins,
                pool: s.pool.map(|a| a.index()),
            })
            .collect(),
        batch: scene
            .time
            .end
            .map(|end| (end - stats.from) / stats.batches as Real)
            .filter(|l| *l > 0.0),
    })
}
