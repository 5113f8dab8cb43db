//! One step of the MAC-grid fluid: advection, forces, sources, implicit viscosity and pressure
//! projection, in the order of Stam's stable fluids with the boundary conditions re-imposed
//! before each solve.

use std::time::Instant;

use ndarray::{Array3, ArrayView3, Zip};

use super::advect::{advect, advect_velocity, advect_velocity_into};
use super::average::RunningAverage;
use super::boundary::Boundaries;
use super::diffusion::DiffusionSystem;
use super::forces::{add_cell_acceleration, confinement};
use super::mac::MacGrid;
use super::params::{GridParams, ViscosityScheme};
use super::poisson::{CellKind, FaceFractions, PoissonSystem, SolveError};
use super::project::{max_divergence, project, subtract_gradient};
use super::smoke::SmokeState;
use super::viscosity::diffuse_component;
use crate::geometry::{GeometryError, RigidBody};
use crate::parallel::BLOCK;
use crate::stepping::towards_end;
use crate::{Real, Vec3};
use rayon::prelude::*;

/// Face layers inside static obstacles that advection sees extrapolated fluid velocity on:
/// two cover the trilinear stencil of a departure point up to a cell inside a wall.
const EXTRAPOLATION_LAYERS: usize = 2;

/// Largest CFL number (u_max dt / dx) a step may reach before the run is called unstable.
const CFL_BLOWUP: Real = 50.0;

/// Why the grid solver could not be built or could not go on.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    #[error(
        "obstacle '{body}' covers every cell of the grid: the domain ({domain:?} m) is smaller \
         than the obstacle"
    )]
    NoFluid { body: String, domain: [Real; 3] },
    #[error("grid setting out of range: {0}")]
    Setting(String),
    #[error("static flow: {0}")]
    StaticFlow(String),
    #[error("{what} solve failed at t = {time:.6} s (step {step}): {source}")]
    Solve {
        what: &'static str,
        time: Real,
        step: u64,
        #[source]
        source: SolveError,
    },
    #[error(
        "the grid flow went unstable at t = {time:.6} s (step {step}): {what}; lower time.cfl \
         or time.dt_max"
    )]
    Unstable { time: Real, step: u64, what: String },
}

/// What one step did, with the wall time of its parts.
#[derive(Debug, Clone, Copy, Default)]
pub struct GridStepStats {
    pub dt: Real,
    /// u_max dt / dx.
    pub cfl: Real,
    pub pressure_iterations: usize,
    pub pressure_residual: Real,
    pub viscosity_iterations: usize,
    /// Largest |div u| over fluid cells after the projection, 1/s.
    pub max_divergence: Real,
    /// |u^{n+1} - u^n| / (|u^n| dt), 1/s.
    pub change_rate: Real,
    pub advect_seconds: f64,
    pub project_seconds: f64,
    pub total_seconds: f64,
}

/// A part of a grid step, in the order [`GridSolver::advance`] runs them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    Obstacles,
    Inflow,
    Advect,
    Forces,
    StaticFlow,
    Viscosity,
    Pressure,
    Average,
}

impl Part {
    /// Its name in the plan and in [`GridSolver::ran`].
    fn name(self) -> &'static str {
        match self {
            Part::Obstacles => "obstacles",
            Part::Inflow => "inflow",
            Part::Advect => "advect",
            Part::Forces => "forces",
            Part::StaticFlow => "static flow",
            Part::Viscosity => "viscosity",
            Part::Pressure => "pressure",
            Part::Average => "average",
        }
    }
}

