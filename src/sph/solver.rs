//! One SPH fluid with its boundaries, stepped in time.
//!
//! A step is split in two so that the driver can measure and write the state between them:
//! [`SphSolver::update_neighborhoods`] sorts the particles, rebuilds the neighbour lists and
//! computes densities at the current time; [`SphSolver::advance`] then runs the divergence
//! solve (DFSPH), the non-pressure forces, the CFL step size, the pressure solve and the
//! position update, following Bender & Koschier 2017, Algorithm 1.

use super::boundary::BoundaryParticles;
use super::dfsph::{self, Bounds, Solve, SolveResult};
use super::fluid::FluidParticles;
use super::forces;
use super::iisph;
use super::kernel::CubicSpline;
use super::neighborhood::Neighborhood;
use super::neighbors::{cell_order, CellGrid, NeighborLists};
use super::operators::{self, Operators, WallField};
use super::pair_cache::{Densities, PairCache};
use crate::geometry::RigidBody;
use crate::refine::{self, Refiner, StepContext};
use crate::scene::{Pressure, PressureSolverKind, Scene, Viscosity};
use crate::{Real, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum Instability {
    #[error("unstable at t = {time:.6} s (step {step}): {what} at fluid particle {particle}")]
    NotFinite {
        time: Real,
        step: u64,
        what: &'static str,
        particle: usize,
    },
    #[error(
        "unstable at t = {time:.6} s (step {step}): fluid particle {particle} left the domain at \
         ({:.4}, {:.4}, {:.4}) m", position.x, position.y, position.z
    )]
    Escaped {
        time: Real,
        step: u64,
        particle: usize,
        position: Vec3,
    },
    #[error(
        "unstable at t = {time:.6} s (step {step}): the CFL condition needs dt = {needed:.3e} s, \
         below time.dt_min = {dt_min:.3e} s (max speed {speed:.3} m/s)"
    )]
    CflLimit {
        time: Real,
        step: u64,
        needed: Real,
        dt_min: Real,
        speed: Real,
    },
}

/// Time-stepping settings of the solver.
#[derive(Debug, Clone)]
pub struct Stepping {
    pub cfl: Real,
    pub dt_min: Real,
    pub dt_max: Real,
    pub fixed_dt: Option<Real>,
    /// The run's end time: the last steps are shortened to land on it.
    pub end: Option<Real>,
}

/// What one step did.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepStats {
    pub dt: Real,
    pub divergence: SolveResult,
    pub pressure: SolveResult,
    /// Wall-clock seconds spent in the turbulence refinement.
    pub refinement_seconds: Real,
    /// Wall-clock seconds spent in the divergence solve (DFSPH).
    pub divergence_seconds: Real,
    /// Wall-clock seconds spent in the pressure (density) solve.
    pub pressure_seconds: Real,
}

/// The SPH fluid, its boundary samples, and the settings that drive it.
pub struct SphSolver {
    pub kernel: CubicSpline,
    pub fluid: FluidParticles,
    pub boundary: BoundaryParticles,
    pub bodies: Vec<RigidBody>,
    pub spacing: Real,
    gravity: Vec3,
    pressure: Pressure,
    viscosity: Viscosity,
    stepping: Stepping,
    domain: (Vec3, Vec3),
    grid: CellGrid,
    fluid_lists: NeighborLists,
    boundary_lists: NeighborLists,
    /// Kernel gradients of this step's pairs.
    pairs: PairCache,
    /// rho / rho_0 from the last neighbourhood update.
    density_ratio: Vec<Real>,
    /// DFSPH factors (IISPH reads them as -dt^2 / a_ii).
    factor: Vec<Real>,
    time: Real,
    step: u64,
    /// The last step's size; the stored stiffnesses (kappa dt^2) are rescaled when dt changes.
    last_dt: Option<Real>,
    /// The turbulence refinement, if the scene has one.
    refiner: Option<Box<dyn Refiner>>,
    /// Per fluid particle m / rho, the volume of the refinements' operators (kept across
    /// steps for its memory).
    refine_volume: Vec<Real>,
    /// Boundary samples take part in the difference operators (`refinement.walls`).
    walls_in_operators: bool,
}

