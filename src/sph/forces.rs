//! Non-pressure forces: gravity, the Laplacian viscosity of Liu et al. 2021 Eq. 4, and XSPH.

use super::neighborhood::Neighborhood;
use crate::{Real, Vec3};
use rayon::prelude::*;

/// Viscous acceleration nu * Laplacian(v) at particle i, Liu et al. 2021 Eq. 4 (after Koschier
/// et al. 2019): 2 (d + 2) sum_j (m_j / rho_j) (v_ij . x_ij) / (|x_ij|^2 + 0.01 h^2) grad W_ij,
/// d = 3. Boundary samples take part with their Akinci volume and kinematic velocity, with their
/// own coefficient `nu_boundary` (no-slip strength of the walls).
#[inline]
pub fn viscous_acceleration(
    nb: &Neighborhood,
    density: &[Real],
    rest_density: Real,
    v: &[Vec3],
    i: usize,
    nu: Real,
    nu_boundary: Real,
) -> Vec3 {
    let k = nb.kernel;
    let eps = 0.01 * k.support() * k.support();
    let vi = v[i];
    let mut fluid = Vec3::zeros();
    if nu > 0.0 {
        let mass = nb.volume * rest_density;
        nb.fluid_pairs_grad(i, |j, xij, g| {
            let vij = vi - v[j];
            fluid += (mass / density[j]) * vij.dot(&xij) / (xij.norm_squared() + eps) * g;
        });
    }
    let mut wall = Vec3::zeros();
    if nu_boundary > 0.0 {
        nb.boundary_pairs_grad(i, |b, xib, g| {
            let vib = vi - nb.boundary.v[b];
            wall += nb.boundary.volume[b] * vib.dot(&xib) / (xib.norm_squared() + eps) * g;
        });
    }
    10.0 * (nu * fluid + nu_boundary * wall)
}

/// XSPH velocity smoothing (Monaghan 1989): v_i += eps sum_j (m_j / rho_j) (v_j - v_i) W_ij.
/// It damps particle noise without a time-step limit; `eps` in [0, 1].
pub fn xsph(nb: &Neighborhood, density: &[Real], rest_density: Real, v: &mut [Vec3], eps: Real) {
    let mass = nb.volume * rest_density;
    let k = nb.kernel;
    let delta: Vec<Vec3> = (0..v.len())
        .into_par_iter()
        .map(|i| {
            let mut d = Vec3::zeros();
            nb.fluid_pairs(i, |j, xij| {
                d += (mass / density[j]) * (v[j] - v[i]) * k.w(xij.norm())
            });
            eps * d
        })
        .collect();
    v.par_iter_mut().zip(delta).for_each(|(vi, d)| *vi += d);
}
