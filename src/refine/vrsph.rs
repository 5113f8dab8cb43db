//! Vorticity refinement (VRSPH, Liu et al. 2021, Algorithm 2, Eqs. 5–17).
//!
//! At the point after the divergence solve, where the velocity is the papers' v~ (Eq. 12):
//!
//! 1. zeta~ = curl v~ (Eq. 6, from the shared gradient tensor);
//! 2. the loss Delta zeta = zeta^(n+1) - zeta~ (Eq. 12), with zeta^(n+1) the ideal vorticity
//!    carried from the last step by the vorticity equation (Eqs. 7–11);
//! 3. the local stream function psi (Eq. 15) and the refinement Delta v = curl psi (Eq. 16);
//! 4. v^(n+1) = v~ + alpha Delta v (Eq. 17);
//! 5. zeta^(n+1) = curl v^(n+1) and its ideal successor
//!    zeta^(n+1) + dt (zeta . grad v + nu Laplacian zeta) for the next step (Eqs. 7–10).
//!
//! **Regularised distance in Eq. 15.** The sum runs over the fluid neighbours within the
//! support and the particle itself, with |x_ij| replaced by sqrt(|x_ij|^2 + e^2),
//! e = 2a / 3 and a = (3 V / (4 pi))^(1/3) the radius of a sphere of the particle's rest
//! volume V. With this e, the self term V / (4 pi e) equals the exact stream function at the
//! centre of a uniformly vortical sphere of volume V (a^2 / 2), so the self term is the
//! particle's own contribution rather than a singularity (e is about 0.41 spacings, 0.21 h).
//! Walls carry no loss, so they add nothing to psi.
//!
//! **What Eq. 15 restores.** Truncating the Green's function 1 / (4 pi r) at the support h
//! makes the refinement a band-pass filter: for a divergence-free loss of wavenumber k,
//! psi^(k) = (1 - cos kh) / k^2 loss^(k), so curl Delta v = (1 - cos kh) x loss. Structures much
//! larger than h get back only (kh)^2 / 2 of their loss; those of wavelength about 2h
//! (kh = pi) get back up to twice theirs. `tests/refine_vortex.rs` checks the sign on a single
//! Gaussian vortex of core 1.5 h (VRSPH keeps more of its kinetic energy than DFSPH); at
//! nu = 0 the same vortex gains energy under VRSPH (+30 % in 125 steps, where DFSPH keeps it
//! within 0.1 %), the over-restoration at the particle scale.

use super::{add_scaled, Refiner, StepContext};
use crate::sph::neighbors::permute;
use crate::sph::operators::{curl_of, per_particle, Mat3, Operators, WallField};
use crate::{Real, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// VRSPH with gain alpha.
pub struct Vrsph {
    alpha: Real,
    /// The ideal vorticity zeta^(n+1) per fluid particle; None before the first step.
    ideal: Option<Vec<Vec3>>,
}

impl Vrsph {
    pub fn new(alpha: Real) -> Self {
        Self { alpha, ideal: None }
    }
}

impl Refiner for Vrsph {
    fn permute(&mut self, perm: &[u32]) {
        if let Some(z) = self.ideal.as_mut() {
            permute(z, perm);
        }
    }

    fn before_advection(&mut self, ctx: &StepContext, v: &mut [Vec3], _accel: &mut [Vec3]) {
        if self.alpha == 0.0 {
            return;
        }
        let ops = &ctx.ops;
        let mut grad = ops.gradient(v, WallField::Velocity);
        let mut zeta: Vec<Vec3> = grad.par_iter().map(curl_of).collect();
        if let Some(ideal) = self.ideal.as_ref().filter(|z| z.len() == v.len()) {
            let loss: Vec<Vec3> = ideal
                .par_iter()
                .zip(zeta.par_iter())
                .map(|(ideal, now)| ideal - now)
                .collect();
            let psi = stream_function(ops, &loss);
            let dv = ops.curl(&psi, WallField::Zero);
            add_scaled(v, &dv, self.alpha);
            grad = ops.gradient(v, WallField::Velocity);
            zeta = grad.par_iter().map(curl_of).collect();
        }
        self.ideal = Some(evolve_vorticity(ops, &zeta, &grad, (ctx.nu, ctx.dt), None));
    }
}

/// One explicit step of the vorticity equation (Liu Eq. 7, Ye Eq. 18):
/// zeta + dt ((zeta . grad) v + nu Laplacian zeta), with the stretching of Liu Eq. 9 from the
/// gradient tensors and the Laplacian of Ye Eq. 8 (walls hold zero vorticity); only where
/// `only` holds (zero elsewhere), or everywhere for None.
pub fn evolve_vorticity(
    ops: &Operators,
    zeta: &[Vec3],
    grad: &[Mat3],
    (nu, dt): (Real, Real),
    only: Option<&[bool]>,
) -> Vec<Vec3> {
    per_particle(zeta.len(), only, |i| {
        let mut rate = grad[i] * zeta[i];
        if nu > 0.0 {
            rate += nu * ops.laplacian_at(i, zeta, WallField::Zero);
        }
        zeta[i] + dt * rate
    })
}

/// The regularisation length e of Eq. 15 for a particle of rest volume `volume` (see the
/// module documentation).
pub fn stream_core(volume: Real) -> Real {
    2.0 / 3.0 * (3.0 * volume / (4.0 * PI)).cbrt()
}

/// The local stream function (Liu Eq. 15) of the vorticity `zeta`:
/// psi_i = 1 / (4 pi) sum_{j in N(i) + i} zeta_j V_j / sqrt(|x_ij|^2 + e^2).
pub fn stream_function(ops: &Operators, zeta: &[Vec3]) -> Vec<Vec3> {
    let e = stream_core(ops.nb.volume);
    let e2 = e * e;
    (0..zeta.len())
        .into_par_iter()
        .map(|i| {
            let mut psi = ops.volume[i] * zeta[i] / e;
            ops.nb.fluid_pairs(i, |j, xij| {
                psi += ops.volume[j] * zeta[j] / (xij.norm_squared() + e2).sqrt()
            });
            psi / (4.0 * PI)
        })
        .collect()
}
