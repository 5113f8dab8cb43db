//! One SPH fluid with its boundaries, stepped in time.
//!
//! A step is split so that a driver can measure and write the state between its parts and step
//! several solvers on one clock: [`SphSolver::update_neighborhoods`] sorts the particles,
//! rebuilds the neighbour lists and computes densities at the current time;
//! [`SphSolver::stable_dt`] computes the non-pressure forces and the CFL step they allow;
//! [`SphSolver::advance`] then runs the divergence solve (DFSPH), the step hooks, the pressure
//! solve and the position update over the `dt` the driver chose, following Bender & Koschier
//! 2017, Algorithm 1.

use super::boundary::BoundaryParticles;
use super::dfsph::SolveResult;
use super::energy_bound::EnergyBound;
use super::fluid::FluidParticles;
use super::forces;
use super::hooks::StepHook;
use super::kernel::CubicSpline;
use super::lost::{self, LostParticles};
use super::neighborhood::Neighborhood;
use super::neighbors::{cell_order_and_codes, CellGrid, NeighborLists};
use super::open::OpenBoundaries;
use super::operators::{self, Operators, WallField};
use super::pair_cache::{Densities, PairCache};
use super::params::{DomainSide, PressureSolverKind, SphParams};
use super::ramp::Ramp;
use crate::geometry::RigidBody;
use crate::stepping::{towards_end, StepLimits};
use crate::{Point3, Real, Vec3};
use rayon::prelude::*;

mod persist;
mod step;

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
        "unstable at t = {time:.6} s (step {step}): fluid particle {particle} went through a \
         wall: it is inside a solid beyond the domain's {} side, at ({:.4}, {:.4}, {:.4}) m",
        side.name(), position.x, position.y, position.z
    )]
    Escaped {
        time: Real,
        step: u64,
        particle: usize,
        position: Vec3,
        side: DomainSide,
    },
    #[error(
        "unstable at t = {time:.6} s (step {step}): {lost} fluid particles have left the domain \
         through open sides ({sides}; the last at ({:.4}, {:.4}, {:.4}) m), more than \
         fluid.lost_fraction = {fraction} of the {particles} left",
        last.x, last.y, last.z
    )]
    Lost {
        time: Real,
        step: u64,
        lost: u64,
        /// The count through each side, in words.
        sides: String,
        last: Vec3,
        fraction: Real,
        particles: usize,
    },
    #[error(
        "unstable at t = {time:.6} s (step {step}): the fluid's mean kinetic energy, {energy:.4} \
         J/kg, is above {bound:.4} J/kg, a hundred times what its fastest source and a fall \
         across the domain could give (fastest particle {fastest:.3} m/s)"
    )]
    Energy {
        time: Real,
        step: u64,
        energy: Real,
        bound: Real,
        fastest: Real,
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

/// What one step did.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepStats {
    pub dt: Real,
    pub divergence: SolveResult,
    pub pressure: SolveResult,
    /// Wall-clock seconds spent in the step hooks (the turbulence refinement).
    pub refinement_seconds: Real,
    /// Wall-clock seconds spent in the divergence solve (DFSPH).
    pub divergence_seconds: Real,
    /// Wall-clock seconds spent in the pressure (density) solve.
    pub pressure_seconds: Real,
    /// Wall-clock seconds spent in the open boundaries.
    pub open_seconds: Real,
    /// Wall-clock seconds of the whole step.
    pub step_seconds: Real,
    /// Fluid particles lost through open sides of the domain so far, this step's included.
    pub lost: u64,
}

/// A part of an SPH step, in the order [`SphSolver::advance`] runs them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    Divergence,
    /// The refinement's step hooks, each under its own name.
    Hooks,
    Forces,
    Pressure,
    Advect,
    OpenBoundaries,
}

impl Part {
    /// Its name in the plan and in [`SphSolver::ran`] (the hooks give their own).
    fn name(self) -> &'static str {
        match self {
            Part::Divergence => "divergence",
            Part::Hooks => "refinement",
            Part::Forces => "forces",
            Part::Pressure => "pressure",
            Part::Advect => "advect",
            Part::OpenBoundaries => "open boundaries",
        }
    }
}

