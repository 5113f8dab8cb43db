//! SPH turbulence refinements on top of DFSPH or IISPH, behind one small trait, attached to the
//! solver as a step hook (`crate::sph::hooks`).
//!
//! The solver calls a refinement at two points of its step:
//!
//! - [`Refiner::before_advection`], after the DFSPH divergence solve (which ends the previous
//!   step in Bender & Koschier's order) and before the non-pressure forces are applied: the
//!   velocity there is v^n of the papers. Rankine (Wang et al. Algorithm 1, "before advection"),
//!   VRSPH (Liu et al. Algorithm 2, "after the divergence solve"), micropolar and confinement
//!   act here; MCVSPH records omega^n.
//! - [`Refiner::after_pressure`], after the pressure solve and before positions move: MCVSPH's
//!   correction (Ye et al. Algorithm 2, lines 8–13).
//!
//! Refinements that keep per-particle state are told of every reordering of the fluid.

pub mod biot_savart;
mod clusters;
pub mod confinement;
pub mod lanes;
pub mod mcvsph;
pub mod micropolar;
pub mod packed;
pub mod params;
pub mod rankine;
pub mod vrsph;

pub use crate::sph::hooks::StepContext;
pub use params::{InvalidParam, Refinement};

use crate::sph::hooks::StepHook;
use crate::{Real, Vec3};

/// One turbulence refinement.
pub trait Refiner: Send {
    /// Reorders per-particle state as the fluid was reordered (`perm[k]` is the old index of
    /// the particle now at k).
    fn permute(&mut self, perm: &[u32]);

    /// Drops the state of the particles where `keep` is false and appends state for `added`
    /// new ones (fluid entering at an inflow, whose stream is irrotational: zero vorticity).
    fn resize(&mut self, _keep: &[bool], _added: usize) {}

    /// At v^n (after the divergence solve, before non-pressure forces): may change the
    /// velocities `v` or add to the non-pressure accelerations `accel`.
    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], accel: &mut [Vec3]);

    /// After the pressure solve, before positions move: may change `v`.
    fn after_pressure(&mut self, _ctx: &StepContext, _v: &mut [Vec3]) {}

    /// Rotational kinetic energy the method carries beyond the particles' linear motion, J.
    fn rotational_energy(&self, _mass: Real) -> Real {
        0.0
    }

    /// Per-particle fields the method adds to the output frames.
    fn fields(&self) -> Vec<(&'static str, &[Vec3])> {
        Vec::new()
    }
}

/// The refinement a scene asks for, for `n` fluid particles; None for `none`.
pub fn build(cfg: &Refinement, n: usize, seed: u64) -> Option<Box<dyn Refiner>> {
    Some(match *cfg {
        Refinement::None => return None,
        Refinement::Rankine { beta, .. } => Box::new(rankine::Rankine::new(beta)),
        Refinement::Vrsph { alpha, .. } => Box::new(vrsph::Vrsph::new(alpha)),
        Refinement::Mcvsph {
            sample_fraction,
            volume_coefficient,
            theta,
            ..
        } => Box::new(mcvsph::Mcvsph::new(
            n,
            sample_fraction,
            volume_coefficient,
            theta,
            seed,
        )),
        Refinement::Micropolar {
            nu_t,
            micro_inertia,
            ..
        } => Box::new(micropolar::Micropolar::new(n, nu_t, micro_inertia)),
        Refinement::Confinement { epsilon, .. } => Box::new(confinement::Confinement::new(epsilon)),
    })
}

/// The refinement a scene asks for as a step hook of the SPH solver; None for `none`.
pub fn hook(cfg: &Refinement, n: usize, seed: u64) -> Option<Box<dyn StepHook>> {
    build(cfg, n, seed).map(|refiner| {
        Box::new(RefinementHook {
            refiner,
            cfg: cfg.clone(),
        }) as Box<dyn StepHook>
    })
}

/// A refinement with the parameters it was built from, attached to the solver's step.
struct RefinementHook {
    refiner: Box<dyn Refiner>,
    cfg: Refinement,
}

impl StepHook for RefinementHook {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        self.cfg.plan_line().unwrap_or_default()
    }

    fn walls(&self) -> bool {
        self.cfg.walls()
    }

    fn permute(&mut self, perm: &[u32]) {
        self.refiner.permute(perm);
    }

    fn resize(&mut self, keep: &[bool], added: usize) {
        self.refiner.resize(keep, added);
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], accel: &mut [Vec3]) {
        self.refiner.before_advection(ctx, v, accel);
    }

    fn after_pressure(&mut self, ctx: &StepContext, v: &mut [Vec3]) {
        self.refiner.after_pressure(ctx, v);
    }

    fn rotational_energy(&self, mass: Real) -> Real {
        self.refiner.rotational_energy(mass)
    }

    fn fields(&self) -> Vec<(&'static str, &[Vec3])> {
        self.refiner.fields()
    }
}

/// `v += scale * dv`, in parallel.
pub(crate) fn add_scaled(v: &mut [Vec3], dv: &[Vec3], scale: Real) {
    use rayon::prelude::*;
    v.par_iter_mut()
        .zip(dv.par_iter())
        .for_each(|(v, d)| *v += scale * d);
}