impl SphSolver {
    /// Builds the fluid of `scene` (which must have one) with the given bodies.
    pub fn new(scene: &Scene, bodies: Vec<RigidBody>) -> Self {
        let fluid_cfg = scene
            .fluid
            .as_ref()
            .expect("SphSolver::new needs a scene with a fluid");
        let spacing = fluid_cfg.spacing;
        let kernel = CubicSpline::new(2.0 * spacing);
        // Akinci walls hold fluid about 1.5 spacings off (see `boundary`): lattice sites closer
        // than one spacing to a surface, or inside an obstacle, stay empty.
        let has_container = scene.container.is_some();
        let keep = |x: &Vec3| {
            let p = crate::Point3::from(*x);
            bodies.iter().enumerate().all(|(i, b)| {
                let d = b.signed_distance(0.0, &p);
                if i == 0 && has_container {
                    d <= -spacing
                } else {
                    d >= spacing
                }
            })
        };
        let fluid = FluidParticles::from_blocks(
            &fluid_cfg.blocks,
            spacing,
            fluid_cfg.density,
            &kernel,
            keep,
        );
        let boundary = BoundaryParticles::sample(&bodies, spacing, &kernel, 0.0);
        let n = fluid.len();
        let mut me = Self {
            kernel,
            fluid,
            boundary,
            bodies,
            spacing,
            gravity: Vec3::from(scene.gravity),
            pressure: scene.pressure.clone(),
            viscosity: scene.viscosity.clone(),
            stepping: Stepping {
                cfl: scene.time.cfl,
                dt_min: scene.time.dt_min,
                dt_max: scene.time.dt_max,
                fixed_dt: scene.time.dt,
                end: scene.time.end,
            },
            domain: (Vec3::from(scene.domain.min), Vec3::from(scene.domain.max)),
            grid: CellGrid::build(&[], 2.0 * spacing),
            fluid_lists: NeighborLists::default(),
            boundary_lists: NeighborLists::default(),
            pairs: PairCache::default(),
            density_ratio: vec![1.0; n],
            factor: vec![0.0; n],
            time: 0.0,
            step: 0,
            last_dt: None,
            refiner: refine::build(&scene.refinement, n, scene.seed),
            refine_volume: Vec::new(),
            walls_in_operators: scene.refinement.walls(),
        };
        me.update_neighborhoods();
        me
    }

    /// Ends the run at `end` (the last step lands on it), e.g. an earlier `--until`.
    pub fn stop_at(&mut self, end: Option<Real>) {
        self.stepping.end = end;
    }