/// The SPH fluid, its boundary samples, and the settings that drive it.
pub struct SphSolver {
    pub kernel: CubicSpline,
    pub fluid: FluidParticles,
    pub boundary: BoundaryParticles,
    pub bodies: Vec<RigidBody>,
    pub spacing: Real,
    params: SphParams,
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
    /// The non-pressure accelerations [`Self::stable_dt`] computed for the current state, for
    /// the [`Self::advance`] that follows it.
    pending_accel: Option<Vec<Vec3>>,
    /// Work attached to the step (the turbulence refinement, vortex synthesis), in order.
    hooks: Vec<Box<dyn StepHook>>,
    /// Per fluid particle m / rho, the volume of the hooks' operators (kept across steps for
    /// its memory).
    refine_volume: Vec<Real>,
    /// The parts the last [`Self::advance`] ran, in order (named as [`Self::describe`] names
    /// them).
    ran: Vec<&'static str>,
    /// Inflow emitters and outflow sides.
    open: OpenBoundaries,
    /// Per body, the viscosity Eq. 4 applies over its samples: its `wall_viscosity` times
    /// [`super::boundary::no_slip_gain`]; empty when every wall is free-slip.
    wall_viscosity: Vec<Real>,
    /// The smooth start (none when `params.ramp` is 0).
    ramp: Ramp,
    /// The particles that left through open sides.
    lost: LostParticles,
    /// The energy stop.
    energy: EnergyBound,
}

impl SphSolver {
    /// Builds the fluid of `params` among `bodies` (the container first, when
    /// `params.container`), and its neighbourhood at t = 0.
    pub fn new(params: &SphParams, bodies: Vec<RigidBody>) -> Self {
        Self::with_hooks(params, bodies, |_| Vec::new())
    }

    /// [`Self::new`] with the step hooks `hooks(n)` makes for the n fluid particles, attached
    /// before the first neighbourhood sort, so that per-particle state they draw at random
    /// follows the particles from the start.
    pub fn with_hooks(
        params: &SphParams,
        bodies: Vec<RigidBody>,
        hooks: impl FnOnce(usize) -> Vec<Box<dyn StepHook>>,
    ) -> Self {
        let spacing = params.spacing;
        let kernel = CubicSpline::new(2.0 * spacing);
        // The walls' mirror layer (see `boundary`) completes the lattice from half a spacing
        // off a surface: sites closer than that, or inside an obstacle, stay empty.
        let keep = |x: &Vec3| {
            super::walls::wall_distance(&bodies, params.container, 0.0, &crate::Point3::from(*x))
                >= (0.5 - 1e-6) * spacing
        };
        let mut fluid = FluidParticles::from_blocks(
            &params.blocks,
            spacing,
            params.rest_density,
            &kernel,
            keep,
        );
        let v0 = params
            .blocks
            .first()
            .map_or(Vec3::zeros(), |b| Vec3::from(b.velocity));
        let ramp = Ramp::new(params.ramp, v0);
        if params.ramp > 0.0 {
            fluid.v.fill(Vec3::zeros());
        }
        let mut open = OpenBoundaries::new(
            &params.inflows,
            &params.outflows,
            params.domain,
            spacing,
            keep,
        );
        open.prime(&mut fluid, ramp.factor(0.0));
        let source = params
            .blocks
            .iter()
            .map(|b| b.velocity)
            .chain(params.inflows.iter().map(|i| i.velocity))
            .map(|v| Vec3::from(v).norm())
            .chain(bodies.iter().map(RigidBody::fastest_speed))
            .fold(0.0, Real::max);
        let energy = EnergyBound::new(source, params.gravity, params.domain);
        let boundary = BoundaryParticles::sample(&bodies, params.container, spacing, &kernel, 0.0);
        // One value per body, so the step bound, the plan and the forces read the same walls:
        // a body `params.wall_viscosity` does not cover takes `viscosity.boundary`, as a
        // scene's body without its own value does.
        let mut params = params.clone();
        let given = std::mem::take(&mut params.wall_viscosity);
        params.wall_viscosity = (0..bodies.len())
            .map(|b| given.get(b).copied().unwrap_or(params.viscosity.boundary))
            .collect();
        let no_slip = super::boundary::no_slip_gain(&kernel, spacing);
        let walls = &params.wall_viscosity;
        let wall_viscosity = if walls.iter().any(|&w| w > 0.0) {
            walls.iter().map(|w| no_slip * w).collect()
        } else {
            Vec::new()
        };
        let n = fluid.len();
        let mut me = Self {
            kernel,
            fluid,
            boundary,
            bodies,
            spacing,
            params,
            grid: CellGrid::build(&[], 2.0 * spacing),
            fluid_lists: NeighborLists::default(),
            boundary_lists: NeighborLists::default(),
            pairs: PairCache::default(),
            density_ratio: vec![1.0; n],
            factor: vec![0.0; n],
            time: 0.0,
            step: 0,
            last_dt: None,
            pending_accel: None,
            hooks: hooks(n),
            refine_volume: Vec::new(),
            ran: Vec::new(),
            open,
            wall_viscosity,
            ramp,
            lost: LostParticles::default(),
            energy,
        };
        me.update_neighborhoods();
        me
    }

