//! What a frame shows, computed once per frame time for every output that writes it: the
//! particles' and the grid's fields, the smoke on its fine grid, each medium's vortex
//! particles. Nothing is computed that no output asks for.

use std::borrow::Cow;
use std::cell::OnceCell;

use ndarray::Array3;

use super::Kind;
use crate::grid::forces::vorticity;
use crate::io::{Field, GridField, GridFrame, ParticleFrame};
use crate::pipeline::Simulation;
use crate::vortex::VortexParticles;
use crate::{Real, Vec3};

/// One frame time of a run: the simulation and, on first use, the fields its outputs write.
pub struct Frame<'s> {
    pub sim: &'s Simulation,
    particles: OnceCell<Vec<Vec3>>,
    grid: OnceCell<GridValues<'s>>,
    /// The grid's and the fluid's vortex particles.
    vortices: [OnceCell<Option<VortexValues<'s>>>; 2],
}

/// The grid values a frame holds that the solver does not store as they are written.
struct GridValues<'s> {
    velocity: [Array3<Real>; 3],
    vorticity: [Array3<Real>; 3],
    /// 1 in obstacle cells, 0 in the fluid.
    solid: Array3<Real>,
    /// The smoke's cell means on the flow's grid (its own grid may be finer).
    smoke: Option<Cow<'s, Array3<Real>>>,
    temperature: Option<Cow<'s, Array3<Real>>>,
}

impl<'s> Frame<'s> {
    pub fn new(sim: &'s Simulation) -> Self {
        Self {
            sim,
            particles: OnceCell::new(),
            grid: OnceCell::new(),
            vortices: [OnceCell::new(), OnceCell::new()],
        }
    }

    /// The fluid's frame: position, velocity, vorticity (the solver's curl of the velocity,
    /// 1/s: a wake shows in ParaView without post-processing), density, pressure, the hooks'
    /// fields and the carried fields (`abl_vorticity` with a boundary layer).
    pub fn particles(&self) -> Option<ParticleFrame<'_>> {
        let solver = self.sim.sph.as_ref()?;
        let f = &solver.fluid;
        let omega = self.particles.get_or_init(|| solver.vorticity());
        let mut fields = vec![
            Field::vector("velocity", &f.v),
            Field::vector("vorticity", omega),
            Field::scalar("density", &f.density),
            Field::scalar("pressure", &f.pressure),
        ];
        let carried = f.carried.iter().map(|(name, d)| (*name, d.as_slice()));
        fields.extend(
            solver
                .refinement_fields()
                .into_iter()
                .chain(carried)
                .map(|(name, data)| Field::vector(name, data)),
        );
        Some(ParticleFrame {
            step: solver.steps(),
            time: solver.time(),
            positions: &f.x,
            fields,
        })
    }

    /// The grid's frame: velocity, vorticity, pressure, the obstacle cells, with a boundary
    /// layer its field `abl_vorticity`, and the smoke (and temperature) as cell means.
    pub fn grid(&self) -> Option<GridFrame<'_>> {
        let solver = self.sim.grid.as_ref()?;
        let smoke = solver.smoke.as_ref();
        let values = self.grid.get_or_init(|| GridValues {
            velocity: solver.mac.cell_velocity(),
            vorticity: vorticity(&solver.mac),
            solid: solver
                .bounds
                .fluid_mask()
                .mapv(|f| if f { 0.0 } else { 1.0 }),
            smoke: smoke.map(|s| s.on_flow_cells(&s.density)),
            temperature: smoke.and_then(|s| Some(s.on_flow_cells(s.temperature.as_ref()?))),
        });
        let [u, v, w] = &values.velocity;
        let [wx, wy, wz] = &values.vorticity;
        let mut fields = vec![
            GridField::vector("velocity", [u.view(), v.view(), w.view()]),
            GridField::vector("vorticity", [wx.view(), wy.view(), wz.view()]),
            GridField::scalar("pressure", solver.pressure.view()),
            GridField::scalar("solid", values.solid.view()),
        ];
        let abl = self
            .sim
            .grid_turbulence
            .as_ref()
            .and_then(|t| t.abl.as_ref());
        if let Some([x, y, z]) = abl {
            fields.push(GridField::vector(
                "abl_vorticity",
                [x.view(), y.view(), z.view()],
            ));
        }
        let scalars = [
            ("smoke", &values.smoke),
            ("temperature", &values.temperature),
        ];
        for (name, data) in scalars {
            fields.extend(data.as_ref().map(|d| GridField::scalar(name, d.view())));
        }
        Some(GridFrame {
            step: solver.steps(),
            time: solver.time(),
            origin: solver.mac.origin,
            spacing: solver.mac.dx,
            dims: solver.mac.dims,
            fields,
        })
    }

    /// The smoke (and temperature) on its own finer grid (section 5.2), when it has one.
    pub fn fine_smoke(&self) -> Option<GridFrame<'_>> {
        let solver = self.sim.grid.as_ref()?;
        let smoke = solver.smoke.as_ref()?;
        let grid = &smoke.fine.as_ref()?.mac;
        let mut fields = vec![GridField::scalar("smoke", smoke.density.view())];
        fields.extend(
            smoke
                .temperature
                .as_ref()
                .map(|t| GridField::scalar("temperature", t.view())),
        );
        Some(GridFrame {
            step: solver.steps(),
            time: solver.time(),
            origin: grid.origin,
            spacing: grid.dx,
            dims: grid.dims,
            fields,
        })
    }

    /// The vortex particles of `medium`, when it has a boundary layer.
    pub fn vortices(&self, medium: Kind) -> Option<ParticleFrame<'_>> {
        let (slot, turbulence) = match medium {
            Kind::Grid => (&self.vortices[0], &self.sim.grid_turbulence),
            Kind::Particles => (&self.vortices[1], &self.sim.sph_turbulence),
        };
        let values =
            slot.get_or_init(|| turbulence.as_ref().map(|t| VortexValues::of(&t.vortices)));
        Some(values.as_ref()?.frame(self.sim.steps(), self.sim.time()))
    }
}