    /// Simulated time, s.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// The fluid/boundary neighbourhood of the current state.
    pub fn neighborhood(&self) -> Neighborhood<'_> {
        Neighborhood {
            kernel: &self.kernel,
            x: &self.fluid.x,
            fluid: &self.fluid_lists,
            boundary_lists: &self.boundary_lists,
            boundary: &self.boundary,
            volume: self.fluid.volume(),
            pairs: &self.pairs,
        }
    }

    /// The grid over the fluid particles (valid after [`Self::update_neighborhoods`]).
    pub fn grid(&self) -> &CellGrid {
        &self.grid
    }

    /// Places moving bodies at the current time, sorts the fluid into cell order, rebuilds the
    /// neighbour lists, and computes the pairs' kernel gradients, densities and DFSPH factors.
    pub fn update_neighborhoods(&mut self) {
        self.boundary.place(&self.bodies, self.time, false);
        let h = self.kernel.support();
        let perm = cell_order(&self.fluid.x, h);
        self.fluid.permute(&perm);
        if let Some(r) = self.refiner.as_mut() {
            r.permute(&perm);
        }
        self.grid = CellGrid::build(&self.fluid.x, h);
        self.fluid_lists = NeighborLists::build(
            &self.fluid.x,
            &self.grid,
            &self.fluid.x,
            &self.grid,
            h,
            true,
        );
        self.boundary_lists = NeighborLists::build(
            &self.fluid.x,
            &self.grid,
            &self.boundary.x,
            &self.boundary.grid,
            h,
            false,
        );
        self.density_ratio.resize(self.fluid.len(), 0.0);
        self.factor.resize(self.fluid.len(), 0.0);
        self.pairs.update(
            &self.kernel,
            &self.fluid.x,
            self.fluid.volume(),
            &self.fluid_lists,
            &self.boundary_lists,
            &self.boundary,
            Densities {
                ratio: &mut self.density_ratio,
                factor: &mut self.factor,
            },
        );
        let rho0 = self.fluid.rest_density;
        self.fluid
            .density
            .par_iter_mut()
            .zip(self.density_ratio.par_iter())
            .for_each(|(d, r)| *d = r * rho0);
    }

    /// Advances one step from the state of the last [`Self::update_neighborhoods`].
    pub fn advance(&mut self) -> Result<StepStats, Instability> {
        let mut stats = StepStats::default();
        let FluidParticles {
            x,
            v,
            density,
            pressure,
            kappa,
            kappa_v,
            mass,
            rest_density,
        } = &mut self.fluid;
        let rho0 = *rest_density;
        let nb = Neighborhood {
            kernel: &self.kernel,
            x,
            fluid: &self.fluid_lists,
            boundary_lists: &self.boundary_lists,
            boundary: &self.boundary,
            volume: *mass / rho0,
            pairs: &self.pairs,
        };
        let settings = &self.pressure;
        let dfsph = settings.solver == PressureSolverKind::Dfsph;
        let bounds = |tolerance| Bounds {
            tolerance,
            min_iterations: settings.min_iterations,
            max_iterations: settings.max_iterations,
        };
        let mut accel =
            non_pressure_accelerations(&nb, density, rho0, v, self.gravity, &self.viscosity);
        let dt =
            step_size(&self.stepping, self.spacing, v, &accel).map_err(|(needed, speed)| {
                Instability::CflLimit {
                    time: self.time,
                    step: self.step,
                    needed,
                    dt_min: self.stepping.dt_min,
                    speed,
                }
            })?;
        let dt = self
            .stepping
            .end
            .map_or(dt, |end| crate::stepping::towards_end(dt, end - self.time));
        stats.dt = dt;
        // The warm starts read kappa dt^2 of the last step; a pressure that holds the fluid
        // against gravity keeps kappa, not kappa dt^2, when the step changes (the last steps
        // before the end time are up to halved), so carry kappa over.
        if let Some(last) = self.last_dt.filter(|&last| last != dt) {
            let scale = (dt / last).powi(2);
            kappa.par_iter_mut().for_each(|k| *k *= scale);
            kappa_v.par_iter_mut().for_each(|k| *k *= scale);
        }
        self.last_dt = Some(dt);
        if dfsph && settings.divergence_solver {
            let start = Instant::now();
            stats.divergence = dfsph::solve(
                &nb,
                Solve::Divergence,
                &self.density_ratio,
                &self.factor,
                v,
                kappa_v,
                dt,
                bounds(settings.divergence_tolerance),
            );
            stats.divergence_seconds = start.elapsed().as_secs_f64();
        }
        let walls = self.walls_in_operators;
        let refine_ctx = |volume| StepContext {
            ops: Operators { nb, volume, walls },
            dt,
            nu: self.viscosity.kinematic,
            spacing: self.spacing,
        };
        let volume = &mut self.refine_volume;
        if let Some(r) = self.refiner.as_mut() {
            let start = Instant::now();
            operators::volumes_into(*mass, density, volume);
            r.before_advection(&refine_ctx(volume), v, &mut accel);
            stats.refinement_seconds += start.elapsed().as_secs_f64();
        }
        v.par_iter_mut()
            .zip(accel.par_iter())
            .for_each(|(v, a)| *v += dt * a);
        if self.viscosity.xsph > 0.0 {
            forces::xsph(&nb, density, rho0, v, self.viscosity.xsph);
        }
        let pressure_bounds = bounds(settings.density_tolerance);
        let start = Instant::now();
        stats.pressure = if dfsph {
            dfsph::solve(
                &nb,
                Solve::Density,
                &self.density_ratio,
                &self.factor,
                v,
                kappa,
                dt,
                pressure_bounds,
            )
        } else {
            iisph::solve(
                &nb,
                &self.density_ratio,
                &self.factor,
                v,
                kappa,
                dt,
                pressure_bounds,
            )
        };
        stats.pressure_seconds = start.elapsed().as_secs_f64();
        if let Some(r) = self.refiner.as_mut() {
            let start = Instant::now();
            r.after_pressure(&refine_ctx(volume), v);
            stats.refinement_seconds += start.elapsed().as_secs_f64();
        }
        // p = kappa rho^2 / rho_0, with kappa the step's total stiffness (stored as kappa dt^2).
        pressure
            .par_iter_mut()
            .zip(kappa.par_iter().zip(density.par_iter()))
            .for_each(|(p, (k, rho))| *p = k / (dt * dt) * rho * rho / rho0);
        x.par_iter_mut()
            .zip(v.par_iter())
            .for_each(|(x, v)| *x += dt * v);
        self.time += dt;
        self.step += 1;
        self.check()?;
        Ok(stats)
    }

    /// The vorticity curl v of the current state, by the shared difference curl (with the
    /// walls when the refinement lets them into its operators).
    pub fn vorticity(&self) -> Vec<Vec3> {
        let volume = operators::volumes(self.fluid.mass, &self.fluid.density);
        Operators {
            nb: self.neighborhood(),
            volume: &volume,
            walls: self.walls_in_operators,
        }
        .curl(&self.fluid.v, WallField::Velocity)
    }

    /// Rotational kinetic energy held by the refinement (micropolar), J; zero otherwise.
    pub fn rotational_energy(&self) -> Real {
        self.refiner
            .as_ref()
            .map_or(0.0, |r| r.rotational_energy(self.fluid.mass))
    }

    /// Per-particle fields the refinement adds to output frames.
    pub fn refinement_fields(&self) -> Vec<(&'static str, &[Vec3])> {
        self.refiner.as_ref().map_or_else(Vec::new, |r| r.fields())
    }

    /// Stops the run on a non-finite state or a particle outside the domain.
    fn check(&self) -> Result<(), Instability> {
        let (lo, hi) = self.domain;
        let bad = self
            .fluid
            .x
            .par_iter()
            .zip(self.fluid.v.par_iter())
            .position_any(|(x, v)| {
                !(x.iter().all(|c| c.is_finite()) && v.iter().all(|c| c.is_finite()))
                    || (0..3).any(|a| x[a] < lo[a] || x[a] > hi[a])
            });
        let Some(i) = bad else { return Ok(()) };
        let (x, v) = (self.fluid.x[i], self.fluid.v[i]);
        Err(if !x.iter().all(|c| c.is_finite()) {
            Instability::NotFinite {
                time: self.time,
                step: self.step,
                what: "position is not finite",
                particle: i,
            }
        } else if !v.iter().all(|c| c.is_finite()) {
            Instability::NotFinite {
                time: self.time,
                step: self.step,
                what: "velocity is not finite",
                particle: i,
            }
        } else {
            Instability::Escaped {
                time: self.time,
                step: self.step,
                particle: i,
                position: x,
            }
        })
    }

    /// Bytes held by the solver's particle data, grids and neighbour lists.
    pub fn memory_bytes(&self) -> usize {
        self.fluid.memory_bytes()
            + self.boundary.memory_bytes()
            + self.grid.memory_bytes()
            + self.fluid_lists.memory_bytes()
            + self.boundary_lists.memory_bytes()
            + self.pairs.memory_bytes()
            + (self.density_ratio.capacity()
                + self.factor.capacity()
                + self.refine_volume.capacity())
                * std::mem::size_of::<Real>()
    }
}

