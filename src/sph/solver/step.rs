//! The step of [`SphSolver::advance`], phase by phase (Bender & Koschier 2017, Algorithm 1,
//! with the step hooks and the open boundaries). The phases up to the pressures read the
//! neighbourhood of the step's start and work on one view of the solver's borrowed parts
//! ([`Step`]); that neighbourhood reads the positions, so moving them, the open boundaries'
//! exchange and the checks work on the solver itself.

use super::{max_speed, Instability, Part, SphSolver, StepStats};
use crate::sph::cg::{self, Role};
use crate::sph::dfsph::{self, Bounds, Solve, SolveResult};
use crate::sph::fluid::FluidParticles;
use crate::sph::forces;
use crate::sph::hooks::{StepContext, StepHook};
use crate::sph::iisph;
use crate::sph::neighborhood::Neighborhood;
use crate::sph::open::{Exchange, OpenBoundaries};
use crate::sph::operators::{self, Operators};
use crate::sph::params::{Pressure, PressureSolverKind, Viscosity};
use crate::{Real, Vec3};
use rayon::prelude::*;
use std::time::Instant;

impl SphSolver {
    /// Advances by `dt` from the state of the last [`Self::update_neighborhoods`]; `dt` should
    /// not exceed [`Self::stable_dt`].
    pub fn advance(&mut self, dt: Real) -> Result<StepStats, Instability> {
        let accel = match self.pending_accel.take() {
            Some(accel) => accel,
            None => self.non_pressure_accelerations(),
        };
        let step_start = Instant::now();
        let energy_bound = self.energy.bound(|| max_speed(&self.fluid.v));
        // r(t) and r(t + dt): the inflow buffers' share of their velocity at both ends.
        let (r0, r1) = (
            self.ramp.factor(self.time),
            self.ramp.factor(self.time + dt),
        );
        let parts = self.parts();
        let mut step = Step::new(self, &parts, dt, accel);
        step.impose_inflow(r0);
        step.carry_kappa_over();
        step.divergence();
        step.before_advection();
        step.forces();
        step.pressure();
        step.after_pressure();
        step.impose_inflow(r1);
        step.pressures();
        let mut stats = step.stats;
        self.advect(dt);
        self.exchange_particles(dt, r1, &parts, &mut stats)?;
        stats.step_seconds = step_start.elapsed().as_secs_f64();
        stats.lost = self.lost.total();
        self.check_losses()?;
        self.check_energy(energy_bound)?;
        Ok(stats)
    }

    /// Moves the positions by dt v, and the clock.
    fn advect(&mut self, dt: Real) {
        let fluid = &mut self.fluid;
        fluid
            .x
            .par_iter_mut()
            .zip(fluid.v.par_iter())
            .for_each(|(x, v)| *x += dt * v);
        self.ran.push(Part::Advect.name());
        self.time += dt;
        self.step += 1;
    }

    /// After the positions moved: the open boundaries' exchange (the buffers at `ramp` times
    /// their velocity) and the particles lost through open sides, both dropped from the fluid
    /// and the hooks' state at once; errs as [`Self::leaving`] does.
    fn exchange_particles(
        &mut self,
        dt: Real,
        ramp: Real,
        parts: &[Part],
        stats: &mut StepStats,
    ) -> Result<(), Instability> {
        let start = Instant::now();
        let mut change = self.open.exchange(&self.fluid.x, dt, ramp);
        if parts.contains(&Part::OpenBoundaries) {
            self.ran.push(Part::OpenBoundaries.name());
        }
        let left = self.leaving(change.as_ref().map(|c| &c.keep[..]))?;
        if !left.is_empty() {
            let n = self.fluid.len();
            let change = change.get_or_insert_with(|| Exchange {
                keep: vec![true; n],
                added: Vec::new(),
            });
            for &(i, side) in &left {
                self.lose(i, side);
                change.keep[i] = false;
            }
        }
        if let Some(change) = change {
            self.fluid.exchange(&change.keep, &change.added);
            for hook in &mut self.hooks {
                hook.resize(&change.keep, change.added.len());
            }
        }
        stats.open_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }
}

/// One step's view of the solver: what its phases read ([`Fixed`]) and what they change.
struct Step<'a> {
    fixed: Fixed<'a>,
    v: &'a mut [Vec3],
    /// The density solve's stiffnesses, stored as kappa dt^2 (its warm start).
    kappa: &'a mut [Real],
    /// The divergence solve's, alike.
    kappa_v: &'a mut [Real],
    pressure: &'a mut [Real],
    /// The non-pressure accelerations, which the hooks may add to.
    accel: Vec<Vec3>,
    last_dt: &'a mut Option<Real>,
    hooks: &'a mut [Box<dyn StepHook>],
    /// The hooks' operator volumes m / rho.
    volume: &'a mut Vec<Real>,
    stats: StepStats,
    /// The parts run, as [`SphSolver::ran`] gives them.
    ran: &'a mut Vec<&'static str>,
}