/// The MAC-grid fluid of a scene.
pub struct GridSolver {
    pub mac: MacGrid,
    pub bounds: Boundaries,
    pub bodies: Vec<RigidBody>,
    /// Pressure of the last projection, Pa (with the scene's `grid.density`).
    pub pressure: Array3<Real>,
    pub smoke: Option<SmokeState>,
    pub average: Option<(Real, RunningAverage)>,
    system: PoissonSystem,
    /// The cell kinds `system` was built for: a moving obstacle whose cells stay the same
    /// (a sphere spinning about its centre) keeps its hierarchy.
    system_cells: Array3<CellKind>,
    /// The open fractions `system` was built for (cut cells).
    system_fractions: Option<FaceFractions>,
    /// Each velocity component's viscosity system of the last step.
    diffusion: [Option<DiffusionSystem>; 3],
    /// p dt / (rho dx) of the last projection: the next solve's warm start.
    pub(super) scaled_pressure: Array3<Real>,
    /// The advected velocity of a step, swapped with `mac.u` (no allocation per step).
    advected: [Array3<Real>; 3],
    /// The velocity at the start of a step, for [`GridStepStats::change_rate`].
    before: [Array3<Real>; 3],
    params: GridParams,
    /// The stored face velocities of the static flow-field mode (Pfaff et al. 2009, Figure 11),
    /// restored at the end of every step; `None` for a solved flow.
    frozen: Option<[Array3<Real>; 3]>,
    /// The coupled liquid, a moving solid to this grid (see [`Self::set_liquid`]).
    pub(super) liquid: Option<super::liquid::Liquid>,
    /// The time the boundaries were last placed for by [`Self::set_liquid`], so the step
    /// that follows does not place moving obstacles again.
    pub(super) bounds_time: Option<Real>,
    /// Face velocity changes from outside, applied in the next step's forces.
    pub(super) impulses: Option<[Array3<Real>; 3]>,
    /// Against gravity (y without gravity): the direction smoke rises.
    up: Vec3,
    /// The parts the last [`Self::advance`] ran, in order (named as [`Self::describe`] names
    /// them).
    ran: Vec<&'static str>,
    pub(super) time: Real,
    pub(super) step: u64,
}

impl GridSolver {
    /// Builds the grid of `params` with its obstacles `bodies`, at rest or at the initial
    /// velocity.
    pub fn new(params: &GridParams, bodies: Vec<RigidBody>) -> Result<Self, GridError> {
        let sides = params.sides.clone();
        let periodic = std::array::from_fn(|a| sides[a][0] == super::params::GridSide::Periodic);
        let mut mac = MacGrid::new(params.resolution, params.dx, params.origin, periodic);
        for (a, u) in mac.u.iter_mut().enumerate() {
            u.fill(params.initial_velocity[a]);
        }
        let surface = (params.container, params.obstacle_surface);
        let bounds = Boundaries::new(&mac, sides, &bodies, 0.0, surface, None);
        if bounds.fluid_cells() == 0 {
            let body = bodies
                .first()
                .map(|b| b.name().to_owned())
                .unwrap_or_default();
            let domain = std::array::from_fn(|a| params.resolution[a] as Real * params.dx);
            return Err(GridError::NoFluid { body, domain });
        }
        bounds.apply(&mut mac);
        if !(1..=2).contains(&params.smoke_refinement) {
            return Err(GridError::Setting(format!(
                "smoke refinement {} (1 or 2)",
                params.smoke_refinement
            )));
        }
        let smoke = params
            .smoke
            .as_ref()
            .map(|s| SmokeState::new(&mac, s, params.smoke_refinement, &bodies, params.container))
            .transpose()?;
        let system_cells = bounds.cell_kinds();
        let system_fractions = bounds.face_fractions(mac.dims);
        let system = PoissonSystem::with_fractions(
            &system_cells,
            bounds.pressure_boundary(),
            system_fractions.clone(),
        );
        let average = params
            .average_from
            .map(|start| (start, RunningAverage::new(&mac)));
        Ok(Self {
            pressure: Array3::zeros(mac.dims),
            scaled_pressure: Array3::zeros(mac.dims),
            advected: mac.u.clone(),
            before: mac.u.clone(),
            mac,
            bounds,
            bodies,
            smoke,
            average,
            system,
            system_cells,
            system_fractions,
            diffusion: Default::default(),
            up: up_of(params.gravity),
            ran: Vec::new(),
            params: params.clone(),
            frozen: None,
            liquid: None,
            impulses: None,
            bounds_time: None,
            time: 0.0,
            step: 0,
        })
    }

