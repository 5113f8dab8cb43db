//! A read-only view of one step's neighbourhoods: what every per-particle SPH sum reads.

use super::boundary::BoundaryParticles;
use super::kernel::CubicSpline;
use super::neighbors::NeighborLists;
use crate::{Real, Vec3};

/// Fluid positions and neighbour lists, boundary samples, the kernel and the fluid rest volume.
#[derive(Clone, Copy)]
pub struct Neighborhood<'a> {
    pub kernel: &'a CubicSpline,
    pub x: &'a [Vec3],
    pub fluid: &'a NeighborLists,
    pub boundary_lists: &'a NeighborLists,
    pub boundary: &'a BoundaryParticles,
    /// Rest volume m / rho_0 of a fluid particle.
    pub volume: Real,
}

impl Neighborhood<'_> {
    /// Calls `f(j, x_i - x_j)` for every fluid neighbour j of fluid particle i.
    #[inline]
    pub fn fluid_pairs(&self, i: usize, mut f: impl FnMut(usize, Vec3)) {
        let xi = self.x[i];
        for &j in self.fluid.of(i) {
            let j = j as usize;
            f(j, xi - self.x[j]);
        }
    }

    /// Calls `f(b, x_i - x_b)` for every boundary sample b near fluid particle i.
    #[inline]
    pub fn boundary_pairs(&self, i: usize, mut f: impl FnMut(usize, Vec3)) {
        let xi = self.x[i];
        for &b in self.boundary_lists.of(i) {
            let b = b as usize;
            f(b, xi - self.boundary.x[b]);
        }
    }

    /// Number of fluid plus boundary neighbours of i.
    #[inline]
    pub fn count(&self, i: usize) -> usize {
        self.fluid.of(i).len() + self.boundary_lists.of(i).len()
    }

    /// Density over rest density, rho_i / rho_0 = V W(0) + sum_j V W_ij + sum_b V_b W_ib.
    #[inline]
    pub fn density_ratio(&self, i: usize) -> Real {
        let k = self.kernel;
        let mut sum = self.volume * k.w_zero();
        self.fluid_pairs(i, |_, xij| sum += self.volume * k.w(xij.norm()));
        self.boundary_pairs(i, |b, xib| sum += self.boundary.volume[b] * k.w(xib.norm()));
        sum
    }

    /// Rate of change of the density ratio for velocities `v`:
    /// sum_j V (v_i - v_j) . grad W_ij + sum_b V_b (v_i - v_b) . grad W_ib.
    /// With `walls_still`, the boundary velocities v_b are taken as zero (IISPH applies this
    /// operator to pressure accelerations, which walls do not have).
    #[inline]
    pub fn density_rate(&self, i: usize, v: &[Vec3], walls_still: bool) -> Real {
        let k = self.kernel;
        let vi = v[i];
        let mut rate = 0.0;
        self.fluid_pairs(i, |j, xij| {
            rate += self.volume * (vi - v[j]).dot(&k.grad(&xij))
        });
        self.boundary_pairs(i, |b, xib| {
            let vb = if walls_still {
                Vec3::zeros()
            } else {
                self.boundary.v[b]
            };
            rate += self.boundary.volume[b] * (vi - vb).dot(&k.grad(&xib))
        });
        rate
    }

    /// Acceleration from the stiffness field `kappa` (kappa = rho_0 p / rho^2, so this is the
    /// symmetric SPH pressure gradient); walls push with the particle's own stiffness, as in
    /// Akinci et al. 2012 Eq. 10: -sum_j V (k_i + k_j) grad W_ij - sum_b V_b k_i grad W_ib.
    #[inline]
    pub fn stiffness_acceleration(&self, i: usize, kappa: &[Real]) -> Vec3 {
        let k = self.kernel;
        let ki = kappa[i];
        let mut a = Vec3::zeros();
        self.fluid_pairs(i, |j, xij| {
            a -= (self.volume * (ki + kappa[j])) * k.grad(&xij)
        });
        self.boundary_pairs(i, |b, xib| {
            a -= (self.boundary.volume[b] * ki) * k.grad(&xib)
        });
        a
    }

    /// The DFSPH factor: one over the change of rho_i / rho_0 per unit of k_i dt^2,
    /// |G_f + G_b|^2 + sum_j |V grad W_ij|^2 with G_f = sum_j V grad W_ij and
    /// G_b = sum_b V_b grad W_ib; zero without neighbours.
    #[inline]
    pub fn dfsph_factor(&self, i: usize) -> Real {
        let k = self.kernel;
        let (mut gf, mut gb) = (Vec3::zeros(), Vec3::zeros());
        let mut sq = 0.0;
        self.fluid_pairs(i, |_, xij| {
            let g = self.volume * k.grad(&xij);
            gf += g;
            sq += g.norm_squared();
        });
        self.boundary_pairs(i, |b, xib| gb += self.boundary.volume[b] * k.grad(&xib));
        let denom = sq + (gf + gb).norm_squared();
        if denom > 1e-9 * self.volume * self.volume / (k.support().powi(8)) {
            1.0 / denom
        } else {
            0.0
        }
    }
}