/// What a step reads and none of its phases change.
struct Fixed<'a> {
    /// The neighbourhood of the step's start.
    nb: Neighborhood<'a>,
    density: &'a [Real],
    /// rho / rho_0 and the DFSPH factors of the step's start.
    ratio: &'a [Real],
    factor: &'a [Real],
    mass: Real,
    rho0: Real,
    dt: Real,
    settings: &'a Pressure,
    viscosity: &'a Viscosity,
    spacing: Real,
    /// The signed solve's roles and the stiffness it holds at the outflows (as k dt^2).
    signed: Option<(Vec<Role>, Real)>,
    /// The velocity the smooth start adds over the step.
    ramp: Option<Vec3>,
    open: &'a OpenBoundaries,
    /// The parts the step runs ([`SphSolver::parts`]).
    parts: &'a [Part],
}

impl<'a> Step<'a> {
    /// The view of `solver` for a step of `dt` that runs `parts`, with the non-pressure
    /// accelerations `accel`; the trace starts empty.
    fn new(solver: &'a mut SphSolver, parts: &'a [Part], dt: Real, accel: Vec<Vec3>) -> Self {
        let SphSolver {
            kernel,
            fluid,
            boundary,
            spacing,
            params,
            fluid_lists,
            boundary_lists,
            pairs,
            density_ratio,
            factor,
            time,
            last_dt,
            hooks,
            refine_volume,
            ran,
            open,
            ramp,
            ..
        } = solver;
        ran.clear();
        let FluidParticles {
            x,
            v,
            density,
            pressure,
            kappa,
            kappa_v,
            mass,
            rest_density,
            ..
        } = fluid;
        let rho0 = *rest_density;
        let nb = Neighborhood {
            kernel,
            x,
            fluid: fluid_lists,
            boundary_lists,
            boundary,
            volume: *mass / rho0,
            pairs,
        };
        let settings = &params.pressure;
        let signed = (settings.solver == PressureSolverKind::Dfsph && settings.signed)
            .then(|| (cg::roles(&nb, open), settings.ambient / rho0 * dt * dt));
        Step {
            fixed: Fixed {
                nb,
                density,
                ratio: density_ratio,
                factor,
                mass: *mass,
                rho0,
                dt,
                settings,
                viscosity: &params.viscosity,
                spacing: *spacing,
                signed,
                ramp: ramp.increment(*time, dt),
                open,
                parts,
            },
            v,
            kappa,
            kappa_v,
            pressure,
            accel,
            last_dt,
            hooks,
            volume: refine_volume,
            stats: StepStats {
                dt,
                ..StepStats::default()
            },
            ran,
        }
    }

    /// Sets the inflow buffers' velocities to `ramp` times theirs: before the solves, and again
    /// after them, so that the buffers move at their velocity whatever the solves did.
    fn impose_inflow(&mut self, ramp: Real) {
        let start = Instant::now();
        self.fixed.open.impose(self.fixed.nb.x, self.v, ramp);
        self.stats.open_seconds += start.elapsed().as_secs_f64();
    }

    /// The warm starts read kappa dt^2 of the last step; a pressure that holds the fluid
    /// against gravity keeps kappa, not kappa dt^2, when the step changes (the last steps
    /// before the end time are up to halved), so carry kappa over.
    fn carry_kappa_over(&mut self) {
        let dt = self.fixed.dt;
        if let Some(last) = self.last_dt.filter(|&last| last != dt) {
            let scale = (dt / last).powi(2);
            for kappa in [&mut *self.kappa, &mut *self.kappa_v] {
                kappa.par_iter_mut().for_each(|k| *k *= scale);
            }
        }
        *self.last_dt = Some(dt);
    }

    /// The DFSPH divergence solve.
    fn divergence(&mut self) {
        if !self.fixed.runs(Part::Divergence) {
            return;
        }
        let start = Instant::now();
        let s = self.fixed.settings;
        let bounds = self
            .fixed
            .bounds(s.divergence_tolerance, s.divergence_min_iterations());
        self.stats.divergence =
            self.fixed
                .dfsph(Solve::Divergence, self.v, self.kappa_v, bounds, false);
        self.stats.divergence_seconds = start.elapsed().as_secs_f64();
        self.ran.push(Part::Divergence.name());
    }

