//! The SPH fluid's turbulence stage (see the parent module): Figure 9 on particles. It runs after
//! the neighbourhood update and before the SPH step, as the grid's runs before the grid's step,
//! so the step's divergence and pressure solves see the synthesised velocity as part of v^n
//! (line 25 before line 28); a refinement hook inside the step (`src/refine/`) then acts on that
//! velocity by its own paper's algorithm. Its parts, named as the plan names them:
//!
//! - `wall layer` (lines 2–6): for each obstacle with a database, its motion relative to the
//!   ambient flow (the mean velocity of the particles in the shell), the lookup, and at every
//!   fluid particle within [`LAYER`] spacings of its surface (the kernel support: the particles
//!   that feel the wall) the nearest precomputed point's value in the world frame, kept where
//!   larger in magnitude. The field, [`ABL_FIELD`], rides on the particles, so their motion is
//!   its advection (line 9, section 3.1's separation plume) with no pass of its own.
//! - `seeding` (lines 11–20): the shared routine over the particles with nonzero omega_ABL,
//!   volume m / rho, l_m the distance to the nearest wall, and a radius that also stays clear of
//!   the free surface.
//! - `vortex dynamics` (lines 23–24): the vortex layer through the SPH velocity source.
//! - `liquid bounds` (section 6): a particle centred outside the liquid (no fluid particle within
//!   one spacing, or inside a solid) is removed, and a kernel reaching past the free surface or
//!   into a wall is shrunk to fit, its peak vorticity kept ("we reduce a particle's kernel size
//!   once it extends past the liquid phase to avoid non-divergence free velocity fields").
//! - `synthesis` (line 25): Eq. 12's velocity at the fluid particles, with Eq. 14's weights,
//!   through the SPH sink.
//!
//! The free surface is the fluid particles with fewer neighbours than the divergence solve
//! counts as inside ([`crate::sph::SphSolver::surface_positions`]); their centres lie about
//! half a spacing inside the liquid, so a kernel bounded by them stays inside it.

use rayon::prelude::*;

use super::{
    push_seeds, Common, Laps, Resolution, Turbulence, TurbulenceStats, DYNAMICS, SEEDING,
    SHELL_INNER, SHELL_OUTER, SYNTHESIS, WALL_LAYER,
};
use crate::abl::params::LAYER_SPACINGS;
use crate::abl::seeding::{scatter, seed, SeedSamples};
use crate::abl::{AblSettings, Seeding};
use crate::pipeline::order::Built;
use crate::pipeline::outputs::Kind;
use crate::pipeline::simulation::{Simulation, StepError};
use crate::pipeline::spec::RunSpec;
use crate::pipeline::stages::{AddedColumns, Stage, StepRecord};
use crate::pipeline::RunError;
use crate::spatial::PointHash;
use crate::sph::walls::wall_distance;
use crate::sph::SphSolver;
use crate::vortex::{kernel, synthesize, VortexParticles};
use crate::{Point3, Real, Vec3};

const LIQUID_BOUNDS: &str = "liquid bounds";

/// The stage's parts, in order.
pub const PARTS: [&str; 5] = [WALL_LAYER, SEEDING, DYNAMICS, LIQUID_BOUNDS, SYNTHESIS];

/// Name of the carried per-particle field omega_ABL, 1/s (also its name in the frames).
pub const ABL_FIELD: &str = "abl_vorticity";

/// Thickness of the wall-attached layer, in particle spacings: the kernel support.
pub const LAYER: Real = LAYER_SPACINGS;

/// The stage (see the module documentation).
pub struct SphTurbulence {
    common: Common,
    /// Index of [`ABL_FIELD`] among the fluid's carried fields.
    field: usize,
}

impl SphTurbulence {
    /// The stage of a run with a fluid and an obstacle with a database, unless a grid beside
    /// the fluid takes the turbulence (an uncoupled scene with both drives the grid; a coupled
    /// one seeds and synthesises in each medium).
    pub(in crate::pipeline) fn stage(spec: &RunSpec, sim: &mut Simulation) -> Built {
        let (has_sph, has_grid) = (sim.sph.is_some(), sim.grid.is_some());
        let coupled = spec.coupling.is_some() && sim.both_media();
        match &spec.abl {
            Some(settings) if has_sph && (coupled || !has_grid) => {
                let stage = Self::build(settings.clone(), sim, &spec.shapes)?;
                Ok(Some(Box::new(stage)))
            }
            _ => Ok(None),
        }
    }

