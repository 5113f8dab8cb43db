//! Vorticity confinement in SPH form (Fedkiw et al. 2001; for SPH, Macklin & Müller 2013):
//! a_i = epsilon (N_i x omega_i) with omega = curl v and N = eta / |eta|, eta = grad |omega|,
//! both by the shared difference operators. It pushes fluid around existing vortices' cores
//! and so strengthens them; it cannot create vortices, which is why the papers compare
//! against it. Where eta vanishes there is no direction and no force.

use super::{StepContext, StepHook};
use crate::sph::operators::WallField;
use crate::{Real, Vec3};
use rayon::prelude::*;

/// Confinement with strength epsilon, m/s.
pub struct Confinement {
    epsilon: Real,
    /// Boundary samples take part in the operators.
    walls: bool,
}

impl Confinement {
    pub fn new(epsilon: Real, walls: bool) -> Self {
        Self { epsilon, walls }
    }
}

impl StepHook for Confinement {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn describe(&self) -> String {
        super::plan_line(
            format!("vorticity confinement, epsilon = {} m/s", self.epsilon),
            self.walls,
        )
    }

    fn walls(&self) -> bool {
        self.walls
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], accel: &mut [Vec3]) {
        if self.epsilon == 0.0 {
            return;
        }
        let ops = &ctx.ops;
        let omega = ops.curl(v, WallField::Velocity);
        let magnitude: Vec<Real> = omega.par_iter().map(|w| w.norm()).collect();
        let eta = ops.scalar_gradient(&magnitude);
        accel
            .par_iter_mut()
            .zip(eta.par_iter().zip(omega.par_iter()))
            .for_each(|(a, (eta, w))| {
                let norm = eta.norm();
                if norm > 0.0 {
                    *a += (self.epsilon / norm) * eta.cross(w);
                }
            });
    }
}
