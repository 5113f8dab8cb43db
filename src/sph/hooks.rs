//! Step hooks: work that runs inside an SPH step at fixed points, so that a turbulence
//! refinement (`crate::refine`) and vortex synthesis into the particles can sit side by side
//! without the solver knowing either.
//!
//! The solver calls every hook, in the order they were added, at two points of its step:
//!
//! - [`StepHook::before_advection`], after the DFSPH divergence solve (which ends the previous
//!   step in Bender & Koschier's order) and before the non-pressure forces are applied: the
//!   velocity there is v^n of the papers.
//! - [`StepHook::after_pressure`], after the pressure solve and before positions move.
//!
//! Hooks that keep per-particle state are told of every reordering of the fluid. Every hook
//! says what it carries from one step to the next ([`Persist`]), so that a checkpoint holds
//! it: one that carries nothing saves nothing.

use super::operators::Operators;
use crate::state::Persist;
use crate::{Real, Vec3};

/// What a hook may read during a step.
pub struct StepContext<'a> {
    /// The shared difference operators of the current neighbourhood.
    pub ops: Operators<'a>,
    /// Step size, s.
    pub dt: Real,
    /// Kinematic viscosity of the fluid, m^2/s.
    pub nu: Real,
    /// Particle spacing, m.
    pub spacing: Real,
}

/// Work attached to the SPH step. [`Persist::restore`] is called between steps on the hook
/// built for the same scene, after the fluid's particles are restored.
pub trait StepHook: Send + Persist {
    /// Short name, for the plan and the stage trace.
    fn name(&self) -> &'static str;

    /// What it does, one line for `eddy run --plan`.
    fn describe(&self) -> String;

    /// Whether boundary samples take part in its difference operators.
    fn walls(&self) -> bool {
        false
    }

    /// Reorders per-particle state as the fluid was reordered (`perm[k]` is the old index of
    /// the particle now at k).
    fn permute(&mut self, _perm: &[u32]) {}

    /// Drops the state of the particles where `keep` is false and appends state for `added`
    /// new ones, as the fluid did at its open boundaries (see [`crate::spatial::resize`]).
    fn resize(&mut self, _keep: &[bool], _added: usize) {}

    /// At v^n (after the divergence solve, before non-pressure forces): may change the
    /// velocities `v` or add to the non-pressure accelerations `accel`.
    fn before_advection(&mut self, _ctx: &StepContext, _v: &mut [Vec3], _accel: &mut [Vec3]) {}

    /// After the pressure solve, before positions move: may change `v`.
    fn after_pressure(&mut self, _ctx: &StepContext, _v: &mut [Vec3]) {}

    /// Rotational kinetic energy the hook carries beyond the particles' linear motion, J.
    fn rotational_energy(&self, _mass: Real) -> Real {
        0.0
    }

    /// The count of fluid particles its per-particle state is for (`None` without any, or
    /// before it is made): the solver checks a restored hook against its fluid with it.
    fn particles(&self) -> Option<usize> {
        None
    }

    /// Per-particle fields the hook adds to the output frames.
    fn fields(&self) -> Vec<(&'static str, &[Vec3])> {
        Vec::new()
    }
}
