//! SPH turbulence refinements on top of DFSPH or IISPH. Each is a step hook of the solver
//! ([`StepHook`], the one trait: `crate::sph::hooks`), and says itself what it does in the plan
//! and whether walls take part in its operators.
//!
//! The solver calls a refinement at two points of its step:
//!
//! - [`StepHook::before_advection`], after the DFSPH divergence solve (which ends the previous
//!   step in Bender & Koschier's order) and before the non-pressure forces are applied: the
//!   velocity there is v^n of the papers. Rankine (Wang et al. Algorithm 1, "before advection"),
//!   VRSPH (Liu et al. Algorithm 2, "after the divergence solve"), micropolar and confinement
//!   act here; MCVSPH records omega^n.
//! - [`StepHook::after_pressure`], after the pressure solve and before positions move: MCVSPH's
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
pub mod reference;
pub mod vrsph;

pub use crate::sph::hooks::StepContext;
pub use params::{InvalidParam, Refinement};

pub use crate::sph::hooks::StepHook;
use crate::{Real, Vec3};

/// The refinement a scene asks for, for `n` fluid particles, as a step hook of the SPH
/// solver; None for `none`.
pub fn build(cfg: &Refinement, n: usize, seed: u64) -> Option<Box<dyn StepHook>> {
    Some(match *cfg {
        Refinement::None => return None,
        Refinement::Rankine { beta, walls } => Box::new(rankine::Rankine::new(beta, walls)),
        Refinement::Vrsph { alpha, walls } => Box::new(vrsph::Vrsph::new(alpha, walls)),
        Refinement::Mcvsph {
            sample_fraction,
            volume_coefficient,
            theta,
            walls,
        } => Box::new(mcvsph::Mcvsph::new(
            n,
            sample_fraction,
            volume_coefficient,
            theta,
            seed,
            walls,
        )),
        Refinement::Micropolar {
            nu_t,
            micro_inertia,
            walls,
        } => Box::new(micropolar::Micropolar::new(n, nu_t, micro_inertia, walls)),
        Refinement::Confinement { epsilon, walls } => {
            Box::new(confinement::Confinement::new(epsilon, walls))
        }
    })
}

/// A refinement's line for `eddy run --plan`: what it does, then whether walls take part in
/// its operators.
fn plan_line(what: String, walls: bool) -> String {
    let walls = if walls {
        "walls in the operators"
    } else {
        "fluid-only operators"
    };
    format!("{what}; {walls}")
}

/// `v += scale * dv`, in parallel.
pub(crate) fn add_scaled(v: &mut [Vec3], dv: &[Vec3], scale: Real) {
    use rayon::prelude::*;
    v.par_iter_mut()
        .zip(dv.par_iter())
        .for_each(|(v, d)| *v += scale * d);
}