    /// Simulated time, s.
    pub fn time(&self) -> Real {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// Sets the face velocities from a function of position (then the boundary conditions) and
    /// projects, so the field starts divergence-free.
    pub fn set_velocity(&mut self, f: impl Fn(&Vec3) -> Vec3 + Sync) -> Result<(), GridError> {
        for a in 0..3 {
            let stagger = self.mac.face_stagger(a);
            let (dx, origin) = (self.mac.dx, self.mac.origin);
            Zip::indexed(&mut self.mac.u[a]).par_for_each(|(i, j, k), u| {
                let g = stagger.position([i, j, k]);
                *u = f(&(origin + Vec3::new(g[0], g[1], g[2]) * dx))[a];
            });
        }
        self.bounds.apply(&mut self.mac);
        self.project(1.0)?;
        if self.incremental_pressure() {
            // That projection's potential is no pressure to carry into the next step.
            self.pressure.fill(0.0);
        }
        Ok(())
    }

    /// Sets the face velocities (x, y and z faces, of the shapes of `mac.u`), then the boundary
    /// conditions, as a scene's `initial_velocity` is set; the next step projects them. Used to
    /// edit a flow between steps (the Python bindings).
    pub fn set_faces(&mut self, faces: [ArrayView3<Real>; 3]) -> Result<(), GridError> {
        for (a, f) in faces.iter().enumerate() {
            let want = self.mac.u[a].shape();
            if f.shape() != want {
                return Err(GridError::Setting(format!(
                    "{} faces of shape {:?}, the grid has {want:?}",
                    ["x", "y", "z"][a],
                    f.shape()
                )));
            }
            if f.iter().any(|v| !v.is_finite()) {
                let axis = ["x", "y", "z"][a];
                return Err(GridError::Setting(format!(
                    "{axis} faces: values must be finite"
                )));
            }
        }
        for (u, f) in self.mac.u.iter_mut().zip(faces) {
            u.assign(&f);
        }
        self.bounds.apply(&mut self.mac);
        Ok(())
    }

    /// Sets the relative residual of the pressure and viscosity solves from the next step on
    /// (the scene's `grid.pressure_tolerance` until then): a run can stabilise at a loose
    /// tolerance and measure at a tight one.
    pub fn set_solver_tolerance(&mut self, tolerance: Real) {
        self.params.pressure.tolerance = tolerance;
    }

    /// One step at the solver's own stable step, the last ones shortened to land on `end`
    /// ([`towards_end`]): how a driver of this one solver steps.
    pub fn step(&mut self, end: Option<Real>) -> Result<GridStepStats, GridError> {
        let dt = self.stable_dt()?;
        self.advance(end.map_or(dt, |end| towards_end(dt, end - self.time)))
    }

    /// Advances by `dt`, which should not exceed [`Self::stable_dt`].
    pub fn advance(&mut self, dt: Real) -> Result<GridStepStats, GridError> {
        let started = Instant::now();
        let speed = self.cfl_speed();
        let mut stats = GridStepStats {
            dt,
            cfl: speed * dt / self.mac.dx,
            ..Default::default()
        };
        for (before, u) in self.before.iter_mut().zip(&self.mac.u) {
            before.clone_from(u);
        }
        self.ran.clear();
        let parts = self.parts();
        if parts.contains(&Part::Obstacles) {
            self.ran.push(Part::Obstacles.name());
            if self.bounds_time.take() != Some(self.time + dt) {
                self.rebuild_boundaries(self.time + dt);
            }
        }
        if let Some(modes) = &self.params.inflow_turbulence {
            self.ran.push(Part::Inflow.name());
            self.bounds
                .fluctuate_inflow(&self.mac, modes, self.time + dt);
        }

        let t0 = Instant::now();
        let scheme = self.params.advection;
        self.bounds
            .extrapolate_into_obstacles(&mut self.mac, EXTRAPOLATION_LAYERS);
        if let Some(smoke) = self.smoke.as_mut() {
            smoke.advect(&self.mac, dt, scheme, self.step);
        }
        if parts.contains(&Part::Advect) {
            self.ran.push(Part::Advect.name());
        }
        if let Some(frozen) = &self.frozen {
            // Figure 11: the stored flow, plus what the turbulence stage synthesised onto it
            // this step, has carried the smoke; the velocity itself is not advanced.
            if let Some(smoke) = self.smoke.as_mut() {
                self.ran.push(Part::Forces.name());
                smoke.apply_sources(&mut self.mac, &self.bounds, self.time);
            }
            self.mac.u.clone_from(frozen);
            self.ran.push(Part::StaticFlow.name());
        } else if self.params.reflection {
            self.reflected_update(dt, &mut stats)?;
        } else {
            advect_velocity_into(&self.mac, dt, scheme, &mut self.advected);
            std::mem::swap(&mut self.mac.u, &mut self.advected);
            self.body_forces_and_viscosity(dt, &mut stats)?;
            let t1 = Instant::now();
            let solve = self.project(dt)?;
            stats.project_seconds = t1.elapsed().as_secs_f64();
            stats.pressure_iterations = solve.iterations;
            stats.pressure_residual = solve.relative_residual;
        }
        stats.advect_seconds = t0.elapsed().as_secs_f64() - stats.project_seconds;
        if parts.contains(&Part::Pressure) {
            self.ran.push(Part::Pressure.name());
        }

        self.time += dt;
        self.step += 1;
        stats.max_divergence = max_divergence(&self.mac, &self.bounds);
        stats.change_rate = change_rate(&self.before, &self.mac.u) / dt;
        if let Some((start, avg)) = self.average.as_mut() {
            self.ran.push(Part::Average.name());
            if self.time > *start {
                avg.add(&self.mac, dt.min(self.time - *start));
            }
        }
        self.check_finite()?;
        stats.total_seconds = started.elapsed().as_secs_f64();
        Ok(stats)
    }

    /// Whether the first body is a container holding the fluid (see [`GridParams::container`]).
    pub fn has_container(&self) -> bool {
        self.params.container
    }

    /// Interpolates this step's velocity onto the smoke's fine grid (extrapolated into
    /// obstacles as the step's advection reads it) and lends it beside the flow's faces, so
    /// the turbulence stage adds its kernels to both (Pfaff et al. 2009, section 5.2: the
    /// velocity is up-sampled before line 1). `None` for the fine grid when the smoke has
    /// none; the step then carries the smoke by what this left there.
    pub fn lend_fine_velocity(&mut self) -> (&mut MacGrid, Option<&mut MacGrid>) {
        let step = self.step;
        let fine = self
            .smoke
            .as_mut()
            .and_then(|s| s.fine.as_mut())
            .map(|fine| {
                let bounds = &self.bounds;
                let extrapolate = |f: &mut MacGrid| {
                    bounds.extrapolate_into_obstacles(f, EXTRAPOLATION_LAYERS);
                };
                fine.refresh(&self.mac, extrapolate, step);
                &mut fine.mac
            });
        (&mut self.mac, fine)
    }

    /// Voxelises the obstacles at `t` and the coupled liquid, and rebuilds the pressure system
    /// when the solid cells changed.
    pub(super) fn rebuild_boundaries(&mut self, t: Real) {
        let liquid = self.liquid.as_ref();
        self.bounds = if self.bodies.iter().any(RigidBody::is_moving) {
            let sides = self.bounds.sides.clone();
            let container = self.params.container;
            if let Some(smoke) = self.smoke.as_mut() {
                smoke.place_obstacles(&self.bodies, t, container);
            }
            let surface = (container, self.params.obstacle_surface);
            Boundaries::new(&self.mac, sides, &self.bodies, t, surface, liquid)
        } else {
            self.bounds.with_liquid(&self.mac, &self.bodies, t, liquid)
        };
        let cells = self.bounds.cell_kinds();
        let fractions = self.bounds.face_fractions(self.mac.dims);
        if cells != self.system_cells || fractions != self.system_fractions {
            self.system = PoissonSystem::with_fractions(
                &cells,
                self.bounds.pressure_boundary(),
                fractions.clone(),
            );
            self.system_cells = cells;
            self.system_fractions = fractions;
        }
    }

    /// The parts the last [`Self::advance`] ran, in order.
    pub fn ran(&self) -> &[&'static str] {
        &self.ran
    }

    /// One line on the grid as built, for `eddy run --plan`.
    pub fn summary(&self) -> String {
        let n = self.params.resolution;
        format!(
            "MAC grid of {} x {} x {} cells of {} m, {} obstacles",
            n[0],
            n[1],
            n[2],
            self.params.dx,
            self.bodies.len()
        )
    }

    /// Switches to the static flow-field mode (Pfaff et al. 2009, Figure 11): from now on the
    /// velocity is `cells` (cell-centre components, as grid frames store them) and every step
    /// only carries the smoke. The face values are the means of the cells beside each face,
    /// made discretely divergence-free by one projection with this grid's obstacles and sides.
    pub fn freeze_velocity(&mut self, cells: &[Array3<Real>; 3]) -> Result<(), GridError> {
        let dims = self.mac.dims;
        if let Some(bad) = cells.iter().find(|c| c.shape() != dims) {
            return Err(GridError::StaticFlow(format!(
                "the stored field has {:?} cells, this grid {dims:?}",
                bad.shape()
            )));
        }
        if self.bodies.iter().any(RigidBody::is_moving) {
            return Err(GridError::StaticFlow(
                "a stored flow cannot follow moving obstacles".into(),
            ));
        }
        for (a, (u, c)) in self.mac.u.iter_mut().zip(cells).enumerate() {
            Zip::indexed(u).par_for_each(|idx, f| {
                let idx = [idx.0, idx.1, idx.2];
                let beside = |i: usize| -> Option<Real> {
                    (i < dims[a]).then(|| {
                        let mut m = idx;
                        m[a] = i;
                        c[m]
                    })
                };
                let lo = idx[a].checked_sub(1).and_then(beside);
                *f = match (lo, beside(idx[a])) {
                    (Some(l), Some(h)) => 0.5 * (l + h),
                    (Some(v), None) | (None, Some(v)) => v,
                    (None, None) => 0.0,
                };
            });
        }
        self.mac.sync_periodic();
        self.bounds.apply(&mut self.mac);
        let dt = self.stable_dt()?;
        self.project(dt)?;
        self.frozen = Some(self.mac.u.clone());
        Ok(())
    }

    /// Whether the velocity is a stored flow (see [`Self::freeze_velocity`]).
    pub fn is_static(&self) -> bool {
        self.frozen.is_some()
    }

    /// The parts [`Self::advance`] runs, in order, from the bodies, settings and fields: the
    /// one list that [`Self::describe`] reads and [`Self::ran`] names the same way.
    fn parts(&self) -> Vec<Part> {
        let p = &self.params;
        let mut parts = Vec::new();
        if self.bodies.iter().any(RigidBody::is_moving) {
            parts.push(Part::Obstacles);
        }
        if p.inflow_turbulence.is_some() {
            parts.push(Part::Inflow);
        }
        // A stored flow without smoke has nothing to advect.
        if self.frozen.is_none() || self.smoke.is_some() {
            parts.push(Part::Advect);
        }
        if self.frozen.is_some() {
            if self.smoke.is_some() {
                parts.push(Part::Forces);
            }
            parts.push(Part::StaticFlow);
        } else {
            if self.has_forces() {
                parts.push(Part::Forces);
            }
            if p.viscosity > 0.0 {
                parts.push(Part::Viscosity);
            }
            parts.push(Part::Pressure);
        }
        if p.average_from.is_some() {
            parts.push(Part::Average);
        }
        parts
    }

    /// The parts [`Self::advance`] runs, in order, for `eddy run --plan`: (part, what it does
    /// here).
    pub fn describe(&self) -> Vec<(&'static str, String)> {
        self.parts()
            .into_iter()
            .map(|part| (part.name(), self.describe_part(part)))
            .collect()
    }

    /// What `part` does here.
    fn describe_part(&self, part: Part) -> String {
        let p = &self.params;
        let scheme = p.advection.label();
        match part {
            Part::Obstacles => {
                let moving = self.bodies.iter().filter(|b| b.is_moving()).count();
                format!("{moving} moving obstacles re-voxelised every step")
            }
            Part::Inflow => p.inflow_turbulence.as_ref().map_or(String::new(), |m| {
                let s = &m.spec;
                format!(
                    "inflow turbulence: {} random modes, intensity {} of the inflow speed, \
                     eddy size {} m, carried at the inflow velocity",
                    s.modes, s.intensity, s.length
                )
            }),
            Part::Advect => match (&self.frozen, &self.smoke) {
                (Some(_), Some(s)) => format!(
                    "{scheme} advection of the {} by the stored flow",
                    s.describe()
                ),
                _ => {
                    let scalars = self
                        .smoke
                        .as_ref()
                        .map_or(String::new(), |s| format!(" and {}", s.describe()));
                    let reflection = if p.reflection {
                        ", advection-reflection (two projections)"
                    } else {
                        ""
                    };
                    format!("{scheme} advection of velocity{scalars}{reflection}")
                }
            },
            Part::Forces => self.describe_forces(),
            Part::StaticFlow => {
                "velocity restored to the stored field: no velocity advection, no projection".into()
            }
            Part::Viscosity => format!(
                "implicit ({:?}) nu = {} m^2/s, MGPCG per component",
                p.viscosity_scheme, p.viscosity
            ),
            Part::Pressure => format!(
                "MGPCG projection to relative residual {} (at most {} iterations)",
                p.pressure.tolerance, p.pressure.max_iterations
            ),
            Part::Average => p.average_from.map_or(String::new(), |t| {
                format!("time-averaged velocity from t = {t} s")
            }),
        }
    }

    /// The forces of a step: a stored flow's smoke sources alone, or the smoke's sources and
    /// buoyancy, confinement and gravity.
    fn describe_forces(&self) -> String {
        let p = &self.params;
        if self.frozen.is_some() {
            return self.smoke.as_ref().map_or(String::new(), |s| {
                format!("smoke sources ({})", s.source_count())
            });
        }
        let mut forces = Vec::new();
        if let Some(s) = &self.smoke {
            let (density, heat) = s.buoyancy();
            forces.push(format!(
                "smoke sources ({}), buoyancy {density}, heat buoyancy {heat}{}",
                s.source_count(),
                if s.fine.is_some() {
                    " from the smoke's cell means"
                } else {
                    ""
                }
            ));
        }
        if p.confinement > 0.0 {
            forces.push(format!("vorticity confinement {}", p.confinement));
        }
        if p.gravity_force {
            forces.push(format!("gravity {:?}", p.gravity.as_slice()));
        }
        forces.join(", ")
    }

    /// Forces, sources, boundary conditions and viscosity over `dt`, before a projection.
    fn body_forces_and_viscosity(
        &mut self,
        dt: Real,
        stats: &mut GridStepStats,
    ) -> Result<(), GridError> {
        // Crank–Nicolson takes the forces as its right-hand side, so it keeps the velocity
        // before them (`viscosity::diffuse_component`).
        let unforced = (self.params.viscosity > 0.0
            && self.params.viscosity_scheme == ViscosityScheme::CrankNicolson)
            .then(|| {
                self.bounds.apply(&mut self.mac);
                self.mac.u.clone()
            });
        self.apply_forces(dt);
        if self.incremental_pressure() {
            // u -= dt / rho grad p of the last step, as y = p dt / (rho dx) differences.
            self.scaled_pressure = self
                .pressure
                .mapv(|p| p * dt / (self.params.density * self.mac.dx));
            subtract_gradient(&mut self.mac, &self.bounds, &self.scaled_pressure);
        }
        self.bounds.apply(&mut self.mac);
        if self.params.viscosity > 0.0 {
            stats.viscosity_iterations = self.diffuse(dt, unforced.as_ref())?;
        }
        Ok(())
    }

    /// The advection–reflection step (Zehnder, Narain and Thomaszewski 2018, Algorithm 1):
    /// advect half a step and project, reflect the advected field about its projection
    /// (2 P(u) - u), advect that by the projected field for the second half and project again.
    /// It costs a second projection and removes most of the energy that the first-order
    /// advect-then-project splitting loses.
    ///
    /// The pressure kept for probes, forces and frames is the step's whole pressure, the one
    /// whose gradient over `dt` is the impulse both projections gave: the reflection applies
    /// the first projection's impulse twice and the second projects over half a step, so it is
    /// p1 + p2 / 2. Neither projection's own pressure is: under gravity the first is twice the
    /// hydrostatic pressure and the second minus twice it.
    fn reflected_update(&mut self, dt: Real, stats: &mut GridStepStats) -> Result<(), GridError> {
        let scheme = self.params.advection;
        let half = 0.5 * dt;
        self.mac.u = advect_velocity(&self.mac, half, scheme);
        self.apply_forces(dt);
        self.bounds.apply(&mut self.mac);
        let advected = self.mac.u.clone();
        let t1 = Instant::now();
        let first = self.project(half)?;
        let mut elapsed = t1.elapsed().as_secs_f64();
        let first_pressure = self.pressure.clone();
        let mut projected = self.mac.clone();
        self.bounds
            .extrapolate_into_obstacles(&mut projected, EXTRAPOLATION_LAYERS);
        for (u, tilde) in self.mac.u.iter_mut().zip(&advected) {
            Zip::from(u)
                .and(tilde)
                .par_for_each(|u, &t| *u = 2.0 * *u - t);
        }
        self.mac.u = std::array::from_fn(|a| {
            advect(
                &self.mac.u[a],
                self.mac.face_stagger(a),
                &projected,
                half,
                scheme,
            )
        });
        self.bounds.apply(&mut self.mac);
        if self.params.viscosity > 0.0 {
            stats.viscosity_iterations = self.diffuse(dt, None)?;
        }
        let t2 = Instant::now();
        let second = self.project(half)?;
        elapsed += t2.elapsed().as_secs_f64();
        Zip::from(&mut self.pressure)
            .and(&first_pressure)
            .par_for_each(|p, &p1| *p = p1 + 0.5 * *p);
        stats.project_seconds = elapsed;
        stats.pressure_iterations = first.iterations + second.iterations;
        stats.pressure_residual = second.relative_residual;
        Ok(())
    }

    /// The largest stable step of the current state: the CFL step on the largest face speed
    /// (at most `dt_max`), or the fixed step. Errs when the CFL rule needs less than `dt_min`.
    pub fn stable_dt(&self) -> Result<Real, GridError> {
        let s = &self.params.limits;
        let speed = self.cfl_speed();
        let dt = s.fixed_dt.unwrap_or_else(|| {
            if speed > 0.0 {
                (s.cfl * self.mac.dx / speed).min(s.dt_max)
            } else {
                s.dt_max
            }
        });
        if dt < s.dt_min {
            return Err(GridError::Unstable {
                time: self.time,
                step: self.step,
                what: format!(
                    "the CFL rule needs dt = {dt:.3e} s at speed {speed:.3e} m/s, below time.dt_min = {:.3e} s",
                    s.dt_min
                ),
            });
        }
        Ok(dt)
    }

    /// Whether a step applies forces: smoke sources and buoyancy, confinement or gravity.
    fn has_forces(&self) -> bool {
        self.smoke.is_some() || self.params.confinement > 0.0 || self.params.gravity_force
    }

    /// Buoyancy and vorticity confinement, and the smoke sources; and the impulses added from
    /// outside since the last step ([`Self::add_face_impulse`]).
    fn apply_forces(&mut self, dt: Real) {
        if self.has_forces() {
            self.ran.push(Part::Forces.name());
        }
        self.apply_impulses();
        if let Some(smoke) = self.smoke.as_mut() {
            smoke.apply_sources(&mut self.mac, &self.bounds, self.time);
            if let Some(lift) = smoke.lift(self.up) {
                add_cell_acceleration(&mut self.mac, &lift, dt);
            }
        }
        if self.params.confinement > 0.0 {
            let f = confinement(&self.mac, self.params.confinement);
            add_cell_acceleration(&mut self.mac, &f, dt);
        }
        if self.params.gravity_force {
            let g = self.params.gravity;
            for (u, ga) in self.mac.u.iter_mut().zip(g.iter()) {
                u.par_mapv_inplace(|v| v + dt * ga);
            }
        }
    }

    /// Implicit viscosity, one solve per component, `unforced` the faces before this step's
    /// forces (for Crank–Nicolson); returns the most iterations any solve took.
    fn diffuse(
        &mut self,
        dt: Real,
        unforced: Option<&[Array3<Real>; 3]>,
    ) -> Result<usize, GridError> {
        self.ran.push(Part::Viscosity.name());
        let a = self.params.viscosity * dt / (self.mac.dx * self.mac.dx);
        let mut iterations = 0;
        for c in 0..3 {
            let stats = diffuse_component(
                &self.bounds,
                c,
                a,
                self.params.viscosity_scheme,
                &mut self.mac.u[c],
                unforced.map(|u| &u[c]),
                &self.params.pressure,
                &mut self.diffusion[c],
            )
            .map_err(|source| self.solve_error("viscosity", source))?;
            iterations = iterations.max(stats.iterations);
        }
        self.mac.sync_periodic();
        Ok(iterations)
    }

    /// Whether a step projects the increment of the pressure only (see
    /// [`GridParams::incremental_pressure`]): a liquid's cells change from step to step, and a
    /// pressure carried over would push on the faces it leaves.
    fn incremental_pressure(&self) -> bool {
        self.params.incremental_pressure && !self.params.reflection && self.liquid.is_none()
    }

    /// Projects the velocity and stores the pressure of a step of length `dt`: the solve's, or
    /// with an incremental pressure the last one plus the solve's increment.
    fn project(&mut self, dt: Real) -> Result<super::poisson::SolveStats, GridError> {
        let to_pressure = self.params.density * self.mac.dx / dt;
        let increment = self.incremental_pressure();
        let carried = increment.then(|| self.pressure.mapv(|p| p / to_pressure));
        if increment {
            self.scaled_pressure.fill(0.0);
        } else {
            self.scaled_pressure = self.pressure.mapv(|p| p / to_pressure);
        }
        let stats = project(
            &mut self.mac,
            &self.bounds,
            &mut self.system,
            &mut self.scaled_pressure,
            &self.params.pressure,
            carried.as_ref(),
        )
        .map_err(|source| self.solve_error("pressure", source))?;
        if increment {
            Zip::from(&mut self.pressure)
                .and(&self.scaled_pressure)
                .par_for_each(|p, &y| *p += y * to_pressure);
        } else {
            self.pressure = self.scaled_pressure.mapv(|y| y * to_pressure);
        }
        Ok(stats)
    }

    fn solve_error(&self, what: &'static str, source: SolveError) -> GridError {
        GridError::Solve {
            what,
            time: self.time,
            step: self.step,
            source,
        }
    }

    /// The face speed the CFL rule reads: the largest, except on cut cells the partly covered
    /// faces less than half open ([`super::cut::CutFaces::cfl_speed`]).
    fn cfl_speed(&self) -> Real {
        match self.bounds.cut_faces() {
            Some(cut) => cut.cfl_speed(&self.mac),
            None => self.mac.max_face_speed(),
        }
    }

    /// Stops on a non-finite velocity or a CFL number far past any stable step.
    fn check_finite(&self) -> Result<(), GridError> {
        let speed = self.mac.max_face_speed();
        let unstable = |what: String| GridError::Unstable {
            time: self.time,
            step: self.step,
            what,
        };
        if !speed.is_finite() {
            return Err(unstable("a face velocity is not finite".into()));
        }
        let dt = self
            .params
            .limits
            .fixed_dt
            .unwrap_or(self.params.limits.dt_max);
        if speed * dt / self.mac.dx > CFL_BLOWUP {
            return Err(unstable(format!(
                "speed {speed:.3e} m/s would cross {CFL_BLOWUP} cells per step"
            )));
        }
        Ok(())
    }

    /// Kinetic energy of the fluid cells, J (with `grid.density`).
    pub fn kinetic_energy(&self) -> Real {
        self.params.density * self.mac.kinetic_energy(&self.bounds.fluid_mask())
    }

    /// Fluid density, kg/m^3.
    pub fn density(&self) -> Real {
        self.params.density
    }

    /// Kinematic viscosity, m^2/s.
    pub fn viscosity(&self) -> Real {
        self.params.viscosity
    }
}

/// The unit vector against `gravity`, or y when there is none.
fn up_of(gravity: Vec3) -> Vec3 {
    if gravity.norm() > 0.0 {
        -gravity.normalize()
    } else {
        Vec3::y()
    }
}

/// |after - before| / |before| over all faces (|after| when before is zero).
fn change_rate(before: &[Array3<Real>; 3], after: &[Array3<Real>; 3]) -> Real {
    let add = |(d1, n1): (Real, Real), (d2, n2): (Real, Real)| (d1 + d2, n1 + n2);
    let terms = |(d, n): (Real, Real), b: &Real, a: &Real| (d + (a - b) * (a - b), n + b * b);
    // Blocks in parallel, added in order (see `crate::parallel`); sequential for a
    // non-contiguous array.
    let (diff, norm) = before
        .iter()
        .zip(after)
        .map(|(b, a)| match (b.as_slice(), a.as_slice()) {
            (Some(b), Some(a)) => b
                .par_chunks(BLOCK)
                .zip(a.par_chunks(BLOCK))
                .map(|(b, a)| b.iter().zip(a).fold((0.0, 0.0), |s, (b, a)| terms(s, b, a)))
                .collect::<Vec<_>>()
                .into_iter()
                .fold((0.0, 0.0), add),
            _ => Zip::from(b).and(a).fold((0.0, 0.0), terms),
        })
        .fold((0.0, 0.0), add);
    if norm > 0.0 {
        (diff / norm).sqrt()
    } else {
        diff.sqrt()
    }
}