/// The per-particle values of a vortex set that it does not store, computed once per frame.
struct VortexValues<'a> {
    particles: &'a VortexParticles,
    radius: Vec<Real>,
    energy: Vec<Real>,
}

impl<'a> VortexValues<'a> {
    fn of(particles: &'a VortexParticles) -> Self {
        let n = particles.len();
        Self {
            particles,
            radius: (0..n).map(|i| particles.radius(i)).collect(),
            energy: (0..n).map(|i| particles.energy(i)).collect(),
        }
    }

    /// Position, vorticity vector (1/s), radius `sqrt(6) sigma` (m), kernel energy (m^5/s^2)
    /// and age (s) of every particle.
    fn frame(&self, step: u64, time: Real) -> ParticleFrame<'_> {
        let p = self.particles;
        ParticleFrame {
            step,
            time,
            positions: &p.x,
            fields: vec![
                Field::vector("vorticity", &p.omega),
                Field::scalar("radius", &self.radius),
                Field::scalar("energy", &self.energy),
                Field::scalar("age", &p.age),
            ],
        }
    }
}

/// The media of a simulation that have vortex particles, with the names of their sets:
/// `vortices`, or `grid_vortices` and `particles_vortices` when both have one.
pub fn vortex_sets(sim: &Simulation) -> Vec<(Kind, String)> {
    let media = [
        (Kind::Grid, sim.grid_turbulence.is_some()),
        (Kind::Particles, sim.sph_turbulence.is_some()),
    ];
    let both = media.iter().all(|m| m.1);
    media
        .iter()
        .filter(|m| m.1)
        .map(|&(kind, _)| (kind, kind.file("vortices", both)))
        .collect()
}
