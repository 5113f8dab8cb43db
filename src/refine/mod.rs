//! SPH turbulence refinements on top of DFSPH or IISPH, behind one small trait.
//!
//! The solver calls a refinement at two points of its step (see `crate::sph::solver`):
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

pub mod bench;
pub mod biot_savart;
mod clusters;
pub mod confinement;
pub mod mcvsph;
pub mod micropolar;
pub mod rankine;
pub mod vrsph;

use crate::scene::Refinement;
use crate::sph::operators::Operators;
use crate::{Real, Vec3};

/// What a refinement may read during a step.
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

/// One turbulence refinement.
pub trait Refiner: Send {
    /// Reorders per-particle state as the fluid was reordered (`perm[k]` is the old index of
    /// the particle now at k).
    fn permute(&mut self, perm: &[u32]);

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

/// `v += scale * dv`, in parallel.
pub(crate) fn add_scaled(v: &mut [Vec3], dv: &[Vec3], scale: Real) {
    use rayon::prelude::*;
    v.par_iter_mut()
        .zip(dv.par_iter())
        .for_each(|(v, d)| *v += scale * d);
}