    /// Opens every database (checking it belongs to its obstacle), adds the carried field to
    /// the fluid and builds the empty state into `sim`.
    pub fn build(
        settings: AblSettings,
        sim: &mut Simulation,
        shapes: &[crate::geometry::Shape],
    ) -> Result<Self, RunError> {
        let sph = sim.sph.as_mut().expect("turbulence is built for a fluid");
        let res = Resolution {
            dx: sph.spacing,
            thickness: LAYER * sph.spacing,
            on_particles: true,
        };
        let common = Common::build(settings, shapes, &sph.bodies, res)?;
        let field = sph.fluid.carry(ABL_FIELD);
        sim.sph_turbulence = Some(Turbulence::new(None, &PARTS));
        Ok(Self { common, field })
    }

    /// Lines 2–6: the wall-attached layer of every obstacle into the carried field.
    fn attach(&self, sph: &mut SphSolver) {
        let t = sph.time();
        let scale = self.common.scale();
        let layer = LAYER * sph.spacing;
        for o in &self.common.obstacles {
            let body = &sph.bodies[o.body];
            let attached = sph.particles_near(o.body, Real::NEG_INFINITY, layer);
            if attached.is_empty() {
                continue;
            }
            let shell = sph.particles_near(o.body, SHELL_INNER * o.reach, SHELL_OUTER * o.reach);
            let values = o.values(body, t, sph.mean_velocity(&shell), scale);
            let inverse = body.pose(t).inverse();
            let nearest: Vec<usize> = attached
                .par_iter()
                .map(|&i| o.layer.nearest(&(inverse * Point3::from(sph.fluid.x[i]))))
                .collect();
            let field = &mut sph.fluid.carried[self.field].1;
            for (&i, &p) in attached.iter().zip(&nearest) {
                if values[p].norm_squared() > field[i].norm_squared() {
                    field[i] = values[p];
                }
            }
        }
    }

    /// Lines 11–20: seeds particles from the fluid particles with nonzero omega_ABL.
    fn seed(
        &mut self,
        sph: &mut SphSolver,
        surface: &Surface,
        vortices: &mut VortexParticles,
        dt: Real,
    ) -> usize {
        let fluid = &sph.fluid;
        let idx: Vec<usize> = (0..fluid.len())
            .filter(|&i| fluid.carried[self.field].1[i] != Vec3::zeros())
            .collect();
        let params = self.common.seeding_params();
        let mut samples = SeedSamples::default();
        for &i in &idx {
            let x = fluid.x[i];
            let l = sph.wall_distance(&Point3::from(x)).max(0.0);
            samples.push(
                x,
                fluid.carried[self.field].1[i],
                fluid.mass / fluid.density[i],
                l,
            );
            let last = samples.len() - 1;
            samples.limit_room(last, surface.distance(&x, params.r_max));
        }
        let rng = &mut self.common.rng;
        let mut seeds = seed(&mut samples, &params, dt, rng);
        let field = &mut sph.fluid.carried[self.field].1;
        for (&i, w) in idx.iter().zip(&samples.omega) {
            field[i] = *w;
        }
        if self.common.settings.params.seeding == Seeding::Random && !seeds.is_empty() {
            let sites = &sph.fluid.x;
            let wall = walls(sph);
            let site_distance: Vec<Real> = sites
                .par_iter()
                .map(|x| {
                    let l = wall(x);
                    l.min(surface.distance(x, params.r_max))
                })
                .collect();
            scatter(&mut seeds, sites, &site_distance, sph.spacing, rng);
        }
        push_seeds(&seeds, vortices);
        seeds.len()
    }
}

/// The distance to the nearest wall of `sph` at its time, as a function that threads share
/// (the solver itself holds its step hooks, which they may not).
fn walls(sph: &SphSolver) -> impl Fn(&Vec3) -> Real + Sync + '_ {
    let (bodies, container, t) = (&sph.bodies, sph.has_container(), sph.time());
    move |x| wall_distance(bodies, container, t, &Point3::from(*x))
}

/// The free-surface particles, searched for the distance from a point to the surface.
pub struct Surface {
    x: Vec<Vec3>,
    hash: PointHash,
    /// The search radius, m.
    reach: Real,
}

impl Surface {
    /// The surface of `sph`, searched within `reach` (m; the largest seed radius).
    pub fn of(sph: &SphSolver, reach: Real) -> Self {
        let x = sph.surface_positions();
        let reach = reach.max(sph.spacing);
        let hash = PointHash::new(&x, reach);
        Self { x, hash, reach }
    }