    /// Simulated time, s.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// Whether body 0 is the container the fluid sits in.
    pub fn has_container(&self) -> bool {
        self.params.container
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

    /// rho / rho_0 per fluid particle, from the last neighbourhood update.
    pub fn density_ratios(&self) -> &[Real] {
        &self.density_ratio
    }

    /// The DFSPH factors of the last neighbourhood update (see [`super::pair_cache`]).
    pub fn factors(&self) -> &[Real] {
        &self.factor
    }

    /// The inflow emitters and outflow sides.
    pub fn open_boundaries(&self) -> &OpenBoundaries {
        &self.open
    }

    /// The grid over the fluid particles (valid after [`Self::update_neighborhoods`]).
    pub fn grid(&self) -> &CellGrid {
        &self.grid
    }

    /// Places moving bodies at the current time, sorts the fluid into cell order, rebuilds the
    /// neighbour lists, and computes the pairs' kernel gradients, densities and DFSPH factors.
    pub fn update_neighborhoods(&mut self) {
        self.pending_accel = None;
        self.boundary.place(&self.bodies, self.time, false);
        let h = self.kernel.support();
        let (perm, codes) = cell_order_and_codes(&self.fluid.x, h);
        self.fluid.permute(&perm);
        for hook in &mut self.hooks {
            hook.permute(&perm);
        }
        self.grid = CellGrid::from_codes(&self.fluid.x, &codes, h);
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

    /// One step at the solver's own stable step, the last ones shortened to land on `end`
    /// ([`towards_end`]), then the neighbourhood update: how a driver of this one solver steps.
    pub fn step(&mut self, end: Option<Real>) -> Result<StepStats, Instability> {
        let dt = self.stable_dt()?;
        let dt = end.map_or(dt, |end| towards_end(dt, end - self.time));
        let stats = self.advance(dt)?;
        self.update_neighborhoods();
        Ok(stats)
    }

    /// The largest stable step of the current state: the CFL rule on v + a dt_max with the
    /// non-pressure accelerations a (which the following [`Self::advance`] applies), or the
    /// fixed step. Errs when the CFL rule needs less than `dt_min`.
    pub fn stable_dt(&mut self) -> Result<Real, Instability> {
        let accel = match self.pending_accel.take() {
            Some(accel) => accel,
            None => self.non_pressure_accelerations(),
        };
        let limits = &self.params.limits;
        let p = &self.params;
        let viscous =
            forces::viscous_step_limit(self.spacing, p.viscosity.kinematic, &p.wall_viscosity);
        let dt = step_size(limits, viscous, self.spacing, &self.fluid.v, &accel).map_err(
            |(needed, speed)| Instability::CflLimit {
                time: self.time,
                step: self.step,
                needed,
                dt_min: limits.dt_min,
                speed,
            },
        )?;
        self.pending_accel = Some(accel);
        Ok(dt)
    }

    /// Fluid particles lost through open sides of the domain so far.
    pub fn lost_particles(&self) -> u64 {
        self.lost.total()
    }

    /// Counts particle `i`, lost through `side`; the first loss of a run is a warning.
    fn lose(&mut self, i: usize, side: DomainSide) {
        let x = self.fluid.x[i];
        if self.lost.total() == 0 {
            tracing::warn!(
                "t = {:.4} s: a fluid particle left the domain through its open {} side at \
                 ({:.4}, {:.4}, {:.4}) m; lost particles are removed and counted \
                 (metrics.csv: lost_particles), and the run stops once they exceed \
                 fluid.lost_fraction = {} of the fluid",
                self.time,
                side.name(),
                x.x,
                x.y,
                x.z,
                self.params.lost_fraction
            );
        }
        self.lost.add(side, x);
    }

    /// One line on the fluid as built, for `eddy run --plan`.
    pub fn summary(&self) -> String {
        let moving = match self.bodies.iter().filter(|b| b.is_moving()).count() {
            0 => "all still".to_string(),
            n => format!("{n} moving: re-placed every step"),
        };
        format!(
            "SPH fluid of {} particles at {} m, {} Akinci boundary samples on {} bodies ({moving})",
            self.fluid.len(),
            self.spacing,
            self.boundary.len(),
            self.bodies.len()
        )
    }

    /// The parts [`Self::advance`] runs, in order, from the settings and hooks: the one list
    /// the step branches on and [`Self::describe`] reads.
    fn parts(&self) -> Vec<Part> {
        let settings = &self.params.pressure;
        let mut parts = Vec::new();
        if settings.solver == PressureSolverKind::Dfsph && settings.divergence_solver {
            parts.push(Part::Divergence);
        }
        if !self.hooks.is_empty() {
            parts.push(Part::Hooks);
        }
        parts.extend([Part::Forces, Part::Pressure, Part::Advect]);
        if !self.open.is_empty() {
            parts.push(Part::OpenBoundaries);
        }
        parts
    }

    /// The parts [`Self::advance`] runs, in order, for `eddy run --plan`: (part, what it does
    /// here), each hook by its own name; [`Self::ran`] names the parts a step did run the same
    /// way.
    pub fn describe(&self) -> Vec<(&'static str, String)> {
        self.parts()
            .into_iter()
            .flat_map(|part| self.describe_part(part))
            .collect()
    }

    /// What `part` does here, under its name; the hooks, each under its own, describe
    /// themselves.
    fn describe_part(&self, part: Part) -> Vec<(&'static str, String)> {
        let p = &self.params;
        let settings = &p.pressure;
        let dfsph = settings.solver == PressureSolverKind::Dfsph;
        let signed = if settings.signed {
            format!(
                " (signed pressure, conjugate gradients; outflows held at {} Pa)",
                settings.ambient
            )
        } else {
            String::new()
        };
        let text = match part {
            Part::Hooks => {
                return self
                    .hooks
                    .iter()
                    .map(|h| (h.name(), h.describe()))
                    .collect()
            }
            Part::Divergence => format!(
                "DFSPH divergence solve{}, tolerance {} ({} to {} iterations)",
                signed,
                settings.divergence_tolerance,
                settings.divergence_min_iterations(),
                settings.max_iterations,
            ),
            Part::Forces => {
                let v = &p.viscosity;
                let mut forces = format!("gravity {:?}", p.gravity.as_slice());
                let walls = &p.wall_viscosity;
                if let Some(limit) = forces::viscous_step_limit(self.spacing, v.kinematic, walls) {
                    let walls = match walls.split_first() {
                        Some((first, rest)) if rest.iter().any(|w| w != first) => {
                            format!("{walls:?} by body")
                        }
                        Some((first, _)) => first.to_string(),
                        None => "none".into(),
                    };
                    forces += &format!(
                        ", Laplacian viscosity (Liu et al. 2021 Eq. 4) nu = {}, walls {walls} \
                         (explicit: steps of at most {limit:.3e} s)",
                        v.kinematic
                    );
                }
                if v.xsph > 0.0 {
                    forces += &format!(", XSPH {}", v.xsph);
                }
                if let Some(ramp) = self.ramp.describe() {
                    forces += &format!("; {ramp}");
                }
                forces
            }
            Part::Pressure => format!(
                "{} density solve{}, tolerance {} ({} to {} iterations){}",
                if dfsph { "DFSPH" } else { "IISPH" },
                signed,
                settings.density_tolerance,
                settings.min_iterations,
                settings.max_iterations,
                if !dfsph || settings.second_order {
                    ", density predicted to second order in dt"
                } else {
                    ""
                }
            ),
            Part::Advect => "positions, then NaN and domain checks".into(),
            Part::OpenBoundaries => format!(
                "{}; inflow buffers move at their velocity through the solves",
                self.open.describe()
            ),
        };
        vec![(part.name(), text)]
    }

    /// The parts the last [`Self::advance`] ran, in order.
    pub fn ran(&self) -> &[&'static str] {
        &self.ran
    }

    /// One line on [`Self::update_neighborhoods`], for `eddy run --plan`.
    pub fn describe_neighbourhood(&self) -> String {
        format!(
            "z-order sort and compact hashed grid (cell = support = {} m), densities and DFSPH \
             factors",
            self.kernel.support()
        )
    }

    /// The vorticity curl v of the current state, by the shared difference curl (with the
    /// walls when a hook lets them into its operators).
    pub fn vorticity(&self) -> Vec<Vec3> {
        self.vorticity_on(None)
    }

    /// [`Self::vorticity`] only at the particles where `only` holds (zero elsewhere).
    pub fn vorticity_on(&self, only: Option<&[bool]>) -> Vec<Vec3> {
        let volume = operators::volumes(self.fluid.mass, &self.fluid.density);
        Operators {
            nb: self.neighborhood(),
            volume: &volume,
            walls: self.hooks.iter().any(|h| h.walls()),
        }
        .curl_on(&self.fluid.v, WallField::Velocity, only)
    }

    /// Rotational kinetic energy held by the hooks (a micropolar refinement), J.
    pub fn rotational_energy(&self) -> Real {
        self.hooks
            .iter()
            .fold(0.0, |e, h| e + h.rotational_energy(self.fluid.mass))
    }

    /// Per-particle fields the hooks add to output frames.
    pub fn refinement_fields(&self) -> Vec<(&'static str, &[Vec3])> {
        self.hooks.iter().flat_map(|h| h.fields()).collect()
    }

    /// Gravity plus viscosity on the current state, per fluid particle.
    pub fn non_pressure_accelerations(&self) -> Vec<Vec3> {
        non_pressure_accelerations(
            &self.neighborhood(),
            &self.fluid.density,
            self.fluid.rest_density,
            &self.fluid.v,
            self.params.gravity,
            self.params.viscosity.kinematic,
            &self.wall_viscosity,
        )
    }

    /// After the positions moved, of the particles the open boundaries keep (`keep`; all
    /// without it): the run stops on a non-finite state and on a particle beyond the domain
    /// that lies inside a solid, having gone through a wall ([`super::lost`]); the others
    /// beyond it are returned, each with its side, for removal. Beyond means by more than the
    /// wall layer's depth: a container flush with the domain lets particles touch its walls.
    fn leaving(&self, keep: Option<&[bool]>) -> Result<Vec<(usize, DomainSide)>, Instability> {
        let margin = super::boundary::MIRROR_DEPTH * self.spacing;
        let domain = self.params.domain;
        let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
        let (x, v) = (&self.fluid.x, &self.fluid.v);
        let flagged: Vec<usize> = (0..x.len())
            .into_par_iter()
            .filter(|&i| {
                keep.is_none_or(|k| k[i])
                    && (!finite(&x[i])
                        || !finite(&v[i])
                        || lost::beyond(&x[i], domain, margin).is_some())
            })
            .collect();
        let (time, step) = (self.time, self.step);
        let not_finite = |what, particle| Instability::NotFinite {
            time,
            step,
            what,
            particle,
        };
        if let Some(&i) = flagged.iter().find(|&&i| !finite(&x[i])) {
            return Err(not_finite("position is not finite", i));
        }
        if let Some(&i) = flagged.iter().find(|&&i| !finite(&v[i])) {
            return Err(not_finite("velocity is not finite", i));
        }
        flagged
            .into_iter()
            .map(|i| {
                let side = lost::beyond(&x[i], domain, margin).expect("flagged outside");
                if self.wall_distance(&Point3::from(x[i])) < 0.0 {
                    return Err(Instability::Escaped {
                        time,
                        step,
                        particle: i,
                        position: x[i],
                        side,
                    });
                }
                Ok((i, side))
            })
            .collect()
    }

    /// Stops the run once the lost particles exceed `lost_fraction` of the fluid left.
    fn check_losses(&self) -> Result<(), Instability> {
        let (lost, particles) = (self.lost.total(), self.fluid.len());
        let fraction = self.params.lost_fraction;
        if lost as Real <= fraction * particles as Real {
            return Ok(());
        }
        Err(Instability::Lost {
            time: self.time,
            step: self.step,
            lost,
            sides: self.lost.by_side(),
            last: self.lost.last().unwrap_or_default(),
            fraction,
            particles,
        })
    }

    /// Stops the run when the fluid's mean kinetic energy per unit mass exceeds `bound`
    /// ([`super::energy_bound`]).
    fn check_energy(&self, bound: Real) -> Result<(), Instability> {
        let v = &self.fluid.v;
        if v.is_empty() {
            return Ok(());
        }
        let energy = crate::parallel::sum_by(v, |v| v.norm_squared()) / (2.0 * v.len() as Real);
        if !EnergyBound::exceeded(bound, energy) {
            return Ok(());
        }
        Err(Instability::Energy {
            time: self.time,
            step: self.step,
            energy,
            bound,
            fastest: max_speed(v),
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

/// The CFL step size (Bender & Koschier: dt = cfl * spacing / max |v + a dt_max|), capped by
/// `dt_max` and the explicit viscosity's bound `viscous` ([`forces::viscous_step_limit`]; the
/// scene refuses a `dt_min` above it), or the fixed step. Err gives the step the CFL rule needs
/// and the speed, when below `dt_min`.
fn step_size(
    s: &StepLimits,
    viscous: Option<Real>,
    spacing: Real,
    v: &[Vec3],
    accel: &[Vec3],
) -> Result<Real, (Real, Real)> {
    if let Some(dt) = s.fixed_dt {
        return Ok(dt);
    }
    let dt_max = viscous.map_or(s.dt_max, |limit| limit.min(s.dt_max));
    let speed = v
        .par_iter()
        .zip(accel.par_iter())
        .map(|(v, a)| (v + a * dt_max).norm())
        .reduce(|| 0.0, Real::max);
    let needed = if speed > 0.0 {
        s.cfl * spacing / speed
    } else {
        dt_max
    };
    if needed < s.dt_min {
        return Err((needed, speed));
    }
    Ok(needed.min(dt_max))
}

/// The largest |v|.
fn max_speed(v: &[Vec3]) -> Real {
    v.par_iter().map(|v| v.norm()).reduce(|| 0.0, Real::max)
}

/// Gravity plus viscosity, per fluid particle.
fn non_pressure_accelerations(
    nb: &Neighborhood,
    density: &[Real],
    rest_density: Real,
    v: &[Vec3],
    gravity: Vec3,
    nu: Real,
    walls: &[Real],
) -> Vec<Vec3> {
    let viscous = nu > 0.0 || !walls.is_empty();
    (0..v.len())
        .into_par_iter()
        .map(|i| {
            if viscous {
                gravity + forces::viscous_acceleration(nb, density, rest_density, v, i, nu, walls)
            } else {
                gravity
            }
        })
        .collect()
}
