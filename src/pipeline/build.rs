//! A resolved scene compiled into a [`Pipeline`]: its solvers, the stages a step runs and the
//! outputs it writes. A stage that nothing in the scene needs is not built, so it cannot run.

use std::path::Path;
use std::time::Instant;

use super::footprint::{available_memory, Footprint};
use super::frames::{GridFrames, Kind, ParticleFrames, VortexFrames, VortexValues};
use super::order::{self, SceneKind};
use super::simulation::{Simulation, StepError};
use super::stages::{Stage, StepRecord};
use super::RunError;
use crate::geometry::RigidBody;
use crate::grid::{GridError, GridSolver};
use crate::io::read_velocity;
use crate::io::{write_includes, write_links, AttrValue, IoError, VtkOptions};
use crate::metrics::Probe;
use crate::scene::{build, Scene};
use crate::sph::SphSolver;
use crate::stepping::towards_end;
use crate::{Real, Vec3};

/// A scene ready to step: the simulation, its stages in order and its frame writers.
pub struct Pipeline {
    /// The memory estimate the scene was admitted with.
    pub footprint: Footprint,
    pub sim: Simulation,
    /// Which solvers the scene runs and whether they exchange anything.
    pub kind: SceneKind,
    pub stages: Vec<Box<dyn Stage>>,
    pub frames: Frames,
    /// Grid line probes, written as `profile_NAME.csv` at the end: (name, from, to, points).
    pub profiles: Vec<(String, Vec3, Vec3, usize)>,
    /// Wall time each stage has run for so far, s, in the order of `stages`.
    pub stage_seconds: Vec<f64>,
}

/// The frame writers a scene asked for, opened with [`Pipeline::open`].
pub struct Frames {
    /// Simulated time between frames, s.
    pub interval: Real,
    pub vtk: bool,
    /// How the VTK files store their arrays (`output.precision`, `output.compression`).
    pub vtk_options: VtkOptions,
    pub hdf5: bool,
    /// Deflate level of the HDF5 datasets (`output.compression`).
    pub compression: u8,
    attrs: Vec<(&'static str, AttrValue)>,
    both: bool,
    pub particles: Option<ParticleFrames>,
    pub grid: Option<GridFrames>,
    /// The grid's and the fluid's vortex particles.
    pub vortices: [Option<VortexFrames>; 2],
}

/// The file names of the grid's and the fluid's vortex particles, where they have them:
/// `vortices`, or `grid_vortices` and `particles_vortices` when both do.
fn vortex_sets(sim: &Simulation) -> [Option<String>; 2] {
    let both = sim.grid_turbulence.is_some() && sim.sph_turbulence.is_some();
    [
        (&sim.grid_turbulence, Kind::Grid),
        (&sim.sph_turbulence, Kind::Particles),
    ]
    .map(|(t, kind)| t.as_ref().map(|_| kind.file("vortices", both)))
}

impl Frames {
    /// Writes one frame of every solver, with each medium's vortex particles.
    pub fn write(&mut self, sim: &Simulation) -> Result<(), IoError> {
        let values = [&sim.grid_turbulence, &sim.sph_turbulence]
            .map(|t| t.as_ref().map(|t| VortexValues::of(&t.vortices)));
        let [grid_set, fluid_set] = values
            .each_ref()
            .map(|v| v.as_ref().map(|v| v.frame(sim.steps, sim.time)));
        if let (Some(w), Some(sph)) = (self.particles.as_mut(), sim.sph.as_ref()) {
            w.write(sph, fluid_set.as_ref())?;
        }
        if let (Some(w), Some(grid)) = (self.grid.as_mut(), sim.grid.as_ref()) {
            w.write(grid, sim.grid_turbulence.as_ref(), grid_set.as_ref())?;
        }
        for (w, set) in self.vortices.iter_mut().zip([grid_set, fluid_set]) {
            if let (Some(w), Some(set)) = (w, set) {
                w.write(&set)?;
            }
        }
        Ok(())
    }

    /// Frames written so far (of the kind written most: both kinds are written together).
    pub fn count(&self) -> usize {
        let p = self.particles.as_ref().map_or(0, |w| w.count());
        let g = self.grid.as_ref().map_or(0, |w| w.count());
        p.max(g)
    }