    /// Distance from `p` to the nearest surface particle within `cap` (searched up to the
    /// reach), else `cap`.
    pub fn distance(&self, p: &Vec3, cap: Real) -> Real {
        let mut best2 = cap * cap;
        self.hash.for_each_near(p, cap.min(self.reach), |i| {
            best2 = best2.min((self.x[i] - p).norm_squared());
        });
        best2.sqrt()
    }
}

/// Section 6: removes the particles centred outside the liquid and shrinks the kernels that
/// reach past the free surface or into a wall, keeping their peak vorticity. Returns how many
/// were removed.
pub fn fit_to_liquid(vortices: &mut VortexParticles, sph: &SphSolver, surface: &Surface) -> usize {
    let (fluid, grid, h) = (&sph.fluid, sph.grid(), sph.spacing);
    let wall = walls(sph);
    let room: Vec<Option<Real>> = (0..vortices.len())
        .into_par_iter()
        .map(|q| {
            let x = vortices.x[q];
            let mut inside = false;
            grid.for_each_near(&x, &fluid.x, h, |_| inside = true);
            let wall = wall(&x);
            (inside && wall > 0.0).then(|| {
                let r = vortices.radius(q);
                wall.min(surface.distance(&x, r))
            })
        })
        .collect();
    for (q, r) in room.iter().enumerate() {
        if let Some(r) = *r {
            if r < vortices.radius(q) {
                vortices.sigma[q] = kernel::sigma_for_radius(r);
            }
        }
    }
    let keep: Vec<bool> = room.iter().map(Option::is_some).collect();
    let removed = keep.iter().filter(|k| !**k).count();
    if removed > 0 {
        vortices.retain(&keep);
    }
    removed
}

impl Stage for SphTurbulence {
    fn name(&self) -> &'static str {
        "turbulence"
    }

    fn save(&self, into: &mut crate::state::Saver) {
        self.common.save(into);
    }

    fn restore(&mut self, from: &crate::state::Restorer) -> Result<(), crate::state::StateError> {
        self.common.restore(from)
    }

    fn describe(&self, _sim: &Simulation) -> (String, Vec<(&'static str, String)>) {
        let (headline, [wall, seeding, dynamics]) = self.common.describe("spacings");
        (
            headline,
            vec![
                (
                    WALL_LAYER,
                    format!(
                        "{wall}, nearest point per particle within {LAYER} spacings, max \
                         magnitude, carried by the particles as {ABL_FIELD}"
                    ),
                ),
                (SEEDING, format!("{seeding}, clear of the free surface")),
                (DYNAMICS, format!("{dynamics}, through the SPH velocity")),
                (
                    LIQUID_BOUNDS,
                    "remove particles outside the liquid, shrink kernels past the free surface \
                     or into walls (section 6)"
                        .into(),
                ),
                (
                    SYNTHESIS,
                    "Eq. 12 at the fluid particles with Eq. 14 weights".into(),
                ),
            ],
        )
    }

    fn run(&mut self, sim: &mut Simulation, rec: &mut StepRecord) -> Result<(), StepError> {
        let sph = sim.sph.as_mut().expect("turbulence is built for a fluid");
        let state = sim
            .sph_turbulence
            .as_mut()
            .expect("built with the turbulence state");
        let dt = rec.dt;
        let mut stats = TurbulenceStats::default();
        let mut laps = Laps::start(&PARTS);
        self.attach(sph);
        laps.lap(WALL_LAYER);
        let surface = Surface::of(sph, self.common.seeding_params().r_max);
        stats.seeded = self.seed(sph, &surface, &mut state.vortices, dt);
        laps.lap(SEEDING);
        let report =
            self.common
                .dynamics
                .step(&mut state.vortices, &sph.velocity_source(), dt, sph.spacing);
        stats.dynamics(report);
        laps.lap(DYNAMICS);
        stats.removed = fit_to_liquid(&mut state.vortices, sph, &surface);
        laps.lap(LIQUID_BOUNDS);
        synthesize(&state.vortices, sph, 1)?;
        laps.lap(SYNTHESIS);
        stats.seconds = laps.seconds;
        stats.particles = state.vortices.len();
        stats.energy = state.vortices.total_energy();
        stats.abl_sum = sph.fluid.carried[self.field]
            .1
            .iter()
            .map(|w| w.norm())
            .sum();
        state.record(stats, Kind::Particles, rec);
        Ok(())
    }

    fn ran<'a>(&self, _sim: &'a Simulation) -> &'a [&'static str] {
        &PARTS
    }

    fn added_columns(&self, sim: &Simulation) -> Option<AddedColumns> {
        let state = sim.sph_turbulence.as_ref()?;
        Some(state.added_columns(Kind::Particles))
    }
}
