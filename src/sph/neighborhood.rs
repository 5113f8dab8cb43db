//! A read-only view of one step's neighbourhoods: what every per-particle SPH sum reads.
//!
//! The `_grad` iterators hand out this step's cached kernel gradients (see
//! [`super::pair_cache`]); they are valid for the positions of the last neighbourhood update,
//! which do not change until the step's position update.

use super::boundary::BoundaryParticles;
use super::kernel::CubicSpline;
use super::neighbors::NeighborLists;
use super::pair_cache::{widen, PairCache};
use crate::{Real, Vec3};
use std::ops::Add;

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
    /// Kernel gradients and wall sums of the positions of the last neighbourhood update.
    pub pairs: &'a PairCache,
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

    /// Calls `f(j, x_i - x_j, grad W_ij)` for every fluid neighbour j of fluid particle i, with
    /// the gradient from this step's cache (f32 precision; see [`super::pair_cache`]).
    #[inline]
    pub fn fluid_pairs_grad(&self, i: usize, mut f: impl FnMut(usize, Vec3, Vec3)) {
        let xi = self.x[i];
        let (lists, grads) = (self.fluid, &self.pairs.fluid);
        let range = lists.offsets[i] as usize..lists.offsets[i + 1] as usize;
        for (&j, g) in lists.indices[range.clone()].iter().zip(&grads[range]) {
            let j = j as usize;
            f(j, xi - self.x[j], widen(g));
        }
    }

    /// Calls `f(b, x_i - x_b, grad W_ib)` for every boundary sample b near fluid particle i,
    /// with the gradient from this step's cache.
    #[inline]
    pub fn boundary_pairs_grad(&self, i: usize, mut f: impl FnMut(usize, Vec3, Vec3)) {
        let xi = self.x[i];
        let (lists, grads) = (self.boundary_lists, &self.pairs.boundary);
        let range = lists.offsets[i] as usize..lists.offsets[i + 1] as usize;
        for (&b, g) in lists.indices[range.clone()].iter().zip(&grads[range]) {
            let b = b as usize;
            f(b, xi - self.boundary.x[b], widen(g));
        }
    }

    /// sum_j term(j, grad W_ij) over the fluid neighbours j of i: the solvers' inner loop,
    /// which needs no positions. Even and odd pairs go to two partial sums, because one chain
    /// of dependent additions would bound the loop by the adder's latency.
    #[inline]
    fn fluid_sum<T: Copy + Add<Output = T>>(
        &self,
        i: usize,
        zero: T,
        term: impl Fn(usize, Vec3) -> T,
    ) -> T {
        let (lists, grads) = (self.fluid, &self.pairs.fluid);
        let range = lists.offsets[i] as usize..lists.offsets[i + 1] as usize;
        let (idx, grads) = (&lists.indices[range.clone()], &grads[range]);
        let (mut even, mut odd) = (zero, zero);
        let pairs = idx.chunks_exact(2).zip(grads.chunks_exact(2));
        for (j, g) in pairs {
            even = even + term(j[0] as usize, widen(&g[0]));
            odd = odd + term(j[1] as usize, widen(&g[1]));
        }
        if idx.len() % 2 == 1 {
            let last = idx.len() - 1;
            even = even + term(idx[last] as usize, widen(&grads[last]));
        }
        even + odd
    }

    /// Number of fluid plus boundary neighbours of i.
    #[inline]
    pub fn count(&self, i: usize) -> usize {
        self.fluid.of(i).len() + self.boundary_lists.of(i).len()
    }

    /// Rate of change of the density ratio for velocities `v`:
    /// sum_j V (v_i - v_j) . grad W_ij + sum_b V_b (v_i - v_b) . grad W_ib.
    /// With `walls_still`, the boundary velocities v_b are taken as zero (IISPH applies this
    /// operator to pressure accelerations, which walls do not have).
    #[inline]
    pub fn density_rate(&self, i: usize, v: &[Vec3], walls_still: bool) -> Real {
        let vi = v[i];
        let rate = self.fluid_sum(i, 0.0, |j, g| (vi - v[j]).dot(&g));
        let wall = vi.dot(&self.pairs.wall_grad[i]);
        let moving = if walls_still {
            0.0
        } else {
            self.pairs.wall_rate[i]
        };
        self.volume * rate + wall - moving
    }

    /// Acceleration from the stiffness field `kappa` (kappa = rho_0 p / rho^2, so this is the
    /// symmetric SPH pressure gradient); walls push with the particle's own stiffness, as in
    /// Akinci et al. 2012 Eq. 10: -sum_j V (k_i + k_j) grad W_ij - sum_b V_b k_i grad W_ib.
    #[inline]
    pub fn stiffness_acceleration(&self, i: usize, kappa: &[Real]) -> Vec3 {
        let ki = kappa[i];
        let a = self.fluid_sum(i, Vec3::zeros(), |j, g| (ki + kappa[j]) * g);
        -(self.volume * a + ki * self.pairs.wall_grad[i])
    }
}