    /// The plan's lines on the frames: (name, what is written).
    pub fn describe(&self, sim: &Simulation) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        let kinds = [
            (sim.sph.is_some(), Kind::Particles, "particles"),
            (sim.grid.is_some(), Kind::Grid, "grid"),
        ];
        let with_vortices = |kind: &Kind| match kind {
            Kind::Particles => sim.sph_turbulence.is_some(),
            Kind::Grid => sim.grid_turbulence.is_some(),
        };
        for name in vortex_sets(sim).into_iter().flatten() {
            if self.vtk {
                out.push((
                    "vtk",
                    format!("vortex particles + {name}.pvd every {} s", self.interval),
                ));
            }
        }
        for (_, kind, name) in kinds.iter().filter(|k| k.0) {
            if self.vtk {
                out.push((
                    "vtk",
                    format!("VTK frames + {name}.pvd every {} s", self.interval),
                ));
            }
            if self.hdf5 {
                out.push((
                    "hdf5",
                    format!(
                        "{} ({name}{}) every {} s",
                        kind.file("frames.h5", self.both),
                        if with_vortices(kind) {
                            ", vortex particles in each frame's group `vortices`"
                        } else {
                            ""
                        },
                        self.interval
                    ),
                ));
            }
        }
        if self.hdf5 && self.both {
            out.push((
                "hdf5",
                "frames.h5: /particles and /grid, links to both series, open together".into(),
            ));
        }
        let fine = sim
            .grid
            .as_ref()
            .and_then(|g| g.smoke.as_ref()?.fine.as_ref());
        if let Some(fine) = fine.filter(|_| self.vtk || self.hdf5) {
            let files = [
                (self.vtk, "VTK frames + smoke_fine.pvd"),
                (self.hdf5, "smoke_fine.h5"),
            ]
            .iter()
            .filter(|f| f.0)
            .map(|f| f.1)
            .collect::<Vec<_>>()
            .join(", ");
            out.push((
                "smoke",
                format!(
                    "{files}: smoke on its {:?} grid every {} s (the grid frames hold its cell \
                     means)",
                    fine.mac.dims, self.interval
                ),
            ));
        }
        out
    }
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
        let both = has_sph && has_grid;
        let sph = has_sph
            .then(|| sph_among(scene, bodies.clone()))
            .transpose()?;
        let grid = has_grid.then(|| grid_among(scene, bodies)).transpose()?;
        let mut sim = Simulation::new(sph, grid);
        let (kind, stages) = order::stages(scene, &mut sim)?;
        let profiles = scene
            .probes
            .iter()
            .filter_map(|p| match p {
                Probe::Line {
                    name,
                    from,
                    to,
                    points,
                } if sim.grid.is_some() => {
                    Some((name.clone(), Vec3::from(*from), Vec3::from(*to), *points))
                }
                _ => None,
            })
            .collect();
        let out = &scene.output;
        let frames = Frames {
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
            both,
            particles: None,
            grid: None,
            vortices: [None, None],
        };
        Ok(Self {
            footprint,
            sim,
            kind,
            stages,
            frames,
            profiles,
            stage_seconds: Vec::new(),
        })
    }

    /// One step: every solver's stable step, the smallest of them shortened to land on `end`,
    /// then every stage in order with it. With `trace`, appends each stage's name and then
    /// `name/part` for each part it ran.
    pub fn step(
        &mut self,
        end: Option<Real>,
        mut trace: Option<&mut Vec<String>>,
    ) -> Result<StepRecord, StepError> {
        let sim = &mut self.sim;
        let dt = sim.stable_dt()?;
        let dt = end.map_or(dt, |t| towards_end(dt, t - sim.time));
        let mut rec = StepRecord {
            step: sim.steps,
            time: sim.time,
            dt,
            ..Default::default()
        };
        self.stage_seconds.resize(self.stages.len(), 0.0);
        for (stage, seconds) in self.stages.iter_mut().zip(&mut self.stage_seconds) {
            let started = Instant::now();
            stage.run(sim, &mut rec)?;
            *seconds += started.elapsed().as_secs_f64();
            if let Some(trace) = trace.as_deref_mut() {
                trace.push(stage.name().to_owned());
                let parts = stage.ran(sim).iter();
                trace.extend(parts.map(|part| format!("{}/{part}", stage.name())));
            }
        }
        sim.time += dt;
        sim.steps += 1;
        Ok(rec)
    }

    /// Creates the output files of every stage and frame writer in `out`.
    pub fn open(&mut self, out: &Path) -> Result<(), IoError> {
        for stage in &mut self.stages {
            stage.open(&self.sim, out)?;
        }
        let f = &mut self.frames;
        let hdf5 = |kind: Kind| f.hdf5.then(|| kind.file("frames.h5", f.both));
        if let Some(sph) = self.sim.sph.as_ref() {
            let name = hdf5(Kind::Particles);
            f.particles = Some(ParticleFrames::new(
                out,
                f.vtk.then_some(f.vtk_options),
                name.as_deref().map(|n| (n, f.compression)),
                &f.attrs,
                sph,
            )?);
        }
        if let Some(grid) = self.sim.grid.as_ref() {
            let name = hdf5(Kind::Grid);
            f.grid = Some(GridFrames::new(
                out,
                f.vtk.then_some(f.vtk_options),
                name.as_deref().map(|n| (n, f.compression)),
                &f.attrs,
                grid,
            )?);
        }
        if f.hdf5 && f.both {
            // One file that opens both series: /particles and /grid link to their indexes.
            let links = [Kind::Particles, Kind::Grid].map(|k| k.file("frames.h5", true));
            write_links(
                &out.join("frames.h5"),
                &f.attrs,
                &[("particles", &links[0]), ("grid", &links[1])],
            )?;
            let series = [Kind::Particles, Kind::Grid].map(|k| k.file("frames.xmf", true));
            write_includes(&out.join("frames.xmf"), &[&series[0], &series[1]])?;
        }
        for (w, name) in f.vortices.iter_mut().zip(vortex_sets(&self.sim)) {
            if let Some(name) = name {
                *w = Some(VortexFrames::new(
                    out,
                    &name,
                    f.vtk.then_some(f.vtk_options),
                ));
            }
        }
        Ok(())
    }
}
