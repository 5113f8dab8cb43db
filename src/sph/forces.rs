//! Non-pressure forces: gravity, the Laplacian viscosity of Liu et al. 2021 Eq. 4, and XSPH.

use super::neighborhood::Neighborhood;
use crate::{Real, Vec3};
use rayon::prelude::*;

/// The explicit viscosity's step bound as a multiple of spacing^2 / nu. The viscous update is
/// forward Euler on nu L v, stable while dt <= 2 / (nu rho(L)); over the Fourier modes of the
/// rest lattice (support two spacings) Eq. 4's operator has rho(L) = 14.25 / spacing^2, so
/// dt <= 0.140 spacing^2 / nu (the test below). Moving particles are not a lattice: at 0.125
/// (the h^2 / (8 nu) of other SPH codes) the sloshing tank gains energy at 0.01 and 0.005 m
/// spacing; at 0.1 it does not (`tests/sph_physics.rs`).
pub const VISCOUS_STEP: Real = 0.1;

/// The largest stable step of the explicit viscosity, fluid and walls together
/// (VISCOUS_STEP spacing^2 / (nu + the strongest wall's nu)); None without viscosity.
pub fn viscous_step_limit(spacing: Real, kinematic: Real, walls: &[Real]) -> Option<Real> {
    let nu = kinematic + walls.iter().copied().fold(0.0, Real::max);
    (nu > 0.0).then(|| VISCOUS_STEP * spacing * spacing / nu)
}

/// Viscous acceleration nu * Laplacian(v) at particle i, Liu et al. 2021 Eq. 4 (after Koschier
/// et al. 2019): 2 (d + 2) sum_j (m_j / rho_j) (v_ij . x_ij) / (|x_ij|^2 + 0.01 h^2) grad W_ij,
/// d = 3. Boundary samples take part with their Akinci volume and kinematic velocity, with
/// their body's coefficient `walls[body]` (its no-slip strength); `walls` empty when every wall
/// is free-slip.
#[inline]
pub fn viscous_acceleration(
    nb: &Neighborhood,
    density: &[Real],
    rest_density: Real,
    v: &[Vec3],
    i: usize,
    nu: Real,
    walls: &[Real],
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
    if !walls.is_empty() {
        let samples = nb.boundary;
        nb.boundary_pairs_grad(i, |b, xib, g| {
            let vib = vi - samples.v[b];
            let nu_b = walls[samples.body[b] as usize];
            wall += nu_b * samples.volume[b] * vib.dot(&xib) / (xib.norm_squared() + eps) * g;
        });
    }
    10.0 * (nu * fluid + wall)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sph::kernel::CubicSpline;
    use nalgebra::Matrix3;

    /// The spectral radius of Eq. 4's operator on the rest lattice, from its Fourier symbol
    /// M(k) = sum_j B_j (1 - cos(k . x_j)), B_j the pair's 3 x 3 block, over a 7^3 grid of
    /// wave vectors in [0, pi]^3 per spacing: [`VISCOUS_STEP`] lies inside the forward-Euler
    /// bound 2 / rho, by at most 30 %.
    #[test]
    fn the_viscous_step_bound_lies_inside_the_lattice_stability_limit() {
        let spacing: Real = 0.01;
        let kernel = CubicSpline::new(2.0 * spacing);
        let eps = 0.01 * kernel.support() * kernel.support();
        let volume = spacing.powi(3);
        let mut blocks = Vec::new();
        for (i, j, k) in cube(3) {
            let x = Vec3::new(i as Real, j as Real, k as Real) * spacing;
            let g = kernel.grad(&x);
            if (i, j, k) == (0, 0, 0) || g.norm() == 0.0 {
                continue;
            }
            // a_i = 10 nu V (v_ij . x) g / (r^2 + eps), g = -|g| x / r: minus B_j v_ij.
            let b: Matrix3<Real> = -10.0 * volume / (x.norm_squared() + eps) * g * x.transpose();
            blocks.push((x, b));
        }
        let mut rho: Real = 0.0;
        for (a, b, c) in cube(6).filter(|&(a, b, c)| a >= 0 && b >= 0 && c >= 0) {
            let k =
                Vec3::new(a as Real, b as Real, c as Real) * (std::f64::consts::PI / 6.0 / spacing);
            let m: Matrix3<Real> = blocks.iter().map(|(x, b)| b * (1.0 - k.dot(x).cos())).sum();
            rho = rho.max(m.symmetric_eigen().eigenvalues.max());
        }
        let bound = 2.0 / rho / (spacing * spacing);
        println!("forward-Euler bound {bound:.4} spacing^2 / nu");
        assert!(
            VISCOUS_STEP <= bound && VISCOUS_STEP > 0.7 * bound,
            "{bound}"
        );
    }

    /// The integer points of [-m, m]^3.
    fn cube(m: i32) -> impl Iterator<Item = (i32, i32, i32)> {
        (-m..=m).flat_map(move |i| (-m..=m).flat_map(move |j| (-m..=m).map(move |k| (i, j, k))))
    }
}