    /// The hooks at v^n, before the non-pressure forces, each traced under its own name.
    fn before_advection(&mut self) {
        if !self.fixed.runs(Part::Hooks) {
            return;
        }
        let start = Instant::now();
        operators::volumes_into(self.fixed.mass, self.fixed.density, self.volume);
        for hook in self.hooks.iter_mut() {
            let ctx = self.fixed.hook_context(self.volume, hook.walls());
            hook.before_advection(&ctx, self.v, &mut self.accel);
            self.ran.push(hook.name());
        }
        self.stats.refinement_seconds += start.elapsed().as_secs_f64();
    }

    /// The non-pressure accelerations over dt, the smooth start's velocity and XSPH.
    fn forces(&mut self) {
        self.ran.push(Part::Forces.name());
        let Fixed {
            nb,
            density,
            rho0,
            dt,
            viscosity,
            ramp,
            ..
        } = self.fixed;
        self.v
            .par_iter_mut()
            .zip(self.accel.par_iter())
            .for_each(|(v, a)| *v += dt * a);
        if let Some(dv) = ramp {
            self.v.par_iter_mut().for_each(|v| *v += dv);
        }
        if viscosity.xsph > 0.0 {
            forces::xsph(&nb, density, rho0, self.v, viscosity.xsph);
        }
    }

    /// The density solve: DFSPH (clamped or signed) or IISPH.
    fn pressure(&mut self) {
        let fixed = &self.fixed;
        let s = fixed.settings;
        let bounds = fixed.bounds(s.density_tolerance, s.min_iterations);
        let start = Instant::now();
        self.ran.push(Part::Pressure.name());
        self.stats.pressure = if s.solver == PressureSolverKind::Dfsph {
            fixed.dfsph(Solve::Density, self.v, self.kappa, bounds, s.second_order)
        } else {
            iisph::solve(
                &fixed.nb,
                fixed.ratio,
                fixed.factor,
                self.v,
                self.kappa,
                fixed.dt,
                bounds,
            )
        };
        self.stats.pressure_seconds = start.elapsed().as_secs_f64();
    }

    /// The hooks after the pressure solve, before positions move.
    fn after_pressure(&mut self) {
        if !self.fixed.runs(Part::Hooks) {
            return;
        }
        let start = Instant::now();
        for hook in self.hooks.iter_mut() {
            let ctx = self.fixed.hook_context(self.volume, hook.walls());
            hook.after_pressure(&ctx, self.v);
        }
        self.stats.refinement_seconds += start.elapsed().as_secs_f64();
    }

    /// p = kappa rho^2 / rho_0, with kappa the step's total stiffness (stored as kappa dt^2):
    /// the divergence solve's and the density solve's, both pressure impulses of this step.
    fn pressures(&mut self) {
        let Fixed {
            density, dt, rho0, ..
        } = self.fixed;
        self.pressure
            .par_iter_mut()
            .zip(self.kappa.par_iter().zip(self.kappa_v.par_iter()))
            .zip(density.par_iter())
            .for_each(|((p, (k, kv)), rho)| *p = (k + kv) / (dt * dt) * rho * rho / rho0);
    }
}

impl Fixed<'_> {
    fn runs(&self, part: Part) -> bool {
        self.parts.contains(&part)
    }

    /// A solve's bounds: `tolerance`, from `min_iterations` to the settings' most.
    fn bounds(&self, tolerance: Real, min_iterations: u32) -> Bounds {
        Bounds {
            tolerance,
            min_iterations,
            max_iterations: self.settings.max_iterations,
        }
    }

    /// The DFSPH solve `which` of the velocities `v` from the stiffnesses `warm`: by conjugate
    /// gradients on a signed pressure when the settings ask for it.
    fn dfsph(
        &self,
        which: Solve,
        v: &mut [Vec3],
        warm: &mut [Real],
        bounds: Bounds,
        second_order: bool,
    ) -> SolveResult {
        let (nb, ratio, factor, dt) = (&self.nb, self.ratio, self.factor, self.dt);
        match &self.signed {
            Some((roles, held)) => cg::solve(
                nb,
                which,
                roles,
                *held,
                ratio,
                factor,
                v,
                warm,
                dt,
                bounds,
                second_order,
            ),
            None => dfsph::solve(nb, which, ratio, factor, v, warm, dt, bounds, second_order),
        }
    }

    /// What a hook reads: the step's operators over `volume`, with the walls when it `walls`.
    fn hook_context<'b>(&'b self, volume: &'b [Real], walls: bool) -> StepContext<'b> {
        StepContext {
            ops: Operators {
                nb: self.nb,
                volume,
                walls,
            },
            dt: self.dt,
            nu: self.viscosity.kinematic,
            spacing: self.spacing,
        }
    }
}