/// The CFL step size (Bender & Koschier: dt = cfl * spacing / max |v + a dt_max|), or the
/// fixed step. Err gives the step the CFL rule needs and the speed, when below `dt_min`.
fn step_size(
    s: &Stepping,
    spacing: Real,
    v: &[Vec3],
    accel: &[Vec3],
) -> Result<Real, (Real, Real)> {
    if let Some(dt) = s.fixed_dt {
        return Ok(dt);
    }
    let speed = v
        .par_iter()
        .zip(accel.par_iter())
        .map(|(v, a)| (v + a * s.dt_max).norm())
        .reduce(|| 0.0, Real::max);
    let needed = if speed > 0.0 {
        s.cfl * spacing / speed
    } else {
        s.dt_max
    };
    if needed < s.dt_min {
        return Err((needed, speed));
    }
    Ok(needed.min(s.dt_max))
}

/// Gravity plus viscosity, per fluid particle.
fn non_pressure_accelerations(
    nb: &Neighborhood,
    density: &[Real],
    rest_density: Real,
    v: &[Vec3],
    gravity: Vec3,
    viscosity: &Viscosity,
) -> Vec<Vec3> {
    let viscous = viscosity.kinematic > 0.0 || viscosity.boundary > 0.0;
    (0..v.len())
        .into_par_iter()
        .map(|i| {
            if viscous {
                gravity
                    + forces::viscous_acceleration(
                        nb,
                        density,
                        rest_density,
                        v,
                        i,
                        viscosity.kinematic,
                        viscosity.boundary,
                    )
            } else {
                gravity
            }
        })
        .collect()
}
